//! Crowds (paper Alg. 1): several bodies, each driven by its own controller, walking to their goals
//! through one world. Agents take one primitive each in turn; before choosing, an agent senses the
//! others' 2D boxes and the moving obstacles at its clock, with the same rays, observation and
//! reward as the training environment ([`crate::walker`]). The others are seen where they
//! will stand when its primitive ends (someone who stepped earlier in the round where that
//! primitive ends, someone yet to step moved on at the velocity of their last primitive) and the
//! primitive is judged against them moving; EgoGen's loop, every box where it was last put, is
//! [`WalkerSettings::anticipate_people`] off. No multi-agent learning: every agent runs the
//! single-agent controller, and every agent chooses its primitive by the same step as the
//! training environment and `egogen policy eval` (`walker::step`: one judge, the
//! best of its controller's proposals, redraws, the hold). One guard beyond the paper: a policy primitive that ends with the
//! body's box on blocked cells (Eq. 7: a wall, an obstacle, another person), that puts a body
//! marker inside another person's box or an obstacle in any of its frames, or that ends with the
//! pelvis off the walkable floor, is redrawn: up to `penetration_redraws` times from the same
//! policy output, then as many times from the motion model's prior. The scene is tested at
//! every frame a primitive spans ([`WalkerSettings::scene_every_frame`]), and a primitive whose
//! pelvis would pass over a wall is never taken: after the redraws, a batch from the prior,
//! then the body holds its pose for the primitive.
//!
//! An agent walks its goals in order; with `wander` it draws a new goal on the walkable map
//! when its list runs out, until the take ends. A goal counts as reached when the pelvis comes
//! within `success_m`; after `max_primitives_per_goal` primitives without reaching it, it is
//! reported missed and the agent moves on. An agent that falls (head below half its standing
//! height) or whose decoder output is not finite stops there and is reported, as is one that
//! runs out of goals: it stands still (its last pose held) for the rest of the take, still an
//! obstacle to the others.
//!
//! Where the take asks for activities ([`run_crowd_with_activities`], `[activities]`), what
//! comes after each walk is drawn ([`crate::synth::activity`]): walk on, stand and look
//! around, pick something up (played where the walk ended; a first pick-up walks to one of
//! the scene's small things on the floor first, where one is near), or sit (walk to the free
//! seat nearest on foot first, and to the next one where that one is not reached); an activity's frames are taken [`NEW_FRAMES`] a round, the
//! others seeing the person where it is, and the walker takes over from its last two frames;
//! a walk comes between two activities. An activity that would enter the scene is skipped with its reason.
//!
//! When the take ends, each agent's motion is finished as written: the velocity jump where
//! one primitive (or activity, or held pose) hands over to the next is spread over ±0.2 s
//! (up to ±0.4 s for the largest changes; [`crate::motion::joins`]; not where that would take
//! the pelvis over a wall the walk kept off) and the neck and head turn against the torso's sway
//! ([`crate::motion::head_stabilise`]), `[walker] smooth_joins` and `steady_head`; the
//! walk itself (what was chosen, where it went) is as stepped.
//!
//! Deterministic per seed: agent `i` draws from a generator seeded by `(seed, i)` alone
//! (`walker::controller::walker_rng`; its activities from one of their own).
//!
//! Here: the rounds and the take (`mod.rs`); one person, its controller and walker, goal to
//! goal (`person`); what it does between walks (`acting`); where starts and goals are drawn
//! (`goals`); what it did, finished as written (`track`). How a person steps is the walker
//! layer's (`crate::walker`).

use glam::DVec2;
use serde::Serialize;

use crate::body::{BodyModel, BodyParams};
use crate::math::{Affine3, Vec3};
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::{BodyContext, MotionModel};
use crate::motion::primitive::{PRIMITIVE_RATE_HZ, SEED_FRAMES};
use crate::policy::Actor;
use crate::scene::{MovingObstacle, Obstacle2, WalkableMap};
use crate::sensing::Sensor;
use crate::synth::activity::{Activity, ActivityWorld, Phase};
use crate::walker::reward::path_leaves_floor;
use crate::walker::state::{frame_time_s, seen_ahead, Surroundings, PRIMITIVE_S};
use crate::walker::SeedBank;
use crate::walker::{ControllerSpec, PosePrior, WalkerSettings};

