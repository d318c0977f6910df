//! The evaluation suite (`egogen eval`) in a tiny form, so that it cannot rot: every
//! controller on three scenarios, two episodes each, its files checked, then Table 3's
//! ablated policies, Table 2's apartment rows and the speed suite (with its ray-count and
//! width rows) beside it; the A* planner and the diversity measure on cases whose answers are
//! known.

mod common;

use std::process::Command;

use egogen::eval::metrics::{lateral_offsets, path_diversity};
use egogen::scene::{guide_aim, line_is_clear, plan_path, Guide, Obstacle2, WalkableMap};
use glam::DVec2;

/// A guide aiming `lookahead_m` along the shortest path (no centring, the unknown not disliked).
fn guide(lookahead_m: f64) -> Guide {
    Guide {
        lookahead_m,
        centre_weight: 0.0,
        unknown_cost: 0.0,
    }
}

/// A 6 × 6 m room, a wall across x = 0 from y = −3 to y = 1.5: the way round is above it.
fn walled_room() -> WalkableMap {
    let n = 60;
    let walkable = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            !((29..=30).contains(&i) && j < 45)
        })
        .collect();
    WalkableMap::from_walkable(DVec2::splat(-3.0), 0.1, n, n, walkable)
}

#[test]
fn the_planner_goes_around_a_wall_and_a_person_keeping_its_clearance() {
    let map = walled_room();
    let from = DVec2::new(-2.0, -2.0);
    let to = DVec2::new(2.0, -2.0);
    let path = plan_path(&map, &[], 0.3, from, to);
    assert!(path.found);
    assert_eq!(path.points.first(), Some(&from));
    assert_eq!(path.points.last(), Some(&to));
    let highest = path.points.iter().map(|p| p.y).fold(f64::MIN, f64::max);
    assert!(
        highest > 1.5 + 0.3 - 0.1,
        "the path stays below the wall's end: {highest}"
    );
    for p in &path.points[1..path.points.len() - 1] {
        assert!(
            map.sdf_at(*p) >= 0.3 - 1e-9,
            "{p} is within the clearance of the wall"
        );
    }
    // Round the wall's end: at least the two straight legs via the corner it clears
    // (2 × 4.16 m), at most 30 % longer (grid steps).
    let legs = 2.0 * DVec2::new(1.7, 3.8).length();
    assert!(
        path.length_m() > legs && path.length_m() < 1.3 * legs,
        "{} m against legs of {legs} m",
        path.length_m()
    );
    // A person standing on the way: the path keeps 0.3 m from their box.
    let person = Obstacle2::Box {
        centre: DVec2::new(-2.0, 0.0),
        half_extents: DVec2::new(0.3, 0.2),
        yaw_rad: 0.0,
    };
    let around = plan_path(&map, &[person], 0.3, from, DVec2::new(-2.0, 2.0));
    assert!(around.found);
    for p in &around.points[1..around.points.len() - 1] {
        assert!(
            !person.grown(0.3).contains(*p),
            "{p} is inside the person's clearance"
        );
    }
    // A goal inside a wall: no path, the straight line instead.
    let walled = plan_path(&map, &[], 0.3, from, DVec2::new(0.0, -2.0));
    assert!(!walled.found);
    assert_eq!(walled.points, vec![from, DVec2::new(0.0, -2.0)]);
    // Points along the path: the start, the goal beyond the end.
    assert_eq!(path.point_along(0.0), from);
    assert_eq!(path.point_along(1e6), to);
}

