//! Crowds (paper Alg. 1): several bodies, each driven by its own controller, walking to their goals
//! through one world. Agents take one primitive each in turn; before choosing, an agent senses the
//! others' 2D boxes and the moving obstacles at its clock, with the same rays, observation and
//! reward as the training environment ([`crate::policy::walker`]). The others are seen where they
//! will stand when its primitive ends (someone who stepped earlier in the round where that
//! primitive ends, someone yet to step moved on at the velocity of their last primitive) and the
//! primitive is judged against them moving; EgoGen's loop, every box where it was last put, is
//! [`WalkerSettings::anticipate_people`] off. No multi-agent learning: every agent runs the
//! single-agent controller, and every agent chooses its primitive by the same step as the
//! training environment and `egogen policy eval` (`policy::step`: one judge, the
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
//! around, pick something up (played where the walk ended), or sit (walk to the nearest free
//! seat first); an activity's frames are taken [`NEW_FRAMES`] a round, the others seeing the
//! person where it is, and the walker takes over from its last two frames; a walk comes
//! between two activities. An activity that would enter the scene is skipped with its reason.
//!
//! When the take ends, each agent's motion is finished as written: the velocity jump where
//! one primitive (or activity, or held pose) hands over to the next is spread over ±0.2 s
//! (up to ±0.4 s for the largest changes; [`crate::motion::joins`]) and the neck and head turn against the torso's sway
//! ([`crate::motion::head_stabilise`]), `[walker] smooth_joins` and `steady_head`; the
//! walk itself (what was chosen, where it went) is as stepped.
//!
//! Deterministic per seed: agent `i` draws from a generator seeded by `(seed, i)` alone (and
//! its activities from one of their own).

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};
use serde::Serialize;

use crate::body::{joint, BodyModel, BodyParams};
use crate::math::random::{normal_samples, uniform_open01};
use crate::math::{Affine3, Vec3};
use crate::motion::activity_clip::max_joint_speed;
use crate::motion::cvae::contact::contact_score;
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::tensor_body::RigGeometry;
use crate::motion::cvae::{BodyContext, DecodedPrimitive, MotionModel, PrimitiveSeed};
use crate::motion::head_stabilise::{stabilise_head, HeadStabiliser};
use crate::motion::joins::{smooth_joins, JoinWindow};
use crate::motion::primitive::{PRIMITIVE_FRAMES, PRIMITIVE_RATE_HZ, SEED_FRAMES};
use crate::policy::env::SeedBank;
use crate::policy::reward::{path_leaves_floor, Judged, Limits, RewardWeights};
use crate::policy::step::{
    choose_primitive, draw_action, finite_reward, Judge, Proposal, Redraws, SceneCheck, StepContext,
};
use crate::policy::walker::{
    frame_time_s, memory_scan, place_seed, seen_ahead, SeedView, Surroundings, Walker, PRIMITIVE_S,
};
use crate::policy::{Actor, PosePrior, WalkerSettings};
use crate::scene::{
    guide_aim_remembered, plan_path, MovingObstacle, Obstacle2, SeenMap, WalkableMap,
};
use crate::sensing::Sensor;
use crate::synth::activity::{
    Activity, ActivityRecord, ActivitySegment, ActivityWorld, Performance, Phase, SkippedActivity,
};

/// A primitive moving the pelvis less than this (m, horizontal) with the goal still ahead
/// counts as stuck (a walking primitive covers 0.2–0.7 m).
pub const STUCK_STEP_M: f64 = 0.05;

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

/// How an agent chooses its next primitive.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Controller {
    /// The trained policy: an action sampled from π, its standard deviation scaled by
    /// `spread` (1: as trained; smaller draws nearer the mean), or its mean.
    Policy {
        mean_action: bool,
        #[serde(skip_serializing_if = "is_one")]
        spread: f32,
    },
    /// The best of `k` random latents by the environment's reward (one primitive ahead).
    Sampling { k: usize },
    /// The path-planning baseline (in the spirit of GAMMA's and DIMOS's A* paths): an A* path
    /// on the walkable map around the others' boxes as the agent sees them and the moving
    /// obstacles where they stand, replanned every primitive; of `k` random latents the one
    /// whose primitive ends nearest the path's point [`PATH_LOOKAHEAD_M`] ahead (a primitive
    /// that penetrates, Eq. 7, counts [`PATH_PENETRATION_COST_M`] farther). No policy, no
    /// reward.
    PathFollow { k: usize },
}

impl Controller {
    /// The trained policy's sampled actions, as trained.
    pub const POLICY: Controller = Controller::Policy {
        mean_action: false,
        spread: 1.0,
    };
    /// The trained policy's mean action.
    pub(crate) const POLICY_MEAN: Controller = Controller::Policy {
        mean_action: true,
        spread: 1.0,
    };
}

fn is_one(x: &f32) -> bool {
    *x == 1.0
}

/// How far along the planned path the path follower aims a primitive (m; a walking
/// primitive covers 0.2–0.7 m).
pub const PATH_LOOKAHEAD_M: f64 = 0.8;

