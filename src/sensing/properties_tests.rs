//! Sensing against analytic references: the grid DDA vs closed squares (including rays along
//! grid lines, through cell corners, starting inside, hitting nothing), dynamic boxes and
//! discs vs parry2d, and the paper's encoding.

use crate::scene::{
    scenario, walkable_map, Obstacle2, ScenarioKind, WalkableMap, WalkableSettings,
};
use crate::sensing::ray::grid::hit_grid;
use crate::sensing::ray::hit_obstacle;
use crate::sensing::ray::oriented_box::slab_hit;
use crate::sensing::{EgoPose2, EgoSensor, LocalMap, Ray2, RayScan, SensingWorld};
use glam::DVec2;
use proptest::prelude::*;

const TOL_M: f64 = 1e-4;
const CELL: f64 = 0.25; // exactly representable: grid lines are exact
const N: usize = 24;

fn random_map(bits: &[bool]) -> WalkableMap {
    WalkableMap::from_walkable(DVec2::new(-3.0, -3.0), CELL, N, N, bits.to_vec())
}

/// Reference: union of closed blocked squares, plus everything outside the grid.
fn reference_hit(map: &WalkableMap, ray: Ray2, max_t: f64) -> Option<f64> {
    let mut best: Option<f64> = None;
    let mut take = |t: Option<f64>| {
        if let Some(t) = t {
            best = Some(best.map_or(t, |b| b.min(t)));
        }
    };
    for j in 0..map.ny {
        for i in 0..map.nx {
            if !map.walkable[j * map.nx + i] {
                let lo = map.origin + DVec2::new(i as f64, j as f64) * map.cell_m;
                take(slab_hit(ray, lo, lo + DVec2::splat(map.cell_m), max_t));
            }
        }
    }
    // Outside the grid: four half-planes as huge boxes.
    let (lo, hi) = (
        map.origin,
        map.origin + DVec2::new(map.nx as f64, map.ny as f64) * map.cell_m,
    );
    let big = 1e6;
    take(slab_hit(
        ray,
        DVec2::new(-big, -big),
        DVec2::new(lo.x, big),
        max_t,
    ));
    take(slab_hit(
        ray,
        DVec2::new(hi.x, -big),
        DVec2::new(big, big),
        max_t,
    ));
    take(slab_hit(
        ray,
        DVec2::new(-big, -big),
        DVec2::new(big, lo.y),
        max_t,
    ));
    take(slab_hit(
        ray,
        DVec2::new(-big, hi.y),
        DVec2::new(big, big),
        max_t,
    ));
    best
}

fn agree(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => (x - y).abs() <= TOL_M,
        _ => false,
    }
}

fn bits() -> impl Strategy<Value = Vec<bool>> {
    prop::collection::vec(prop::bool::weighted(0.12), N * N)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn dda_matches_squares_random_rays(bits in bits(), ox in -3.5f64..3.5, oy in -3.5f64..3.5, angle in 0.0f64..std::f64::consts::TAU, max_t in 0.1f64..9.0) {
        let map = random_map(&bits);
        let ray = Ray2 { origin: DVec2::new(ox, oy), dir: DVec2::from_angle(angle) };
        let (got, want) = (hit_grid(&map, ray, max_t), reference_hit(&map, ray, max_t));
        prop_assert!(agree(got, want), "got {got:?} want {want:?}");
    }

    /// Origins on grid lines and grid vertices; axis-aligned and exactly diagonal directions.
    #[test]
    fn dda_matches_squares_on_grid_lines_and_corners(bits in bits(), gi in 0i32..=24, gj in 0i32..=24, frac in prop::sample::select(vec![0.0, 0.5, 0.25]), on_vertex in prop::bool::ANY, dir_k in 0usize..8, max_t in 0.1f64..9.0) {
        let map = random_map(&bits);
        let x = -3.0 + gi as f64 * CELL + if on_vertex { 0.0 } else { frac * CELL };
        let y = -3.0 + gj as f64 * CELL;
        let dirs = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];
        let d = DVec2::new(dirs[dir_k].0, dirs[dir_k].1).normalize();
        let ray = Ray2 { origin: DVec2::new(x, y), dir: d };
        let (got, want) = (hit_grid(&map, ray, max_t), reference_hit(&map, ray, max_t));
        prop_assert!(agree(got, want), "origin ({x}, {y}) dir {d:?}: got {got:?} want {want:?}");
    }

    #[test]
    fn dynamic_obstacles_match_parry(cx in -5.0f64..5.0, cy in -5.0f64..5.0, hx in 0.05f64..2.0, hy in 0.05f64..2.0, yaw in -4.0f64..4.0, r in 0.05f64..2.0,
                                     ox in -6.0f64..6.0, oy in -6.0f64..6.0, angle in 0.0f64..std::f64::consts::TAU) {
        use parry2d_f64::math::{Pose, Vector};
        use parry2d_f64::query::{Ray as PRay, RayCast};
        use parry2d_f64::shape::{Ball, Cuboid};
        let ray = Ray2 { origin: DVec2::new(ox, oy), dir: DVec2::from_angle(angle) };
        let pray = PRay::new(Vector::new(ox, oy), Vector::new(ray.dir.x, ray.dir.y));
        let max_t = 7.0;
        let bx = Obstacle2::Box { centre: DVec2::new(cx, cy), half_extents: DVec2::new(hx, hy), yaw_rad: yaw };
        let want_box = Cuboid::new(Vector::new(hx, hy)).cast_ray(&Pose::new(Vector::new(cx, cy), yaw), &pray, max_t, true);
        prop_assert!(agree(hit_obstacle(&bx, ray, max_t), want_box), "box: {:?} vs {:?}", hit_obstacle(&bx, ray, max_t), want_box);
        let circle = Obstacle2::Circle { centre: DVec2::new(cx, cy), radius_m: r };
        let want_ball = Ball::new(r).cast_ray(&Pose::new(Vector::new(cx, cy), 0.0), &pray, max_t, true);
        prop_assert!(agree(hit_obstacle(&circle, ray, max_t), want_ball), "circle: {:?} vs {:?}", hit_obstacle(&circle, ray, max_t), want_ball);
    }

    /// The 2D SDF equals the brute-force distance between cell centres of opposite classes,
    /// minus half a cell.
    #[test]
    fn sdf_matches_brute_force(bits in prop::collection::vec(prop::bool::weighted(0.8), 12 * 9)) {
        prop_assume!(bits.iter().any(|&b| b) && bits.iter().any(|&b| !b));
        let map = WalkableMap::from_walkable(DVec2::ZERO, 0.1, 12, 9, bits.clone());
        for k in 0..bits.len() {
            let c = map.centre(k % 12, k / 12);
            let d = (0..bits.len()).filter(|&o| bits[o] != bits[k]).map(|o| map.centre(o % 12, o / 12).distance(c)).fold(f64::INFINITY, f64::min);
            let want = if bits[k] { d - 0.05 } else { -(d - 0.05) };
            prop_assert!((map.sdf_m[k] - want).abs() < 1e-12);
        }
    }
}

