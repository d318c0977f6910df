//! The folder a synthesized sequence is written to. Everything is written into
//! `<dir>.partial/` first and renamed into place at the end, so a failed or killed run never
//! leaves a half-written sequence under the final name.
//!
//! Layout: `motion.npz` (AMASS-style SMPL-X), `cpf_trajectory.json` (`world_from_cpf` per
//! frame, row-major 4×4), `meshes/frame_NNNNN.obj` (every N frames), `preview.png`,
//! `manifest.json` (files with sizes).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde::Serialize;

use super::BodyTrack;
use crate::atomic_file::{partial_of, refuse_existing_folder, write_atomically};
use crate::body::export::write_obj;
use crate::body::{BodyModel, PosedBody};
use crate::manifest::{build_manifest, MANIFEST};
use crate::math::Vec3;
use crate::motion::MotionSequence;
use crate::preview::{MeshView, RgbImage};

/// What a finished sequence folder holds.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct SequenceOutputs {
    pub dir: PathBuf,
    pub frames: usize,
    pub meshes: usize,
    pub files: Vec<(String, u64)>,
}

#[derive(Serialize, serde::Deserialize)]
struct CpfFrame {
    frame: usize,
    time_s: f64,
    /// Row-major 4×4 `world_from_cpf` (CPF axes: x left, y up, z forward).
    world_from_cpf: [[f64; 4]; 4],
}

/// `cpf_trajectory.json`: `world_from_cpf` of every frame at `rate_hz`, row-major 4×4.
pub(crate) fn cpf_trajectory_json(
    frames: &[crate::math::Affine3],
    rate_hz: f64,
) -> Result<Vec<u8>> {
    let cpf: Vec<CpfFrame> = frames
        .iter()
        .enumerate()
        .map(|(i, m)| CpfFrame {
            frame: i,
            time_s: i as f64 / rate_hz,
            world_from_cpf: crate::math::row_major(*m),
        })
        .collect();
    Ok(serde_json::to_vec_pretty(&cpf)?)
}

/// How far a pose's rotation may be from orthonormal (max |RᵀR − I|): rounding of a written
/// pose is ~1e-15; a scaled or sheared one is far beyond.
const RIGID_TOLERANCE: f64 = 1e-6;

/// Reads a `cpf_trajectory.json`: its frame rate (from the frames' times, which must be
/// regular) and poses (rigid); errors name the file, the frame and the key.
pub fn read_cpf_trajectory(path: &Path) -> Result<(f64, Vec<crate::math::Affine3>)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let frames: Vec<CpfFrame> = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: expected a list of {{frame, time_s, world_from_cpf (row-major 4×4)}}",
            path.display()
        )
    })?;
    if frames.is_empty() {
        bail!("{}: no frames", path.display());
    }
    let mut poses = Vec::with_capacity(frames.len());
    for (i, f) in frames.iter().enumerate() {
        if f.frame != i {
            bail!(
                "{}: entry {i} is frame {}; expected frames 0, 1, 2, … in order",
                path.display(),
                f.frame
            );
        }
        let pose = crate::math::affine_from_row_major(&f.world_from_cpf).with_context(|| {
            format!(
                "{}: frame {i}: key `world_from_cpf`: expected finite numbers",
                path.display()
            )
        })?;
        let r = pose.matrix3;
        let off_rigid = (r.transpose() * r - glam::DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0_f64, |m, x| m.max(x.abs()));
        if off_rigid > RIGID_TOLERANCE || r.determinant() <= 0.0 {
            bail!(
                "{}: frame {i}: key `world_from_cpf`: its 3×3 part is not a rotation (RᵀR differs from I by {off_rigid:.3e}, det {:.6}); expected a rigid pose",
                path.display(),
                r.determinant()
            );
        }
        poses.push(pose);
    }
    let mut rate = if frames.len() > 1 {
        1.0 / frames[1].time_s
    } else {
        40.0
    };
    // Times are written as i / rate: a whole rate comes back within rounding.
    if (rate - rate.round()).abs() < 1e-9 * rate {
        rate = rate.round();
    }
    if !(rate.is_finite() && rate > 0.0 && rate <= 10_000.0) {
        bail!(
            "{}: frame 1 at time_s = {}: expected a frame rate in (0, 10000] Hz",
            path.display(),
            frames[1].time_s
        );
    }
    // The exports sample frames as regular: every frame's time must be i / rate.
    for (i, f) in frames.iter().enumerate() {
        let expected = i as f64 / rate;
        if !((f.time_s - expected).abs() <= 1e-6 + 1e-12 * expected) {
            bail!(
                "{}: frame {i}: key `time_s`: {} s, expected {expected} s (frames at a constant {rate} Hz, from frame 1's time)",
                path.display(),
                f.time_s
            );
        }
    }
    Ok((rate, poses))
}