/// Free space the planned path keeps from walls and other people (m, about half a body's
/// width).
pub(crate) const PATH_CLEARANCE_M: f64 = 0.3;

/// What a penetrating primitive costs the path follower, as extra distance (m).
pub const PATH_PENETRATION_COST_M: f64 = 1.0;

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
    pub steering: Controller,
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

/// Why an agent stopped before the take ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AgentState {
    /// Still walking when the take ended.
    Walking,
    /// No goals left (all reached or missed).
    Done,
    /// The head came below half the standing head height.
    Fell,
    /// The decoder produced a non-finite primitive.
    DecoderFailure,
}

/// One goal an agent walked to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GoalRecord {
    pub goal: [f64; 2],
    pub reached: bool,
    /// Primitives spent on it.
    pub primitives: usize,
    /// Frame at which it was reached or given up.
    pub end_frame: usize,
    pub final_distance_m: f64,
}

/// What an agent did: every frame of its body at 40 Hz, eye frames and markers, goals.
#[derive(Debug, Clone, Serialize)]
pub struct AgentTrack {
    pub name: String,
    pub betas: Vec<f64>,
    pub steering: Controller,
    #[serde(skip)]
    pub frames: Vec<BodyParams>,
    #[serde(skip)]
    pub world_from_cpf: Vec<Affine3>,
    #[serde(skip)]
    pub markers: Vec<Vec<Vec3>>,
    /// Horizontal pelvis position per frame.
    #[serde(skip)]
    pub pelvis_xy: Vec<DVec2>,
    /// First frame of each primitive walked (its 18 new frames follow its two seed frames).
    #[serde(skip)]
    pub primitive_starts: Vec<usize>,
    /// Frames where what the body does hands over to what comes next: each primitive's
    /// first frame, an activity's, the held pose's after a stop ([`crate::motion::joins`]).
    #[serde(skip)]
    pub joins: Vec<usize>,
    pub goals: Vec<GoalRecord>,
    pub state: AgentState,
    /// First frame of the held pose, when the agent stopped before the take ended.
    pub stopped_at_frame: Option<usize>,
    /// Primitives taken.
    pub primitives: usize,
    /// Primitives in which the pelvis moved less than [`STUCK_STEP_M`] with the goal not
    /// reached: time spent stuck.
    pub stuck_primitives: usize,
    /// Mean foot contact (3-D, Eq. 12) over the primitives walked, as written (joins
    /// smoothed, head steadied).
    pub contact: f64,
    /// Share of new frames with a body marker inside a static obstacle, a moving obstacle or
    /// another agent's 2D box.
    pub penetration_share: f64,
    /// Frames of the take whose pelvis path from the frame before passes over a cell of the
    /// walkable map that is not walkable (a wall, furniture, a closed doorway), measured on
    /// the track as written ([`crate::policy::reward::path_leaves_floor`]); frames sitting
    /// down, seated or standing up (over the seat) not counted.
    pub pelvis_off_floor_frames: usize,
    /// Primitives in which the body held its pose because every draw would have taken its
    /// pelvis over a wall ([`WalkerSettings::scene_every_frame`]).
    pub held_primitives: usize,
    /// Horizontal walking speed over the primitives taken (m/s).
    pub speed_m_s: f64,
    /// Mean cos(angle) between the viewing direction and the direction to the goal at the
    /// primitives' ends.
    pub view_cos: f64,
    /// Mean pose-prior score (−ln p / 63) over the primitives.
    pub pose_score: f64,
    /// Activities done besides walking ([`crate::synth::activity`]), in order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub activities: Vec<ActivityRecord>,
    /// Which frames each activity's phases span (frames in none: walking).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub activity_segments: Vec<ActivitySegment>,
    /// Activities drawn but not done, with why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub skipped_activities: Vec<SkippedActivity>,
}

impl AgentTrack {
    /// Lifts a track walked on the flat floor at the map's `floor_z_m` onto its stepped
    /// floors ([`crate::scene::WalkableSettings::floor_steps_m`]), rigidly, frame by frame:
    /// at least to the floor under the pelvis ([`WalkableMap::floor_under`]), and high
    /// enough that no marker stands lower under the floor of its own cell than it stood under
    /// the flat floor (a foot over a step up lifts the body onto it); that lift is the
    /// largest within ±[`FLOOR_FOLLOW_FRAMES`] of each frame, averaged over as many, so the
    /// body rises or sinks over 0.2 s and never puts a foot into a step. The motion model
    /// walks a flat floor, so the body is lifted onto a step up to 0.1 s before its foot
    /// lands there, and the other foot lifts off the floor below. Nothing changes on a flat
    /// floor.
    pub(crate) fn follow_floor(&mut self, map: &WalkableMap) {
        if map.is_flat() || self.frames.is_empty() {
            return;
        }
        let z0 = map.floor_z_m;
        let need: Vec<f64> = (0..self.frames.len())
            .map(|f| {
                self.markers[f]
                    .iter()
                    .filter_map(|m| {
                        let under = map.cell_floor_at(DVec2::new(m.x, m.y))?;
                        Some(under - z0 - (m.z - z0).max(0.0))
                    })
                    .fold(map.floor_under(self.pelvis_xy[f]) - z0, f64::max)
            })
            .collect();
        let last = need.len() - 1;
        let window = |f: usize| {
            (
                f.saturating_sub(FLOOR_FOLLOW_FRAMES),
                (f + FLOOR_FOLLOW_FRAMES).min(last),
            )
        };
        let most: Vec<f64> = (0..need.len())
            .map(|f| {
                let (a, b) = window(f);
                need[a..=b]
                    .iter()
                    .copied()
                    .fold(f64::NEG_INFINITY, f64::max)
            })
            .collect();
        for f in 0..self.frames.len() {
            let (a, b) = window(f);
            let dz = most[a..=b].iter().sum::<f64>() / (b - a + 1) as f64;
            self.frames[f].transl.z += dz;
            self.world_from_cpf[f].translation.z += dz;
            for m in &mut self.markers[f] {
                m.z += dz;
            }
        }
    }

