//! A chain of primitives shown to people: one JSON line per primitive (`--chain-trace`) and
//! stick figures from above and from the side (`--walk-png`).

use std::path::Path;

use anyhow::Result;

use crate::math::Vec3;
use crate::preview::MeshView;

/// One JSON line per primitive of a chain: pelvis height above the floor (m, min and max),
/// the largest tilt of the trunk (pelvis → neck) from the vertical (deg), the mean horizontal
/// pelvis speed (m/s) and the lowest foot joint above the floor (m, min and max).
pub(super) fn write_chain_trace(
    prims: &[crate::motion::cvae::DecodedPrimitive],
    file: &Path,
) -> Result<()> {
    use crate::body::joint;
    use crate::motion::primitive::{PRIMITIVE_RATE_HZ, SEED_FRAMES};
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::fs::File::create(file)?);
    for (i, p) in prims.iter().enumerate() {
        let frames = &p.joints[SEED_FRAMES..];
        let range = |v: Vec<f64>| {
            v.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                    (lo.min(x), hi.max(x))
                })
        };
        let pelvis = range(
            frames
                .iter()
                .map(|j| j[joint::PELVIS].z - p.floor_z)
                .collect(),
        );
        let foot = range(
            frames
                .iter()
                .map(|j| {
                    [
                        joint::LEFT_FOOT,
                        joint::RIGHT_FOOT,
                        joint::LEFT_ANKLE,
                        joint::RIGHT_ANKLE,
                    ]
                    .iter()
                    .map(|&k| j[k].z)
                    .fold(f64::INFINITY, f64::min)
                        - p.floor_z
                })
                .collect(),
        );
        let tilt_deg = frames
            .iter()
            .map(|j| {
                let up = (j[joint::NECK] - j[joint::PELVIS]).normalize();
                up.z.clamp(-1.0, 1.0).acos().to_degrees()
            })
            .fold(0.0, f64::max);
        let start = p.joints[SEED_FRAMES - 1][joint::PELVIS];
        let end = p.joints[p.joints.len() - 1][joint::PELVIS];
        let speed = ((end.x - start.x).powi(2) + (end.y - start.y).powi(2)).sqrt()
            * PRIMITIVE_RATE_HZ
            / frames.len() as f64;
        writeln!(
            out,
            "{}",
            serde_json::json!({
                "primitive": i,
                "pelvis_min_m": pelvis.0, "pelvis_max_m": pelvis.1,
                "trunk_tilt_max_deg": tilt_deg,
                "pelvis_speed_m_s": speed,
                "lowest_foot_min_m": foot.0, "lowest_foot_max_m": foot.1,
            })
        )?;
    }
    out.flush()?;
    Ok(())
}

/// Stick figures every 0.5 s over the first 10 s of a chain, from above (left) and from the
/// side (right), with the pelvis path.
pub(super) fn draw_walk(prims: &[crate::motion::cvae::DecodedPrimitive], png: &Path) -> Result<()> {
    use crate::body::PARENTS;
    use crate::motion::primitive::SEED_FRAMES;
    use crate::preview::sticks::bone_mesh;
    let frames: Vec<&Vec<Vec3>> = prims
        .iter()
        .flat_map(|p| p.joints[SEED_FRAMES..].iter())
        .take(400)
        .collect();
    let mut bones = Vec::new();
    for f in frames.iter().step_by(20) {
        for j in 1..22 {
            bones.push((f[PARENTS[j].unwrap_or(0)], f[j]));
        }
    }
    let path: Vec<(Vec3, Vec3)> = frames.windows(2).map(|w| (w[0][0], w[1][0])).collect();
    // The floor under the walk (world z = 0 for mocap seeds, below the canonical origin for
    // seeds taken from training primitives).
    let floor_z = prims.first().map_or(0.0, |p| p.floor_z);
    let floor = {
        let (lo, hi) = frames.iter().fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), f| (lo.min(f[0]), hi.max(f[0])),
        );
        let (lo, hi) = (lo - Vec3::splat(0.5), hi + Vec3::splat(0.5));
        vec![
            (
                Vec3::new(lo.x, lo.y, floor_z),
                Vec3::new(hi.x, lo.y, floor_z),
            ),
            (
                Vec3::new(hi.x, lo.y, floor_z),
                Vec3::new(hi.x, hi.y, floor_z),
            ),
            (
                Vec3::new(hi.x, hi.y, floor_z),
                Vec3::new(lo.x, hi.y, floor_z),
            ),
            (
                Vec3::new(lo.x, hi.y, floor_z),
                Vec3::new(lo.x, lo.y, floor_z),
            ),
        ]
    };
    let (bv, bf) = bone_mesh(&bones, 0.015);
    let (pv, pf) = bone_mesh(&path, 0.01);
    let (fv, ff) = bone_mesh(&floor, 0.01);
    let meshes = [
        (&bv[..], &bf[..], [0.3, 0.45, 0.8]),
        (&pv[..], &pf[..], [0.85, 0.3, 0.2]),
        (&fv[..], &ff[..], [0.5, 0.5, 0.5]),
    ];
    let top = MeshView::looking_from(Vec3::Z, Vec3::Y).render(&meshes, 640, 640);
    // Side view: across the overall walking direction.
    let travel =
        frames.last().map_or(Vec3::X, |f| f[0]) - frames.first().map_or(Vec3::ZERO, |f| f[0]);
    let across = Vec3::new(-travel.y, travel.x, 0.0)
        .try_normalize()
        .unwrap_or(Vec3::NEG_Y);
    let side = MeshView::looking_from(across, Vec3::Z).render(&meshes, 960, 640);
    top.hconcat(&side, [255, 255, 255]).write_png(png)?;
    Ok(())
}
