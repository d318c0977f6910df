//! The shipped body model carries MakeHuman's UV layout: each region mask shipped beside it
//! (`assets/body/textures/`), read at every triangle corner's UV, selects the anatomy it is
//! named for on the rest body. Scrambled or mis-split UVs would scatter the selections.

use std::collections::BTreeSet;
use std::path::PathBuf;

use egogen::body::{BodyModel, JOINT_NAMES};
use egogen::math::Vec3;
use egogen::render::skin_tone::SKIN_REGIONS;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A grey mask as (width, height, row-major luma, row 0 at the top).
fn mask(file: &str) -> (usize, usize, Vec<u8>) {
    let path = repo().join("assets/body/textures").join(file);
    let bytes = std::fs::read(&path).unwrap();
    let options = zune_jpeg::zune_core::options::DecoderOptions::default()
        .jpeg_set_out_colorspace(zune_jpeg::zune_core::colorspace::ColorSpace::Luma);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(
        zune_jpeg::zune_core::bytestream::ZCursor::new(&bytes),
        options,
    );
    let pixels = decoder.decode().unwrap();
    let (w, h) = decoder.dimensions().unwrap();
    assert_eq!(pixels.len(), w * h, "{}", path.display());
    (w, h, pixels)
}

/// Rest-pose vertices (zero shape) whose corner UV falls inside `file`'s mask.
fn region(model: &BodyModel, file: &str) -> Vec<Vec3> {
    let uvs = model.uvs.as_ref().expect("the shipped model has UVs");
    let (w, h, px) = mask(file);
    let mut picked = BTreeSet::new();
    for (tri, uv_tri) in model.faces.iter().zip(&uvs.faces) {
        for c in 0..3 {
            let [u, v] = uvs.coords[uv_tri[c] as usize];
            // v up: row 0 of the image is v = 1.
            let x = ((u * w as f32) as usize).min(w - 1);
            let y = (((1.0 - v) * h as f32) as usize).min(h - 1);
            if px[y * w + x] > 127 {
                picked.insert(tri[c]);
            }
        }
    }
    picked
        .into_iter()
        .map(|i| model.v_template[i as usize])
        .collect()
}

fn joint(joints: &[Vec3], name: &str) -> Vec3 {
    joints[JOINT_NAMES.iter().position(|n| *n == name).unwrap()]
}

#[test]
fn shipped_uvs_are_whole_and_in_the_unit_square() {
    let model = BodyModel::load(repo().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let uvs = model.uvs.as_ref().unwrap();
    assert_eq!(uvs.faces.len(), model.faces.len());
    assert!(uvs
        .coords
        .iter()
        .all(|c| c.iter().all(|x| (0.0..=1.0).contains(x))));
    let used: BTreeSet<u32> = uvs.faces.iter().flatten().copied().collect();
    assert_eq!(used.len(), uvs.coords.len(), "every coordinate is used");
    assert_eq!(uvs.per_corner().len(), 3 * model.faces.len());
    // Seams: more coordinates than vertices, each vertex with at least one.
    assert!(uvs.coords.len() > model.num_vertices());
}

#[test]
fn region_masks_select_the_anatomy_they_are_named_for() {
    let model = BodyModel::load(repo().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let shaped = model.shape(&[], &[]).unwrap();
    let j = shaped.rest_joints.to_vec();
    let eyes = [joint(&j, "left_eye_smplhf"), joint(&j, "right_eye_smplhf")];
    let distal: Vec<Vec3> = JOINT_NAMES
        .iter()
        .zip(&j)
        .filter(|(n, _)| n.ends_with('3') && !n.contains("spine"))
        .map(|(_, p)| *p)
        .collect();
    assert_eq!(distal.len(), 10);
    let feet = [joint(&j, "left_foot"), joint(&j, "right_foot")];
    let near = |p: &Vec3, set: &[Vec3], r: f64| set.iter().any(|q| p.distance(*q) < r);
    let both_sides = |ps: &[Vec3]| ps.iter().any(|p| p.x > 0.0) && ps.iter().any(|p| p.x < 0.0);
    assert_eq!(SKIN_REGIONS.len(), 7);
    for r in SKIN_REGIONS {
        let ps = region(&model, r.mask_file);
        assert!(ps.len() >= 30, "{}: {} vertices", r.name, ps.len());
        let ok = |p: &Vec3| match r.name {
            // On the midline below the eyes, at the front of the face.
            "lips" => {
                p.x.abs() < 0.03
                    && p.y < eyes[0].y - 0.04
                    && p.y > eyes[0].y - 0.1
                    && p.z > eyes[0].z
            }
            "eyelids" => near(p, &eyes, 0.03),
            // The sockets MakeHuman paints red: at the eye joints.
            "eyes" => near(p, &eyes, 0.025),
            // At the sides of the head, behind the eyes.
            "ears" => p.x.abs() > 0.06 && near(p, &[joint(&j, "head")], 0.1) && p.z < eyes[0].z,
            // On the front of the chest.
            "areolae" => {
                (0.05..0.15).contains(&p.x.abs())
                    && p.y > joint(&j, "spine2").y
                    && p.y < joint(&j, "neck").y
                    && p.z > joint(&j, "spine3").z + 0.1
            }
            "fingernails" => near(p, &distal, 0.03),
            "toenails" => p.y < 0.04 && p.z > feet[0].z && near(p, &feet, 0.07),
            other => panic!("a region without an anatomical check: {other}"),
        };
        let bad: Vec<&Vec3> = ps.iter().filter(|p| !ok(p)).collect();
        assert!(
            bad.is_empty(),
            "{}: {} of {} vertices off, e.g. {:?}",
            r.name,
            bad.len(),
            ps.len(),
            bad[0]
        );
        assert!(both_sides(&ps), "{}: one side only", r.name);
    }
}
