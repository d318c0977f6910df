//! projectaria-tools, installed from PyPI into the egogen cache on first use (as Blender is),
//! reads every Aria stream of a take with its own readers: `tests/python/test_aria_streams.py`
//! under pytest, against this build's `egogen`. Without network on a first run it says
//! SKIPPED, unless `EGOGEN_REQUIRE_SYSTEM_TOOLS=1` (CI) makes that a failure.

mod common;

use std::path::PathBuf;
use std::process::Command;

/// The PyPI packages the check runs with (the reader version is pinned: it is the oracle).
const PACKAGES: [&str; 3] = ["projectaria-tools==2.3.0", "numpy", "pytest"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn projectaria_tools_reads_the_aria_streams() {
    let python = match common::cached_python("projectaria-tools-2.3.0", &PACKAGES) {
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