    /// The agent's frames as a motion sequence (neutral gender; the body model's).
    pub(crate) fn motion_sequence(&self, frame_rate_hz: f64) -> crate::motion::MotionSequence {
        crate::motion::MotionSequence {
            frame_rate_hz,
            betas: self.betas.clone(),
            gender: "neutral".into(),
            poses: self.frames.iter().map(|f| f.pose).collect(),
            trans: self.frames.iter().map(|f| f.transl).collect(),
        }
    }
}

/// What went wrong running a crowd.
#[derive(Debug, thiserror::Error)]
pub enum CrowdError {
    #[error("agent {agent}: {message}")]
    Agent { agent: String, message: String },
    #[error(transparent)]
    Decode(#[from] DecodeError),
}

struct Agent<'m> {
    plan: AgentPlan,
    body: BodyContext<'m>,
    foot_markers: Vec<usize>,
    standing_head_m: f64,
    walker: Walker,
    /// What the agent has seen, where its guide plans on that
    /// ([`WalkerSettings::guide_memory`]).
    seen: Option<SeenMap>,
    goal: DVec2,
    goal_steps: usize,
    next_goal: usize,
    rng: ChaCha8Rng,
    track: AgentTrack,
    /// The activity being played and how many of its frames are taken.
    acting: Option<(Performance, usize)>,
    /// The seat being walked to (to sit on when reached) and the frame the walk began.
    approaching: Option<(usize, usize)>,
    /// Draws what comes after each walk: a stream of its own, so walking draws as without
    /// activities.
    activity_rng: ChaCha8Rng,
}

fn agent_rng(seed: u64, i: usize) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(
        seed.rotate_left(17) ^ (i as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03),
    )
}

/// Whether cell `k` may hold a drawn start or goal: walkable, in the region, with
/// `clearance_m` of free space.
fn drawable(map: &WalkableMap, region: Option<&[bool]>, clearance_m: f64, k: usize) -> bool {
    map.walkable[k] && map.sdf_m[k] >= clearance_m && region.is_none_or(|r| r[k])
}

/// A point on the walkable map (in `region` when given) with `clearance_m` of free space,
/// uniform over such cells.
pub fn sample_point(
    map: &WalkableMap,
    region: Option<&[bool]>,
    clearance_m: f64,
    rng: &mut ChaCha8Rng,
) -> Option<DVec2> {
    let cells: Vec<usize> = (0..map.nx * map.ny)
        .filter(|&k| drawable(map, region, clearance_m, k))
        .collect();
    if cells.is_empty() {
        return None;
    }
    let k = cells[(rng.next_u64() % cells.len() as u64) as usize];
    Some(map.centre(k % map.nx, k / map.nx))
}

/// A goal on the walkable map, in the same connected region as `from`, `distance_m` away,
/// with `clearance_m` of free space; `None` when the map has none after many draws.
pub(crate) fn sample_goal(
    map: &WalkableMap,
    region: Option<&[bool]>,
    from: DVec2,
    distance_m: (f64, f64),
    clearance_m: f64,
    rng: &mut ChaCha8Rng,
) -> Option<DVec2> {
    let component = map
        .cell_of(from)
        .map(|(i, j)| map.component[j * map.nx + i])
        .unwrap_or(0);
    for _ in 0..2000 {
        let d = distance_m.0 + (distance_m.1 - distance_m.0) * uniform_open01(rng);
        let a = std::f64::consts::TAU * uniform_open01(rng);
        let p = from + DVec2::from_angle(a) * d;
        let Some((i, j)) = map.cell_of(p) else {
            continue;
        };
        let k = j * map.nx + i;
        if drawable(map, region, clearance_m, k)
            && (component == 0 || map.component[k] == component)
        {
            return Some(p);
        }
    }
    None
}

