//! The scenarios of the paper's Table 1 (Sec. 5.1, S4.1) as crowd takes on an open floor:
//! a box moving across between a person and the goal; people evenly on a circle, each walking
//! to the opposite point (EgoGen's `main_crowd_eval.py`, 2, 4, 8 and 16 people); a static box
//! at the midpoint of a fixed start–goal line, walked again and again for path diversity.
//! Episode `n` of a scenario under seed `s` is drawn from a generator seeded by
//! `(s, scenario, n)` alone.

use std::sync::Arc;

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::Serialize;

use crate::math::random::uniform_open01;
use crate::scene::{MovingObstacle, Obstacle2, WalkableMap};
use crate::synth::crowd::{AgentPlan, CrowdSettings, CrowdWorld};
use crate::walker::ControllerSpec;

/// A person has reached the goal when the walk ends this close to it (m; paper S4.2's SR).
pub(crate) const SUCCESS_M: f64 = 0.3;

/// A walk ends when the pelvis comes this close to the goal (m): the paper's goal threshold,
/// where its environment ends an episode (EgoGen's `goal_thresh`, the success reward's
/// radius, Eq. 10), so Dist is measured where its walkers stop.
pub(crate) const ARRIVAL_M: f64 = 0.1;

/// Side of the open floor every scenario stands on (m).
pub(crate) const FLOOR_M: f64 = 14.0;

/// Start–goal distance of the one-person scenarios (m).
pub(crate) const WALK_M: f64 = 5.0;

/// A scenario of Table 1.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub(crate) enum Scenario {
    /// One person walks [`WALK_M`]; a box of side U(0.5, 1) m crosses the line between start
    /// and goal at right angles (± 30°), at U(0.5, 1.0) m/s, through a point 35–65 % of the
    /// way, timed to be there when a walker at 0.7 m/s would (± 1 s).
    MovingObstacle,
    /// `people` evenly on a circle of `radius_m` (random phase), each walking to the opposite
    /// point.
    Circle { people: usize, radius_m: f64 },
    /// One person walks [`WALK_M`] along the x axis; a 1 × 1 m box stands at the midpoint.
    /// Every episode is the same scene: only the controller's draws differ.
    StaticBox,
}

impl Scenario {
    /// Table 1's rows, beyond the paper's 2 and 4 people also 8 and 16.
    pub(crate) fn table1() -> Vec<Scenario> {
        vec![
            Scenario::MovingObstacle,
            Scenario::Circle {
                people: 2,
                radius_m: 2.0,
            },
            Scenario::Circle {
                people: 4,
                radius_m: 2.0,
            },
            Scenario::Circle {
                people: 8,
                radius_m: 3.0,
            },
            Scenario::Circle {
                people: 16,
                radius_m: 4.0,
            },
            Scenario::StaticBox,
        ]
    }

    /// A short name for files and tables.
    pub(crate) fn name(&self) -> String {
        match self {
            Scenario::MovingObstacle => "moving_obstacle".into(),
            Scenario::Circle { people, .. } => format!("circle_{people}"),
            Scenario::StaticBox => "static_box".into(),
        }
    }

    /// What a reader sees in a table.
    pub(crate) fn label(&self) -> String {
        match self {
            Scenario::MovingObstacle => "moving obstacle".into(),
            Scenario::Circle { people, radius_m } => {
                format!("{people} people, circle r = {radius_m} m")
            }
            Scenario::StaticBox => "static box (diversity)".into(),
        }
    }

    /// Primitives each person may take: time for the longest walk at 0.5 m/s, plus 2 s.
    pub(crate) fn max_primitives(&self) -> usize {
        let longest = match self {
            Scenario::Circle { radius_m, .. } => 2.0 * radius_m,
            _ => WALK_M,
        };
        ((longest / 0.5 + 2.0) / 0.5).ceil() as usize
    }

    fn index(&self) -> u64 {
        match self {
            Scenario::MovingObstacle => 1,
            Scenario::Circle { people, .. } => 100 + *people as u64,
            Scenario::StaticBox => 2,
        }
    }
}

