//! `egogen policy rooms` and `egogen policy eval --paths-png` draw their pictures and keep an
//! existing one (the environment's own tests are `policy::env::tests`, in the crate).

mod common;

#[test]
fn floor_plans_and_evaluated_walks_are_drawn_and_existing_pictures_kept() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_egogen");
    let root = common::repo_root();
    let dir = tempfile::tempdir().unwrap();
    let plans = dir.path().join("plans.png");
    common::succeeds(
        Command::new(bin)
            .args(["policy", "rooms", "--count", "4", "--out"])
            .arg(&plans),
    );
    // Three tiles of 320 px to a row, two rows.
    assert_eq!(common::png_size(&plans), (960, 640));
    let walks = dir.path().join("walks.png");
    let eval = |png: &std::path::Path| {
        let mut cmd = Command::new(bin);
        cmd.current_dir(&root)
            .args([
                "policy",
                "eval",
                "--rooms-share",
                "1",
                "--episodes",
                "3",
                "--envs",
                "3",
            ])
            .args([
                "--paths",
                "2",
                "--policy",
                "assets/policy/policy.safetensors",
                "--paths-png",
            ])
            .arg(png);
        cmd
    };
    let out = common::succeeds(&mut eval(&walks));
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(report.contains("\"report\""), "{report}");
    assert_eq!(common::png_size(&walks), (640, 320));
    // An existing picture is not overwritten; two controllers cannot share one picture.
    let before = std::fs::read(&walks).unwrap();
    assert!(!eval(&walks).output().unwrap().status.success());
    assert_eq!(std::fs::read(&walks).unwrap(), before);
    let both = eval(&dir.path().join("other.png"))
        .args(["--k", "1"])
        .output()
        .unwrap();
    assert!(!both.status.success());
    assert!(String::from_utf8_lossy(&both.stderr).contains("--paths-png"));
}
