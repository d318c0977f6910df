//! `egogen motion head-stats`: how a head moves (`motion::head_motion`) for take
//! folders, AMASS-style clips (or folders of them) and projectaria-tools MPS trajectories, each
//! read into a head track (a take's activities marked, a clip's head posed by the body model,
//! an MPS device trajectory moved to the CPF by a rig), a true IMU computed from it as the
//! exports compute theirs; JSON lines, a table, optionally every record as JSON
//! (docs/MOTION.md "Head motion"). Here because it reads take folders (`take_folder`) and
//! computes the IMU with `imu`, which `motion` may not use.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::imu::simulate_imu;
use crate::body::{BodyModel, CpfCalibration};
use crate::math::pose_spline::PoseSpline;
use crate::math::{Affine3, Vec3};
use crate::motion::head_motion::{
    read_mps_trajectory, resample_poses, HeadMotionStats, HeadTrack, ImuTrace, STATS_RATE_HZ,
};
use crate::motion::MotionSequence;

/// One source `egogen motion head-stats` measures.
enum HeadSource {
    /// A take folder: every agent's head (`cpf_trajectory.json`) and pelvis (`motion.npz`).
    Take(PathBuf),
    /// An AMASS-style clip: its head (CPF) by the body model.
    Clip(PathBuf),
    /// A projectaria-tools MPS trajectory CSV: the device poses, moved to the CPF.
    Mps(PathBuf),
}

fn head_source(path: &Path) -> Result<Vec<HeadSource>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    Ok(match ext.as_deref() {
        Some("npz") => vec![HeadSource::Clip(path.to_path_buf())],
        Some("csv") => vec![HeadSource::Mps(path.to_path_buf())],
        _ if path.is_dir() => {
            let mut clips: Vec<PathBuf> = std::fs::read_dir(path)
                .with_context(|| format!("reading {}", path.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "npz"))
                .collect();
            clips.sort();
            if clips.is_empty() {
                vec![HeadSource::Take(path.to_path_buf())]
            } else {
                clips.into_iter().map(HeadSource::Clip).collect()
            }
        }
        _ => bail!(
            "{}: expected a take folder, a folder of AMASS-style .npz clips, an .npz clip or an MPS trajectory .csv",
            path.display()
        ),
    })
}

/// The true IMU (no device errors) at the head's own frame, from a C² spline of its poses
/// (as the Aria and EuRoC exports make theirs), at `rate_hz`.
fn head_imu(head: &HeadTrack, rate_hz: f64) -> Result<ImuTrace> {
    let spline = PoseSpline::interpolate(head.rate_hz, &head.world_from_head)?;
    let samples = simulate_imu(&spline, Affine3::IDENTITY, rate_hz, None);
    Ok(ImuTrace {
        rate_hz,
        specific_force: samples.iter().map(|s| s.accel.length()).collect(),
        gyro: samples.iter().map(|s| s.gyro.length()).collect(),
    })
}

/// One head measured: its label, track, pelvis positions (where it has a body) and the frames
/// it spends in activities (a take's).
type LabelledHead = (String, HeadTrack, Option<Vec<Vec3>>, Option<Vec<bool>>);

/// Frames each agent of a take spends in an activity (not walking to it), by agent name, from
/// its `summary.json` (none where it has none).
fn take_activity_frames(root: &Path, name: &str, frames: usize) -> Result<Option<Vec<bool>>> {
    let path = root.join("summary.json");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(None);
    };
    let summary: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: expected JSON", path.display()))?;
    let Some(agent) = summary["agents"]
        .as_array()
        .and_then(|a| a.iter().find(|a| a["name"].as_str() == Some(name)))
    else {
        return Ok(None);
    };
    let mut busy = vec![false; frames];
    for seg in agent["activity_segments"].as_array().into_iter().flatten() {
        if seg["phase"].as_str() == Some("approach") {
            continue;
        }
        let (Some(a), Some(b)) = (seg["start_frame"].as_u64(), seg["end_frame"].as_u64()) else {
            bail!(
                "{}: agent {name}: an activity segment without start_frame and end_frame",
                path.display()
            );
        };
        for f in busy.iter_mut().take(b as usize).skip(a as usize) {
            *f = true;
        }
    }
    Ok(Some(busy))
}

