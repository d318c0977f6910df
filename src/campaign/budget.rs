//! The campaign's budget, stated before any work: takes, frames per camera, disk and
//! worker/core-hours, the last two from measured figures — the pool reports and manifests of
//! an earlier start of this campaign, or of a campaign or dataset folder given with
//! `--throughput-from` — never from assumed ones.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use super::plan::CampaignPlan;
use crate::plan::{Backend, MotionPlan, RunPlan};
use crate::synth::crowd::{frames_of, primitives_for};

/// What a campaign will cost.
#[derive(Debug, Clone)]
pub(crate) struct Budget {
    /// Planned frames of each take, all cameras.
    pub frames_per_take: Vec<usize>,
    pub cameras: Vec<String>,
    /// Seconds a worker spends on a frame, per camera name, and where that was measured.
    pub seconds_per_frame: Option<(BTreeMap<String, f64>, PathBuf, usize)>,
    /// Bytes written per frame (finished datasets), and where.
    pub bytes_per_frame: Option<(f64, PathBuf)>,
    text: Vec<String>,
}

impl Budget {
    /// The budget as lines for the log.
    pub(crate) fn lines(&self) -> impl Iterator<Item = &str> {
        self.text.iter().map(String::as_str)
    }

    /// Estimated worker-seconds of rendering.
    pub(crate) fn worker_seconds(&self) -> Option<f64> {
        let (spf, _, _) = self.seconds_per_frame.as_ref()?;
        let mean = spf.values().sum::<f64>() / spf.len().max(1) as f64;
        let per_camera_frames =
            self.frames_per_take.iter().sum::<usize>() as f64 / self.cameras.len().max(1) as f64;
        Some(
            self.cameras
                .iter()
                .map(|c| spf.get(c).copied().unwrap_or(mean) * per_camera_frames)
                .sum(),
        )
    }
}

/// Planned frames of one take: motion frames at the plan's rate, every n-th rendered, on every
/// camera of every wearer.
fn planned_frames(plan: &RunPlan, duration_s: Option<f64>) -> usize {
    let Some(render) = &plan.render else {
        return 0;
    };
    let (motion_frames, wearers) = match &plan.motion {
        MotionPlan::Agents { synth, wearers } => (
            frames_of(primitives_for(duration_s.unwrap_or(synth.duration_s))),
            wearers.len(),
        ),
        MotionPlan::ScriptedWalk {
            duration_s: d,
            frame_rate_hz,
            ..
        } => (
            (duration_s.unwrap_or(*d) * frame_rate_hz).round() as usize,
            1,
        ),
        MotionPlan::File { path } => (
            crate::motion::MotionSequence::read(path).map_or(0, |m| m.len()),
            1,
        ),
    };
    motion_frames.div_ceil(render.every_n_frames) * render.cameras.len() * wearers
}

/// A pool report's attempts: camera, seconds, frames finished; why not, when the report is
/// unreadable or holds an attempt that is not one (no camera, seconds not a finite number ≥ 0,
/// no count of frames finished).
fn report_attempts(path: &Path) -> std::result::Result<Vec<(String, f64, usize)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("unreadable ({e})"))?;
    let report: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("not JSON ({e})"))?;
    let shards = report["shards"]
        .as_array()
        .ok_or("key `shards`: missing or not a list")?;
    let mut out = Vec::new();
    for (i, s) in shards.iter().enumerate() {
        let camera = s["camera"]
            .as_str()
            .ok_or_else(|| format!("key `shards[{i}].camera`: missing or not a name"))?;
        let attempts = s["attempts"]
            .as_array()
            .ok_or_else(|| format!("key `shards[{i}].attempts`: missing or not a list"))?;
        for (j, a) in attempts.iter().enumerate() {
            let key = format!("shards[{i}].attempts[{j}]");
            let seconds = a["seconds"]
                .as_f64()
                .filter(|s| s.is_finite() && *s >= 0.0)
                .ok_or_else(|| {
                    format!(
                        "key `{key}.seconds`: {}, expected seconds ≥ 0",
                        a["seconds"]
                    )
                })?;
            let finished = a["finished"].as_u64().ok_or_else(|| {
                format!(
                    "key `{key}.finished`: {}, expected a count of frames",
                    a["finished"]
                )
            })?;
            out.push((camera.to_string(), seconds, finished as usize));
        }
    }
    Ok(out)
}

