//! EgoGen's random single-box training scenes: a square floor, one box standing on it, a
//! start on one side of the box and the goal mirrored through the box centre, so that the box
//! always stands between them.
//!
//! As EgoGen's box scenes (built by DIMOS's `test_box_obstacle`): footprint U(0.5, 1) ×
//! U(0.5, 1) m, yaw U(0, 2π); the start is drawn in the box's bounding square grown by
//! `start_margin_m`, at least `clearance_m` from the box (the loose navmesh's agent radius,
//! 0.4 m), and the goal is `−start` about the box centre. The floor is a walkable map of
//! 0.1 m cells (the box's cells blocked, the floor's edge blocking like a wall) that sensing
//! and the Eq. 7 collision test read.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;

use crate::math::random::uniform_open01;
use crate::scene::{Obstacle2, WalkableMap};

/// How box scenes are drawn.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoxSceneSettings {
    /// Side of the square floor (m), centred on the box.
    pub floor_m: f64,
    /// Cell size of the walkable map (m).
    pub cell_m: f64,
    /// Range of the box's side lengths (m).
    pub box_side_m: (f64, f64),
    /// How far beyond the box's bounding square starts may lie (m).
    pub start_margin_m: f64,
    /// Least distance from the start (and goal) to the box (m).
    pub clearance_m: f64,
}

impl Default for BoxSceneSettings {
    fn default() -> Self {
        Self {
            floor_m: 8.0,
            cell_m: 0.1,
            box_side_m: (0.5, 1.0),
            start_margin_m: 1.0,
            clearance_m: 0.4,
        }
    }
}

/// What is drawn for a box scene (the start relative to the box centre).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct BoxParams {
    pub centre: [f64; 2],
    pub half_extents: [f64; 2],
    pub yaw_rad: f64,
    pub start: [f64; 2],
}

/// One drawn box scene.
#[derive(Debug, Clone)]
pub(crate) struct BoxScene {
    pub map: WalkableMap,
    pub obstacle: Obstacle2,
    pub start: DVec2,
    pub goal: DVec2,
    pub params: BoxParams,
}

/// Distance (m) from `p` to an oriented box footprint (0 inside).
fn distance_to_box(p: DVec2, centre: DVec2, half: DVec2, yaw_rad: f64) -> f64 {
    let local = DVec2::from_angle(-yaw_rad).rotate(p - centre);
    (local.abs() - half).max(DVec2::ZERO).length()
}

impl BoxScene {
    /// Draws a scene with `rng`.
    pub(crate) fn sample(settings: &BoxSceneSettings, rng: &mut ChaCha8Rng) -> Self {
        let mut u = |a: f64, b: f64| a + (b - a) * uniform_open01(rng);
        let (lo, hi) = settings.box_side_m;
        let half = DVec2::new(u(lo, hi), u(lo, hi)) * 0.5;
        let yaw = u(0.0, std::f64::consts::TAU);
        let centre = DVec2::ZERO;
        // Half side of the box's axis-aligned bounding square, grown by the margin.
        let rot = DVec2::from_angle(yaw);
        let bound = DVec2::new(
            (rot.x * half.x).abs() + (rot.y * half.y).abs(),
            (rot.y * half.x).abs() + (rot.x * half.y).abs(),
        ) + settings.start_margin_m;
        let mut start = DVec2::new(bound.x, 0.0);
        for _ in 0..1000 {
            let p = DVec2::new(u(-bound.x, bound.x), u(-bound.y, bound.y));
            if distance_to_box(p, centre, half, yaw) >= settings.clearance_m {
                start = p;
                break;
            }
        }
        Self::build(
            settings,
            BoxParams {
                centre: centre.to_array(),
                half_extents: half.to_array(),
                yaw_rad: yaw,
                start: start.to_array(),
            },
        )
    }

    /// The scene of drawn parameters: the box, the start, the goal mirrored through the box.
    pub(crate) fn build(settings: &BoxSceneSettings, p: BoxParams) -> Self {
        let centre = DVec2::from_array(p.centre);
        let start = DVec2::from_array(p.start);
        let obstacle = Obstacle2::Box {
            centre,
            half_extents: DVec2::from_array(p.half_extents),
            yaw_rad: p.yaw_rad,
        };
        let n = (settings.floor_m / settings.cell_m).round().max(1.0) as usize;
        let origin = centre - DVec2::splat(n as f64 * settings.cell_m / 2.0);
        let walkable = (0..n * n)
            .map(|k| {
                let c =
                    origin + (DVec2::new((k % n) as f64, (k / n) as f64) + 0.5) * settings.cell_m;
                !obstacle.contains(c)
            })
            .collect();
        Self {
            map: WalkableMap::from_walkable(origin, settings.cell_m, n, n, walkable),
            obstacle,
            start: centre + start,
            goal: centre - start,
            params: p,
        }
    }
}
