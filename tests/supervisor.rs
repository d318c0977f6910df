//! The supervisor against real Blender workers: an uninterrupted run, and a run whose Blender
//! workers are killed with SIGKILL at random moments, some right after a frame is written (at
//! least 10 kills a run), and the supervisor itself twice, then resumed once more — ten seeds in
//! a row, each dataset identical to the uninterrupted one file for file (SHA-256); no partial
//! file may be listed, and `egogen-run verify` must pass (and fail on a tampered file).

use std::path::{Path, PathBuf};
use std::process::{Child, Command};
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
every_n_frames = 2
samples = 2
frames_per_shard = 2
[render.aria]
streams = ["trajectory", "calibration", "imu", "gaze"]
[supervisor]
workers = 1
retries = 40
"#;

fn egogen_run() -> Command {
    Command::new(env!("CARGO_BIN_EXE_egogen-run"))
}

fn setup() -> (tempfile::TempDir, PathBuf) {
    common::run_dir(CONFIG)
}

/// Kills a run as soon as it has staged its `.partial` folder (its `work/run.json` exists).
fn kill_once_staged(mut child: Child, partial: &Path) {
    let state = partial.join("work/run.json");
    let deadline = Instant::now() + Duration::from_secs(120);
    while !state.is_file() {
        assert!(Instant::now() < deadline, "the run never staged");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
}

fn kill9(pid: i32) -> bool {
    Command::new("kill")
        .args(["-9", &pid.to_string()])
        .status()
        .is_ok_and(|s| s.success())
}

/// Small deterministic generator for kill delays.
struct Lcg(u64);
impl Lcg {
    fn millis(&mut self, lo: u64, hi: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (self.0 >> 33) % (hi - lo)
    }
}

/// Retries count frames, not attempts: with `retries = 0`, a worker killed after it has
/// written its shard's one frame (its attempt fails, but no frame is lost) does not fail the
/// run. Every worker is killed as soon as its frame is finished, before Blender exits.
#[test]
fn a_worker_killed_after_writing_its_frames_does_not_use_up_a_retry() {
    let config = CONFIG
        .replace("duration_s = 1.0", "duration_s = 0.25")
        .replace("frames_per_shard = 2", "frames_per_shard = 1")
        .replace("retries = 40", "retries = 0");
    let (dir, config) = common::run_dir(&config);
    let mut child = egogen_run().arg(&config).spawn().unwrap();
    let needle = dir.path().display().to_string();
    let frames_dir = dir.path().join("out.partial/cameras/camera-slam-left");
    let deadline = Instant::now() + Duration::from_secs(300);
    let (mut seen, mut kills) = (0, 0);
    let status = loop {
        assert!(Instant::now() < deadline, "the run is stuck");
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        let done = std::fs::read_dir(&frames_dir)
            .map(|d| d.count())
            .unwrap_or(0);
        if done > seen {
            seen = done;
            for pid in common::pids_with(&["render_shard.py", &needle]) {
                if kill9(pid) {
                    kills += 1;
                }
            }
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    eprintln!("{kills} workers killed after their frame");
    assert!(kills >= 1, "no worker was caught after its frame");
    assert!(status.success(), "a kill after the frame failed the run");
    let listed = common::read_manifest(&dir.path().join("out"));
    let frames = listed
        .files
        .iter()
        .filter(|f| f.path.ends_with(".exr"))
        .count();
    assert_eq!(frames, 5);
    let report = verify(&dir.path().join("out")).unwrap();
    assert_eq!(report.frames, 5);
    // The pool report shows attempts that were killed although their frame was finished.
    let pool: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/logs/start_01/pool_report.json")).unwrap(),
    )
    .unwrap();
    let killed_after_frame = pool["shards"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["attempts"].as_array().unwrap())
        .filter(|a| a["outcome"] != "ok" && a["finished"] == a["frames"])
        .count();
    assert!(killed_after_frame >= 1, "{pool}");
    // An attempt that finished frames says where its time went, Blender's and Rust's.
    for attempt in pool["shards"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["attempts"].as_array().unwrap())
        .filter(|a| a["finished"].as_u64().unwrap() > 0)
    {
        for stage in ["blender_start_up", "scene_import", "assemble", "finish"] {
            assert!(
                attempt["stages"][stage].as_f64().unwrap() > 0.0,
                "{stage}: {attempt}"
            );
        }
    }
}

/// How many frame files a run has finished so far (temporaries not counted).
fn frames_done(run_dir: &Path) -> usize {
    std::fs::read_dir(run_dir.join("out.partial/cameras/camera-slam-left"))
        .map(|d| {
            d.flatten()
                .filter(|e| e.path().extension().is_some_and(|x| x == "exr"))
                .count()
        })
        .unwrap_or(0)
}

/// When the next worker kill is due.
enum NextKill {
    At(Instant),
    /// Right after the next frame file appears.
    OnFrame,
}

/// What one interrupted start did.
struct Chaos {
    status: std::process::ExitStatus,
    worker_kills: usize,
    supervisor_killed: bool,
}

/// One start of `egogen-run` (a `--resume` when `resume`) whose Blender workers are killed at
/// random moments — after a random delay, or right after a frame file appears — `worker_kills`
/// times; then, once this start has finished a frame, the supervisor itself is killed.
fn chaotic_start(
    config: &Path,
    run_dir: &Path,
    resume: bool,
    worker_kills: usize,
    rng: &mut Lcg,
) -> Chaos {
    let mut command = egogen_run();
    command.arg(config);
    if resume {
        command.arg("--resume");
    }
    let mut child = command.stderr(std::process::Stdio::null()).spawn().unwrap();
    let needle = run_dir.display().to_string();
    let at_start = frames_done(run_dir);
    let mut seen = at_start;
    let mut kills = 0;
    let mut next = NextKill::At(Instant::now() + Duration::from_millis(rng.millis(100, 800)));
    let deadline = Instant::now() + Duration::from_secs(300);
    loop {
        assert!(Instant::now() < deadline, "a start is stuck");
        if let Some(status) = child.try_wait().unwrap() {
            return Chaos {
                status,
                worker_kills: kills,
                supervisor_killed: false,
            };
        }
        let done = frames_done(run_dir);
        if kills < worker_kills {
            let due = match next {
                NextKill::At(t) => Instant::now() >= t,
                NextKill::OnFrame => done > seen,
            };
            if due {
                let killed = common::pids_with(&["render_shard.py", &needle])
                    .into_iter()
                    .filter(|&pid| kill9(pid))
                    .count();
                kills += killed;
                if killed > 0 || matches!(next, NextKill::OnFrame) {
                    next = match rng.millis(0, 3) {
                        0 => NextKill::OnFrame,
                        _ => NextKill::At(
                            Instant::now() + Duration::from_millis(rng.millis(100, 800)),
                        ),
                    };
                }
            }
        } else if done > at_start {
            assert!(kill9(child.id() as i32));
            let status = child.wait().unwrap();
            return Chaos {
                status,
                worker_kills: kills,
                supervisor_killed: true,
            };
        }
        seen = done;
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Ten seeds in a row: each run's workers are killed at random moments at least 10 times (some
/// right after a frame was written) and its supervisor twice (the first start and the first
/// resume); one more `--resume` then finishes a dataset identical to the uninterrupted one.
#[test]
fn killed_workers_and_killed_supervisors_still_give_the_same_dataset_ten_seeds_in_a_row() {
    // Reference: uninterrupted.
    let (ref_dir, ref_config) = setup();
    common::succeeds(egogen_run().arg(&ref_config));
    let reference = common::read_manifest(&ref_dir.path().join("out"));
    let frames = reference
        .files
        .iter()
        .filter(|f| f.path.ends_with(".exr"))
        .count();
    assert_eq!(frames, 20);
    // The wearer's Aria streams are part of the dataset (and compared below, file for file).
    for f in [
        "aria/agent_0/slam/closed_loop_trajectory.csv",
        "aria/agent_0/slam/online_calibration.jsonl",
        "aria/agent_0/device_calibration.json",
        "aria/agent_0/imu/imu-left.csv",
        "aria/agent_0/imu/imu-right.csv",
        "aria/agent_0/eye_gaze/general_eye_gaze.csv",
    ] {
        assert!(
            reference.files.iter().any(|e| e.path == f),
            "{f} not in the manifest"
        );
    }

    let mut last = None;
    for seed in 0..10u64 {
        let (dir, config) = setup();
        let mut rng = Lcg(seed * 7919 + 7);
        // The first start: workers killed 3-5 times, then the supervisor.
        let first = chaotic_start(
            &config,
            dir.path(),
            false,
            rng.millis(3, 6) as usize,
            &mut rng,
        );
        assert!(
            first.supervisor_killed,
            "seed {seed}: the first start finished first"
        );
        assert!(!first.status.success());
        assert!(dir.path().join("out.partial").is_dir());
        assert!(!dir.path().join("out").exists());
        if seed == 0 {
            // Without --resume nothing is touched.
            let refused = egogen_run().arg(&config).output().unwrap();
            assert!(!refused.status.success());
            assert!(String::from_utf8_lossy(&refused.stderr).contains("--resume"));
        }
        // The first resume: workers killed until 10 kills in all, then the supervisor again.
        let second = chaotic_start(
            &config,
            dir.path(),
            true,
            10usize.saturating_sub(first.worker_kills),
            &mut rng,
        );
        assert!(
            second.supervisor_killed,
            "seed {seed}: the first resume finished first"
        );
        let kills = first.worker_kills + second.worker_kills;
        assert!(kills >= 10, "seed {seed}: {kills} worker kills");
        let left = frames - frames_done(dir.path());
        // One more resume finishes it.
        common::succeeds(egogen_run().arg(&config).arg("--resume"));
        let dataset = dir.path().join("out");
        let faulty = common::read_manifest(&dataset);
        assert_eq!(faulty, reference, "seed {seed}: datasets differ");
        assert!(faulty
            .files
            .iter()
            .all(|f| !f.path.contains(".partial") && !f.path.ends_with(".tmp")));
        eprintln!("seed {seed}: {kills} worker kills, 2 supervisor kills, {left} frames left for the last resume");
        last = Some((dir, faulty));
    }
    let (dir, faulty) = last.unwrap();
    let dataset = dir.path().join("out");
    // Some shard attempts failed and were retried (their logs are kept).
    // Every start keeps its own logs: the killed first start's, then each resume's.
    let starts: Vec<_> = std::fs::read_dir(dataset.join("logs"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    assert!(starts.len() >= 3, "{starts:?}");
    assert!(dataset.join("logs/start_01").is_dir());
    let logs: usize = starts
        .iter()
        .map(|s| std::fs::read_dir(s).unwrap().count())
        .sum();
    assert!(logs > 5, "{logs} log files");

    // verify passes, and catches a changed byte.
    let report = verify(&dataset).unwrap();
    assert_eq!(report.frames, 20);
    let ok = egogen_run().arg("verify").arg(&dataset).output().unwrap();
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let victim = dataset.join(
        &faulty
            .files
            .iter()
            .find(|f| f.path.ends_with(".exr"))
            .unwrap()
            .path,
    );
    let mut bytes = std::fs::read(&victim).unwrap();
    let n = bytes.len();
    bytes[n - 10] ^= 0xff;
    std::fs::write(&victim, bytes).unwrap();
    let bad = egogen_run().arg("verify").arg(&dataset).output().unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("checksum"), "{err}");
}

#[test]
fn resume_repairs_a_damaged_frame_and_drops_leftover_temporaries() {
    let (dir, config) = setup();
    common::succeeds(egogen_run().arg(&config));
    let dataset = dir.path().join("out");
    let reference = common::read_manifest(&dataset);
    // The state a killed run can leave: the staging folder without its manifest, a frame file
    // damaged after it was finished, temporaries of atomic writes and of frame finishing.
    let staging = dir.path().join("out.partial");
    std::fs::rename(&dataset, &staging).unwrap();
    std::fs::remove_file(staging.join("manifest.json")).unwrap();
    let frames = staging.join("cameras/camera-slam-left");
    let victim = frames.join("frame_00004.exr");
    let bytes = std::fs::read(&victim).unwrap();
    std::fs::write(&victim, &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(staging.join("manifest.json.partial"), b"{\"files\": [").unwrap();
    std::fs::write(frames.join("frame_00006.exr.tmp"), b"half a frame").unwrap();
    // Frame records (annotation, checksum) a killed supervisor can leave missing, or stale
    // beside a frame file: both are recorded again from the file, not rendered again.
    let records = staging.join("work/frames/camera-slam-left");
    std::fs::remove_file(records.join("frame_00002.json")).unwrap();
    std::fs::copy(
        records.join("frame_00010.json"),
        records.join("frame_00008.json"),
    )
    .unwrap();

    let out = egogen_run()
        .arg(&config)
        .arg("--resume")
        .env("EGOGEN_PROGRESS_EVERY_S", "0.2")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    // Standard error is a pipe here: plain progress lines instead of a bar.
    assert!(err.contains("egogen-run: rendering 19/20 frames"), "{err}");
    assert!(
        err.contains("frame_00004.exr is damaged") && err.contains("1 to render"),
        "{err}"
    );
    assert_eq!(
        common::read_manifest(&dataset),
        reference,
        "datasets differ"
    );
    // The resume's pool report names its logs inside the finished dataset.
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dataset.join("logs/start_02/pool_report.json")).unwrap(),
    )
    .unwrap();
    let attempt = &report["shards"][0]["attempts"][0];
    let log = attempt["log"].as_str().unwrap();
    assert!(log.starts_with("logs/start_02/"), "{attempt}");
    assert!(dataset.join(log).is_file(), "{log}");
    assert!(!dataset.join("manifest.json.partial").exists());
    assert!(!dataset
        .join("cameras/camera-slam-left/frame_00006.exr.tmp")
        .exists());
    // Scratch only Blender read is gone from the finished dataset (the body cache is large).
    assert!(!dataset.join("work/agent_0.pc2").exists());
    assert!(!dataset.join("work/raw").exists());
    verify(&dataset).unwrap();
}

#[test]
fn a_run_that_fails_before_rendering_stages_nothing() {
    // A scene that is not a scene, and a Blender that is not there: both refused before
    // `out.partial` exists, so the fixed rerun starts clean.
    let (dir, config) = setup();
    std::fs::write(dir.path().join("bad.glb"), b"glTF but not really").unwrap();
    let text = std::fs::read_to_string(&config).unwrap();
    std::fs::write(&config, format!("[scene]\npath = \"bad.glb\"\n{text}")).unwrap();
    let out = egogen_run().arg(&config).output().unwrap();
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("bad.glb"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!dir.path().join("out.partial").exists());

    let (dir, config) = setup();
    let out = egogen_run()
        .arg(&config)
        .arg("--blender")
        .arg(dir.path().join("no-blender-here"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("no-blender-here"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!dir.path().join("out.partial").exists());
}

#[test]
fn the_slurm_backend_without_slurm_is_refused_before_anything_is_staged() {
    let (dir, config) = setup();
    // A PATH with Python (a first run installs Blender with it) and nothing else.
    let bin = dir.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    for python in ["python3", "python3.11"] {
        let found = Command::new("sh")
            .args(["-c", &format!("command -v {python}")])
            .output()
            .unwrap();
        let found = String::from_utf8_lossy(&found.stdout).trim().to_string();
        if !found.is_empty() {
            std::os::unix::fs::symlink(found, bin.join(python)).unwrap();
        }
    }
    let out = egogen_run()
        .arg(&config)
        .args(["--backend", "slurm"])
        .env("PATH", &bin)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("sbatch"), "{err}");
    assert!(!dir.path().join("out.partial").exists());
}

#[test]
fn a_scene_blender_cannot_load_fails_once_without_retries() {
    // The scene is read by egogen, then taken away before Blender imports it: every try
    // would fail the same way, so there is one attempt, not `retries` + 1.
    let (dir, config) = setup();
    let scene = dir.path().join("room.glb");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/apartment.glb"),
        &scene,
    )
    .unwrap();
    let text = std::fs::read_to_string(&config).unwrap();
    std::fs::write(&config, format!("[scene]\npath = \"room.glb\"\n{text}")).unwrap();
    let mut child = egogen_run().arg(&config).spawn().unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    while !dir.path().join("out.partial").exists() {
        assert!(Instant::now() < deadline, "the run never staged");
        assert!(child.try_wait().unwrap().is_none(), "the run ended early");
        std::thread::sleep(Duration::from_millis(5));
    }
    std::fs::write(&scene, b"not a scene any more").unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success());
    let logs: Vec<_> = std::fs::read_dir(dir.path().join("out.partial/logs/start_01"))
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".log"))
        .collect();
    assert_eq!(logs, ["shard_0000_attempt_1.log"], "retried: {logs:?}");
    // The failed start still reports what it did.
    let report = std::fs::read_to_string(
        dir.path()
            .join("out.partial/logs/start_01/pool_report.json"),
    )
    .unwrap();
    assert!(report.contains("could not set up the scene"), "{report}");
}

#[test]
fn a_resume_with_another_rig_is_refused() {
    let (dir, config) = setup();
    let child = egogen_run().arg(&config).spawn().unwrap();
    kill_once_staged(child, &dir.path().join("out.partial"));
    // The same rig file with one camera moved by a centimetre.
    let rig = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("camera_rigs/aria_gen1.json"),
    )
    .unwrap()
    .replacen("0.06905099990228451", "0.07905099990228451", 1);
    let moved = dir.path().join("moved_rig.json");
    std::fs::write(&moved, rig).unwrap();
    let out = egogen_run()
        .arg(&config)
        .arg("--resume")
        .arg("--rig")
        .arg(&moved)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("different camera rig"), "{err}");
}

