//! The Python tools' outputs (`tools/outputs.py`): an existing output is refused before any
//! work, naming its flag and path, and left as it was, byte for byte; an output inside the
//! tool's input is refused; `--replace` overwrites; no `<path>.partial` is left behind. Runs
//! the system `python3` (standard library only): the helpers' own unit tests
//! (`tests/tools/test_outputs.py`) and tools whose argument checks need no other package.
//! Their command lines (`tools/arguments.py`): an option that takes one value is refused when
//! given twice, as egogen's own commands refuse it (`tests/tools/test_arguments.py`). The parts
//! proposed for an opt-in furniture library's models (`tests/tools/test_furniture_roles.py`).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn tool(name: &str) -> PathBuf {
    common::repo_root().join("tools").join(name)
}

fn python(script: &Path, args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    let mut cmd = Command::new("python3");
    cmd.arg(script).current_dir(common::repo_root());
    for a in args {
        cmd.arg(a);
    }
    cmd.output().expect("python3 runs")
}

/// The tool failed, its message names `path`, `path` holds `mine` still and no
/// `<path>.partial` is left.
fn refused(out: &Output, path: &Path, mine: &[u8], says: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "succeeded:\n{err}");
    assert!(err.contains(&path.display().to_string()), "{err}");
    assert!(err.contains(says), "{err}");
    assert_eq!(
        std::fs::read(path).unwrap(),
        mine,
        "{} changed",
        path.display()
    );
    let partial = PathBuf::from(format!("{}.partial", path.display()));
    assert!(!partial.exists(), "{} left behind", partial.display());
}

const EXISTS: &str = "exists; choose a new path or pass --replace";

/// `tests/tools/<file>` (unittest) passes.
fn unit_tests_pass(file: &str) {
    let out = python(&common::repo_root().join("tests/tools").join(file), &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("\nOK"), "{err}");
}

#[test]
fn the_output_helpers_pass_their_unit_tests() {
    unit_tests_pass("test_outputs.py");
}

#[test]
fn the_argument_parser_passes_its_unit_tests() {
    unit_tests_pass("test_arguments.py");
}

/// The parts proposed for an opt-in furniture library's models (`tools/furniture_roles.py`)
/// are egogen's `Role`s, given by name, category and size.
#[test]
fn the_furniture_roles_pass_their_unit_tests() {
    unit_tests_pass("test_furniture_roles.py");
}

/// A tool given one of its single-value options twice (either form) exits with status 2
/// naming the option, before any work: neither `--png` is written; the same for a switch
/// of a tool that reads its command line by hand.
#[test]
fn a_repeated_option_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let summary = dir.path().join("summary.jsonl");
    std::fs::write(&summary, b"").unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let png_b = format!("--png={}", b.display());
    let out = python(
        &tool("dwelling_survey.py"),
        &[&summary, &"--png", &a, &png_b],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "argument --png: given twice (--png {}, --png {}); give it once",
            a.display(),
            b.display()
        )),
        "{err}"
    );
    assert!(!a.exists() && !b.exists(), "written:\n{err}");

    let obj = dir.path().join("house.obj");
    let out = python(
        &tool("make_stepped_house.py"),
        &[&obj, &"--replace", &"--replace"],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("argument --replace: given twice (--replace, --replace)"),
        "{err}"
    );
    assert!(!obj.exists(), "written:\n{err}");
}

/// `make_textured_gltf.py DIR` with one of its files already in DIR writes none of them.
#[test]
fn make_textured_gltf_refuses_an_existing_file_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let gltf = dir.path().join("room.gltf");
    std::fs::write(&gltf, b"mine").unwrap();
    let out = python(&tool("make_textured_gltf.py"), &[&dir.path()]);
    refused(&out, &gltf, b"mine", EXISTS);
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["room.gltf"], "written beside it");
    // With --replace the room is written, and no partial is left.
    common::succeeds(
        Command::new("python3")
            .arg(tool("make_textured_gltf.py"))
            .arg(dir.path())
            .arg("--replace"),
    );
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["checker.png", "room.bin", "room.gltf"]);
    assert!(std::fs::read_to_string(&gltf).unwrap().contains("room.bin"));
}

/// The output is checked before the input is read: a summary that does not exist is not
/// what stops `dwelling_survey.py` when its `--png` exists.
#[test]
fn dwelling_survey_refuses_an_existing_png_before_reading_its_summary() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("histograms.png");
    std::fs::write(&png, b"\x89PNG mine").unwrap();
    let summary = dir.path().join("no_such_summary.jsonl");
    let out = python(&tool("dwelling_survey.py"), &[&summary, &"--png", &png]);
    refused(&out, &png, b"\x89PNG mine", EXISTS);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--png"));
}

/// `hand_view_stats.py`: an existing `--json` and a `--json` inside the take are refused
/// before the take is read.
#[test]
fn hand_view_stats_refuses_an_existing_json_and_one_inside_the_take() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("stats.json");
    std::fs::write(&json, b"{\"mine\": 1}").unwrap();
    let take = dir.path().join("take");
    std::fs::create_dir(&take).unwrap();
    let out = python(&tool("hand_view_stats.py"), &[&take, &"--json", &json]);
    refused(&out, &json, b"{\"mine\": 1}", EXISTS);

    let inside = take.join("stats.json");
    std::fs::write(&inside, b"mine").unwrap();
    let out = python(
        &tool("hand_view_stats.py"),
        &[&take, &"--json", &inside, &"--replace"],
    );
    refused(&out, &inside, b"mine", "inside the take");
}

/// `appearance_sheet.py` refuses its existing `--sheet` before rendering any seed (its takes'
/// folder is left unmade).
#[test]
fn appearance_sheet_refuses_an_existing_sheet_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = dir.path().join("sheet.png");
    std::fs::write(&sheet, b"mine").unwrap();
    let takes = dir.path().join("takes");
    let out = python(
        &tool("appearance_sheet.py"),
        &[&"--seeds", &"0", &"--out", &takes, &"--sheet", &sheet],
    );
    refused(&out, &sheet, b"mine", EXISTS);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--sheet"));
    assert!(!takes.exists(), "rendered before refusing");
}

/// A generator of a shipped asset overwrites only with `--replace`, through its partial.
#[test]
fn make_stepped_house_overwrites_only_with_replace() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("house.obj");
    std::fs::write(&obj, b"mine").unwrap();
    let out = python(&tool("make_stepped_house.py"), &[&obj]);
    refused(&out, &obj, b"mine", EXISTS);
    common::succeeds(
        Command::new("python3")
            .arg(tool("make_stepped_house.py"))
            .arg(&obj)
            .arg("--replace"),
    );
    assert_eq!(
        std::fs::read(&obj).unwrap(),
        std::fs::read(common::repo_root().join("assets/scenes/stepped_house.obj")).unwrap()
    );
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1, "a partial left beside it");
}