mod acting;
mod goals;
mod person;
mod track;

pub use goals::sample_point;
use person::Agent;
pub use track::{AgentState, AgentTrack, GoalRecord};

/// A primitive moving the pelvis less than this (m, horizontal) with the goal still ahead
/// counts as stuck (a walking primitive covers 0.2–0.7 m).
pub(crate) const STUCK_STEP_M: f64 = 0.05;

pub use crate::motion::primitive::NEW_FRAMES;

/// Primitives a take of `duration_s` walks (at least one): enough for its frames at
/// [`PRIMITIVE_RATE_HZ`] after the seed frames.
pub(crate) fn primitives_for(duration_s: f64) -> usize {
    let frames = (duration_s * crate::motion::primitive::PRIMITIVE_RATE_HZ).round() as usize;
    frames
        .saturating_sub(SEED_FRAMES)
        .div_ceil(NEW_FRAMES)
        .max(1)
}

/// Frames of a take of `primitives` primitives.
pub(crate) fn frames_of(primitives: usize) -> usize {
    SEED_FRAMES + primitives * NEW_FRAMES
}

/// Bytes a take holds per agent and frame while it walks, at least: the body parameters (its
/// `betas` shape coefficients copied into each frame), the CPF pose, the body markers, the
/// pelvis and the joints of the tracks made from it. What memory checks multiply by agents ×
/// [`frames_of`].
pub(crate) fn bytes_per_agent_frame(betas: usize) -> f64 {
    use std::mem::size_of;
    (size_of::<BodyParams>()
        + betas * size_of::<f64>()
        + size_of::<Affine3>()
        + size_of::<Vec<Vec3>>()
        + crate::body::markers::NUM_MARKERS * size_of::<Vec3>()
        + size_of::<DVec2>()
        + size_of::<crate::synth::body_track::TrackFrame>()) as f64
}

/// One agent of a crowd, as planned.
#[derive(Debug, Clone, PartialEq)]
pub struct AgentPlan {
    pub name: String,
    /// Shape coefficients (standard deviations).
    pub betas: Vec<f64>,
    pub start: DVec2,
    /// Walking direction of the first seed (rad from +x); `None`: towards the first goal.
    pub facing_rad: Option<f64>,
    pub goals: Vec<DVec2>,
    /// Draw new goals when the list runs out.
    pub wander: bool,
    pub steering: ControllerSpec,
}

/// How a crowd walks: how each person steps ([`WalkerSettings`], `[walker]`), and the take
/// around them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CrowdSettings {
    #[serde(flatten)]
    pub walker: WalkerSettings,
    /// Where the walk to a goal ends: `None` (default) as soon as it is reached; `Some(r)` only
    /// once the pelvis comes within `r` m (or the goal's primitives run out), the goal counting
    /// as reached if the walk ends within `success_m` — EgoGen's evaluation, whose walkers go
    /// on to its training threshold of 0.1 m and are scored at 0.3 m.
    pub arrival_m: Option<f64>,
    /// Primitives per agent in the take (all agents step together).
    pub primitives: usize,
    /// Stop as soon as every agent is done (no goals left, fallen or failed).
    pub stop_when_done: bool,
    /// Distance of a wandering agent's new goal (m).
    pub wander_distance_m: (f64, f64),
    /// Free space around sampled goals (m to the nearest non-walkable cell).
    pub clearance_m: f64,
    pub seed: u64,
}

impl Default for CrowdSettings {
    fn default() -> Self {
        Self {
            walker: WalkerSettings::default(),
            arrival_m: None,
            primitives: 20,
            stop_when_done: true,
            wander_distance_m: (2.0, 5.0),
            clearance_m: 0.4,
            seed: 0,
        }
    }
}

/// The world a crowd walks in: the walkable map, static 2D obstacles and obstacles that move
/// on the take's clock (time 0 at the first seed frame).
#[derive(Debug, Clone)]
pub struct CrowdWorld {
    pub map: std::sync::Arc<WalkableMap>,
    /// Cells starts and goals are drawn on (e.g. inside the walls); `None`: every walkable
    /// cell.
    pub region: Option<Vec<bool>>,
    pub obstacles: Vec<Obstacle2>,
    pub moving: Vec<MovingObstacle>,
}

