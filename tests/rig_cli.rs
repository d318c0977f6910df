//! `egogen rig check | project | convert` as a user runs them.

use std::path::PathBuf;
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn egogen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("egogen runs")
}

fn ok(args: &[&str]) -> String {
    let out = egogen(args);
    assert!(
        out.status.success(),
        "egogen {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn fails(args: &[&str]) -> String {
    let out = egogen(args);
    assert!(!out.status.success(), "egogen {args:?} should fail");
    String::from_utf8(out.stderr).unwrap()
}

const ARIA_FIXTURE: &str = "tests/fixtures/aria_gen1_device_calibration.json";

#[test]
fn check_prints_every_camera_of_the_aria_rig() {
    let out = ok(&["rig", "check", "camera_rigs/aria_gen1.json"]);
    for needle in [
        "rig `aria_gen1`",
        "3 camera(s)",
        "camera-slam-left",
        "camera-slam-right",
        "camera-rgb",
        "model        fisheye624",
        "resolution   1408 x 1408 px",
        "resolution   640 x 480 px",
        "fov          horizontal",
        "diagonal",
        "position     (57.08, 6.60, 13.15) mm in the CPF",
        "yaw -1.46°, pitch -7.60°, roll 91.32°",
        "axis-angle",
        "CAD",
    ] {
        assert!(out.contains(needle), "`{needle}` missing from:\n{out}");
    }
}

#[test]
fn check_reads_an_aria_calibration_directly() {
    let out = ok(&["rig", "check", ARIA_FIXTURE]);
    assert!(out.contains("resolution   2880 x 2880 px"), "{out}");
    assert!(out.contains("valid radius 1415 px"), "{out}");
    let out = ok(&["rig", "check", ARIA_FIXTURE, "--aria-rgb-1408"]);
    assert!(out.contains("resolution   1408 x 1408 px"), "{out}");
}

#[test]
fn check_prints_the_hololens_and_pinhole_rigs() {
    let out = ok(&["rig", "check", "camera_rigs/hololens2.json"]);
    for needle in [
        "pv",
        "horizontal 64.69°",
        "vlc-lf",
        "vlc-rr",
        "kannala_brandt4",
        "depth-long-throw",
        "320 x 288 px",
        "ESTIMATES",
    ] {
        assert!(out.contains(needle), "`{needle}` missing from:\n{out}");
    }
    let out = ok(&["rig", "check", "camera_rigs/pinhole.json"]);
    assert!(
        out.contains("horizontal 90.00°") && out.contains("(0.00, 0.00, 0.00) mm"),
        "{out}"
    );
}

#[test]
fn project_prints_the_pixel() {
    // The optical axis lands on the principal point.
    let out = ok(&[
        "rig",
        "project",
        ARIA_FIXTURE,
        "--camera",
        "camera-rgb",
        "0",
        "0",
        "1",
    ]);
    assert!(out.contains("pixel (1461.091250, 1447.087208)"), "{out}");
    // Negative coordinates are numbers, not flags.
    let out = ok(&[
        "rig",
        "project",
        "camera_rigs/pinhole.json",
        "--camera",
        "forward",
        "-0.5",
        "0.25",
        "2",
    ]);
    // u = 320·(−0.25) + 319.5, v = 320·0.125 + 239.5.
    assert!(
        out.contains("forward: point (-0.5, 0.25, 2) m -> pixel (239.500000, 279.500000)"),
        "{out}"
    );
}

#[test]
fn project_says_when_a_point_is_outside() {
    let out = ok(&[
        "rig",
        "project",
        "camera_rigs/aria_gen1.json",
        "--camera",
        "camera-slam-left",
        "0",
        "0",
        "-1",
    ]);
    assert!(out.contains("outside the valid field of view"), "{out}");
    assert!(out.contains("180.00° from the optical axis"), "{out}");
}

#[test]
fn unknown_camera_lists_the_names() {
    let err = fails(&[
        "rig",
        "project",
        "camera_rigs/hololens2.json",
        "--camera",
        "rgb",
        "0",
        "0",
        "1",
    ]);
    assert!(err.contains("no camera named `rgb`"), "{err}");
    assert!(
        err.contains("available: pv, vlc-lf, vlc-rf, vlc-ll, vlc-rr, depth-long-throw"),
        "{err}"
    );
}

#[test]
fn broken_rig_is_reported_with_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.json");
    let text = std::fs::read_to_string(root().join("camera_rigs/pinhole.json"))
        .unwrap()
        .replace("\"fy\": 320.0, ", "");
    std::fs::write(&path, text).unwrap();
    let err = fails(&["rig", "check", path.to_str().unwrap()]);
    assert!(err.contains("broken.json"), "{err}");
    assert!(
        err.contains("cameras[0] (forward).model: missing field `fy`"),
        "{err}"
    );
}

#[test]
fn convert_writes_a_rig_that_checks() {
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("aria.json");
    let out = ok(&[
        "rig",
        "convert",
        ARIA_FIXTURE,
        "--aria-rgb-1408",
        "--name",
        "aria_gen1",
        "--out",
        out_path.to_str().unwrap(),
    ]);
    assert!(out.contains("wrote") && out.contains("3 cameras"), "{out}");
    let written = std::fs::read_to_string(&out_path).unwrap();
    let shipped = std::fs::read_to_string(root().join("camera_rigs/aria_gen1.json")).unwrap();
    assert_eq!(written, shipped);
    let err = fails(&[
        "rig",
        "convert",
        ARIA_FIXTURE,
        "--out",
        out_path.to_str().unwrap(),
    ]);
    assert!(err.contains("already exists"), "{err}");
}
