//! The Blender runtime: the managed PyPI `bpy` 4.5 environment (provisioned on first use, as a
//! user's first render would), explicit paths, and clear refusals.

use std::process::Command;

fn egogen() -> Command {
    Command::new(env!("CARGO_BIN_EXE_egogen"))
}

#[test]
fn managed_environment_provides_blender_45() {
    // Uses (and on a fresh machine creates) the default managed environment; EGOGEN_BLENDER is
    // cleared so the managed path is what gets checked.
    let out = egogen()
        .arg("blender")
        .env_remove("EGOGEN_BLENDER")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}\n{}",
        text,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.starts_with("Blender 4.5."), "{text}");
    // The same interpreter, passed explicitly, is accepted too.
    let python = text.trim().rsplit(" at ").next().unwrap();
    let out = egogen()
        .args(["blender", "--blender", python])
        .output()
        .unwrap();
    assert!(out.status.success());
}

#[test]
fn a_python_without_bpy_is_refused_by_name() {
    let out = egogen()
        .args(["blender", "--blender", "/usr/bin/env"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let python = ["python3", "python3.11"].iter().find_map(|p| {
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!("command -v {p}"))
            .output()
            .ok()?;
        o.status
            .success()
            .then(|| String::from_utf8_lossy(&o.stdout).trim().to_string())
    });
    let python = python.expect("a python3 on PATH");
    let out = egogen()
        .args(["blender", "--blender", &python])
        .env("EGOGEN_BLENDER", "")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains(&python) && err.contains("bpy"), "{err}");
}

#[test]
fn missing_and_unsupported_blenders_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere/python");
    let out = egogen()
        .args(["blender", "--blender"])
        .arg(&missing)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("nowhere/python") && err.contains("not found"),
        "{err}"
    );
    // A blender executable that reports 5.0 (its --version output only) is refused with the reason.
    let fake = dir.path().join("blender");
    std::fs::write(&fake, "#!/bin/sh\necho 'Blender 5.0.1'\n").unwrap();
    std::process::Command::new("chmod")
        .arg("+x")
        .arg(&fake)
        .status()
        .unwrap();
    let out = egogen()
        .args(["blender", "--blender"])
        .arg(&fake)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("5.0.1") && err.contains("4.5"),
        "{err}"
    );
}
