//! The body tool's output ends quietly when its reader goes away. (The body's and the
//! rotations' property tests read their internals: `body::properties_tests`.)

#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    // `egogen body info | head -1`: the reader is gone before the output is written.
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["body", "info"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "{err}"
    );
}