/// A seed TOML cannot write (2^63) is refused by its key before anything is made; `--seed`
/// is bounded the same way.
#[test]
fn a_seed_beyond_toml_is_refused_by_its_key() {
    let (dir, config) = setup();
    let text = std::fs::read_to_string(&config).unwrap().replace(
        "[supervisor]",
        "[render.lighting]\nlamp_watts = [100.0, 500.0]\nseed = 9223372036854775808\n[supervisor]",
    );
    std::fs::write(&config, text).unwrap();
    let out = egogen_run().arg(&config).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("render.lighting.seed = 9223372036854775808") && err.contains("2^63"),
        "{err}"
    );
    let out = egogen_run()
        .arg(&config)
        .args(["--seed", "18446744073709551615"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    // The flag is bounded where it is read.
    assert!(
        err.contains("--seed") && err.contains("9223372036854775807"),
        "{err}"
    );
    assert!(std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .all(|e| !e.file_name().to_string_lossy().ends_with(".partial")));
}

#[test]
fn out_and_seed_overrides_are_recorded_and_a_resume_must_repeat_them() {
    let (dir, config) = setup();
    // Give the config a seeded section the override reaches.
    let text = std::fs::read_to_string(&config).unwrap().replace(
        "[supervisor]",
        "[render.lighting]\nlamp_watts = [100.0, 500.0]\nseed = 1\n[supervisor]",
    );
    std::fs::write(&config, text).unwrap();
    let other = dir.path().join("other");
    let partial = dir.path().join("other.partial");
    let child = egogen_run()
        .arg(&config)
        .args(["--seed", "7", "--out"])
        .arg(&other)
        .spawn()
        .unwrap();
    kill_once_staged(child, &partial);
    assert!(
        !dir.path().join("out.partial").exists(),
        "--out was not used"
    );
    // Another seed is another run: refused, nothing touched.
    let refused = egogen_run()
        .arg(&config)
        .args(["--resume", "--seed", "8", "--out"])
        .arg(&other)
        .output()
        .unwrap();
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("different config"), "{err}");
    // Every override that changes the config is named, the activity weights and materials too.
    for flag in [
        "--seed",
        "--activity-weights",
        "--materials",
        "--duration-s",
    ] {
        assert!(err.contains(flag), "{flag}: {err}");
    }
    // The same overrides with more workers: the same run, resumed to the end.
    let resumed = egogen_run()
        .arg(&config)
        .args(["--resume", "--seed", "7", "--workers", "2", "--out"])
        .arg(&other)
        .output()
        .unwrap();
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    // The dataset's config.toml holds the effective values and reads back as a config.
    let recorded = std::fs::read_to_string(other.join("config.toml")).unwrap();
    let raw: egogen::cli::RawRun = toml::from_str(&recorded).unwrap();
    assert_eq!(raw.scene.seed, Some(7), "the scripted walk's placement");
    assert_eq!(raw.render.unwrap().lighting.unwrap().seed, Some(7));
    assert_eq!(raw.output.dir, other);
    assert!(recorded.starts_with("# The effective config"), "{recorded}");
    let doc: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(other.join("cameras/camera-slam-left/annotations.json")).unwrap(),
    )
    .unwrap();
    let watts = doc["lighting"]["point_lights"][0]["watts"]
        .as_f64()
        .unwrap();
    assert!((100.0..=500.0).contains(&watts), "{watts}");
    verify(&other).unwrap();
}

