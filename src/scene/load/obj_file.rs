//! Reading Wavefront OBJ files (`tobj`): one part per object or group, named as Blender's
//! importer names its objects.

use std::path::Path;

use super::Part;

/// tobj's name for faces that come before any `o` or `g` line.
const TOBJ_UNNAMED: &str = "unnamed_object";

/// An OBJ's objects and groups (`o`, `g`), each one part; the pieces tobj splits off where
/// the material changes (`usemtl`) join their object again, in order of first appearance, so
/// that parts are named as Blender's importer names its objects (one per object or group).
/// Faces before any `o` or `g` line (a file without them: all its faces) are one part named
/// after the file, as Blender names that object.
pub(super) fn read_obj(path: &Path) -> Result<Vec<Part>, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let (models, materials) = crate::parser_guard::catch_parser_panic(|| {
        tobj::load_obj_buf(&mut std::io::BufReader::new(file), &opts, |mtl| {
            load_mtl(&path.parent().unwrap_or(Path::new("")).join(mtl))
        })
    })?
    .map_err(|e| e.to_string())?;
    // A missing or unreadable MTL leaves the faces untextured, as Blender's importer does.
    let materials = materials.unwrap_or_default();
    let leading = obj_faces_before_any_object(path)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "obj".into());
    let mut parts: Vec<Part> = Vec::new();
    let mut index = std::collections::HashMap::new();
    for m in models {
        let name = match (&leading, m.name.as_str()) {
            (Some(named_unnamed), TOBJ_UNNAMED) if !named_unnamed => stem.clone(),
            _ => m.name,
        };
        let k = *index.entry(name.clone()).or_insert_with(|| {
            parts.push(Part::empty(name));
            parts.len() - 1
        });
        let part = &mut parts[k];
        if let Some(mat) = m.mesh.material_id.and_then(|i| materials.get(i)) {
            part.textured |= mat
                .diffuse_texture
                .as_deref()
                .is_some_and(|t| !t.is_empty());
            part.see_through |=
                mat.dissolve.is_some_and(|d| d < 1.0) || mat.dissolve_texture.is_some();
        }
        let base = part.positions.len() as u32;
        part.positions.extend(
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]),
        );
        part.triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]].map(|i| i.saturating_add(base))),
        );
    }
    Ok(parts)
}

/// A material library as tobj reads it; one tobj cannot read (it panics on a colour of fewer
/// than three numbers) is an error, as a missing one is.
fn load_mtl(path: &Path) -> tobj::MTLLoadResult {
    crate::parser_guard::catch_parser_panic(|| tobj::load_mtl(path))
        .unwrap_or(Err(tobj::LoadError::MaterialParseError))
}

/// Whether an OBJ has faces before its first `o` or `g` line (`Some`), and then whether one of
/// its `o`/`g` lines is itself named tobj's [`TOBJ_UNNAMED`] (then both are one part, as tobj
/// reads them).
fn obj_faces_before_any_object(path: &Path) -> Result<Option<bool>, String> {
    use std::io::BufRead;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut leading = false;
    let mut named_unnamed = false;
    for line in std::io::BufReader::new(file).split(b'\n') {
        let line = line.map_err(|e| e.to_string())?;
        let line = line.trim_ascii_start();
        match line.first() {
            // (An `o`/`g` line before any face has returned already.)
            Some(b'f') if line.get(1).is_some_and(u8::is_ascii_whitespace) => leading = true,
            Some(b'o' | b'g') if line.get(1).is_none_or(u8::is_ascii_whitespace) => {
                if !leading {
                    return Ok(None);
                }
                if line[1..].trim_ascii() == TOBJ_UNNAMED.as_bytes() {
                    named_unnamed = true;
                }
            }
            _ => {}
        }
    }
    Ok(leading.then_some(named_unnamed))
}