#[test]
fn the_guide_shows_a_visible_goal_itself_and_a_hidden_one_along_the_way_round() {
    let map = walled_room();
    let from = DVec2::new(-2.0, -2.0);
    // Same side of the wall: the straight way is clear, the aim is the goal.
    let near = DVec2::new(-2.0, 1.0);
    assert!(line_is_clear(&map, &[], 0.3, from, near));
    assert_eq!(guide_aim(&map, &[], from, near, &guide(2.0), None), near);
    // No lookahead, no guide: the goal, hidden or not.
    assert_eq!(
        guide_aim(&map, &[], from, DVec2::new(2.0, -2.0), &guide(0.0), None),
        DVec2::new(2.0, -2.0)
    );
    // Behind the wall: 2 m along the way round, which first heads up, away from the goal.
    let hidden = DVec2::new(2.0, -2.0);
    assert!(!line_is_clear(&map, &[], 0.3, from, hidden));
    let aim = guide_aim(&map, &[], from, hidden, &guide(2.0), None);
    let path = plan_path(&map, &[], 0.3, from, hidden);
    assert_eq!(aim, path.point_along(2.0));
    assert!(
        aim.distance(from) <= 2.0 + 1e-9 && aim.distance(from) > 1.5,
        "{aim}"
    );
    assert!(
        aim.y > from.y + 1.0,
        "{aim} does not head round the wall's end"
    );
    // A person standing on the straight way hides the goal too.
    let person = Obstacle2::Box {
        centre: DVec2::new(-2.0, -0.5),
        half_extents: DVec2::new(0.3, 0.2),
        yaw_rad: 0.0,
    };
    assert!(!line_is_clear(&map, &[person], 0.3, from, near));
    assert_ne!(
        guide_aim(&map, &[person], from, near, &guide(2.0), None),
        near
    );
    // A goal inside the wall: no way round, the goal itself.
    let walled = DVec2::new(0.0, -2.0);
    assert_eq!(
        guide_aim(&map, &[], from, walled, &guide(2.0), None),
        walled
    );
}

/// An open 6 × 6 m floor of 0.1 m cells with its corner at `origin`, a square box of half side
/// `half` turned by `yaw` centred at `origin + centre`, and a start and goal at `origin +
/// start`, `origin + goal`.
fn far_floor_with_box(
    origin: DVec2,
    start: (f64, f64),
    goal: (f64, f64),
    centre: (f64, f64),
    half: f64,
    yaw: f64,
) -> (WalkableMap, Obstacle2, DVec2, DVec2) {
    let n = 60;
    let map = WalkableMap::from_walkable(origin, 0.1, n, n, vec![true; n * n]);
    let b = Obstacle2::Box {
        centre: origin + DVec2::from(centre),
        half_extents: DVec2::splat(half),
        yaw_rad: yaw,
    };
    (
        map,
        b,
        origin + DVec2::from(start),
        origin + DVec2::from(goal),
    )
}

