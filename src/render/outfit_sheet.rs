//! `egogen body outfits`: a sheet of people drawn as takes draw them — a shape, a skin and an
//! outfit each from the seed — standing with their arms down, rendered front and back by
//! Blender with the take's own materials (`render_shard.py --outfit-sheet`).

use std::path::Path;

use anyhow::{bail, Context, Result};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use super::outfit::regions::garment_fields;
use super::outfit::{OutfitPlan, ShardOutfit, SLOTS};
use crate::body::{joint, BodyModel, BodyParams};
use crate::math::random::standard_normal;
use crate::math::Vec3;
use crate::render::protocol::ShardSkinRegion;
use crate::render::skin_tone::{SkinPlan, SkinTextures};
use crate::render::BlenderRuntime;
use crate::vertex_cache::{write_corner_uvs_npy, write_faces_npy, write_vertex_rows_npy};

/// What the sheet shows and how it is rendered.
struct Sheet {
    people: usize,
    seed: u64,
    cell_px: u32,
    samples: u32,
}

/// Renders `people` people drawn from `seed` with `model` to `out` (PNG, refused if it
/// exists): each picture `cell_px` high and half as wide, `samples` Cycles samples a pixel.
pub(crate) fn outfit_sheet(
    model_path: &Path,
    people: usize,
    seed: u64,
    cell_px: u32,
    samples: u32,
    blender: Option<&Path>,
    out: &Path,
) -> Result<()> {
    let sheet = Sheet {
        people,
        seed,
        cell_px,
        samples,
    };
    crate::atomic_file::refuse_existing(out)?;
    if sheet.people == 0 || sheet.cell_px < 16 || sheet.samples == 0 {
        bail!("--people, --samples must be ≥ 1 and --cell-px ≥ 16");
    }
    let model = BodyModel::load(model_path)?;
    let runtime = BlenderRuntime::resolve(blender)?;
    let scratch = tempfile::Builder::new()
        .prefix("egogen-outfits-")
        .tempdir()
        .context("making a scratch folder")?;
    let work = scratch.path();
    let faces = work.join("faces.npy");
    write_faces_npy(&faces, &model.faces)?;
    let textures = SkinTextures::of(&model)?;
    let uvs = match (&model.uvs, textures.need_uvs()) {
        (Some(uvs), true) => {
            let path = work.join("uvs.npy");
            write_corner_uvs_npy(&path, &uvs.per_corner())?;
            Some(path)
        }
        _ => None,
    };
    let skins = SkinPlan {
        seed: sheet.seed,
        ..SkinPlan::default()
    };
    let outfits = OutfitPlan {
        seed: sheet.seed,
        ..OutfitPlan::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(sheet.seed ^ 0x5EE7);
    let mut people = Vec::new();
    for k in 0..sheet.people {
        let betas: Vec<f64> = (0..4).map(|_| 1.2 * standard_normal(&mut rng)).collect();
        let mut params = BodyParams {
            betas: betas.clone(),
            ..Default::default()
        };
        // Arms down by the sides, a little away from the body.
        params.set_joint_axis_angle(joint::LEFT_SHOULDER, Vec3::new(0.0, 0.0, -1.2));
        params.set_joint_axis_angle(joint::RIGHT_SHOULDER, Vec3::new(0.0, 0.0, 1.2));
        let posed = model.pose(&params)?;
        let vertices = work.join(format!("person_{k}_vertices.npy"));
        let rows: Vec<[f32; 3]> = posed
            .vertices
            .iter()
            .map(|v| [v.x as f32, v.y as f32, v.z as f32])
            .collect();
        write_vertex_rows_npy(&vertices, &rows)?;
        let skin = skins.draw(k);
        let outfit = outfits.draw(k).expect("outfits are on");
        let fields = work.join(format!("person_{k}_outfit.npy"));
        write_vertex_rows_npy(&fields, &garment_fields(&model, &betas, &outfit)?)?;
        let regions = ShardSkinRegion::painted(&textures, &skin);
        people.push(serde_json::json!({
            "name": format!("person_{k}"),
            "vertices_npy": vertices,
            "faces_npy": faces,
            "uvs_npy": uvs,
            "skin": skin,
            "skin_regions": regions,
            "skin_detail": textures.detail,
            "outfit": ShardOutfit {
                fields_npy: fields,
                slots: SLOTS.iter().map(|s| s.to_string()).collect(),
                outfit,
            },
        }));
    }
    let spec = work.join("sheet.json");
    let doc = serde_json::json!({
        "people": people,
        "cell_px": sheet.cell_px,
        "samples": sheet.samples,
        "out": work.join("sheet.png"),
    });
    std::fs::write(&spec, serde_json::to_vec_pretty(&doc)?)
        .with_context(|| format!("writing {}", spec.display()))?;
    eprintln!(
        "rendering {} people front and back with Blender {} …",
        sheet.people, runtime.version
    );
    let status = crate::render::shard::script_command(
        &runtime,
        &["--outfit-sheet".as_ref(), spec.as_os_str()],
    )
    .status()
    .context("starting Blender")?;
    if !status.success() {
        bail!("Blender failed on the outfit sheet ({status})");
    }
    let png = std::fs::read(work.join("sheet.png")).context("reading Blender's sheet")?;
    crate::atomic_file::write_atomically(out, &png)
        .with_context(|| format!("writing {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(())
}
