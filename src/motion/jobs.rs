//! Jobs of the `egogen motion` and `egogen body` commands that read and write motion data:
//! `motion stats` (pace and turn distributions of the training data), `motion hand-stats` (how
//! the fingers of AMASS-style SMPL-X files and of takes' people move, `hands::stats`, as JSON
//! lines and a table, docs/HANDS.md) and `body pose` (a frame of a motion file or of the
//! scripted walk posed to OBJ). `cli` parses the flags and calls them.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::atomic_file::refuse_existing;
use crate::body::export::write_obj;
use crate::body::{BodyModel, BodyParams};
use crate::motion::cvae::train::TrainPlan;
use crate::motion::hands::stats::HandStats;
use crate::motion::hands::HandAxes;
use crate::motion::scripted::WalkCycle;
use crate::motion::MotionSequence;

/// `egogen motion stats`: pace and turn distributions of a config's primitives; `load_plan`
/// reads the config.
pub(crate) fn motion_stats(
    config: &Path,
    json: Option<&Path>,
    load_plan: impl FnOnce(&Path) -> Result<TrainPlan>,
) -> Result<()> {
    use crate::motion::cvae::pace::{set_paces, speed_by_turn, PaceSummary};
    use crate::motion::cvae::tensor_body::{RigGeometry, TensorRig};
    use crate::motion::cvae::train::evaluation_sets;
    let plan = load_plan(config)?;
    let body = BodyModel::load(&plan.body_model)?;
    let (train, held) = evaluation_sets(&plan, &body, true)?;
    let (train_all, _) = evaluation_sets(&plan, &body, false)?;
    let geo = RigGeometry::new(&body, &[])?;
    let rig = TensorRig::<crate::motion::cvae::infer::InferBackend>::new(&geo, &Default::default());
    let mut doc = serde_json::json!({"config": config});
    for (name, set) in [("train", &train), ("held_out", &held)] {
        let paces = set_paces(&rig, set, 256);
        println!(
            "{}",
            serde_json::json!({
                "set": name,
                "primitives": set.len(),
                "seconds_of_motion": set.len() as f64 * plan.stride_frames as f64 / 40.0,
                "summary": PaceSummary::of(&paces),
                "speed_by_turn": speed_by_turn(&paces),
            })
        );
        doc[name] = serde_json::json!({
            "speed_m_s": paces.iter().map(|p| p.speed_m_s).collect::<Vec<_>>(),
            "turn_deg": paces.iter().map(|p| p.turn_deg).collect::<Vec<_>>(),
        });
    }
    println!(
        "{}",
        serde_json::json!({
            "contact_filter": plan.min_contact_score,
            "train_primitives_before_filter": train_all.len(),
            "train_primitives_kept": train.len(),
        })
    );
    if let Some(file) = json {
        crate::atomic_file::write_atomically(file, doc.to_string().as_bytes())?;
        println!("wrote {}", file.display());
    }
    Ok(())
}

/// The motion files of `path`: itself (`.npz`), or a take folder's people
/// (`agents/*/motion.npz`).
fn motion_files(path: &Path) -> Result<Vec<PathBuf>> {
    if path.extension().is_some_and(|e| e == "npz") {
        return Ok(vec![path.to_path_buf()]);
    }
    let agents = path.join("agents");
    if !agents.is_dir() {
        bail!(
            "{}: expected an AMASS-style .npz file or a take folder (with agents/*/motion.npz)",
            path.display()
        );
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&agents)
        .with_context(|| format!("reading {}", agents.display()))?
        .filter_map(|e| e.ok().map(|e| e.path().join("motion.npz")))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("{}: no agents/*/motion.npz", path.display());
    }
    Ok(files)
}

/// Prints each motion's finger statistics as a JSON line, then a table on standard error;
/// writes them all to `json` when given.
pub(crate) fn motion_hand_stats(
    sources: &[PathBuf],
    model: &Path,
    json: Option<&Path>,
) -> Result<()> {
    let m = BodyModel::load(model)?;
    let mut all = Vec::new();
    for source in sources {
        for file in motion_files(source)? {
            let seq = MotionSequence::read(&file)?;
            let shaped = m.shape(&seq.betas, &[])?;
            let axes = HandAxes::from_rest(&shaped.rest_joints);
            let frames: Vec<_> = (0..seq.len()).map(|i| seq.frame(i)).collect();
            let stats = HandStats::of(&frames, &axes, seq.frame_rate_hz);
            let line = serde_json::json!({ "file": file, "stats": stats });
            println!("{line}");
            all.push((file, stats));
        }
    }
    eprintln!(
        "{:<48} {:>6} {:>6} {:>7} {:>8} {:>17} {:>13} {:>15}",
        "file",
        "frames",
        "posed",
        "outside",
        "most (°)",
        "closed p5/50/95 °",
        "speed p95/max",
        "acc p95/max"
    );
    for (file, s) in &all {
        let name = file.display().to_string();
        let name = &name[name.len().saturating_sub(48)..];
        eprintln!(
            "{:<48} {:>6} {:>6} {:>7} {:>8.3} {:>17} {:>13} {:>15}",
            name,
            s.frames,
            s.frames_with_hand_pose,
            s.frames_outside_range,
            s.most_outside_range_deg,
            format!(
                "{:.0}/{:.0}/{:.0}",
                s.added_flexion_deg.p05, s.added_flexion_deg.p50, s.added_flexion_deg.p95
            ),
            format!(
                "{:.2}/{:.2}",
                s.flexion_speed_rad_s.p95, s.flexion_speed_rad_s.max
            ),
            format!(
                "{:.1}/{:.1}",
                s.flexion_acceleration_rad_s2.p95, s.flexion_acceleration_rad_s2.max
            ),
        );
    }
    if let Some(path) = json {
        let value: Vec<_> = all
            .iter()
            .map(|(file, stats)| serde_json::json!({ "file": file, "stats": stats }))
            .collect();
        crate::atomic_file::write_atomically(
            path,
            serde_json::to_string_pretty(&value)?.as_bytes(),
        )
        .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Poses frame `frame` of `motion` (or of the scripted walk at 40 fps) and writes it as OBJ.
pub(crate) fn body_pose(
    model: &Path,
    motion: Option<&Path>,
    frame: usize,
    out: &Path,
) -> Result<()> {
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

/// The scripted walk's frame at `t_s`, standing on the floor.
pub(crate) fn walk_params(m: &BodyModel, betas: &[f64], t_s: f64) -> Result<BodyParams> {
    let shaped = m.shape(betas, &[])?;
    Ok(WalkCycle::default().params_at(t_s, betas, shaped.rest_joints[0], shaped.rest_sole_y()))
}
