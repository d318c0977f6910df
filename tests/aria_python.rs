//! projectaria-tools, installed from PyPI into the egogen cache on first use (as Blender is),
//! reads every Aria stream of a take with its own readers: `tests/python/test_aria_streams.py`
//! under pytest, against this build's `egogen`. Without network on a first run it says
//! SKIPPED, unless `EGOGEN_REQUIRE_SYSTEM_TOOLS=1` (CI) makes that a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The PyPI packages the check runs with (the reader version is pinned: it is the oracle).
const PACKAGES: [&str; 3] = ["projectaria-tools==2.3.0", "numpy", "pytest"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A Python with the packages, created at `<venv>.partial` and renamed when complete.
fn provision(venv: &Path) -> Result<PathBuf, String> {
    let python = venv.join("bin/python");
    if python.is_file() {
        return Ok(python);
    }
    let partial = PathBuf::from(format!("{}.partial", venv.display()));
    let _ = std::fs::remove_dir_all(&partial);
    std::fs::create_dir_all(partial.parent().unwrap()).map_err(|e| e.to_string())?;
    let ok = |c: &mut Command| c.status().map(|s| s.success()).unwrap_or(false);
    if !ok(Command::new("python3").args(["-m", "venv"]).arg(&partial)) {
        return Err("python3 -m venv failed".into());
    }
    let mut pip = Command::new(partial.join("bin/python"));
    pip.args(["-m", "pip", "install", "-q", "--disable-pip-version-check"])
        .args(PACKAGES);
    if !ok(&mut pip) {
        return Err(format!("pip install {} failed", PACKAGES.join(" ")));
    }
    std::fs::rename(&partial, venv).map_err(|e| e.to_string())?;
    Ok(python)
}

#[test]
fn projectaria_tools_reads_the_aria_streams() {
    let venv = egogen::render::blender_runtime::cache_dir().join("projectaria-tools-2.3.0");
    let python = match provision(&venv) {
        Ok(p) => p,
        Err(e) if std::env::var_os("EGOGEN_REQUIRE_SYSTEM_TOOLS").is_none() => {
            eprintln!("SKIPPED aria_python: could not install projectaria-tools: {e}");
            return;
        }
        Err(e) => panic!("could not install projectaria-tools: {e}"),
    };
    let out = Command::new(python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(root().join("tests/python"))
        .env("EGOGEN_BIN", env!("CARGO_BIN_EXE_egogen"))
        .current_dir(root())
        .output()
        .expect("running pytest");
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "pytest failed:\n{text}");
    assert!(text.contains(" passed"), "pytest ran nothing:\n{text}");
}