impl<'m> Agent<'m> {
    /// `neutral`: the mocap seeds' body (zero betas), shared by all agents.
    fn new(
        parts: &CrowdParts<'m>,
        neutral: &BodyContext,
        world: &CrowdWorld,
        plan: &AgentPlan,
        index: usize,
        settings: &CrowdSettings,
    ) -> Result<Self, CrowdError> {
        let err = |message: String| CrowdError::Agent {
            agent: plan.name.clone(),
            message,
        };
        if parts.bank.seeds.is_empty() {
            return Err(err("the seed bank is empty".into()));
        }
        if matches!(plan.steering, Controller::Policy { .. }) && parts.policy.is_none() {
            return Err(err("steered by the policy, but no policy was loaded".into()));
        }
        let body = BodyContext::new(parts.body_model, &plan.betas)
            .map_err(|e| err(format!("betas: {e}")))?;
        let foot_markers = RigGeometry::new(body.model, &body.betas)
            .map_err(|e| err(format!("body: {e}")))?
            .foot_markers;
        let mut rng = agent_rng(settings.seed, index);
        let mut goals = plan.goals.iter().copied();
        let goal = match goals.next() {
            Some(g) => g,
            None => sample_goal(
                &world.map,
                world.region.as_deref(),
                plan.start,
                settings.wander_distance_m,
                settings.clearance_m,
                &mut rng,
            )
            .ok_or_else(|| {
                err(format!(
                    "no goal given and none could be drawn around the start: no walkable cell \
                     {}–{} m away (`[motion] wander_distance_m`) with {} m of free space \
                     (`clearance_m`) on the start's floor; shorten the distances or give goals",
                    settings.wander_distance_m.0,
                    settings.wander_distance_m.1,
                    settings.clearance_m
                ))
            })?,
        };
        let (frames, floor) =
            &parts.bank.seeds[(rng.next_u64() % parts.bank.seeds.len() as u64) as usize];
        let to_goal = goal - plan.start;
        let facing = plan
            .facing_rad
            .unwrap_or_else(|| to_goal.y.atan2(to_goal.x));
        let rest_pelvis = body.shaped.rest_joints[joint::PELVIS];
        let map = &*world.map;
        let mut seed = place_seed(
            frames,
            *floor,
            plan.start,
            facing,
            map.floor_z_m,
            rest_pelvis,
        );
        // The bank's floor is the mocap body's; a body of another shape stands its lowest foot
        // marker at the same height over the floor.
        let lowest = |b: &BodyContext, s: &crate::motion::cvae::PrimitiveSeed| {
            s.frames
                .iter()
                .map(|f| {
                    b.shaped
                        .marker_frame(&f.pose, f.transl, &b.marker_ids)
                        .map(|m| m.markers.iter().map(|v| v.z).fold(f64::INFINITY, f64::min))
                })
                .try_fold(f64::INFINITY, |acc, z| z.map(|z| acc.min(z)))
        };
        let neutral_seed = place_seed(
            frames,
            *floor,
            plan.start,
            facing,
            map.floor_z_m,
            neutral.shaped.rest_joints[joint::PELVIS],
        );
        let dz = lowest(neutral, &neutral_seed).map_err(DecodeError::from)?
            - lowest(&body, &seed).map_err(DecodeError::from)?;
        for f in &mut seed.frames {
            f.transl.z += dz;
        }
        let view = SeedView::new(&body, seed)?;
        let f0 = &view.seed.frames[0];
        let standing_head_m = body
            .shaped
            .skeleton(&f0.pose, f0.transl)
            .map_err(DecodeError::from)?
            .joints[joint::HEAD]
            .z
            - map.floor_z_m;
        let walker = Walker::new(view.clone(), goal);
        let mut track = AgentTrack {
            name: plan.name.clone(),
            betas: plan.betas.clone(),
            steering: plan.steering,
            frames: view.seed.frames.to_vec(),
            world_from_cpf: view.world_from_cpf.to_vec(),
            markers: view.markers.to_vec(),
            pelvis_xy: vec![view.pelvis; SEED_FRAMES],
            primitive_starts: Vec::new(),
            joins: Vec::new(),
            goals: Vec::new(),
            state: AgentState::Walking,
            stopped_at_frame: None,
            primitives: 0,
            stuck_primitives: 0,
            contact: 0.0,
            penetration_share: 0.0,
            pelvis_off_floor_frames: 0,
            held_primitives: 0,
            speed_m_s: 0.0,
            view_cos: 0.0,
            pose_score: 0.0,
            activities: Vec::new(),
            activity_segments: Vec::new(),
            skipped_activities: Vec::new(),
        };
        track
            .frames
            .iter_mut()
            .for_each(|f| f.betas = plan.betas.clone());
        Ok(Self {
            plan: plan.clone(),
            body,
            foot_markers,
            standing_head_m,
            walker,
            seen: None,
            goal,
            goal_steps: 0,
            next_goal: 1,
            rng,
            track,
            acting: None,
            approaching: None,
            activity_rng: agent_rng(settings.seed ^ 0xAC71_7117, index),
        })
    }

    fn active(&self) -> bool {
        self.track.state == AgentState::Walking
    }

