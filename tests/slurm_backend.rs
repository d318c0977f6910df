//! The Slurm backend against a real single-node Slurm (Debian `slurm-wlm` + `munge`, started by
//! `tools/slurm_single_node.sh`): the run submits an array, one running array task is cancelled
//! with `scancel JOB_TASK`, the shard is resubmitted, and the finished dataset is identical
//! (SHA-256, file for file) to the local backend's. Without Slurm on this machine the test says
//! so and returns; `EGOGEN_REQUIRE_SYSTEM_TOOLS=1` (set by `.ci/run`) makes that a failure.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use egogen::supervisor::verify;

mod common;

const CONFIG: &str = r#"
[body]
betas = []
[motion]
source = "scripted_walk"
duration_s = 1.0
frame_rate_hz = 40.0
[output]
dir = "out"
mesh_every_n_frames = 0
[render]
cameras = ["camera-slam-left"]
resolution_scale = 0.1
every_n_frames = 4
samples = 2
frames_per_shard = 2
[supervisor]
backend = "slurm"
workers = 2
retries = 2
[supervisor.slurm]
cpus_per_task = 1
mem_gb = 1.0
poll_interval_s = 0.5
"#;

fn egogen_run() -> Command {
    Command::new(env!("CARGO_BIN_EXE_egogen-run"))
}

fn setup() -> (tempfile::TempDir, PathBuf) {
    common::run_dir(CONFIG)
}