/// `keep_blender = true`: each worker keeps one Blender across the take's shards. Its frames are
/// the same bytes as one Blender per shard's; the pool report says which attempts ran in a kept
/// Blender and what it held; and a kept Blender killed with SIGKILL while it renders costs no
/// try (`retries = 0`): the frame is rendered again in a fresh Blender and the run succeeds.
#[test]
fn a_kept_blender_renders_the_same_frames_and_its_kill_costs_no_try() {
    let frames_of = |dir: &Path| -> Vec<(String, String)> {
        let listed = common::read_manifest(dir);
        let mut frames: Vec<(String, String)> = listed
            .files
            .iter()
            .filter(|f| f.path.ends_with(".exr"))
            .map(|f| (f.path.clone(), f.sha256.clone()))
            .collect();
        frames.sort();
        frames
    };
    let (one_shot, config) = setup();
    common::succeeds(egogen_run().arg(&config));
    let expected = frames_of(&one_shot.path().join("out"));
    assert_eq!(expected.len(), 20);

    let kept_config = CONFIG.replace("retries = 40", "retries = 0\nkeep_blender = true");
    let (dir, config) = common::run_dir(&kept_config);
    let mut child = egogen_run()
        .arg(&config)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let needle = dir.path().display().to_string();
    let frames_dir = dir.path().join("out.partial/cameras/camera-slam-left");
    let deadline = Instant::now() + Duration::from_secs(300);
    // Once the kept Blender has finished a few shards, kill it (while it renders, mostly).
    while std::fs::read_dir(&frames_dir).map_or(0, |d| d.count()) < 8 {
        assert!(Instant::now() < deadline, "the run is stuck");
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended too soon"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let killed: usize = common::pids_with(&["render_shard.py", "--serve", &needle])
        .into_iter()
        .filter(|&pid| kill9(pid))
        .count();
    assert_eq!(killed, 1, "one kept Blender");
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/logs/start_01/pool_report.json")).unwrap(),
    )
    .unwrap();
    let attempts: Vec<&serde_json::Value> = report["shards"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["attempts"].as_array().unwrap())
        .collect();
    // Shards after the first ran in the kept Blender, which says what it held.
    assert!(
        attempts
            .iter()
            .any(|a| a["blender"]["shards_before"].as_u64() > Some(2)
                && a["blender"]["resident_mb"]
                    .as_f64()
                    .is_some_and(|mb| mb > 50.0)),
        "{report}"
    );
    // After the kill a fresh Blender took over (the killed one's attempt, if it was rendering,
    // failed without a try charged: with retries = 0 the run would have failed otherwise).
    let fresh = attempts
        .iter()
        .filter(|a| a["blender"]["shards_before"] == 0)
        .count();
    assert!(fresh >= 2, "{report}");
    assert_eq!(frames_of(&dir.path().join("out")), expected);
}

/// `egogen-run verify` names what it was given when it is no dataset: a campaign's folder (verify
/// its takes), a manifest that is not text.
#[test]
fn verify_names_a_campaign_folder_and_a_binary_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let campaign = dir.path().join("campaign");
    std::fs::create_dir_all(campaign.join("takes")).unwrap();
    std::fs::write(campaign.join("campaign.json"), "{}").unwrap();
    let binary = dir.path().join("binary");
    std::fs::create_dir_all(&binary).unwrap();
    std::fs::write(binary.join("manifest.json"), [0xff_u8, 0xfe, 0x00, 0x81]).unwrap();
    for (folder, says) in [(&campaign, "a campaign's folder"), (&binary, "not text")] {
        let out = egogen_run().arg("verify").arg(folder).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{err}");
        assert!(err.contains(says) && !err.contains("panicked"), "{err}");
    }
}