/// Posed meshes every `every_n` frames (none for 0), with a progress bar.
pub(crate) fn pose_meshes(
    model: &BodyModel,
    motion: &MotionSequence,
    every_n: usize,
) -> Result<Vec<(usize, PosedBody)>> {
    let frames: Vec<usize> = match every_n {
        0 => Vec::new(),
        n => (0..motion.len()).step_by(n).collect(),
    };
    let bar = indicatif::ProgressBar::new(frames.len() as u64).with_style(
        indicatif::ProgressStyle::with_template(
            "posing meshes {bar:30} {pos}/{len} [{elapsed_precise} < {eta_precise}]",
        )
        .context("progress template")?,
    );
    let shaped = model.shape(&motion.betas, &[])?;
    let mut meshes = Vec::with_capacity(frames.len());
    for i in frames {
        meshes.push((i, shaped.pose(&motion.poses[i], motion.trans[i])?));
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(meshes)
}

/// Files a sequence folder holds while it is written.
const SEQUENCE_ENTRIES: [&str; 5] = [
    "meshes",
    "motion.npz",
    "cpf_trajectory.json",
    "preview.png",
    "manifest.json",
];

/// Whether `dir` holds only the named entries (or their temporaries, `<name>.…`): a
/// leftover of a writer that writes those.
pub(crate) fn holds_only(dir: &Path, entries: &[&str]) -> bool {
    std::fs::read_dir(dir).is_ok_and(|found| {
        found.flatten().all(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            entries
                .iter()
                .any(|s| name == *s || name.starts_with(&format!("{s}.")))
        })
    })
}

/// Whether `dir` holds only what [`write_sequence_dir`] writes.
fn is_sequence_leftover(dir: &Path) -> bool {
    holds_only(dir, &SEQUENCE_ENTRIES)
}

/// Writes a sequence folder; `dir` must not exist or be empty (nothing is overwritten).
pub(crate) fn write_sequence_dir(
    dir: &Path,
    model: &BodyModel,
    motion: &MotionSequence,
    track: &BodyTrack,
    meshes: &[(usize, PosedBody)],
) -> Result<SequenceOutputs> {
    refuse_existing_folder(dir, "output.dir")?;
    let staging = partial_of(dir);
    if staging.exists() {
        // A sequence folder is written in one go: its own leftover is worthless and replaced.
        // Anything else there (an interrupted render run's frames) is not ours to delete.
        if !is_sequence_leftover(&staging) {
            bail!(
                "{} exists and is not an interrupted sequence folder (an interrupted render run? continue it with --resume); move it away or delete it (nothing was touched)",
                staging.display()
            );
        }
        std::fs::remove_dir_all(&staging)
            .with_context(|| format!("removing stale {}", staging.display()))?;
    }
    std::fs::create_dir_all(staging.join("meshes"))
        .with_context(|| format!("creating {}", staging.display()))?;

    motion.write_amass(&staging.join("motion.npz"))?;
    std::fs::write(
        staging.join("cpf_trajectory.json"),
        cpf_trajectory_json(
            &track
                .frames
                .iter()
                .map(|f| f.world_from_cpf)
                .collect::<Vec<_>>(),
            track.frame_rate_hz,
        )?,
    )?;
    for (i, body) in meshes {
        write_obj(
            &staging.join(format!("meshes/frame_{i:05}.obj")),
            &body.vertices,
            &model.faces,
        )?;
    }
    side_view(model, meshes).write_png(&staging.join("preview.png"))?;

    // The same manifest as a dataset's (sizes and SHA-256, so `egogen-run verify` checks a
    // sequence folder too), with what the sequence is.
    let listed = build_manifest(&staging)?;
    let files = listed
        .files
        .iter()
        .map(|e| (e.path.clone(), e.bytes))
        .collect();
    let mut manifest = serde_json::to_value(&listed)?;
    manifest["frames"] = motion.len().into();
    manifest["frame_rate_hz"] = motion.frame_rate_hz.into();
    manifest["body_model"] = serde_json::to_value(&model.source)?;
    let manifest_path = staging.join(MANIFEST);
    write_atomically(&manifest_path, &serde_json::to_vec_pretty(&manifest)?)
        .with_context(|| format!("writing {}", manifest_path.display()))?;
    if dir.exists() {
        std::fs::remove_dir(dir)?;
    }
    std::fs::rename(&staging, dir)
        .with_context(|| format!("moving {} into place", staging.display()))?;
    Ok(SequenceOutputs {
        dir: dir.into(),
        frames: motion.len(),
        meshes: meshes.len(),
        files,
    })
}

