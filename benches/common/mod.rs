//! Running `egogen-run` from a bench: a config in a temporary folder, the Blender attempt's time
//! read from the pool report; and a plain median-of-runs timer.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

/// A finished run: its folder (kept until dropped) and the seconds of each shard's first
/// Blender attempt (start-up, both renders and frame assembly).
pub struct Run {
    pub dir: tempfile::TempDir,
    pub attempt_seconds: Vec<f64>,
    /// The whole `logs/start_01/pool_report.json`.
    pub report: serde_json::Value,
    /// Wall time of the `egogen-run` process, seconds.
    pub wall_seconds: f64,
}

impl Run {
    /// The dataset folder (`[output] dir = "out"`).
    pub fn out(&self) -> PathBuf {
        self.dir.path().join("out")
    }
}

/// A run config: the scripted walk at 40 Hz for `frames` frames (the default body, no meshes),
/// output in `out`, and the `[render]` keys given.
pub fn walk_config(frames: usize, render: &str) -> String {
    format!(
        r#"
[body]
betas = []
[motion]
source = "scripted_walk"
duration_s = {duration}
frame_rate_hz = 40.0
[output]
dir = "out"
mesh_every_n_frames = 0
[render]
{render}
"#,
        duration = frames as f64 / 40.0
    )
}

/// Runs `egogen-run` on a config whose output folder is `out`.
pub fn egogen_run(config: &str) -> Run {
    egogen_run_with(config, &[])
}

/// Runs `egogen-run` on a config whose output folder is `out`, with further arguments.
pub fn egogen_run_with(config: &str, args: &[&str]) -> Run {
    egogen_run_env(config, args, &[])
}

/// [`egogen_run_with`] with environment variables set for it (and its Blender workers).
pub fn egogen_run_env(config: &str, args: &[&str], envs: &[(&str, &str)]) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("run.toml");
    std::fs::write(&cfg, config).unwrap();
    let started = std::time::Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_egogen-run"))
        .arg(&cfg)
        .args(args)
        .envs(envs.iter().copied())
        .output()
        .unwrap();
    let wall_seconds = started.elapsed().as_secs_f64();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = dir.path().join("out/logs/start_01/pool_report.json");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    let attempt_seconds = report["shards"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["attempts"][0]["seconds"].as_f64().unwrap())
        .collect();
    Run {
        dir,
        attempt_seconds,
        report,
        wall_seconds,
    }
}

/// The shipped default run (`configs/default.toml`) with its output in `out`, its `[render]`
/// keys `samples`, `denoise`, `denoise_prefilter` and `frames_per_shard` and its `[supervisor]` key `workers`
/// dropped, and the
/// lines of `render` and `supervisor` added to those tables.
pub fn default_run_config(render: &str, supervisor: &str) -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("configs/default.toml")).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let key = line.split('=').next().unwrap_or("").trim();
        if matches!(
            key,
            "samples" | "denoise" | "denoise_prefilter" | "frames_per_shard" | "workers"
        ) {
            continue;
        }
        if key == "dir" {
            out.push_str("dir = \"out\"\n");
            continue;
        }
        out.push_str(line);
        out.push('\n');
        if line.trim() == "[render]" {
            out.push_str(render);
            out.push('\n');
        }
        if line.trim() == "[supervisor]" {
            out.push_str(supervisor);
            out.push('\n');
        }
    }
    out
}

/// The median wall time of `reps` runs of `f`, in seconds (a plain timing harness for work too
/// slow for criterion's sampling).
pub fn median_s(mut f: impl FnMut(), reps: usize) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = std::time::Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[reps / 2]
}

/// A campaign file of `takes` takes in `dir` (output `out_<takes>`): the default run over the
/// apartment and three floor plans, 1–4 people, 4–12 s.
pub fn campaign_file(dir: &std::path::Path, takes: usize) -> PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = dir.join(format!("campaign_{takes}.toml"));
    std::fs::write(
        &path,
        format!(
            "[campaign]\nrun = \"{}\"\nout = \"out_{takes}\"\ntakes = {takes}\nscenes = [\"{}\"]\nfloor_plans = [1, 2, 3]\ncrowd_count = [1, 4]\nduration_s = [4.0, 12.0]\n",
            root.join("configs/default.toml").display(),
            root.join("assets/scenes/apartment.glb").display()
        ),
    )
    .unwrap();
    path
}
