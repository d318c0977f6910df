//! `egogen motion import`: a CMU BVH clip (or a DeepMimic motion file) retargeted to the body
//! model, resampled, written as an AMASS-style npz (and its mirror), with an optional strip of
//! the source skeleton above the retargeted body.

use std::path::Path;

use anyhow::{bail, Result};

use crate::atomic_file::refuse_existing;
use crate::body::BodyModel;
use crate::math::Vec3;
use crate::preview::MeshView;

/// Imports `bvh` into `out` at `rate_hz` with the body model at `model`; `mirror` writes
/// `<out>_mirror.npz` too; `strip` a PNG of `strip_frames` columns; the first `skip_frames`
/// source frames are dropped.
#[allow(clippy::too_many_arguments)]
pub fn import_bvh(
    bvh: &Path,
    out: &Path,
    model: &Path,
    rate_hz: f64,
    mirror: bool,
    strip: Option<&Path>,
    strip_frames: usize,
    skip_frames: usize,
) -> Result<()> {
    use crate::motion::bvh::BvhClip;
    use crate::motion::resample::{mirror as mirror_seq, resample};
    use crate::motion::retarget::{retarget_cmu, CMU_TO_SMPLX, CMU_UNIT_M};
    use crate::preview::sticks::bone_mesh;

    refuse_existing(out)?;
    let mirror_path = out.with_file_name(format!(
        "{}_mirror.npz",
        out.file_stem().unwrap_or_default().to_string_lossy()
    ));
    if mirror {
        refuse_existing(&mirror_path)?;
    }
    if let Some(s) = strip {
        refuse_existing(s)?;
    }
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        bail!("--rate-hz must be positive, got {rate_hz}");
    }
    let m = BodyModel::load(model)?;
    let is_bvh = bvh
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"));
    let (clip, mut full) = if is_bvh {
        let mut clip = BvhClip::read(bvh)?;
        if skip_frames >= clip.frames.len() {
            bail!(
                "--skip-frames {skip_frames}: {} has only {} frames",
                bvh.display(),
                clip.frames.len()
            );
        }
        clip.frames.drain(..skip_frames);
        let seq = retarget_cmu(&clip, &m)?;
        (Some(clip), seq)
    } else {
        let mut seq = crate::motion::deepmimic::import_deepmimic(bvh, &m)?;
        if skip_frames >= seq.len() {
            bail!(
                "--skip-frames {skip_frames}: {} has only {} frames",
                bvh.display(),
                seq.len()
            );
        }
        seq.poses.drain(..skip_frames);
        seq.trans.drain(..skip_frames);
        (None, seq)
    };
    full.gender = "neutral".into();
    let seq = resample(&full, rate_hz);
    seq.write_amass(out)?;
    println!(
        "wrote {} ({} frames at {} Hz from {} at {} Hz)",
        out.display(),
        seq.len(),
        rate_hz,
        bvh.display(),
        full.frame_rate_hz
    );
    if mirror {
        mirror_seq(&seq, &m)?.write_amass(&mirror_path)?;
        println!("wrote {}", mirror_path.display());
    }
    if let Some(strip) = strip {
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
                    let place =
                        |q: Vec3| to_world(q) - Vec3::new(root.x, root.y, 0.0) + offset + lift;
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
    }
    Ok(())
}