    fn head_height_m(&self, p: &DecodedPrimitive) -> f64 {
        let last = &p.joints[p.joints.len() - 1];
        last[joint::HEAD].z - p.floor_z
    }

    /// Chooses, decodes and judges the next primitive: sensing `around`, judged against
    /// `judged` (the same map, the others as [`WalkerSettings::anticipate_people`] says);
    /// `standing`: the world's obstacles that do not move, which the guide plans round.
    #[allow(clippy::too_many_arguments)]
    fn choose(
        &mut self,
        parts: &CrowdParts,
        sensor: &Sensor,
        around: &Surroundings,
        judged: &Surroundings,
        standing: &[Obstacle2],
        t0_s: f64,
        settings: &CrowdSettings,
    ) -> Result<Option<(DecodedPrimitive, Judged, f64)>, CrowdError> {
        let l = parts.model.latent_dim();
        // The policy's action distribution, kept for redraws.
        let mut policy_dist: Option<(Vec<f32>, Vec<f32>)> = None;
        let latents: Vec<Vec<f32>> = match self.plan.steering {
            Controller::Policy {
                mean_action,
                spread,
            } => {
                let actor = parts.policy.expect("checked when the agent was made");
                let mut obs = vec![0f32; actor.obs_layout().dim()];
                let time_left =
                    1.0 - self.goal_steps as f64 / settings.walker.max_primitives_per_goal as f64;
                let memory = settings.walker.remembers().then(|| {
                    let seen = self.seen.get_or_insert_with(|| SeenMap::unseen(around.map));
                    self.walker
                        .look(&memory_scan(sensor), around.map, standing, seen);
                    &*seen
                });
                let aim = guide_aim_remembered(
                    memory,
                    around.map,
                    standing,
                    self.walker.view.pelvis,
                    self.goal,
                    &settings.walker.guide(),
                );
                self.walker.observe_into(
                    &self.body,
                    sensor,
                    aim,
                    around,
                    t0_s,
                    time_left.max(0.0),
                    &mut obs,
                );
                let (mean, mut std) = actor.distribution(&obs);
                if spread != 1.0 {
                    std.iter_mut().for_each(|s| *s *= spread);
                }
                let a = if mean_action {
                    mean.clone()
                } else {
                    draw_action(&mean, &std, &mut self.rng)
                };
                policy_dist = Some((mean, std));
                vec![a]
            }
            Controller::Sampling { k } | Controller::PathFollow { k } => {
                normal_samples(&mut self.rng, k.max(1) * l)
                    .chunks(l)
                    .map(<[f32]>::to_vec)
                    .collect()
            }
        };
        // The path follower's aim: a point ahead on a path planned now.
        let aim = match self.plan.steering {
            Controller::PathFollow { .. } => {
                let obstacles: Vec<Obstacle2> = around
                    .moving
                    .iter()
                    .map(|m| m.at(t0_s))
                    .chain(around.obstacle.copied())
                    .collect();
                let path = plan_path(
                    around.map,
                    &obstacles,
                    PATH_CLEARANCE_M,
                    self.walker.view.pelvis,
                    self.goal,
                );
                Some(path.point_along(PATH_LOOKAHEAD_M))
            }
            _ => None,
        };
        let seeds = vec![self.walker.view.seed.clone(); latents.len()];
        let decoded = parts.model.decode_each(&self.body, &seeds, &latents)?;
        let judge = Judge {
            limits: match settings.walker.scene_every_frame {
                true => Limits::swept(settings.walker.success_m),
                false => Limits::eq7(settings.walker.success_m),
            },
            weights: RewardWeights::default(),
            primitives_left: settings
                .walker
                .max_primitives_per_goal
                .saturating_sub(self.goal_steps + 1),
            foot_markers: &self.foot_markers,
            prior: parts.prior,
            scene: SceneCheck::Cells,
            no_progress_through_walls: false,
        };
        let situation = self.walker.situation(judged, self.goal, t0_s);
        let mut proposals = Vec::with_capacity(decoded.len());
        for (d, latent) in decoded.into_iter().zip(latents) {
            match d {
                Ok(p) => {
                    let (j, r) = judge.judge(&self.body, &p, &situation)?;
                    let score = match aim {
                        Some(aim) => {
                            let end = p.joints[p.joints.len() - 1][joint::PELVIS];
                            let miss = DVec2::new(end.x, end.y).distance(aim);
                            -(miss
                                + if j.penetrated {
                                    PATH_PENETRATION_COST_M
                                } else {
                                    0.0
                                })
                        }
                        None => r,
                    };
                    proposals.push(Proposal {
                        latent,
                        primitive: p,
                        judged: j,
                        reward: finite_reward(r),
                        score,
                    });
                }
                Err(DecodeError::NonFinite { .. }) => {}
                Err(e) => return Err(e.into()),
            }
        }
        let ctx = StepContext {
            model: parts.model,
            body: &self.body,
            seed: &self.walker.view.seed,
            judge: &judge,
            situation: &situation,
            pelvis: self.walker.view.pelvis,
        };
        let redraws = Redraws {
            count: settings.walker.penetration_redraws,
            policy: policy_dist
                .as_ref()
                .map(|(mean, std)| (mean.as_slice(), std.as_slice())),
        };
        let chosen = choose_primitive(&ctx, proposals, Some((&redraws, &mut self.rng)))?;
        if chosen.as_ref().is_some_and(|c| c.held) {
            self.track.held_primitives += 1;
        }
        Ok(chosen.map(|c| (c.primitive, c.judged, c.reward)))
    }

