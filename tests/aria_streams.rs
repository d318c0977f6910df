//! The Aria streams of real takes: the head spline between a take's frames and the trajectory
//! rate's trade, a take exported by `egogen aria export` with every stream, readable and
//! consistent, and render configs' Aria errors. (The models' own tests read their internals:
//! `export::aria_tests`.)

use std::path::PathBuf;
use std::process::Command;

use egogen::export::aria::closed_loop_trajectory_csv;
use egogen::math::pose_spline::PoseSpline;
use egogen::math::{axis_angle_to_matrix, matrix_to_axis_angle, Affine3, Mat3, Vec3};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A 3-person take of `seconds` in the shipped apartment, by `egogen synth`.
fn make_take(dir: &std::path::Path, seconds: f64) -> PathBuf {
    let config = std::fs::read_to_string(root().join("configs/apartment3.toml"))
        .unwrap()
        .replace("\"../", &format!("\"{}/", root().display()))
        .replace("duration_s = 30.0", &format!("duration_s = {seconds:?}"))
        .replace(
            &format!("dir = \"{}/out/apartment3\"", root().display()),
            &format!("dir = \"{}\"", dir.join("take").display()),
        );
    std::fs::write(dir.join("take.toml"), config).unwrap();
    let synth = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["synth", dir.join("take.toml").to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(
        synth.status.success(),
        "{}",
        String::from_utf8_lossy(&synth.stderr)
    );
    dir.join("take")
}

/// `world_from_cpf` per frame of an agent of a take.
fn head_poses(take: &std::path::Path, agent: &str) -> Vec<Affine3> {
    let path = take.join("agents").join(agent).join("cpf_trajectory.json");
    egogen::synth::sequence_dir::read_cpf_trajectory(&path)
        .unwrap()
        .1
}

/// How well the spline reconstructs a synthesized head between its samples (through every
/// second frame, against the frames left out), and the trajectory rate's trade: how far a
/// reader interpolating linearly between rows is from the spline, against rows per second.
#[test]
fn spline_accuracy_and_the_trajectory_rate_trade_on_a_take() {
    let tmp = tempfile::tempdir().unwrap();
    let take = make_take(tmp.path(), 20.0);
    let poses = head_poses(&take, "crowd_00");
    let even: Vec<Affine3> = poses.iter().step_by(2).copied().collect();
    let half = PoseSpline::interpolate(20.0, &even).unwrap();
    let (mut dp, mut dr) = (Vec::new(), Vec::new());
    for (i, p) in poses.iter().enumerate().skip(1).step_by(2) {
        if i + 1 >= poses.len() {
            break;
        }
        let s = half.sample(i as f64 / 40.0).world_from_body;
        dp.push((s.translation - p.translation).length());
        dr.push(matrix_to_axis_angle(s.matrix3.transpose() * p.matrix3).length());
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[v.len() - 1])
    };
    let (p50, pmax) = median(&mut dp);
    let (r50, rmax) = median(&mut dr);
    eprintln!("spline through 20 Hz vs the 40 Hz frames between: position median {p50:.2e} m, max {pmax:.2e} m; rotation median {r50:.2e} rad, max {rmax:.2e} rad");
    assert!(p50 < 5e-3 && r50 < 5e-3);

    let spline = PoseSpline::interpolate(40.0, &poses).unwrap();
    let mut last = f64::INFINITY;
    for rate in [100.0, 250.0, 500.0, 1000.0] {
        let start = std::time::Instant::now();
        let (csv, rows) = closed_loop_trajectory_csv(&spline, Affine3::IDENTITY, rate, "w");
        let secs = start.elapsed().as_secs_f64();
        // Linear interpolation halfway between rows, the worst place.
        let dt = 1.0 / rate;
        let mut worst = 0.0f64;
        for k in 0..rows - 1 {
            let (a, b) = (
                spline.sample(k as f64 * dt),
                spline.sample((k + 1) as f64 * dt),
            );
            let mid = spline
                .sample((k as f64 + 0.5) * dt)
                .world_from_body
                .translation;
            let lin = (a.world_from_body.translation + b.world_from_body.translation) * 0.5;
            worst = worst.max((mid - lin).length());
        }
        eprintln!(
            "trajectory at {rate} Hz: {rows} rows, {:.0} kB per second of take, written in {:.1} ms; linear interpolation off the spline by at most {worst:.2e} m",
            csv.len() as f64 / 1e3 / spline.duration_s(),
            secs * 1e3
        );
        assert!(worst < last);
        last = worst;
    }
    assert!(last < 1e-4);
}