/// Starts the single-node cluster when needed; false (with the reason printed) when this
/// machine has no Slurm.
fn slurm_cluster() -> bool {
    let has = |bin: &str| {
        Command::new("sh")
            .args(["-c", &format!("command -v {bin}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let required = std::env::var("EGOGEN_REQUIRE_SYSTEM_TOOLS").is_ok_and(|v| v == "1");
    if !(has("sbatch") && has("slurmctld") && has("slurmd") && has("munged")) {
        assert!(
            !required,
            "EGOGEN_REQUIRE_SYSTEM_TOOLS=1 but Slurm is not installed (apt-get install slurmctld slurmd slurm-client munge)"
        );
        eprintln!(
            "SKIPPED slurm_backend: no Slurm on this machine (apt-get install slurmctld slurmd slurm-client munge)"
        );
        return false;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/slurm_single_node.sh");
    let out = Command::new("bash").arg(&script).output().unwrap();
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!required, "could not start Slurm: {err}");
        eprintln!("SKIPPED slurm_backend: could not start Slurm: {err}");
        return false;
    }
    true
}

/// `(task, state)` of the array's tasks in the queue.
fn queue(job: &str) -> Vec<(u32, String)> {
    let out = Command::new("squeue")
        .args(["--noheader", "--array", "--jobs", job, "--format=%K %T"])
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let (t, s) = l.trim().split_once(' ')?;
            Some((t.parse().ok()?, s.to_string()))
        })
        .collect()
}

#[test]
fn a_slurm_array_survives_a_cancelled_task_and_matches_the_local_backend() {
    if !slurm_cluster() {
        return;
    }
    // Reference: the local backend.
    let (ref_dir, ref_config) = setup();
    common::succeeds(egogen_run().arg(&ref_config).args(["--backend", "local"]));
    let reference = common::read_manifest(&ref_dir.path().join("out"));

    // Slurm: cancel the first task seen running, once.
    let (dir, config) = setup();
    let mut child = egogen_run().arg(&config).spawn().unwrap();
    let jobs = dir.path().join("out.partial/work/slurm/jobs.txt");
    let deadline = Instant::now() + Duration::from_secs(600);
    let mut cancelled: Option<String> = None;
    let status = loop {
        assert!(Instant::now() < deadline, "the Slurm run is stuck");
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if cancelled.is_none() {
            let first_job = std::fs::read_to_string(&jobs)
                .ok()
                .and_then(|t| t.lines().next().map(str::to_string));
            if let Some(job) = first_job {
                if let Some((task, _)) = queue(&job).into_iter().find(|(_, s)| s == "RUNNING") {
                    let target = format!("{job}_{task}");
                    let ok = Command::new("scancel").arg(&target).status().unwrap();
                    assert!(ok.success(), "scancel {target}");
                    eprintln!("cancelled array task {target}");
                    cancelled = Some(target);
                }
            }
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "the Slurm run failed");
    let cancelled = cancelled.expect("no array task was ever seen running");

    let dataset = dir.path().join("out");
    assert_eq!(
        common::read_manifest(&dataset),
        reference,
        "Slurm and local datasets differ"
    );
    assert_eq!(verify(&dataset).unwrap().frames, 10);

    // The cancelled task's shard was resubmitted in a later array — unless the cancel came
    // after the task had written its frames: a finished frame counts, so nothing is retried
    // (docs/SUPERVISOR.md, "retries count frames"). Arrays overlap (a new one goes out as
    // soon as a task's place is free), so the number of arrays does not say which.
    let report = dataset.join("logs/start_01/pool_report.json");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
    // Each task that ended well says where its time went (the worker's timings in its log).
    for attempt in report["shards"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["attempts"].as_array().unwrap())
        .filter(|a| a["outcome"] == "ok")
    {
        assert!(
            attempt["stages"]["scene_import"].as_f64().unwrap() > 0.0,
            "{attempt}"
        );
    }
    let retried = report["shards"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["attempts"].as_array().unwrap().len() > 1)
        .count();
    let (job, task) = cancelled.split_once('_').unwrap();
    let log = format!("slurm_{job}_{task}.log");
    let attempts = report["shards"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["attempts"].as_array().unwrap())
        .find(|a| a.iter().any(|t| t["log"].as_str().unwrap().ends_with(&log)))
        .unwrap_or_else(|| panic!("no attempt of {cancelled} in {report:#}"));
    let hit = attempts
        .iter()
        .position(|t| t["log"].as_str().unwrap().ends_with(&log))
        .unwrap();
    // Cancelled too late to matter: the task ended well, or Slurm recorded the cancel after
    // the task had written all its frames (the supervisor says so and keeps them).
    let outcome = attempts[hit]["outcome"].as_str().unwrap();
    if outcome == "ok" || outcome.ends_with("after finishing its frames") {
        eprintln!("{cancelled} was cancelled after writing its frames: nothing to retry");
        assert_eq!(retried, 0, "{report:#}");
        return;
    }
    assert!(
        attempts[hit]["outcome"]
            .as_str()
            .unwrap()
            .contains("CANCELLED"),
        "{}",
        attempts[hit]
    );
    assert_eq!(attempts.len(), hit + 2, "{report:#}");
    assert_eq!(attempts[hit + 1]["outcome"], "ok", "{report:#}");
    assert_eq!(retried, 1, "{report:#}");
}

#[test]
fn a_campaign_on_slurm_matches_the_local_pool() {
    if !slurm_cluster() {
        return;
    }
    // The tiny campaign on the local pool, moved aside; then the same campaign, in the same
    // place, its takes' shards as Slurm arrays with one task in flight: takes are staged on
    // demand (4 shards a task pending), so the third take goes out in a later array.
    let dir = tempfile::tempdir().unwrap();
    let campaign = common::tiny_campaign(dir.path(), true);
    let out = dir.path().join("out");
    common::succeeds(egogen_run().arg(&campaign).args(["--backend", "local"]));
    let local = common::campaign_digest(&out);
    std::fs::rename(&out, dir.path().join("local")).unwrap();
    let run = common::succeeds(egogen_run().arg(&campaign).args(["--workers", "1"]));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("Slurm array job"), "{said}");
    assert_eq!(common::campaign_digest(&out), local, "{said}");
    let script = std::fs::read_to_string(out.join("work/slurm/round_001/array.sh")).unwrap();
    assert!(script.contains("%1"), "{script}");
    // Which takes each round's task specs render.
    let takes_of = |round: &str| -> std::collections::BTreeSet<String> {
        let dir = out.join("work/slurm").join(round);
        std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with("task_"))
            .flat_map(|e| {
                let spec = std::fs::read_to_string(e.path()).unwrap();
                let state = egogen::campaign::CampaignState::read(&out).unwrap();
                state
                    .takes
                    .into_iter()
                    .map(|t| t.def.id)
                    .filter(move |id| spec.contains(&format!("takes/{id}.partial")))
            })
            .collect()
    };
    let state = egogen::campaign::CampaignState::read(&out).unwrap();
    let ids: Vec<String> = state.takes.iter().map(|t| t.def.id.clone()).collect();
    assert_eq!(
        takes_of("round_001"),
        ids[..2].iter().cloned().collect(),
        "two takes staged for the first array"
    );
    // (A task that failed in the first array would be retried in the second too.)
    assert!(takes_of("round_002").contains(&ids[2]));
}