/// Whether `to`'s cell is reached from `from`'s by steps between edge-sharing cells whose
/// centres are outside `grown` and at least `clearance_m` from the floor's edge (the start's
/// own cell always counts): the way the planner may go, as it never cuts a corner.
fn reachable(
    map: &WalkableMap,
    grown: &Obstacle2,
    clearance_m: f64,
    from: DVec2,
    to: DVec2,
) -> bool {
    let (start, goal) = (map.cell_of(from).unwrap(), map.cell_of(to).unwrap());
    let free = |(i, j): (usize, usize)| {
        (i, j) == start
            || (map.sdf_m[j * map.nx + i] >= clearance_m && !grown.contains(map.centre(i, j)))
    };
    if !free(goal) {
        return false;
    }
    let mut seen = vec![false; map.nx * map.ny];
    let mut todo = vec![start];
    seen[start.1 * map.nx + start.0] = true;
    while let Some((i, j)) = todo.pop() {
        if (i, j) == goal {
            return true;
        }
        let next = [
            (i.wrapping_sub(1), j),
            (i + 1, j),
            (i, j.wrapping_sub(1)),
            (i, j + 1),
        ];
        for (ni, nj) in next {
            if ni < map.nx && nj < map.ny && !seen[nj * map.nx + ni] && free((ni, nj)) {
                seen[nj * map.nx + ni] = true;
                todo.push((ni, nj));
            }
        }
    }
    false
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// On a floor far from the origin with a random box in it: a path found is connected
    /// (steps of at most a cell's diagonal between cell centres), keeps its clearance from the
    /// box, and is no shorter than the straight line.
    #[test]
    fn planned_paths_are_connected_and_keep_clear(
        sx in 0.3f64..5.7, sy in 0.3f64..5.7, gx in 0.3f64..5.7, gy in 0.3f64..5.7,
        bx in 1.0f64..5.0, by in 1.0f64..5.0, half in 0.1f64..1.0, yaw in 0.0f64..6.3,
    ) {
        let (map, b, from, to) =
            far_floor_with_box(DVec2::new(1.0e5, -2.0e5), (sx, sy), (gx, gy), (bx, by), half, yaw);
        let path = plan_path(&map, &[b], 0.2, from, to);
        proptest::prop_assert_eq!(path.points.first(), Some(&from));
        proptest::prop_assert_eq!(path.points.last(), Some(&to));
        proptest::prop_assert!(path.length_m() >= from.distance(to) - 1e-9);
        if path.found {
            let inner = &path.points[1..path.points.len() - 1];
            for w in inner.windows(2) {
                proptest::prop_assert!(w[0].distance(w[1]) <= 0.1 * 2f64.sqrt() + 1e-6);
            }
            for (k, p) in inner.iter().enumerate() {
                // The start's own cell may be inside the clearance; every other is not.
                if k > 0 {
                    proptest::prop_assert!(!b.grown(0.2).contains(*p), "{} in the box", p);
                }
            }
        } else {
            // No way only when the goal's cell cannot be reached from the start's over cells
            // clear of the box and the floor's edge (the box's clearance may wall off a
            // corner of the floor).
            proptest::prop_assert!(
                !reachable(&map, &b.grown(0.2), 0.2, from, to),
                "no path from {} to {}",
                from,
                to
            );
            proptest::prop_assert_eq!(path.points.len(), 2);
        }
    }

    /// The guide far from the origin: its aim is the goal when the straight way is clear,
    /// else a point of the planned path no farther than the lookahead (straight-line) from
    /// the walker, outside the box's clearance once past the start's cell.
    #[test]
    fn the_guide_aims_at_the_goal_or_along_a_clear_path_near_the_walker(
        sx in 0.3f64..5.7, sy in 0.3f64..5.7, gx in 0.3f64..5.7, gy in 0.3f64..5.7,
        bx in 1.0f64..5.0, by in 1.0f64..5.0, half in 0.1f64..1.0, yaw in 0.0f64..6.3,
        lookahead in 0.1f64..4.0,
    ) {
        let (map, b, from, to) =
            far_floor_with_box(DVec2::new(-3.0e5, 7.0e4), (sx, sy), (gx, gy), (bx, by), half, yaw);
        let aim = guide_aim(&map, &[b], from, to, &guide(lookahead), None);
        proptest::prop_assert!(aim.is_finite());
        // Ground disliked nowhere changes nothing.
        let nowhere = vec![0f32; map.nx * map.ny];
        proptest::prop_assert_eq!(guide_aim(&map, &[b], from, to, &guide(lookahead), Some(&nowhere)), aim);
        if line_is_clear(&map, &[b], 0.3, from, to) {
            proptest::prop_assert_eq!(aim, to);
        } else {
            let path = plan_path(&map, &[b], 0.3, from, to);
            if path.found {
                proptest::prop_assert_eq!(aim, path.point_along(lookahead));
                proptest::prop_assert!(aim.distance(from) <= lookahead + 1e-6);
                if aim.distance(from) > 0.15 {
                    proptest::prop_assert!(!b.grown(0.3 - 0.08).contains(aim), "{} in the box", aim);
                }
            } else {
                proptest::prop_assert_eq!(aim, to);
            }
        }
    }
}

#[test]
fn path_diversity_is_the_spread_of_lateral_offsets() {
    let (start, goal) = (DVec2::new(-2.5, 0.0), DVec2::new(2.5, 0.0));
    // Straight walks at constant offsets −0.2, 0 and +0.4 m: std 0.306 m at every station.
    let walk = |y: f64| -> Vec<[f64; 2]> { (0..=50).map(|k| [-2.5 + 0.1 * k as f64, y]).collect() };
    let paths = [walk(-0.2), walk(0.0), walk(0.4)];
    let offsets = lateral_offsets(&paths[2], start, goal, 9);
    assert!(offsets.iter().all(|o| (o.unwrap() - 0.4).abs() < 1e-12));
    let refs: Vec<&[[f64; 2]]> = paths.iter().map(|p| p.as_slice()).collect();
    let (std, left) = path_diversity(&refs, start, goal).unwrap();
    let mean = (-0.2 + 0.0 + 0.4) / 3.0;
    let var = ((-0.2f64 - mean).powi(2) + (0.0f64 - mean).powi(2) + (0.4f64 - mean).powi(2)) / 2.0;
    assert!((std - var.sqrt()).abs() < 1e-12, "{std} vs {}", var.sqrt());
    assert!((left - 1.0 / 3.0).abs() < 1e-12);
    // A walk that stops halfway has no offsets beyond.
    let half: Vec<[f64; 2]> = (0..=25).map(|k| [-2.5 + 0.1 * k as f64, 0.1]).collect();
    let o = lateral_offsets(&half, start, goal, 9);
    assert!(o[0].is_some() && o[8].is_none());
}

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