/// Every attempt in the pool reports under `dir` (`logs/start_*/pool_report.json`, also in
/// `takes/*/`): camera, seconds, frames finished; and each report left out, with why.
fn attempts(dir: &Path) -> (Vec<(String, f64, usize)>, Vec<String>) {
    let pattern = |p: &str| dir.join(p).to_string_lossy().into_owned();
    let mut found: Vec<PathBuf> = [
        "logs/start_*/pool_report.json",
        "takes/*/logs/start_*/pool_report.json",
    ]
    .iter()
    .filter_map(|p| glob::glob(&pattern(p)).ok())
    .flat_map(|g| g.flatten())
    .collect();
    found.sort();
    let (mut out, mut skipped) = (Vec::new(), Vec::new());
    for report in &found {
        match report_attempts(report) {
            Ok(a) => out.extend(a),
            Err(why) => skipped.push(format!("{}: {why}", report.display())),
        }
    }
    (out, skipped)
}

/// Seconds per frame per camera: every attempt's time over the frames it finished (failed
/// attempts' time counted too: a farm pays for them); and the frames measured.
fn throughput(attempts: &[(String, f64, usize)]) -> (BTreeMap<String, f64>, usize) {
    let mut sums: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    for (camera, seconds, finished) in attempts {
        let e = sums.entry(camera.clone()).or_default();
        e.0 += seconds;
        e.1 += finished;
    }
    let frames = sums.values().map(|v| v.1).sum();
    (
        sums.into_iter()
            .filter(|(_, (_, n))| *n > 0)
            .map(|(c, (s, n))| (c, s / n as f64))
            .collect(),
        frames,
    )
}

/// Bytes per frame of the finished datasets under `dir` (itself, or `takes/*`).
fn disk_per_frame(dir: &Path) -> Option<f64> {
    let mut datasets: Vec<PathBuf> =
        glob::glob(&dir.join("takes/*/manifest.json").to_string_lossy())
            .ok()?
            .flatten()
            .collect();
    if dir.join("manifest.json").is_file() {
        datasets.push(dir.join("manifest.json"));
    }
    let (mut bytes, mut frames) = (0u64, 0usize);
    for m in datasets {
        let Ok(text) = std::fs::read_to_string(&m) else {
            continue;
        };
        let Ok(manifest) = serde_json::from_str::<crate::manifest::Manifest>(&text) else {
            continue;
        };
        bytes += manifest.files.iter().map(|f| f.bytes).sum::<u64>();
        frames += manifest
            .files
            .iter()
            .filter(|f| f.path.starts_with("cameras/") && f.path.ends_with(".exr"))
            .count();
    }
    (frames > 0).then(|| bytes as f64 / frames as f64)
}