/// The loaded parts a crowd needs.
pub struct CrowdParts<'m> {
    pub model: &'m MotionModel,
    pub body_model: &'m BodyModel,
    pub prior: &'m PosePrior,
    pub bank: &'m SeedBank,
    /// Needed when an agent is steered by the policy.
    pub policy: Option<&'m Actor>,
}

/// What went wrong running a crowd.
#[derive(Debug, thiserror::Error)]
pub enum CrowdError {
    #[error("agent {agent}: {message}")]
    Agent { agent: String, message: String },
    #[error(transparent)]
    Decode(#[from] DecodeError),
}

/// An agent's box after a primitive of `primitive_s` seconds took its centre from `before` to
/// `now`'s, at `t_now_s`: moving on at the primitive's velocity when `moving_on` (it still
/// walks and people are anticipated), else standing there.
fn stepped_box(
    before: DVec2,
    now: Obstacle2,
    t_now_s: f64,
    primitive_s: f64,
    moving_on: bool,
) -> MovingObstacle {
    let velocity = if moving_on {
        (now.centre() - before) / primitive_s
    } else {
        DVec2::ZERO
    };
    MovingObstacle {
        at_start: now.translated(-velocity * t_now_s),
        velocity_m_per_s: velocity,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn footprint(x: f64, y: f64) -> Obstacle2 {
        Obstacle2::Box {
            centre: DVec2::new(x, y),
            half_extents: DVec2::new(0.3, 0.15),
            yaw_rad: 0.4,
        }
    }

    #[test]
    fn a_stepped_box_moves_on_along_its_primitive_or_stands() {
        let d = PRIMITIVE_S;
        // At (1, 2) at 0.9 s; its primitive to 1.35 s ends at (1.45, 2.0).
        let before = DVec2::new(1.0, 2.0);
        let (t0, t1) = (frame_time_s(2, 0), frame_time_s(3, 0));
        let now = footprint(1.45, 2.0);
        let on = stepped_box(before, now, t1, d, true);
        assert!((on.velocity_m_per_s - DVec2::new(1.0, 0.0)).length() < 1e-9);
        assert!((on.at(t1).centre() - now.centre()).length() < 1e-9);
        assert!((on.at(t0).centre() - DVec2::new(1.0, 2.0)).length() < 1e-9);
        assert!((on.at(t1 + d).centre() - DVec2::new(1.9, 2.0)).length() < 1e-9);
        // The shape and turn are the new footprint's.
        let Obstacle2::Box { yaw_rad, .. } = on.at(t0) else {
            panic!("a box")
        };
        assert_eq!(yaw_rad, 0.4);
        let still = stepped_box(before, now, t1, d, false);
        assert_eq!(still.velocity_m_per_s, DVec2::ZERO);
        assert_eq!(still.at(0.0), now);
        assert_eq!(still.at(t1 + 10.0), now);
    }
}

/// A finished take: every agent's track, all of the same length.
#[derive(Debug, Clone, Serialize)]
pub struct CrowdTake {
    pub frames: usize,
    pub frame_rate_hz: f64,
    pub primitives: usize,
    pub agents: Vec<AgentTrack>,
}

/// Runs a crowd (see the module docs); `progress(step, steps)` after every round.
pub fn run_crowd(
    parts: &CrowdParts,
    world: &CrowdWorld,
    plans: &[AgentPlan],
    settings: &CrowdSettings,
    progress: impl FnMut(usize, usize),
) -> Result<CrowdTake, CrowdError> {
    run_crowd_with_activities(parts, world, plans, settings, None, progress)
}

/// [`run_crowd`] where people do more than walk: what comes after each walk is drawn from
/// `acts` ([`crate::synth::activity`]).
pub(crate) fn run_crowd_with_activities(
    parts: &CrowdParts,
    world: &CrowdWorld,
    plans: &[AgentPlan],
    settings: &CrowdSettings,
    mut acts: Option<ActivityWorld>,
    mut progress: impl FnMut(usize, usize),
) -> Result<CrowdTake, CrowdError> {
    let neutral = BodyContext::new(parts.body_model, &[]).map_err(DecodeError::from)?;
    let mut agents: Vec<Agent> = plans
        .iter()
        .enumerate()
        .map(|(i, p)| Agent::new(parts, &neutral, world, p, i, settings))
        .collect::<Result<_, _>>()?;
    // The policy's own sensing (steering without a policy observes nothing).
    let sensor = parts
        .policy
        .map_or_else(Sensor::default, |actor| actor.sensing().sensor());
    let fixed: Vec<MovingObstacle> = world
        .obstacles
        .iter()
        .map(|&o| MovingObstacle {
            at_start: o,
            velocity_m_per_s: DVec2::ZERO,
        })
        .chain(world.moving.iter().copied())
        .collect();
    // Every agent's 2D box on the take's clock: where its last primitive put it, moving on at
    // that primitive's velocity (zero before its first, once it stops, and when people are not
    // anticipated). Renewed when the agent steps.
    let mut boxes: Vec<MovingObstacle> = agents
        .iter()
        .map(|a| MovingObstacle {
            at_start: a.walker.view.footprint(),
            velocity_m_per_s: DVec2::ZERO,
        })
        .collect();
    let mut seen = Vec::with_capacity(fixed.len() + agents.len());
    let mut judged = Vec::with_capacity(fixed.len() + agents.len());
    let mut rounds = 0;
    for step in 0..settings.primitives {
        if settings.stop_when_done && !agents.iter().any(Agent::active) {
            break;
        }
        let t0_s = frame_time_s(step, 0);
        for i in 0..agents.len() {
            if !agents[i].active() {
                continue;
            }
            // The others: seen still where they stand when this primitive ends, judged moving
            // through it (with `anticipate_people` off, both where they were last put).
            let others = || {
                boxes
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| *k != i)
                    .map(|(_, b)| b)
            };
            seen.clear();
            seen.extend_from_slice(&fixed);
            seen.extend(seen_ahead(others(), t0_s));
            judged.clear();
            judged.extend_from_slice(&fixed);
            judged.extend(others().copied());
            let around_seen = Surroundings {
                map: &world.map,
                obstacle: None,
                moving: &seen,
            };
            let around_judged = Surroundings {
                moving: &judged,
                ..around_seen
            };
            let a = &mut agents[i];
            if let (Some(_), Some(acts)) = (&a.acting, acts.as_mut()) {
                a.act(acts, world, settings)?;
                boxes[i] = stepped_box(
                    boxes[i].at(t0_s).centre(),
                    a.walker.view.footprint(),
                    frame_time_s(step + 1, 0),
                    PRIMITIVE_S,
                    false,
                );
                continue;
            }
            match a.choose(
                parts,
                &sensor,
                &around_seen,
                &around_judged,
                &world.obstacles,
                t0_s,
                settings,
            )? {
                Some((p, j, r)) => a.take(p, j, r, world, settings, acts.as_mut()),
                None => {
                    a.walker.fail(0.0);
                    a.stop(AgentState::DecoderFailure);
                }
            }
            boxes[i] = stepped_box(
                boxes[i].at(t0_s).centre(),
                a.walker.view.footprint(),
                frame_time_s(step + 1, 0),
                PRIMITIVE_S,
                settings.walker.anticipate_people && a.active(),
            );
        }
        rounds = step + 1;
        progress(rounds, settings.primitives);
    }
    let frames = SEED_FRAMES + rounds * NEW_FRAMES;
    Ok(CrowdTake {
        frames,
        frame_rate_hz: PRIMITIVE_RATE_HZ,
        primitives: rounds,
        agents: agents
            .into_iter()
            .map(|a| {
                let mut track = a.finish(frames, &settings.walker, &world.map)?;
                track.follow_floor(&world.map);
                // Sitting down, seated and standing up, the pelvis is over its seat.
                let seated = |f: usize| {
                    track.activity_segments.iter().any(|s| {
                        s.activity == Activity::Sit
                            && s.phase != Phase::Approach
                            && (s.start_frame..s.end_frame).contains(&f)
                    })
                };
                track.pelvis_off_floor_at = (1..track.pelvis_xy.len())
                    .filter(|&f| !seated(f))
                    .filter(|&f| {
                        path_leaves_floor(&world.map, track.pelvis_xy[f - 1], track.pelvis_xy[f])
                    })
                    .collect();
                track.pelvis_off_floor_frames = track.pelvis_off_floor_at.len();
                Ok(track)
            })
            .collect::<Result<_, CrowdError>>()?,
    })
}
