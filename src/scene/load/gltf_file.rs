//! Reading glTF/GLB files (`gltf`): one part per mesh node, its transform applied, and which
//! parts are textured or let light through.

use std::path::Path;

use super::Part;

pub(super) fn read_gltf(path: &Path) -> Result<Vec<Part>, String> {
    crate::parser_guard::catch_parser_panic(|| read_gltf_parts(path))
        .map_err(|e| format!("not a valid glTF file ({e})"))?
}

fn read_gltf_parts(path: &Path) -> Result<Vec<Part>, String> {
    let gltf = gltf::Gltf::open(path).map_err(|e| e.to_string())?;
    let buffers = gltf::import_buffers(&gltf.document, path.parent(), gltf.blob.clone())
        .map_err(|e| e.to_string())?;
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or("the file has no scene")?;
    let mut parts = Vec::new();
    let mut stack: Vec<(gltf::Node, glam::DMat4)> =
        scene.nodes().map(|n| (n, glam::DMat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        stack.extend(node.children().map(|c| (c, world)));
        let Some(mesh) = node.mesh() else { continue };
        let name = node
            .name()
            .or(mesh.name())
            .map(str::to_owned)
            .unwrap_or_else(|| format!("node_{}", node.index()));
        let mut part = Part::empty(name);
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            part.textured |= prim
                .material()
                .pbr_metallic_roughness()
                .base_color_texture()
                .is_some()
                || prim.get(&gltf::Semantic::Colors(0)).is_some();
            part.see_through |= prim.material().alpha_mode() != gltf::material::AlphaMode::Opaque;
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(pos) = reader.read_positions() else {
                continue;
            };
            let base = part.positions.len() as u32;
            part.positions.extend(pos.map(|p| {
                world
                    .transform_point3(glam::Vec3::from(p).as_dvec3())
                    .to_array()
            }));
            let n = part.positions.len() as u32 - base;
            let idx: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..n).collect(),
            };
            part.triangles.extend(
                idx.chunks_exact(3)
                    .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
            );
        }
        parts.push(part);
    }
    parts.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(parts)
}