/// Side view (from −y, z up) of the written meshes, overlaid.
fn side_view(model: &BodyModel, meshes: &[(usize, PosedBody)]) -> RgbImage {
    let parts: Vec<(&[Vec3], &[[u32; 3]], [f64; 3])> = meshes
        .iter()
        .map(|(_, b)| {
            (
                b.vertices.as_slice(),
                model.faces.as_slice(),
                [0.85, 0.7, 0.6],
            )
        })
        .collect();
    MeshView::looking_from(Vec3::new(0.0, -1.0, 0.0), Vec3::Z).render(&parts, 960, 360)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{axis_angle_to_matrix, Affine3, Vec3};

    fn written(frames: usize) -> serde_json::Value {
        let poses: Vec<Affine3> = (0..frames)
            .map(|i| Affine3 {
                matrix3: axis_angle_to_matrix(Vec3::new(0.1, 0.3 * i as f64, 3.0)),
                translation: Vec3::new(i as f64 * 0.05, 1.6, -2.0),
            })
            .collect();
        serde_json::from_slice(&cpf_trajectory_json(&poses, 30.0).unwrap()).unwrap()
    }

    fn read(doc: &serde_json::Value) -> Result<(f64, Vec<Affine3>)> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cpf_trajectory.json");
        std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
        read_cpf_trajectory(&path)
    }

    #[test]
    fn a_trajectory_with_a_scaled_rotation_or_irregular_times_is_refused() {
        let good = written(6);
        let (rate, poses) = read(&good).unwrap();
        assert_eq!((rate, poses.len()), (30.0, 6));

        let mut scaled = good.clone();
        for row in scaled[3]["world_from_cpf"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .take(3)
        {
            for x in row.as_array_mut().unwrap().iter_mut().take(3) {
                *x = (x.as_f64().unwrap() * 2.0).into();
            }
        }
        let err = format!("{:#}", read(&scaled).unwrap_err());
        assert!(
            err.contains("frame 3: key `world_from_cpf`: its 3×3 part is not a rotation"),
            "{err}"
        );

        let mut mirrored = good.clone();
        for x in mirrored[2]["world_from_cpf"][0]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .take(3)
        {
            *x = (-x.as_f64().unwrap()).into();
        }
        let err = format!("{:#}", read(&mirrored).unwrap_err());
        assert!(err.contains("frame 2: key `world_from_cpf`"), "{err}");

        let mut jump = good.clone();
        for i in 4..6 {
            jump[i]["time_s"] = (i as f64 / 30.0 + 100.0).into();
        }
        let err = format!("{:#}", read(&jump).unwrap_err());
        assert!(err.contains("frame 4: key `time_s`: 100.13"), "{err}");
        assert!(err.contains("expected 0.1333"), "{err}");
    }
}
