//! Tests of the A* planner and the guide on cases whose answers are known (around a wall and a
//! person keeping clearance, a visible goal aimed at directly and a hidden one along the way
//! round, connected paths and clear aims as properties far from the origin), and of the
//! diversity measure (the spread of lateral offsets). They read the planner's internals, so
//! they live in the crate (at the layer of `eval`, which uses `scene`); `tests/eval_suite.rs`
//! runs the `egogen eval` binary.

use glam::DVec2;

use crate::eval::metrics::{lateral_offsets, path_diversity};
use crate::scene::path_plan::{guide_aim, line_is_clear};
use crate::scene::{plan_path, Guide, Obstacle2, WalkableMap};

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
