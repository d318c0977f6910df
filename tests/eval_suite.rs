//! The evaluation suite (`egogen eval`) in a tiny form, so that it cannot rot: every
//! controller on three scenarios, two episodes each, its files checked, then Table 3's
//! ablated policies, Table 2's apartment rows and the speed suite (with its ray-count and
//! width rows) beside it. The A* planner, the guide and the diversity measure on cases whose
//! answers are known are tested in the crate (`eval::planner_tests`).

mod common;

use std::process::Command;

/// `egogen eval ARGS --out OUT`.
fn egogen_eval(args: &[&str], out: impl AsRef<std::path::Path>) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_egogen"))
        .arg("eval")
        .args(args)
        .arg("--out")
        .arg(out.as_ref())
        .output()
        .unwrap()
}

/// `egogen eval ARGS --out OUT`, which must succeed; the RESULTS.md it leaves.
fn results_after(args: &[&str], out: &std::path::Path) -> String {
    let run = egogen_eval(args, out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::read_to_string(out.join("RESULTS.md")).unwrap()
}

#[test]
fn a_tiny_table_1_runs_every_controller_and_refuses_to_overwrite() {
    // Table 3 and the speed suite join the same RESULTS.md further down.
    let out = tempfile::tempdir().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "--episodes",
            "2",
            "--scenarios",
            "moving_obstacle,circle_2,static_box",
            "--k",
            "4",
            "--quiet",
        ];
        args.extend_from_slice(extra);
        egogen_eval(&args, out.path())
    };
    let first = run(&[]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let md = std::fs::read_to_string(out.path().join("RESULTS.md")).unwrap();
    for row in [
        "| moving obstacle | policy |",
        "| 2 people, circle r = 2 m | policy_mean |",
        "| static box (diversity) | sampling_k4 |",
        "| static box (diversity) | path_follow_k4 |",
    ] {
        assert!(md.contains(row), "{row} missing from\n{md}");
    }
    let episodes =
        std::fs::read_to_string(out.path().join("results/table1_episodes.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = episodes
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3 * 4 * 2);
    for e in &lines {
        for a in e["agents"].as_array().unwrap() {
            assert!(a["contact"].as_f64().unwrap() > 0.5, "{e}");
            assert!(!a["fell"].as_bool().unwrap(), "{e}");
        }
        // Two people: Pene-H measured; one person: Pene-S measured instead.
        let crowd = e["agents"].as_array().unwrap().len() > 1;
        assert_eq!(e["human_penetration_share"].is_number(), crowd, "{e}");
        assert_eq!(
            e["agents"][0]["obstacle_penetration_share"].is_number(),
            !crowd,
            "{e}"
        );
    }
    let rows: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("results/table1.json")).unwrap())
            .unwrap();
    let static_box = rows["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["scenario"] == "static_box" && r["controller"] == "policy")
        .unwrap();
    assert!(static_box["path_std_m"].is_number(), "{static_box}");
    for png in [
        "table1_static_box_policy.png",
        "table1_circle_2_path_follow_k4.png",
    ] {
        let bytes = std::fs::read(out.path().join("results").join(png)).unwrap();
        assert_eq!(&bytes[1..4], b"PNG", "{png}");
    }
    // Deterministic per seed: the same episodes again, byte for byte, when asked to replace.
    let again = run(&["--force"]);
    assert!(again.status.success());
    let episodes_again =
        std::fs::read_to_string(out.path().join("results/table1_episodes.jsonl")).unwrap();
    let strip = |s: &str| -> Vec<serde_json::Value> {
        s.lines()
            .map(|l| {
                let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                v["wall_s"] = serde_json::Value::Null;
                v
            })
            .collect()
    };
    assert_eq!(strip(&episodes), strip(&episodes_again));
    // Without --force nothing is replaced.
    let before = std::fs::read(out.path().join("RESULTS.md")).unwrap();
    let refused = run(&[]);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        err.contains("table1.json") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(out.path().join("RESULTS.md")).unwrap(),
        before
    );
    // Another policy's rows beside the kept ones (`--keep-other-rows`): the rows that do not
    // read the policy and their episodes stay as they were, the table says which were kept.
    let other = common::repo_root().join("assets/policy/indoors/policy.safetensors");
    let other = other.to_str().unwrap();
    let table = |out: &std::path::Path| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(out.join("results/table1.json")).unwrap()).unwrap()
    };
    let before = table(out.path());
    // A policy row left to be kept under another policy is refused, nothing written.
    let refused = run(&[
        "--keep-other-rows",
        "--controllers",
        "policy",
        "--policy",
        other,
    ]);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        err.contains("policy_mean") && err.contains("--controllers"),
        "{err}"
    );
    // So are rows measured otherwise (here: one episode per row against two).
    let refused = egogen_eval(
        &[
            "--episodes",
            "1",
            "--k",
            "4",
            "--quiet",
            "--keep-other-rows",
            "--controllers",
            "policy,policy_mean",
        ],
        out.path(),
    );
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("\"episodes\" is 2"), "{err}");
    assert_eq!(table(out.path()), before);
    let kept = run(&[
        "--keep-other-rows",
        "--controllers",
        "policy,policy_mean",
        "--policy",
        other,
    ]);
    assert!(
        kept.status.success(),
        "{}",
        String::from_utf8_lossy(&kept.stderr)
    );
    let after = table(out.path());
    let rows = |t: &serde_json::Value| -> Vec<(String, serde_json::Value)> {
        t["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| (format!("{}/{}", r["scenario"], r["controller"]), r.clone()))
            .collect()
    };
    let (rows_before, rows_after) = (rows(&before), rows(&after));
    // Same rows in the same order; those of the policy measured again, the others kept.
    assert_eq!(rows_before.len(), 12);
    assert_eq!(
        rows_before.iter().map(|r| &r.0).collect::<Vec<_>>(),
        rows_after.iter().map(|r| &r.0).collect::<Vec<_>>()
    );
    for ((key, b), (_, a)) in rows_before.iter().zip(&rows_after) {
        if !key.contains("\"policy") {
            assert_eq!(a, b, "{key} kept");
        }
    }
    assert_ne!(rows_before, rows_after, "the other policy's rows differ");
    assert_eq!(after["kept"][0]["rows"].as_array().unwrap().len(), 6);
    assert!(after["policy"]
        .as_str()
        .unwrap()
        .ends_with("indoors/policy.safetensors"));
    let kept_episodes =
        std::fs::read_to_string(out.path().join("results/table1_episodes.jsonl")).unwrap();
    assert_eq!(kept_episodes.lines().count(), 3 * 4 * 2);
    let baselines = |s: &str| -> Vec<String> {
        let mut v: Vec<String> = s
            .lines()
            .filter(|l| !l.contains("\"controller\":\"policy"))
            .map(str::to_string)
            .collect();
        v.sort();
        v
    };
    assert_eq!(baselines(&episodes_again), baselines(&kept_episodes));
    let md = std::fs::read_to_string(out.path().join("RESULTS.md")).unwrap();
    assert!(
        md.contains("The `sampling_k4`, `path_follow_k4` rows of `moving_obstacle`, `circle_2`, `static_box` are kept from an earlier run"),
        "{md}"
    );
    // Table 3 beside it: the ablated policies' rows join RESULTS.md, Table 1 stays.
    let md = results_after(
        &["--suite", "table3", "--episodes", "2", "--quiet"],
        out.path(),
    );
    assert!(
        md.contains("## Table 1") && md.contains("## Table 3"),
        "{md}"
    );
    for row in [
        "| no pretraining | box scenes | sampled |",
        "| no attention reward | crossings | mean |",
        "| full (pretraining + attention reward) | box scenes | mean |",
    ] {
        assert!(md.contains(row), "{row} missing from\n{md}");
    }
    // Table 2 beside them: rays against local maps in the apartment, and sampling.
    let md = results_after(
        &[
            "--suite",
            "table2",
            "--episodes",
            "2",
            "--k",
            "2",
            "--quiet",
        ],
        out.path(),
    );
    assert!(
        md.contains("## Table 2") && md.contains("## Table 3"),
        "{md}"
    );
    for row in [
        "| egocentric sensing (32 rays) | sampled |",
        "| local map 0.8 m | mean |",
        "| local map 7 m | sampled |",
        "| sampling controller (no policy) | best of 2 |",
        "| A* path following (no policy) | best of 2 |",
        "| the shipped policy, guided round walls by an A* path (2 m ahead; not the paper's) | mean |",
    ] {
        assert!(md.contains(row), "{row} missing from\n{md}");
    }
    let t2: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("results/table2.json")).unwrap())
            .unwrap();
    for r in t2["rows"].as_array().unwrap() {
        assert_eq!(r["episodes"], 2, "{r}");
        // Eq. 11 is measured in the apartment, but not on the path follower's crowd takes.
        let crowd_take = r["policy"].as_str().unwrap().starts_with("A*");
        assert_eq!(r["scene_penetration_share"].is_number(), !crowd_take, "{r}");
    }
    // The speed suite beside them: the policy and sampling with K = 4 … 32 in one scenario.
    let md = results_after(
        &[
            "--suite",
            "speed",
            "--episodes",
            "1",
            "--scenarios",
            "moving_obstacle",
            "--quiet",
        ],
        out.path(),
    );
    assert!(md.contains("## Table 1") && md.contains("## Speed and accuracy"));
    for row in [
        "| moving obstacle | policy | ",
        "| moving obstacle | policy_mean | ",
        "| moving obstacle | sampling_k4 | ",
        "| moving obstacle | sampling_k32 | ",
    ] {
        assert!(md.contains(row), "{row} missing from\n{md}");
    }
    // … and the ray-count and width knobs in the same run.
    for row in [
        "| 8 rays | box scenes | sampled |",
        "| 64 rays | crossings | mean |",
        "| H = 64 | box scenes | sampled |",
        "| H = 256 | crossings | mean |",
    ] {
        assert!(md.contains(row), "{row} missing from\n{md}");
    }
    // A scenario that does not exist is named.
    let bad = egogen_eval(
        &["--episodes", "1", "--scenarios", "circle_3"],
        out.path().join("other"),
    );
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("circle_3") && err.contains("circle_4"),
        "{err}"
    );
    // So is a controller that does not exist.
    let bad = egogen_eval(
        &["--episodes", "1", "--controllers", "policy,oracle"],
        out.path().join("other"),
    );
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("oracle") && err.contains("path_follow_k16"),
        "{err}"
    );
}
