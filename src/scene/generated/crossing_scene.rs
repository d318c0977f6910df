//! Crossing scenes: an empty square floor, a start and a goal, and another person walking
//! across the path — a 2D box (a body's footprint) moving on a straight line that crosses the
//! start–goal segment about when the walker gets there (the paper's crossing scenarios, with
//! the other person as a moving box as EgoGen's crowd training models them).
//!
//! Drawn per episode: start–goal distance U(`distance_m`), centred on the floor, direction
//! U(0, 2π); the crossing point at U(0.35, 0.65) of the way; the other person's heading across
//! the path ±U(`cross_angle_rad`) off the perpendicular, speed U(`speed_m_s`), timed to reach
//! the crossing point when a walker at `walker_speed_m_s` would (± `timing_jitter_s`).

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;
use serde::{Deserialize, Serialize};

use crate::math::random::uniform_open01;
use crate::scene::{MovingObstacle, Obstacle2, WalkableMap};

/// Most other people a crossing scene may have (a config's `people` is checked against it).
pub(crate) const MAX_PEOPLE: usize = 16;

/// Whether `(MIN, MAX)` other people is a count a crossing scene draws from:
/// 1 ≤ MIN ≤ MAX ≤ [`MAX_PEOPLE`].
pub(crate) fn people_in_range((lo, hi): (usize, usize)) -> bool {
    (1..=hi).contains(&lo) && hi <= MAX_PEOPLE
}

/// How crossing scenes are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CrossingSettings {
    /// Share of episodes that are crossings instead of box scenes (0: none).
    pub share: f64,
    /// Side of the square floor (m).
    pub floor_m: f64,
    /// Range of the start–goal distance (m).
    pub distance_m: (f64, f64),
    /// Range of the other person's speed (m/s).
    pub speed_m_s: (f64, f64),
    /// Largest angle of the other person's path off the perpendicular to the walker's (rad).
    pub cross_angle_rad: f64,
    /// The walker's assumed pace when timing the crossing (m/s).
    pub walker_speed_m_s: f64,
    /// Spread of the crossing time (s).
    pub timing_jitter_s: f64,
    /// The other person's footprint: length along its walk and width (m).
    pub footprint_m: (f64, f64),
    /// Range of how many other people cross, each drawn independently (default one).
    pub people: (usize, usize),
}

impl Default for CrossingSettings {
    fn default() -> Self {
        Self {
            share: 0.0,
            floor_m: 8.0,
            distance_m: (2.5, 4.5),
            speed_m_s: (0.6, 1.3),
            cross_angle_rad: std::f64::consts::FRAC_PI_4,
            walker_speed_m_s: 0.7,
            timing_jitter_s: 1.0,
            footprint_m: (0.35, 0.6),
            people: (1, 1),
        }
    }
}

/// What is drawn for a crossing scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct CrossingParams {
    pub start: [f64; 2],
    pub goal: [f64; 2],
    /// The (first) other person's footprint centre at time 0 and its velocity (m/s).
    pub mover_start: [f64; 2],
    pub mover_velocity: [f64; 2],
    /// The people after the first: footprint centre at time 0, velocity (m/s).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub more_movers: Vec<([f64; 2], [f64; 2])>,
}

/// One drawn crossing scene (its floor, the same for every scene, is [`CrossingScene::floor`]).
#[derive(Debug, Clone)]
pub(crate) struct CrossingScene {
    /// The other people, the first of [`CrossingParams::mover_start`] first.
    pub movers: Vec<MovingObstacle>,
    pub start: DVec2,
    pub goal: DVec2,
    pub params: CrossingParams,
}

impl CrossingScene {
    /// Draws a scene with `rng`.
    pub(crate) fn sample(settings: &CrossingSettings, rng: &mut ChaCha8Rng) -> Self {
        let mut u = |a: f64, b: f64| a + (b - a) * uniform_open01(rng);
        let d = u(settings.distance_m.0, settings.distance_m.1);
        let dir = DVec2::from_angle(u(0.0, std::f64::consts::TAU));
        let (start, goal) = (-dir * d / 2.0, dir * d / 2.0);
        let crosser = |rng: &mut ChaCha8Rng| {
            let mut u = |a: f64, b: f64| a + (b - a) * uniform_open01(rng);
            let at = u(0.35, 0.65);
            let cross = start + (goal - start) * at;
            let side = if u(0.0, 1.0) < 0.5 { 1.0 } else { -1.0 };
            let heading = DVec2::from_angle(
                side * std::f64::consts::FRAC_PI_2
                    + u(-settings.cross_angle_rad, settings.cross_angle_rad),
            )
            .rotate(dir);
            let speed = u(settings.speed_m_s.0, settings.speed_m_s.1);
            let t_cross = (at * d / settings.walker_speed_m_s.max(0.1)
                + u(-settings.timing_jitter_s, settings.timing_jitter_s))
            .max(0.0);
            let velocity = heading * speed;
            ((cross - velocity * t_cross).to_array(), velocity.to_array())
        };
        let (mover_start, mover_velocity) = crosser(rng);
        // No draw with one person: scenes of one crossing stay as they were.
        let (lo, hi) = (settings.people.0.max(1), settings.people.1.max(1));
        let people = match hi > lo {
            true => lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize,
            false => lo,
        };
        let more_movers = (1..people).map(|_| crosser(rng)).collect();
        Self::build(
            settings,
            CrossingParams {
                start: start.to_array(),
                goal: goal.to_array(),
                mover_start,
                mover_velocity,
                more_movers,
            },
        )
    }