/// One episode: the world, the people and how they walk.
#[derive(Debug, Clone)]
pub(crate) struct Episode {
    pub world: CrowdWorld,
    pub agents: Vec<AgentPlan>,
    pub settings: CrowdSettings,
}

/// The open floor every scenario stands on, built once.
pub(crate) fn open_floor() -> Arc<WalkableMap> {
    let cell = 0.1;
    let n = (FLOOR_M / cell).round() as usize;
    Arc::new(WalkableMap::from_walkable(
        DVec2::splat(-0.5 * FLOOR_M),
        cell,
        n,
        n,
        vec![true; n * n],
    ))
}

fn unit(rng: &mut ChaCha8Rng) -> f64 {
    uniform_open01(rng)
}

/// Episode `n` of `scenario` under `seed`, every person steered by `steering`.
pub(crate) fn episode(
    scenario: Scenario,
    floor: &Arc<WalkableMap>,
    steering: ControllerSpec,
    seed: u64,
    n: u64,
) -> Episode {
    let episode_seed = seed.rotate_left(24) ^ scenario.index().rotate_left(48) ^ n;
    let mut rng = ChaCha8Rng::seed_from_u64(episode_seed);
    let person = |name: String, start: DVec2, goal: DVec2| AgentPlan {
        name,
        betas: Vec::new(),
        start,
        facing_rad: None,
        goals: vec![goal],
        wander: false,
        steering,
    };
    let mut moving = Vec::new();
    let mut obstacles = Vec::new();
    let agents = match scenario {
        Scenario::MovingObstacle => {
            let yaw = std::f64::consts::TAU * unit(&mut rng);
            let along = DVec2::from_angle(yaw);
            let start = -0.5 * WALK_M * along;
            let goal = 0.5 * WALK_M * along;
            let side = 0.5 + 0.5 * unit(&mut rng);
            let speed = 0.5 + 0.5 * unit(&mut rng);
            let share = 0.35 + 0.3 * unit(&mut rng);
            let cross = start + along * (share * WALK_M);
            let angle = yaw
                + std::f64::consts::FRAC_PI_2
                + (unit(&mut rng) - 0.5) * std::f64::consts::FRAC_PI_3;
            let dir = DVec2::from_angle(angle) * if unit(&mut rng) < 0.5 { 1.0 } else { -1.0 };
            let meet_s = share * WALK_M / 0.7 + 2.0 * unit(&mut rng) - 1.0;
            moving.push(MovingObstacle {
                at_start: Obstacle2::Box {
                    centre: cross - dir * speed * meet_s,
                    half_extents: DVec2::splat(0.5 * side),
                    yaw_rad: angle,
                },
                velocity_m_per_s: dir * speed,
            });
            vec![person("person".into(), start, goal)]
        }
        Scenario::Circle { people, radius_m } => {
            let phase = std::f64::consts::TAU * unit(&mut rng);
            let at = |k: usize| {
                DVec2::from_angle(phase + std::f64::consts::TAU * k as f64 / people as f64)
                    * radius_m
            };
            (0..people)
                .map(|k| person(format!("person_{k}"), at(k), -at(k)))
                .collect()
        }
        Scenario::StaticBox => {
            obstacles.push(Obstacle2::Box {
                centre: DVec2::ZERO,
                half_extents: DVec2::splat(0.5),
                yaw_rad: 0.0,
            });
            vec![person(
                "person".into(),
                DVec2::new(-0.5 * WALK_M, 0.0),
                DVec2::new(0.5 * WALK_M, 0.0),
            )]
        }
    };
    Episode {
        world: CrowdWorld {
            map: floor.clone(),
            region: None,
            obstacles,
            moving,
        },
        agents,
        settings: CrowdSettings {
            walker: crate::walker::WalkerSettings {
                success_m: SUCCESS_M,
                max_primitives_per_goal: scenario.max_primitives(),
                // The policy as trained and evaluated by the paper: no redraws, no guide.
                penetration_redraws: 0,
                ..crate::walker::WalkerSettings::default().unguided()
            },
            arrival_m: Some(ARRIVAL_M),
            primitives: scenario.max_primitives(),
            stop_when_done: true,
            seed: episode_seed,
            ..CrowdSettings::default()
        },
    }
}
