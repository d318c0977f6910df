//! The job of `egogen motion hand-stats`: how the fingers of AMASS-style SMPL-X files and of
//! takes' people move (`motion::hands::stats`), as JSON lines and a table (docs/HANDS.md).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::body::BodyModel;
use crate::motion::hands::stats::HandStats;
use crate::motion::hands::HandAxes;
use crate::motion::MotionSequence;

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
pub fn motion_hand_stats(sources: &[PathBuf], model: &Path, json: Option<&Path>) -> Result<()> {
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