/// The campaign's budget; `first` is its first take's plan (render settings, supervisor).
pub(crate) fn estimate(
    plan: &CampaignPlan,
    first: &RunPlan,
    throughput_from: Option<&Path>,
) -> Result<Budget> {
    let frames_per_take: Vec<usize> = plan
        .takes
        .iter()
        .map(|t| planned_frames(first, t.duration_s))
        .collect();
    let cameras: Vec<String> = first
        .render
        .as_ref()
        .map(|r| r.cameras.iter().map(|c| c.name.clone()).collect())
        .unwrap_or_default();
    if let Some(dir) = throughput_from {
        if !dir.is_dir() {
            bail!(
                "--throughput-from {}: {}; expected the folder of a campaign or of a dataset (its logs/start_*/pool_report.json and manifest.json are read)",
                dir.display(),
                if dir.exists() { "not a folder" } else { "no such folder" }
            );
        }
    }
    let source = throughput_from.unwrap_or(&plan.out).to_path_buf();
    let (found, skipped) = attempts(&source);
    let (spf, measured) = throughput(&found);
    let sup = &first.supervisor;
    let workers = sup.workers.max(1);
    let cores_per_worker = match sup.backend {
        Backend::Local => {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            (cores as f64 / workers as f64).max(1.0)
        }
        Backend::Slurm => sup.slurm.cpus_per_task as f64,
    };
    let mut budget = Budget {
        frames_per_take,
        cameras,
        seconds_per_frame: (!spf.is_empty()).then(|| (spf, source.clone(), measured)),
        bytes_per_frame: disk_per_frame(&source).map(|b| (b, source.clone())),
        text: Vec::new(),
    };
    let total: usize = budget.frames_per_take.iter().sum();
    let scenes: std::collections::BTreeSet<&PathBuf> =
        plan.takes.iter().map(|t| &t.scene).collect();
    let per_camera = total / budget.cameras.len().max(1);
    let mut text = vec![format!(
        "{} takes over {} scene(s), seeds {}..={}: {total} frames ({per_camera} per camera: {})",
        plan.takes.len(),
        scenes.len(),
        plan.takes[0].seed,
        plan.takes[plan.takes.len() - 1].seed,
        budget.cameras.join(", ")
    )];
    text.push(match &budget.bytes_per_frame {
        Some((b, from)) => format!(
            "disk: about {:.2} GB ({:.2} MB per frame, measured on the datasets in {})",
            b * total as f64 / 1e9,
            b / 1e6,
            from.display()
        ),
        None => format!(
            "disk: not known yet (no finished take in {}; --throughput-from DIR reads another campaign's)",
            source.display()
        ),
    });
    text.push(match (budget.worker_seconds(), &budget.seconds_per_frame) {
        (Some(ws), Some((spf, from, n))) => format!(
            "time: about {:.2} worker-hours = {:.2} core-hours ({:.1} cores per worker); {:.1} min on {workers} worker(s) ({} measured over {n} frames in {})",
            ws / 3600.0,
            ws * cores_per_worker / 3600.0,
            cores_per_worker,
            ws / workers as f64 / 60.0,
            spf.iter()
                .map(|(c, s)| format!("{c} {s:.1} s/frame"))
                .collect::<Vec<_>>()
                .join(", "),
            from.display()
        ),
        _ => format!(
            "time: not known yet (no pool report in {}; the first start measures it, or --throughput-from DIR reads another campaign's)",
            source.display()
        ),
    });
    for why in skipped {
        text.push(format!("time: left out the pool report {why}"));
    }
    let (plans, dwellings) = (
        plan.floor_plans
            .iter()
            .filter(|(_, f)| !f.is_file())
            .count(),
        plan.dwellings.iter().filter(|(_, f)| !f.is_file()).count(),
    );
    if plans + dwellings > 0 {
        // Generated on one core before the first take: a floor plan in milliseconds, a
        // furnished dwelling in about 0.03 s and 2.5 MB (v3: median 2.46, p95 3.17 MB) (docs/SCENES.md "Generated dwellings").
        text.push(format!(
            "scenes: {plans} floor plan(s) and {dwellings} dwelling(s) to generate first, about {:.0} s and {:.2} GB",
            0.03 * dwellings as f64 + 0.01 * plans as f64,
            (2.5e6 * dwellings as f64 + 0.2e6 * plans as f64) / 1e9
        ));
    }
    budget.text = text;
    Ok(budget)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_damaged_or_negative_pool_report_is_left_out_and_said() {
        let dir = tempfile::tempdir().unwrap();
        let write = |start: &str, text: &str| {
            let p = dir.path().join("logs").join(start);
            std::fs::create_dir_all(&p).unwrap();
            std::fs::write(p.join("pool_report.json"), text).unwrap();
        };
        let report = |seconds: &str| {
            format!(
                r#"{{"shards": [{{"camera": "rgb", "attempts": [{{"seconds": {seconds}, "finished": 10}}]}}]}}"#
            )
        };
        write("start_1", &report("20.0"));
        write("start_2", &report("-500.0"));
        write("start_3", "{\"shards\": [");
        let (found, skipped) = attempts(dir.path());
        assert_eq!(found, [("rgb".to_string(), 20.0, 10)]);
        assert_eq!(skipped.len(), 2, "{skipped:?}");
        assert!(skipped[0].contains("start_2/pool_report.json: key `shards[0].attempts[0].seconds`: -500.0, expected seconds ≥ 0"), "{skipped:?}");
        assert!(
            skipped[1].contains("start_3/pool_report.json: not JSON"),
            "{skipped:?}"
        );
        let (spf, frames) = throughput(&found);
        assert_eq!((spf["rgb"], frames), (2.0, 10));
    }
}