    /// The empty square floor every crossing scene of `settings` walks on (0.1 m cells, its
    /// edge blocking like a wall).
    pub(crate) fn floor(settings: &CrossingSettings) -> WalkableMap {
        let cell = 0.1;
        let n = (settings.floor_m / cell).round().max(1.0) as usize;
        let origin = DVec2::splat(-(n as f64) * cell / 2.0);
        WalkableMap::from_walkable(origin, cell, n, n, vec![true; n * n])
    }

    /// The scene of drawn parameters.
    pub(crate) fn build(settings: &CrossingSettings, p: CrossingParams) -> Self {
        let mover = |(at_start, velocity): ([f64; 2], [f64; 2])| {
            let velocity = DVec2::from_array(velocity);
            MovingObstacle {
                at_start: Obstacle2::Box {
                    centre: DVec2::from_array(at_start),
                    half_extents: DVec2::new(settings.footprint_m.0, settings.footprint_m.1) / 2.0,
                    yaw_rad: velocity.y.atan2(velocity.x),
                },
                velocity_m_per_s: velocity,
            }
        };
        let movers = std::iter::once((p.mover_start, p.mover_velocity))
            .chain(p.more_movers.iter().copied())
            .map(mover)
            .collect();
        Self {
            movers,
            start: DVec2::from_array(p.start),
            goal: DVec2::from_array(p.goal),
            params: p,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;

    #[test]
    fn the_other_person_crosses_the_path_about_when_the_walker_gets_there() {
        let s = CrossingSettings::default();
        for seed in 0..200 {
            let c = CrossingScene::sample(&s, &mut ChaCha8Rng::seed_from_u64(seed));
            let d = c.start.distance(c.goal);
            assert!((s.distance_m.0..=s.distance_m.1).contains(&d));
            // The mover's line meets the start–goal segment.
            assert_eq!(c.movers.len(), 1);
            let v = c.movers[0].velocity_m_per_s;
            let p0 = DVec2::from_array(c.params.mover_start);
            let seg = c.goal - c.start;
            let t = (c.start - p0).perp_dot(seg) / v.perp_dot(seg);
            let hit = p0 + v * t;
            let along = (hit - c.start).dot(seg) / seg.length_squared();
            assert!((0.34..0.66).contains(&along), "{seed}: {along}");
            // … at about the walker's arrival there.
            let walker_t = along * d / s.walker_speed_m_s;
            assert!((t - walker_t).abs() <= s.timing_jitter_s + 1e-9 || t.abs() < 1e-9);
            // Start and goal are on the floor and free.
            let floor = CrossingScene::floor(&s);
            assert!(floor.is_walkable_at(c.start) && floor.is_walkable_at(c.goal));
        }
    }

    #[test]
    fn more_people_cross_the_same_path_and_the_first_stays_as_alone() {
        let one = CrossingSettings::default();
        let many = CrossingSettings {
            people: (2, 4),
            ..one
        };
        let mut counts = [0usize; 5];
        for seed in 0..200 {
            let a = CrossingScene::sample(&one, &mut ChaCha8Rng::seed_from_u64(seed));
            let c = CrossingScene::sample(&many, &mut ChaCha8Rng::seed_from_u64(seed));
            assert_eq!(c.movers[0], a.movers[0]);
            assert_eq!((c.start, c.goal), (a.start, a.goal));
            counts[c.movers.len()] += 1;
            let seg = c.goal - c.start;
            for m in &c.movers {
                let v = m.velocity_m_per_s;
                let Obstacle2::Box { centre: p0, .. } = m.at_start else {
                    panic!("a box")
                };
                let t = (c.start - p0).perp_dot(seg) / v.perp_dot(seg);
                let along = (p0 + v * t - c.start).dot(seg) / seg.length_squared();
                assert!((0.34..0.66).contains(&along), "{seed}: {along}");
            }
            // The scene rebuilt from its parameters is the same scene.
            let rebuilt = CrossingScene::build(&many, c.params.clone());
            assert_eq!(rebuilt.movers, c.movers);
        }
        assert!(
            counts[2] > 0 && counts[3] > 0 && counts[4] > 0,
            "{counts:?}"
        );
        assert_eq!(counts[0] + counts[1], 0);
    }
}