/// Against true geometry: SDF of a mesh scene vs the exact distance to a rotated box footprint.
#[test]
fn sdf_vs_geometry_within_half_a_cell() {
    let sc = scenario(ScenarioKind::SingleBox); // 1 m box at the origin, floor 16 m
    let map = walkable_map(
        &sc.mesh,
        std::path::Path::new("single_box"),
        WalkableSettings::default(),
    )
    .unwrap();
    let mut worst: f64 = 0.0;
    for j in 0..map.ny {
        for i in 0..map.nx {
            let c = map.centre(i, j);
            if c.x.abs() > 3.0 || c.y.abs() > 3.0 {
                continue;
            }
            let q = (c.abs() - DVec2::splat(0.5)).max(DVec2::ZERO);
            let outside = q.length();
            let inside = (c.abs() - DVec2::splat(0.5)).max_element().min(0.0);
            let truth = outside + inside; // > 0 outside the box (walkable side)
            worst = worst.max((map.sdf_m[j * map.nx + i] - truth).abs());
        }
    }
    eprintln!("2D SDF vs exact box distance: max error {worst:.4} m (cell 0.1 m)");
    assert!(worst <= 0.5 * map.cell_m + 1e-9, "max error {worst}");
}

#[test]
fn ray_scan_encoding_and_beam_order() {
    let sc = scenario(ScenarioKind::SingleBox);
    let map = walkable_map(
        &sc.mesh,
        std::path::Path::new("single_box"),
        WalkableSettings::default(),
    )
    .unwrap();
    let world = SensingWorld {
        map: &map,
        obstacles: &[],
    };
    let scan = RayScan::default();
    assert_eq!(scan.dim(), 32);
    // Standing 3 m west of the box facing east: the middle beams hit its west face at ~2.5 m.
    let pose = EgoPose2 {
        position: DVec2::new(-3.0, 0.0),
        heading_rad: 0.0,
    };
    let obs = scan.observe(&world, pose);
    let d = scan.distances(&world, pose);
    for k in [15, 16] {
        let expect = 2.5 / (scan.beam_dir(pose, k).x);
        assert!(
            (d[k] - expect).abs() < 0.11,
            "beam {k}: {} vs {expect}",
            d[k]
        );
        assert!(((obs[k] as f64) - (-1.0 + 2.0 * d[k] / 7.0)).abs() < 1e-6);
    }
    // Beam 0 points right (−y), beam 31 left (+y); both see open floor for 7 m.
    assert!((scan.beam_dir(pose, 0) - DVec2::new(0.0, -1.0)).length() < 1e-12);
    assert!((scan.beam_dir(pose, 31) - DVec2::new(0.0, 1.0)).length() < 1e-12);
    assert_eq!(obs[0], 1.0);
    assert_eq!(obs[31], 1.0);
    // Inside the box: every beam reads −1.
    let inside = scan.observe(
        &world,
        EgoPose2 {
            position: DVec2::ZERO,
            heading_rad: 1.0,
        },
    );
    assert!(inside.iter().all(|&v| v == -1.0));
    // Batch = one by one.
    let poses = [
        pose,
        EgoPose2 {
            position: DVec2::new(2.0, 1.0),
            heading_rad: 2.5,
        },
    ];
    let batch = scan.observe_batch(&world, &poses);
    assert_eq!(&batch[..32], scan.observe(&world, poses[0]).as_slice());
    assert_eq!(&batch[32..], scan.observe(&world, poses[1]).as_slice());
}

