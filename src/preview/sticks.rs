//! Stick figures: bones as thin square prisms, to draw skeletons with the mesh rasteriser.

use crate::math::Vec3;

/// A closed square prism around each segment (`radius` = half side), as one triangle mesh.
pub(crate) fn bone_mesh(segments: &[(Vec3, Vec3)], radius: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut verts = Vec::with_capacity(segments.len() * 8);
    let mut tris = Vec::with_capacity(segments.len() * 12);
    for &(a, b) in segments {
        let Some(axis) = (b - a).try_normalize() else {
            continue;
        };
        let u = axis.any_orthonormal_vector() * radius;
        let v = axis.cross(u);
        let base = verts.len() as u32;
        for end in [a, b] {
            for (su, sv) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
                verts.push(end + u * su + v * sv);
            }
        }
        for k in 0..4u32 {
            let (i, j) = (k, (k + 1) % 4);
            tris.push([base + i, base + j, base + 4 + j]);
            tris.push([base + i, base + 4 + j, base + 4 + i]);
        }
        tris.push([base, base + 1, base + 2]);
        tris.push([base, base + 2, base + 3]);
        tris.push([base + 4, base + 6, base + 5]);
        tris.push([base + 4, base + 7, base + 6]);
    }
    (verts, tris)
}
