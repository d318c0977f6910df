//! Pictures of bodies for people: a body model along one beta (`egogen body shapes`), at rest
//! and walking (`egogen body preview`), its hands doing each thing a hand does (`egogen body
//! hands`, `motion::hands`) and an imported clip's strip, the source skeleton above the
//! retargeted body (`egogen motion import --strip`). Here because they draw bodies and their
//! motion with `preview`, which neither `body` nor `motion` may use.

use std::path::Path;

use anyhow::{bail, Result};

use crate::atomic_file::refuse_existing;
use crate::body::{BodyModel, BodyParams};
use crate::math::Vec3;
use crate::motion::clip_import::ImportedClip;
use crate::motion::hands::{HandAxes, HandDoing, HandStyle};
use crate::motion::jobs::walk_params;
use crate::preview::MeshView;

/// Colour the previews draw skin in (linear RGB).
const SKIN: [f64; 3] = [0.86, 0.72, 0.62];
/// Background between the preview's panels.
const PANEL_GAP: [u8; 3] = [245, 245, 240];

/// Draws the rest body for each of `values` of beta `beta`, side by side, to `out` (PNG).
pub(crate) fn body_shapes(model: &Path, beta: usize, values: &[f64], out: &Path) -> Result<()> {
    let m = BodyModel::load(model)?;
    if beta >= m.num_betas() {
        bail!("--beta {beta}: the model has betas 0..{}", m.num_betas());
    }
    let bodies = values
        .iter()
        .map(|&v| {
            let mut betas = vec![0.0; beta + 1];
            betas[beta] = v;
            m.pose(&BodyParams {
                betas,
                ..Default::default()
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    // One shared frame so sizes compare: offset bodies along x, draw them together.
    let mut verts = Vec::new();
    let mut faces = Vec::new();
    for (k, b) in bodies.iter().enumerate() {
        let base = verts.len() as u32;
        verts.extend(
            b.vertices
                .iter()
                .map(|v| *v + Vec3::new(2.2 * k as f64, 0.0, 0.0)),
        );
        faces.extend(m.faces.iter().map(|f| f.map(|i| i + base)));
    }
    let img = MeshView::looking_from(Vec3::Z, Vec3::Y).render(
        &[(&verts, &faces, SKIN)],
        360 * values.len(),
        400,
    );
    img.write_png(out)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The body with `betas` at rest (front, side) and mid-stride (front, side), to `out` (PNG).
pub(crate) fn body_preview(
    model: &Path,
    betas: &[f64],
    out: &Path,
    height_px: usize,
) -> Result<()> {
    let m = BodyModel::load(model)?;
    let rest = m.pose(&BodyParams {
        betas: betas.to_vec(),
        ..Default::default()
    })?;
    let walk = m.pose(&walk_params(&m, betas, 0.2)?)?;
    // The walk is in the z-up world; bring it back to the model's y-up frame for the picture.
    let to_y_up = |v: &Vec3| Vec3::new(v.y, v.z, v.x);
    let walk_y_up: Vec<Vec3> = walk.vertices.iter().map(to_y_up).collect();
    let front = MeshView::looking_from(Vec3::Z, Vec3::Y);
    let side = MeshView::looking_from(Vec3::X, Vec3::Y);
    let w = height_px * 3 / 4;
    let mut img = front.render(&[(&rest.vertices, &m.faces, SKIN)], w, height_px);
    img = img.hconcat(
        &side.render(&[(&rest.vertices, &m.faces, SKIN)], w / 2, height_px),
        PANEL_GAP,
    );
    img = img.hconcat(
        &front.render(&[(&walk_y_up, &m.faces, SKIN)], w / 2, height_px),
        PANEL_GAP,
    );
    img = img.hconcat(
        &side.render(&[(&walk_y_up, &m.faces, SKIN)], w / 2, height_px),
        PANEL_GAP,
    );
    img.write_png(out)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// What `egogen body hands` draws, row by row.
const HAND_ROWS: [HandDoing; 5] = [
    HandDoing::Walking,
    HandDoing::Standing,
    HandDoing::Seated,
    HandDoing::Reaching,
    HandDoing::HOLDING_A_CUP,
];

/// The right hand of `people` people (their hands drawn from seeds 0, 1, …) doing each thing a
/// hand does (rows: walking, standing, seated, reaching, holding; the drift at its first
/// frame), seen from the thumb's side and from the palm, to `out` (PNG); the rest hand of the
/// body model in the first column.
pub(crate) fn body_hands(model: &Path, people: usize, out: &Path, cell_px: usize) -> Result<()> {
    use rand_core::SeedableRng;
    refuse_existing(out)?;
    let m = BodyModel::load(model)?;
    let shaped = m.shape(&[], &[])?;
    let axes = HandAxes::from_rest(&shaped.rest_joints);
    let (wrist, hand_joints) = (21, 40..55);
    // The right hand's vertices: those beyond the wrist along −x.
    let cut = shaped.rest_joints[wrist].x + 0.01;
    let keep: Vec<Option<u32>> = {
        let mut next = 0u32;
        shaped
            .v_shaped
            .iter()
            .map(|v| {
                (v.x < cut).then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect()
    };
    let faces: Vec<[u32; 3]> = m
        .faces
        .iter()
        .filter_map(|f| {
            let [a, b, c] = f.map(|i| keep[i as usize]);
            Some([a?, b?, c?])
        })
        .collect();
    let views = [
        MeshView::looking_from(Vec3::new(-0.3, 0.35, 1.0), Vec3::Y),
        MeshView::looking_from(Vec3::new(-0.2, -1.0, 0.25), Vec3::Z),
    ];
    let draw = |frame: &BodyParams| -> Result<Vec<crate::preview::RgbImage>> {
        let body = shaped.pose(&frame.pose, Vec3::ZERO)?;
        let verts: Vec<Vec3> = body
            .vertices
            .iter()
            .zip(&keep)
            .filter_map(|(v, k)| k.map(|_| *v))
            .collect();
        Ok(views
            .iter()
            .map(|view| view.render(&[(&verts, &faces, SKIN)], cell_px, cell_px))
            .collect())
    };
    let _ = hand_joints;
    let mut cells = Vec::new();
    let columns = 2 * (people + 1);
    for doing in HAND_ROWS {
        cells.extend(draw(&BodyParams::default())?);
        for person in 0..people {
            let style = HandStyle::draw(&mut rand_chacha::ChaCha8Rng::seed_from_u64(person as u64));
            let mut frame = [BodyParams::default()];
            crate::motion::hands::move_fingers(&mut frame, &[[doing; 2]], &axes, &style, 40.0);
            cells.extend(draw(&frame[0])?);
        }
    }
    let sheet = crate::preview::RgbImage::contact_sheet(&cells, cell_px, columns, PANEL_GAP);
    sheet.write_png(out)?;
    println!(
        "wrote {} (rows: walking, standing, seated, reaching, holding; columns: the rest hand, then {people} people; each from the thumb's side and the palm)",
        out.display()
    );
    Ok(())
}

/// The strip of an imported clip (`egogen motion import --strip`), to `strip` (PNG): columns
/// every 0.5 s of the clip at `rate_hz`, `strip_frames` of them; top: the source skeleton
/// (metres, z up), bottom: the body it was retargeted to.
pub(crate) fn import_strip(
    imported: &ImportedClip,
    rate_hz: f64,
    strip_frames: usize,
    strip: &Path,
) -> Result<()> {
    use crate::motion::retarget::{CMU_TO_SMPLX, CMU_UNIT_M};
    use crate::preview::sticks::bone_mesh;
    let ImportedClip {
        clip,
        seq,
        model: m,
    } = imported;
    // Columns every 0.5 s; top: the source skeleton (metres, z up), bottom: our body.
    let step = ((0.5 * rate_hz).round() as usize).max(1);
    let frames: Vec<usize> = (0..seq.len()).step_by(step).take(strip_frames).collect();
    let to_world = |p: Vec3| Vec3::new(p.x, -p.z, p.y) * CMU_UNIT_M;
    let used: Vec<usize> = clip
        .iter()
        .flat_map(|c| CMU_TO_SMPLX.iter().filter_map(|(_, n, _)| c.joint_index(n)))
        .collect();
    let shaped = m.shape(&[], &[])?;
    let mut verts = Vec::new();
    let mut faces = Vec::new();
    let mut bones_v = Vec::new();
    let mut bones_f = Vec::new();
    for (col, &f) in frames.iter().enumerate() {
        let body = shaped.pose(&seq.poses[f], seq.trans[f])?;
        let pelvis = body.joints[0];
        let offset = Vec3::new(1.2 * col as f64, 0.0, 0.0);
        let segs: Vec<(Vec3, Vec3)> = match &clip {
            Some(clip) => {
                let src_f = ((f as f64 / rate_hz) * clip.frame_rate_hz).round() as usize;
                let g = clip.global_transforms(src_f.min(clip.frames.len() - 1));
                let root = to_world(g[used[0]].translation);
                let lift = Vec3::new(0.0, 0.0, 2.2);
                let place = |q: Vec3| to_world(q) - Vec3::new(root.x, root.y, 0.0) + offset + lift;
                clip.joints
                    .iter()
                    .enumerate()
                    .filter_map(|(i, j)| {
                        j.parent
                            .map(|p| (place(g[p].translation), place(g[i].translation)))
                    })
                    .collect()
            }
            None => Vec::new(),
        };
        let (bv, bf) = bone_mesh(&segs, 0.02);
        let base = bones_v.len() as u32;
        bones_v.extend(bv);
        bones_f.extend(bf.iter().map(|t| t.map(|i| i + base)));
        let base = verts.len() as u32;
        verts.extend(
            body.vertices
                .iter()
                .map(|v| *v - Vec3::new(pelvis.x, pelvis.y, 0.0) + offset),
        );
        faces.extend(m.faces.iter().map(|t| t.map(|i| i + base)));
    }
    // Front view: the retargeted body faces −y, so look from −y.
    let view = MeshView::looking_from(Vec3::new(0.0, -1.0, 0.0), Vec3::Z);
    let img = view.render(
        &[
            (&verts, &faces, [0.86, 0.72, 0.62]),
            (&bones_v, &bones_f, [0.3, 0.45, 0.8]),
        ],
        150 * frames.len(),
        560,
    );
    img.write_png(strip)?;
    println!("wrote {}", strip.display());
    Ok(())
}