    /// Takes the chosen primitive and, when this goal is over, moves on: to what `acts`
    /// draws (where the take asks for activities), else to the next goal.
    fn take(
        &mut self,
        p: DecodedPrimitive,
        j: Judged,
        reward: f64,
        world: &CrowdWorld,
        settings: &CrowdSettings,
        acts: Option<&mut ActivityWorld>,
    ) {
        let before = self.walker.view.pelvis;
        self.walker.advance(&p, &j, reward);
        self.goal_steps += 1;
        self.track.primitives += 1;
        // Stuck: hardly moving with the goal still ahead.
        if self.walker.view.pelvis.distance(before) < STUCK_STEP_M
            && j.distance_m >= settings.walker.success_m
        {
            self.track.stuck_primitives += 1;
        }
        let start = self.track.frames.len();
        self.track.primitive_starts.push(start);
        self.track.joins.push(start);
        for k in SEED_FRAMES..p.world.len() {
            let mut f = p.world[k].clone();
            f.betas = self.plan.betas.clone();
            self.track.frames.push(f);
            self.track.world_from_cpf.push(p.world_from_cpf[k]);
            self.track.markers.push(p.markers[k].clone());
            let q = p.joints[k][joint::PELVIS];
            self.track.pelvis_xy.push(DVec2::new(q.x, q.y));
        }
        let frame = self.track.frames.len() - 1;
        if self.head_height_m(&p) < 0.5 * self.standing_head_m {
            self.stop(AgentState::Fell);
            return;
        }
        let reached = j.distance_m < settings.walker.success_m;
        let arrived = settings.arrival_m.map_or(reached, |r| j.distance_m < r);
        if !arrived && self.goal_steps < settings.walker.max_primitives_per_goal {
            return;
        }
        self.track.goals.push(GoalRecord {
            goal: self.goal.to_array(),
            reached,
            primitives: self.goal_steps,
            end_frame: frame,
            final_distance_m: j.distance_m,
        });
        if let Some(acts) = acts {
            if self.after_walk(acts, world) {
                return;
            }
        }
        self.next_goal(world, settings);
    }

    /// Walks on to the next goal given, or drawn when wandering, or stops: no goals left.
    fn next_goal(&mut self, world: &CrowdWorld, settings: &CrowdSettings) {
        let next = match self.plan.goals.get(self.next_goal) {
            Some(&g) => Some(g),
            None if self.plan.wander => sample_goal(
                &world.map,
                world.region.as_deref(),
                self.walker.view.pelvis,
                settings.wander_distance_m,
                settings.clearance_m,
                &mut self.rng,
            ),
            None => None,
        };
        self.next_goal += 1;
        match next {
            Some(g) => {
                self.goal = g;
                self.goal_steps = 0;
                self.walker.retarget(g);
            }
            None => self.stop(AgentState::Done),
        }
    }

    /// After a walk: sits down if it was the walk to a seat, else draws what comes next
    /// from `acts`; whether an activity (or the walk to one) began — `false`: walk on.
    fn after_walk(&mut self, acts: &mut ActivityWorld, world: &CrowdWorld) -> bool {
        let frame = self.track.frames.len();
        let floor_z = self.walker.view.seed.floor_z;
        let last = self.track.frames[frame - 1].clone();
        if let Some((s, began)) = self.approaching.take() {
            self.track.activity_segments.push(ActivitySegment {
                activity: Activity::Sit,
                phase: Phase::Approach,
                start_frame: began,
                end_frame: frame,
            });
            let reached = self.track.goals.last().is_some_and(|g| g.reached);
            let sat = if reached {
                acts.sit(
                    &self.body,
                    &world.map,
                    &last,
                    s,
                    floor_z,
                    &mut self.activity_rng,
                )
            } else {
                Err(format!(
                    "the place in front of the seat of {} was not reached",
                    acts.seats[s].object_name
                ))
            };
            match sat {
                Ok(p) => {
                    self.perform(p);
                    return true;
                }
                Err(reason) => {
                    acts.taken[s] = false;
                    self.skip(Activity::Sit, frame, reason);
                }
            }
        }
        let activity = acts.draw(&mut self.activity_rng);
        let done = match activity {
            Activity::Walk => return false,
            Activity::Stand => acts.stand(
                &self.body,
                &world.map,
                &last,
                floor_z,
                &mut self.activity_rng,
            ),
            Activity::PickUp => acts.pick_up(
                &self.body,
                &world.map,
                &last,
                floor_z,
                &mut self.activity_rng,
            ),
            Activity::Sit => match acts.nearest_free_seat(&world.map, self.walker.view.pelvis) {
                Some(s) => {
                    acts.taken[s] = true;
                    self.approaching = Some((s, frame));
                    self.goal = acts.seats[s].stand();
                    self.goal_steps = 0;
                    self.walker.retarget(self.goal);
                    return true;
                }
                None => Err(match acts.seats.is_empty() {
                    true => "the scene has no seat (`egogen scene inspect` lists them)".into(),
                    false => "every seat on this floor is taken".into(),
                }),
            },
        };
        match done {
            Ok(p) => {
                self.perform(p);
                true
            }
            Err(reason) => {
                self.skip(activity, frame, reason);
                false
            }
        }
    }

