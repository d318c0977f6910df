//! The Python tools' outputs (`tools/outputs.py`): the helpers' own unit tests
//! (`tests/tools/test_outputs.py`), run by the system `python3` (standard library only).

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn python(script: &Path, args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    let mut cmd = Command::new("python3");
    cmd.arg(script).current_dir(common::repo_root());
    for a in args {
        cmd.arg(a);
    }
    cmd.output().expect("python3 runs")
}

#[test]
fn the_output_helpers_pass_their_unit_tests() {
    let out = python(
        &common::repo_root().join("tests/tools/test_outputs.py"),
        &[],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("\nOK"), "{err}");
}