#[test]
fn aria_export_writes_every_stream_of_a_take_and_refuses_bad_requests() {
    let tmp = tempfile::tempdir().unwrap();
    let bin = env!("CARGO_BIN_EXE_egogen");
    let run = |args: &[&str]| Command::new(bin).args(args).output().unwrap();
    make_take(tmp.path(), 3.0);
    let take = tmp.path().join("take");
    let out = tmp.path().join("aria");
    let done = run(&[
        "aria",
        "export",
        take.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--wearer",
        "crowd_01",
    ]);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    for f in [
        "crowd_01/slam/closed_loop_trajectory.csv",
        "crowd_01/slam/online_calibration.jsonl",
        "crowd_01/device_calibration.json",
        "crowd_01/imu/imu-left.csv",
        "crowd_01/imu/imu-right.csv",
        "manifest.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert!(!out.join("crowd_00").exists());
    let csv =
        std::fs::read_to_string(out.join("crowd_01/slam/closed_loop_trajectory.csv")).unwrap();
    let frames = 3 * 40;
    assert!(
        csv.lines().count() >= frames * 25,
        "{} rows",
        csv.lines().count()
    );
    // The same export again: refused, nothing touched.
    let again = run(&[
        "aria",
        "export",
        take.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("already exists"));
    // An export inside its take: refused, nothing written there.
    let inside = take.join("aria_export");
    let refused = run(&[
        "aria",
        "export",
        take.to_str().unwrap(),
        "--out",
        inside.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && err.contains("is inside the take"),
        "{err}"
    );
    assert!(!inside.exists() && !take.join("aria_export.partial").exists());
    let cases: [(&[&str], &str); 4] = [
        (
            &["--streams", "trajectory,odometry"],
            "unknown stream `odometry`",
        ),
        (&["--wearer", "nobody"], "has no agent `nobody`"),
        (&["--trajectory-rate-hz", "0"], "trajectory_rate_hz = 0"),
        (
            &["--rig", "camera_rigs/hololens2.json", "--streams", "imu"],
            "has no IMUs",
        ),
    ];
    for (k, (extra, message)) in cases.iter().enumerate() {
        let dest = tmp.path().join(format!("bad{k}"));
        let mut args = vec![
            "aria",
            "export",
            take.to_str().unwrap(),
            "--out",
            dest.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = Command::new(bin)
            .args(&args)
            .current_dir(root())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(message),
            "{extra:?}: {err}"
        );
        assert!(!dest.exists() && !tmp.path().join(format!("bad{k}.partial")).exists());
    }

    // An export killed part-way leaves OUT.partial: the next one starts it again; a
    // .partial folder holding anything an export does not write is left alone.
    let killed = tmp.path().join("killed");
    std::fs::create_dir_all(tmp.path().join("killed.partial/crowd_01/imu")).unwrap();
    std::fs::write(
        tmp.path().join("killed.partial/crowd_01/imu/imu-left.csv"),
        "half",
    )
    .unwrap();
    let again = run(&[
        "aria",
        "export",
        take.to_str().unwrap(),
        "--out",
        killed.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(again.status.success(), "{err}");
    assert!(
        err.contains("left by an interrupted run; starting it again"),
        "{err}"
    );
    assert!(killed.join("manifest.json").is_file() && !tmp.path().join("killed.partial").exists());
    let foreign = tmp.path().join("foreign");
    std::fs::create_dir_all(tmp.path().join("foreign.partial")).unwrap();
    std::fs::write(tmp.path().join("foreign.partial/notes.txt"), "mine").unwrap();
    let refused = run(&[
        "aria",
        "export",
        take.to_str().unwrap(),
        "--out",
        foreign.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success()
            && err.contains("holds files an export of this take does not write"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(tmp.path().join("foreign.partial/notes.txt")).unwrap(),
        "mine"
    );

    // An export that fails part-way (a head turning half a turn between two frames, found
    // while writing the streams) leaves nothing, and the same command runs again once fixed.
    let cpf = take.join("agents/crowd_01/cpf_trajectory.json");
    let good = std::fs::read_to_string(&cpf).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&good).unwrap();
    let turn = axis_angle_to_matrix(Vec3::new(0.0, 3.1, 0.0));
    for f in doc.as_array_mut().unwrap().iter_mut().skip(20) {
        let m = &mut f["world_from_cpf"];
        let r = Mat3::from_cols_array_2d(
            &[0, 1, 2].map(|c| [0, 1, 2].map(|r| m[r][c].as_f64().unwrap())),
        );
        let turned = turn * r;
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] = turned.col(c)[r].into();
            }
        }
    }
    std::fs::write(&cpf, serde_json::to_string(&doc).unwrap()).unwrap();
    let failed_out = tmp.path().join("failed");
    let failed = run(&[
        "aria",
        "export",
        take.to_str().unwrap(),
        "--out",
        failed_out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&failed.stderr);
    assert!(
        !failed.status.success() && err.contains("sample the motion faster"),
        "{err}"
    );
    assert!(!failed_out.exists() && !tmp.path().join("failed.partial").exists());
    std::fs::write(&cpf, good).unwrap();
    let fixed = run(&[
        "aria",
        "export",
        take.to_str().unwrap(),
        "--out",
        failed_out.to_str().unwrap(),
    ]);
    assert!(
        fixed.status.success(),
        "{}",
        String::from_utf8_lossy(&fixed.stderr)
    );
}

#[test]
fn render_aria_config_errors_name_the_key_and_stage_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let base = r#"
[body]
betas = []
[motion]
source = "scripted_walk"
duration_s = 1.0
frame_rate_hz = 40.0
[output]
dir = "out"
[render]
RIG
[render.aria]
"#;
    let cases = [
        ("", "streams = [\"odometry\"]", "render.aria.streams", "unknown stream `odometry`"),
        ("", "streams = [\"imu\"]\ntrajectory_rate_hz = -5.0", "render.aria", "trajectory_rate_hz = -5"),
        (
            "rig = \"RIGS/hololens2.json\"\ncameras = [\"pv\"]",
            "streams = [\"imu\"]",
            "render.aria",
            "has no IMUs",
        ),
        (
            "",
            "streams = [\"imu\"]\n[render.aria.imu.imu-left]\naccelerometer = { noise_density = -1.0, bias_random_walk = 0.0, turn_on_bias_sigma = 0.0, saturation = 10.0 }\ngyroscope = { noise_density = 0.0, bias_random_walk = 0.0, turn_on_bias_sigma = 0.0, saturation = 10.0 }",
            "render.aria",
            "imu.imu-left.accelerometer.noise_density = -1",
        ),
    ];
    for (k, (rig, aria, key, message)) in cases.iter().enumerate() {
        let config = tmp.path().join(format!("c{k}.toml"));
        let rig = rig.replace("RIGS", &root().join("camera_rigs").display().to_string());
        std::fs::write(&config, format!("{}{aria}\n", base.replace("RIG", &rig))).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_egogen-run"))
            .arg(&config)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "case {k} accepted");
        assert!(
            err.contains(key) && err.contains(message),
            "case {k}: {err}"
        );
        assert!(!tmp.path().join("out").exists() && !tmp.path().join("out.partial").exists());
    }
}