    fn skip(&mut self, activity: Activity, frame: usize, reason: String) {
        self.track.skipped_activities.push(SkippedActivity {
            activity,
            frame,
            reason,
        });
    }

    /// Begins playing `p` from the next frame.
    fn perform(&mut self, mut p: Performance) {
        let start = self.track.frames.len();
        if let Some(look) = p.record.look_at.as_mut() {
            look.start_frame += start;
            look.end_frame += start;
            // A seat is looked at from the walk to it on.
            if let Some(walk) = self.track.activity_segments.last().filter(|s| {
                p.activity == Activity::Sit && s.phase == Phase::Approach && s.end_frame == start
            }) {
                look.start_frame = walk.start_frame;
            }
        }
        let mut k = start;
        for &(phase, n) in &p.phases {
            self.track.activity_segments.push(ActivitySegment {
                activity: p.activity,
                phase,
                start_frame: k,
                end_frame: k + n,
            });
            k += n;
        }
        p.record.start_frame = start;
        p.record.end_frame = k;
        self.track.activities.push(p.record.clone());
        self.acting = Some((p, 0));
    }

    /// Takes the next [`NEW_FRAMES`] frames of the activity being played; when it ends,
    /// gives its seat back and walks on to the next goal.
    fn act(
        &mut self,
        acts: &mut ActivityWorld,
        world: &CrowdWorld,
        settings: &CrowdSettings,
    ) -> Result<(), CrowdError> {
        let Some((p, taken)) = self.acting.as_mut() else {
            return Ok(());
        };
        let end = (*taken + NEW_FRAMES).min(p.frames.len());
        if *taken == 0 {
            self.track.joins.push(self.track.frames.len());
        }
        let frames = p.frames[*taken..end].to_vec();
        *taken = end;
        let over = end == p.frames.len();
        for f in frames {
            let mf = self
                .body
                .shaped
                .marker_frame(&f.pose, f.transl, &self.body.marker_ids)
                .map_err(DecodeError::from)?;
            let q = mf.skeleton.joints[joint::PELVIS];
            self.track
                .world_from_cpf
                .push(self.body.cpf.world_from_cpf(&mf.skeleton));
            self.track.markers.push(mf.markers);
            self.track.pelvis_xy.push(DVec2::new(q.x, q.y));
            self.track.frames.push(f);
        }
        let n = self.track.frames.len();
        let seed = PrimitiveSeed {
            frames: [
                self.track.frames[n - 2].clone(),
                self.track.frames[n - 1].clone(),
            ],
            floor_z: self.walker.view.seed.floor_z,
        };
        self.walker.view = SeedView::new(&self.body, seed)?;
        if over {
            if let Some((p, _)) = self.acting.take() {
                if let Some(s) = p.seat {
                    acts.taken[s] = false;
                }
            }
            // A walk comes between two activities.
            self.next_goal(world, settings);
        }
        Ok(())
    }

    fn stop(&mut self, state: AgentState) {
        self.track.state = state;
        self.track.stopped_at_frame = Some(self.track.frames.len());
    }