#[test]
fn dynamic_obstacles_are_seen_and_local_map_marks_them() {
    let sc = scenario(ScenarioKind::MovingBox);
    let map = walkable_map(
        &sc.mesh,
        std::path::Path::new("moving_box"),
        WalkableSettings::default(),
    )
    .unwrap();
    let at_5s: Vec<Obstacle2> = sc.moving.iter().map(|m| m.at(5.0)).collect(); // box centre (0, 0)
    let world = SensingWorld {
        map: &map,
        obstacles: &at_5s,
    };
    let pose = EgoPose2 {
        position: DVec2::new(-2.0, 0.0),
        heading_rad: 0.0,
    };
    let d = RayScan::default().distances(&world, pose);
    assert!((d[16] - 1.5 / RayScan::default().beam_dir(pose, 16).x).abs() < 1e-9);
    let empty = SensingWorld {
        map: &map,
        obstacles: &[],
    };
    assert_eq!(RayScan::default().distances(&empty, pose)[16], 7.0);
    let lm = LocalMap::default();
    let patch = lm.observe(&world, pose);
    assert_eq!(patch.len(), 256);
    // Cell ahead at 2 m (row (1 + 2)/0.25 = 12), centre column: inside the box.
    assert_eq!(patch[12 * 16 + 8], 1.0);
    assert_eq!(patch[4 * 16 + 8], 0.0);
}

#[test]
fn a_centred_local_map_surrounds_the_body_and_turns_with_it() {
    use crate::sensing::SensingSpec;
    // Free floor with everything at x ≥ 0.5 m blocked.
    let bits: Vec<bool> = (0..N * N)
        .map(|i| -3.0 + ((i % N) as f64 + 0.5) * CELL < 0.5)
        .collect();
    let map = random_map(&bits);
    let world = SensingWorld {
        map: &map,
        obstacles: &[],
    };
    let sensor = SensingSpec::centred_map(0.8, 16).sensor();
    assert_eq!(sensor.dim(), 256);
    let blocked_rows = |heading_rad: f64| -> Vec<usize> {
        let patch = sensor.observe(
            &world,
            EgoPose2 {
                position: DVec2::ZERO,
                heading_rad,
            },
        );
        (0..16)
            .filter(|r| patch[r * 16..(r + 1) * 16].iter().all(|&v| v == 1.0))
            .collect()
    };
    // Rows are 0.1 m deep from 0.8 m behind: centres ≥ 0.5 m ahead are rows 13–15.
    assert_eq!(blocked_rows(0.0), vec![13, 14, 15]);
    // Facing away, the wall is behind.
    assert_eq!(blocked_rows(std::f64::consts::PI), vec![0, 1, 2]);
}

#[test]
fn sensing_specs_read_from_toml_with_defaults_and_refuse_unknown_fields() {
    use crate::sensing::{RayScanSettings, SensingSpec};
    let read = |text: &str| toml::from_str::<SensingSpec>(text);
    assert_eq!(read("kind = \"rays\"").unwrap(), SensingSpec::default());
    assert_eq!(
        read("kind = \"rays\"\nnum_rays = 8").unwrap(),
        SensingSpec::Rays(RayScanSettings {
            num_rays: 8,
            ..Default::default()
        })
    );
    assert_eq!(
        read("kind = \"local_map\"\nrows = 16\ncols = 16\ncell_m = 0.1\nbehind_m = 0.8").unwrap(),
        SensingSpec::centred_map(0.8, 16)
    );
    for bad in [
        "kind = \"rays\"\nrays = 8",
        "kind = \"sonar\"",
        "num_rays = 8",
    ] {
        assert!(read(bad).is_err(), "{bad}");
    }
    assert!(SensingSpec::default().problem().is_none());
    assert!(SensingSpec::centred_map(7.0, 32).problem().is_none());
    let zero_rays = SensingSpec::Rays(RayScanSettings {
        num_rays: 0,
        ..Default::default()
    });
    assert!(zero_rays.problem().unwrap().contains("num_rays"));
    assert!(SensingSpec::centred_map(f64::NAN, 4)
        .problem()
        .unwrap()
        .contains("cell_m"));
}
