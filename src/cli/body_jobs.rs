//! `egogen body info|shapes|pose|preview|hands`: a body model summarised, drawn along one beta,
//! posed to OBJ (from a motion file or the scripted walk), previewed at rest and walking, and
//! its hands drawn doing each thing a hand does (`motion::hands`).

use std::path::Path;

use anyhow::{bail, Result};

use crate::atomic_file::refuse_existing;
use crate::body::export::write_obj;
use crate::body::{BodyModel, BodyParams, CpfCalibration};
use crate::math::Vec3;
use crate::motion::hands::{HandAxes, HandDoing, HandStyle};
use crate::motion::scripted::WalkCycle;
use crate::motion::MotionSequence;
use crate::preview::MeshView;

/// Colour the previews draw skin in (linear RGB).
const SKIN: [f64; 3] = [0.86, 0.72, 0.62];
/// Background between the preview's panels.
const PANEL_GAP: [u8; 3] = [245, 245, 240];

/// Prints the model's sizes, rest stature and CPF calibration.
pub fn body_info(model: &Path) -> Result<()> {
    let m = BodyModel::load(model)?;
    let shaped = m.shape(&[], &[])?;
    let cal = CpfCalibration::from_rest_joints(&shaped.rest_joints);
    let (lo, hi) = shaped.v_shaped.iter().fold(
        (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    println!("model:            {}", m.source.display());
    println!("vertices:         {}", m.num_vertices());
    println!("triangles:        {}", m.faces.len());
    println!("betas:            {}", m.num_betas());
    println!("expression:       {}", m.num_expression());
    println!(
        "pose correctives: {}",
        if m.has_pose_correctives() {
            "yes"
        } else {
            "none (skipped)"
        }
    );
    println!("stature (rest):   {:.3} m", hi.y - lo.y);
    let eyes = (shaped.rest_joints[23] + shaped.rest_joints[24]) * 0.5;
    println!(
        "CPF at rest:      ({:.3}, {:.3}, {:.3}) m; eye-bone plane tilt removed: {:.1}°",
        eyes.x,
        eyes.y,
        eyes.z,
        cal.rest_tilt_down_rad().to_degrees()
    );
    Ok(())
}

/// Draws the rest body for each of `values` of beta `beta`, side by side, to `out` (PNG).
pub fn body_shapes(model: &Path, beta: usize, values: &[f64], out: &Path) -> Result<()> {
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

/// Poses frame `frame` of `motion` (or of the scripted walk at 40 fps) and writes it as OBJ.
pub fn body_pose(model: &Path, motion: Option<&Path>, frame: usize, out: &Path) -> Result<()> {
    refuse_existing(out)?;
    let m = BodyModel::load(model)?;
    let params = match motion {
        Some(p) => {
            let seq = MotionSequence::read(p)?;
            if frame >= seq.len() {
                bail!(
                    "motion file {}: frame {frame} requested but it has {} frames",
                    p.display(),
                    seq.len()
                );
            }
            seq.frame(frame)
        }
        None => walk_params(&m, &[], frame as f64 / 40.0)?,
    };
    let body = m.pose(&params)?;
    write_obj(out, &body.vertices, &m.faces)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The body with `betas` at rest (front, side) and mid-stride (front, side), to `out` (PNG).
pub fn body_preview(model: &Path, betas: &[f64], out: &Path, height_px: usize) -> Result<()> {
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

/// The scripted walk's frame at `t_s`, standing on the floor.
fn walk_params(m: &BodyModel, betas: &[f64], t_s: f64) -> Result<BodyParams> {
    let shaped = m.shape(betas, &[])?;
    Ok(WalkCycle::default().params_at(t_s, betas, shaped.rest_joints[0], shaped.rest_sole_y()))
}

/// What `egogen body hands` draws, row by row.
const HAND_ROWS: [HandDoing; 5] = [
    HandDoing::Walking,
    HandDoing::Standing,
    HandDoing::Seated,
    HandDoing::Reaching,
    HandDoing::Holding,
];

/// The right hand of `people` people (their hands drawn from seeds 0, 1, …) doing each thing a
/// hand does (rows: walking, standing, seated, reaching, holding; the drift at its first
/// frame), seen from the thumb's side and from the palm, to `out` (PNG); the rest hand of the
/// body model in the first column.
pub fn body_hands(model: &Path, people: usize, out: &Path, cell_px: usize) -> Result<()> {
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