    /// Holds the last pose until the take has `frames` frames, smooths the joins and steadies
    /// the head ([`finish_motion`]); closes the summary.
    fn finish(
        mut self,
        frames: usize,
        settings: &WalkerSettings,
    ) -> Result<AgentTrack, CrowdError> {
        let t = &mut self.track;
        for seg in &mut t.activity_segments {
            seg.end_frame = seg.end_frame.min(frames);
        }
        if let Some((_, began)) = self.approaching {
            t.activity_segments.push(ActivitySegment {
                activity: Activity::Sit,
                phase: Phase::Approach,
                start_frame: began,
                end_frame: frames,
            });
        }
        t.activity_segments
            .retain(|seg| seg.start_frame < seg.end_frame);
        for r in &mut t.activities {
            r.end_frame = r.end_frame.min(frames);
            if let Some(look) = r.look_at.as_mut() {
                look.end_frame = look.end_frame.min(frames);
            }
        }
        if t.frames.len() < frames {
            t.joins.push(t.frames.len());
        }
        while t.frames.len() < frames {
            t.frames.push(t.frames[t.frames.len() - 1].clone());
            t.world_from_cpf
                .push(t.world_from_cpf[t.world_from_cpf.len() - 1]);
            t.markers.push(t.markers[t.markers.len() - 1].clone());
            t.pelvis_xy.push(t.pelvis_xy[t.pelvis_xy.len() - 1]);
        }
        finish_motion(t, &self.body, settings)?;
        // How each activity moved: foot contact over its frames, the fastest joint turn where
        // it joins the walk.
        let floor_z = self.walker.view.seed.floor_z;
        for r in &mut t.activities {
            let (a, b) = (r.start_frame, r.end_frame.min(t.frames.len()));
            let feet = foot_points(&t.markers, &self.foot_markers, a..b);
            let scores: Vec<f64> = (0..feet.len().saturating_sub(PRIMITIVE_FRAMES - 1))
                .step_by(NEW_FRAMES)
                .map(|s| contact_score(&feet[s..s + PRIMITIVE_FRAMES], floor_z))
                .collect();
            r.contact = scores.iter().sum::<f64>() / scores.len().max(1) as f64;
            let join = |f: usize| {
                max_joint_speed(&t.frames[f.saturating_sub(4)..(f + 4).min(t.frames.len())])
            };
            r.join_joint_speed_rad_s = join(a).max(join(b));
        }
        let w = &self.walker;
        let n = w.steps.max(1) as f64;
        let walked: Vec<f64> = t
            .primitive_starts
            .iter()
            .filter(|&&s| s + NEW_FRAMES <= t.frames.len())
            .map(|&s| {
                let feet = foot_points(
                    &t.markers,
                    &self.foot_markers,
                    s - SEED_FRAMES..s + NEW_FRAMES,
                );
                contact_score(&feet, floor_z)
            })
            .collect();
        t.contact = walked.iter().sum::<f64>() / walked.len().max(1) as f64;
        t.penetration_share = w.totals.frames_in_obstacle as f64 / w.totals.frames.max(1) as f64;
        t.speed_m_s = w.speed_m_s();
        t.view_cos = w.totals.view_cos / n;
        t.pose_score = w.totals.pose_score / n;
        Ok(self.track)
    }
}

/// The foot markers' positions over `frames`, as the foot-contact score reads them.
fn foot_points(
    markers: &[Vec<Vec3>],
    foot_markers: &[usize],
    frames: std::ops::Range<usize>,
) -> Vec<Vec<[f64; 3]>> {
    frames
        .map(|f| {
            foot_markers
                .iter()
                .map(|&k| markers[f][k].to_array())
                .collect()
        })
        .collect()
}

/// The motion as written: each join's velocity jump spread ([`WalkerSettings::smooth_joins`]),
/// the head steadied against the torso's sway ([`WalkerSettings::steady_head`]); the eye
/// frame, markers and pelvis positions posed again from the frames where either changed them.
fn finish_motion(
    t: &mut AgentTrack,
    body: &BodyContext,
    settings: &WalkerSettings,
) -> Result<(), CrowdError> {
    if !settings.smooth_joins && !settings.steady_head {
        return Ok(());
    }
    if settings.smooth_joins {
        smooth_joins(
            &mut t.frames,
            &t.joins,
            &JoinWindow::at_rate(PRIMITIVE_RATE_HZ),
        );
    }
    if settings.steady_head {
        stabilise_head(
            &mut t.frames,
            &body.shaped,
            &body.cpf,
            PRIMITIVE_RATE_HZ,
            &HeadStabiliser::default(),
        )
        .map_err(DecodeError::from)?;
    }
    for (f, frame) in t.frames.iter().enumerate() {
        let mf = body
            .shaped
            .marker_frame(&frame.pose, frame.transl, &body.marker_ids)
            .map_err(DecodeError::from)?;
        let q = mf.skeleton.joints[joint::PELVIS];
        t.world_from_cpf[f] = body.cpf.world_from_cpf(&mf.skeleton);
        t.markers[f] = mf.markers;
        t.pelvis_xy[f] = DVec2::new(q.x, q.y);
    }
    Ok(())
}

/// Frames either side over which [`AgentTrack::follow_floor`] takes the largest lift a frame
/// needs and averages it (0.1 s at 40 Hz).
pub(crate) const FLOOR_FOLLOW_FRAMES: usize = 4;

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
pub fn run_crowd_with_activities(
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
                let mut track = a.finish(frames, &settings.walker)?;
                track.follow_floor(&world.map);
                // Sitting down, seated and standing up, the pelvis is over its seat.
                let seated = |f: usize| {
                    track.activity_segments.iter().any(|s| {
                        s.activity == Activity::Sit
                            && s.phase != Phase::Approach
                            && (s.start_frame..s.end_frame).contains(&f)
                    })
                };
                track.pelvis_off_floor_frames = (1..track.pelvis_xy.len())
                    .filter(|&f| !seated(f))
                    .filter(|&f| {
                        path_leaves_floor(&world.map, track.pelvis_xy[f - 1], track.pelvis_xy[f])
                    })
                    .count();
                Ok(track)
            })
            .collect::<Result<_, CrowdError>>()?,
    })
}