/// Head tracks of one source, labelled, with pelvis positions where it has a body.
fn head_tracks(source: &HeadSource, model: &BodyModel, rig: &Path) -> Result<Vec<LabelledHead>> {
    match source {
        HeadSource::Take(dir) => {
            let (_, heads) = super::take_folder::read_take_heads(dir, &[])?;
            let root = if dir.join("sequence").is_dir() {
                dir.join("sequence")
            } else {
                dir.clone()
            };
            heads
                .into_iter()
                .map(|h| {
                    let npz = root.join("agents").join(&h.name).join("motion.npz");
                    // The pelvis is `transl` plus the rest pelvis, a constant: its acceleration
                    // is `transl`'s.
                    let pelvis = MotionSequence::read(&npz)
                        .ok()
                        .filter(|m| m.len() == h.world_from_cpf.len())
                        .map(|m| m.trans.clone());
                    let busy = take_activity_frames(&root, &h.name, h.world_from_cpf.len())?;
                    let track = HeadTrack {
                        rate_hz: h.frame_rate_hz,
                        world_from_head: h.world_from_cpf,
                    };
                    Ok((format!("{}:{}", dir.display(), h.name), track, pelvis, busy))
                })
                .collect()
        }
        HeadSource::Clip(path) => {
            let seq = MotionSequence::read(path)
                .with_context(|| format!("reading clip {}", path.display()))?;
            let shaped = model.shape(&seq.betas, &[])?;
            let cpf = CpfCalibration::from_rest_joints(&shaped.rest_joints);
            let mut heads = Vec::with_capacity(seq.len());
            let mut pelvis = Vec::with_capacity(seq.len());
            for i in 0..seq.len() {
                let f = seq.frame(i);
                let sk = shaped.skeleton(&f.pose, f.transl)?;
                heads.push(cpf.world_from_cpf(&sk));
                pelvis.push(sk.joints[crate::body::joint::PELVIS]);
            }
            let times: Vec<f64> = (0..heads.len())
                .map(|i| i as f64 / seq.frame_rate_hz)
                .collect();
            let (heads, pelvis) = if (seq.frame_rate_hz - STATS_RATE_HZ).abs() > 1e-9 {
                let at = |p: &Vec3| Affine3::from_translation(*p);
                let moved: Vec<Affine3> = pelvis.iter().map(at).collect();
                (
                    resample_poses(&times, &heads, STATS_RATE_HZ),
                    resample_poses(&times, &moved, STATS_RATE_HZ)
                        .iter()
                        .map(|p| p.translation)
                        .collect(),
                )
            } else {
                (heads, pelvis)
            };
            Ok(vec![(
                path.display().to_string(),
                HeadTrack {
                    rate_hz: STATS_RATE_HZ,
                    world_from_head: heads,
                },
                Some(pelvis),
                None,
            )])
        }
        HeadSource::Mps(path) => {
            let (times, device) = read_mps_trajectory(path)?;
            let rig = crate::rig::Rig::load(rig)?;
            let device_from_cpf = rig.cpf_from_device().inverse();
            let cpf: Vec<Affine3> = device.iter().map(|p| *p * device_from_cpf).collect();
            Ok(vec![(
                path.display().to_string(),
                HeadTrack {
                    rate_hz: STATS_RATE_HZ,
                    world_from_head: resample_poses(&times, &cpf, STATS_RATE_HZ),
                },
                None,
                None,
            )])
        }
    }
}

/// `egogen motion head-stats`: the head-motion statistics ([`crate::motion::head_motion`]) of
/// every source (take folders, clips or folders of clips, MPS trajectories), one JSON line
/// each, then a table; every record in `json` when given.
pub(crate) fn motion_head_stats(
    sources: &[PathBuf],
    model: &Path,
    rig: &Path,
    imu_rate_hz: f64,
    json: Option<&Path>,
) -> Result<()> {
    if sources.is_empty() {
        bail!("no sources given: name take folders, .npz clips (or folders of them) or MPS trajectory .csv files");
    }
    if !(imu_rate_hz.is_finite() && imu_rate_hz > 0.0) {
        bail!("--imu-rate-hz: expected a positive number of Hz, got {imu_rate_hz}");
    }
    let model = BodyModel::load(model)?;
    let mut all = Vec::new();
    for path in sources {
        for source in head_source(path)? {
            for (label, track, pelvis, busy) in head_tracks(&source, &model, rig)? {
                if track.world_from_head.len() < 3 {
                    bail!("{label}: fewer than 3 poses; nothing to measure");
                }
                let imu = head_imu(&track, imu_rate_hz)?;
                let stats = HeadMotionStats::measure(
                    &label,
                    &track,
                    pelvis.as_deref(),
                    Some(&imu),
                    busy.as_deref(),
                );
                println!("{}", serde_json::to_string(&stats)?);
                all.push(stats);
            }
        }
    }
    eprintln!(
        "{:<48} {:>6} {:>16} {:>12} {:>12} {:>8} {:>7} {:>7} {:>6} {:>12} {:>10}",
        "source",
        "walk s",
        "acc med/p95",
        "join×med/p95",
        "ang med/p95",
        "sway °",
        "ahead °",
        "bob mm",
        "step",
        "f p99/max",
        "gyro p99"
    );
    for s in &all {
        let a = &s.head_acceleration;
        let imu = s.imu.as_ref();
        let label: String = if s.label.chars().count() > 48 {
            let tail: Vec<char> = s.label.chars().rev().take(47).collect();
            std::iter::once('…').chain(tail.into_iter().rev()).collect()
        } else {
            s.label.clone()
        };
        eprintln!(
            "{:<48} {:>6.1} {:>7.2}/{:<8.2} {:>5.2}/{:<6.2} {:>5.2}/{:<6.2} {:>8.2} {:>7.1} {:>7.1} {:>6.2} {:>5.1}/{:<6.1} {:>10.2}",
            label,
            s.walking_s,
            a.all.p50,
            a.all.p95,
            a.join_ratio_median,
            a.join_ratio_p95,
            s.angular_speed.p50,
            s.angular_speed.p95,
            s.yaw_sway_rms_deg,
            s.path_ahead_deg.p50,
            s.bob_rms_mm,
            s.step_hz,
            imu.map_or(f64::NAN, |i| i.specific_force.p99),
            imu.map_or(f64::NAN, |i| i.specific_force.max),
            imu.map_or(f64::NAN, |i| i.gyro.p99),
        );
    }
    if let Some(path) = json {
        crate::atomic_file::write_atomically(path, &serde_json::to_vec_pretty(&all)?)?;
    }
    Ok(())
}
