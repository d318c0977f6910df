//! Writing posed meshes for people and other tools (Wavefront OBJ).

use std::io::Write;
use std::path::Path;

use crate::math::Vec3;

/// Writes a triangle mesh as OBJ (metres, the coordinates as given), atomically.
pub(crate) fn write_obj(path: &Path, vertices: &[Vec3], faces: &[[u32; 3]]) -> std::io::Result<()> {
    let tmp = path.with_extension("obj.partial");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        writeln!(
            w,
            "# egogen posed body: {} vertices, {} triangles, metres",
            vertices.len(),
            faces.len()
        )?;
        for v in vertices {
            writeln!(w, "v {:.6} {:.6} {:.6}", v.x, v.y, v.z)?;
        }
        for f in faces {
            writeln!(w, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
        }
        w.flush()?;
    }
    std::fs::rename(&tmp, path)
}
