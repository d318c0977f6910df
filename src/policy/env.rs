//! The vectorised locomotion environment: `B` episodes stepped together, one primitive each
//! per step, all decoded in one batch. The same code serves training, the sampling controller
//! and evaluation.
//!
//! An episode (EgoGen's box environment): a [`BoxScene`] — or, for configured shares of
//! episodes, a procedural floor plan ([`RoomScene`]: rooms, doorways, furniture) or a
//! [`CrossingScene`], where another person crosses the path as a moving 2D box
//! that the rays see and the penetration test counts, on the episode's clock — a mocap seed
//! (two frames of a training primitive) placed at the start facing the goal within ±`seed_yaw_jitter_rad`,
//! the floor at z = 0. A step decodes the latent, judges the primitive and takes it by the
//! walker's step every walker shares (`walker::step`: the reward of [`crate::walker::reward`]),
//! and ends the episode on success, on penetration (when `terminate_on_penetration`), on a
//! non-finite primitive, or after `walker.max_primitives_per_goal` (a timeout is terminal, as in EgoGen).
//! Finished episodes are replaced by the next episode at once; episode `n` of an
//! environment with `episode_base` b is drawn from a generator seeded by `(b, n)` alone, so
//! runs are deterministic and held-out bases never meet training ones.
//!
//! The observation is the walker's ([`crate::walker::state`]), on the episode's clock.

use std::sync::Arc;

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::body::{joint, BodyParams, POSE_DIM};
use crate::math::random::uniform_open01;
use crate::math::Vec3;
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::tensor_body::RigGeometry;
use crate::motion::cvae::{BodyContext, DecodedPrimitive, MotionModel, PrimitiveSeed};
use crate::motion::primitive::SEED_FRAMES;
use crate::scene::generated::box_scene::{BoxParams, BoxScene, BoxSceneSettings};
use crate::scene::generated::crossing_scene::{CrossingParams, CrossingScene, CrossingSettings};
use crate::scene::generated::room_scene::{RoomParams, RoomScene, RoomSettings};
use crate::scene::{
    blocked_cells_in_box, guide_aim_remembered, Guide, MovingObstacle, Obstacle2, PathField,
    SceneSdf, SeenMap, StartGoal, WalkableMap,
};
use crate::sensing::{EgoSensor, SensingSpec, Sensor};
use crate::walker::controller::{Controller, Sight};
use crate::walker::pose_prior::PosePrior;
use crate::walker::reward::{Judged, Limits, RewardWeights, SceneTest, Situation, WeightChanges};
use crate::walker::state::{
    frame_time_s, memory_scan, place_seed, seen_ahead, SeedView, Surroundings, Totals, Walker,
};
use crate::walker::step::{
    choose_primitive, finite_reward, Judge, Proposal, SceneCheck, StepContext,
};
use crate::walker::{ObsLayout, SeedBank, WalkerSettings};

/// Seed placements tried before an episode starts even with blocked cells under the body
/// (a start too near a wall for every seed).
const MAX_RESET_TRIES: usize = 100;

/// Settings of the environment (defaults: EgoGen's box pretraining).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvSettings {
    pub scene: BoxSceneSettings,
    /// Crossing scenes (another person walking across the path) and their share of episodes.
    pub crossing: CrossingSettings,
    /// Procedural floor plans (rooms, doorways, furniture) and their share of episodes.
    pub rooms: RoomSettings,
    pub weights: RewardWeights,
    /// Changes to `weights` in box-scene episodes (e.g. a stronger cost for looking off the
    /// goal where a box stands in the open). Nothing given: `weights`.
    pub box_weights: WeightChanges,
    /// Changes to `weights` in the indoor episodes, floor plans and the fixed scene's pairs
    /// (e.g. a pace bonus where paths bend round walls). Nothing given: `weights`.
    pub indoor_weights: WeightChanges,
    /// How the walker of every episode steps (`[stages.env.walker]`, the one schema of
    /// [`WalkerSettings`]; keys left out are the paper's, [`WalkerSettings::PAPER`]): the goal
    /// reached within `success_m`, an episode timing out after `max_primitives_per_goal`
    /// primitives (EgoGen's box scenes: 11), the scene tested at every frame or at a
    /// primitive's end, the others seen ahead (`anticipate_people`), the guide round what hides
    /// the goal (`guide_*`; with [`Self::guide_indoors_only`], indoor episodes alone). An
    /// episode takes its controller's best proposal as it is and writes no motion:
    /// `penetration_redraws`, `smooth_joins` and `steady_head` stay off (training configs are
    /// refused otherwise).
    #[serde(deserialize_with = "paper_walker")]
    pub walker: WalkerSettings,
    /// Evaluation as the paper's tables: `Some(r)` ends an episode (and pays the success
    /// term) only when the pelvis comes within `r` m, and an episode that times out within
    /// `success_m` still succeeds — walks go on to EgoGen's goal threshold and are scored at
    /// the tables' radius. `None` (default): both at `success_m`.
    pub arrival_m: Option<f64>,
    /// End the episode when the body penetrates (fine-tuning).
    pub terminate_on_penetration: bool,
    /// Blocked cells in the body's 2D box beyond which it penetrates (paper Eq. 7: 3).
    pub penetration_cells: usize,
    /// Whether a body marker inside another person's box in any frame of a primitive
    /// penetrates too (Eq. 7 looks at the primitive's last frame only, and a person crossing
    /// at 1 m/s moves 0.45 m within one); false: Eq. 7 alone, as EgoGen.
    pub people_every_frame: bool,
    /// Whether a body marker inside a box scene's box in any frame of a primitive penetrates
    /// too (the eval's penetration measure; Eq. 7 looks at the primitive's last frame only);
    /// false: Eq. 7 alone, as EgoGen.
    pub box_every_frame: bool,
    /// With the guide on: only indoor episodes (floor plans and the fixed scene's pairs) are
    /// guided; box scenes and crossings walk to their goals unguided, as the paper's tables
    /// evaluate them. false: every episode.
    pub guide_indoors_only: bool,
    /// Largest angle between the seed's facing and the goal direction (rad; EgoGen's box
    /// environment: 0.2π).
    pub seed_yaw_jitter_rad: f64,
    /// Whether indoor episodes (floor plans and the fixed scene's pairs) pay the goal term by
    /// the walking distance round walls (`scene::PathField`), orientation and attention facing
    /// the way it leads, instead of by the straight distance (not EgoGen's: a training signal
    /// for goals behind walls; observations, success and evaluation measures stay straight).
    pub goal_by_path: bool,
    /// Whether a primitive that penetrates earns no progress towards the goal (its goal term
    /// at most 0): paid along the way round walls, one step through a wall would otherwise
    /// gain the whole way round at once. false: the goal term as measured, as EgoGen.
    pub no_progress_through_walls: bool,
    /// With a fixed scene: the share of episodes that walk one of its pairs (drawn at random),
    /// the others box scenes and crossings as without one; 1 walks only its pairs, in turn.
    pub fixed_share: f64,
    /// Primitives before an episode in the fixed scene times out (EgoGen's apartment: 13);
    /// `None`: `walker.max_primitives_per_goal`.
    pub fixed_max_primitives: Option<usize>,
    /// With N > 0, penetration in a fixed scene with a 3D SDF is paper Eq. 11 on N body
    /// vertices ([`crate::walker::reward::SceneTest`]) instead of Eq. 7 (EgoGen's apartment): the
    /// termination and the penetration reward term. 0: Eq. 7 everywhere.
    pub scene_test_vertices: usize,
    /// With `scene_test_vertices`: Eq. 7's cells still count there too, a primitive penetrating
    /// when either test says so.
    pub scene_test_keeps_cells: bool,
    /// With M > 0, an indoor episode (a floor plan or a pair of the fixed scene) has time for
    /// its way round walls: at least `way round / M` primitives (e.g. 7/13 m: the time 13
    /// primitives give a 7 m straight walk), never fewer than its own limit. 0: the limit
    /// alone, as EgoGen.
    pub time_by_way_round_m: f64,
}

impl Default for EnvSettings {
    fn default() -> Self {
        Self {
            scene: BoxSceneSettings::default(),
            crossing: CrossingSettings::default(),
            rooms: RoomSettings::default(),
            weights: RewardWeights::default(),
            box_weights: WeightChanges::default(),
            indoor_weights: WeightChanges::default(),
            walker: WalkerSettings::PAPER,
            arrival_m: None,
            terminate_on_penetration: false,
            penetration_cells: crate::walker::reward::EQ7_PENETRATION_CELLS,
            people_every_frame: false,
            box_every_frame: false,
            guide_indoors_only: false,
            seed_yaw_jitter_rad: 0.2 * std::f64::consts::PI,
            goal_by_path: false,
            no_progress_through_walls: false,
            fixed_share: 1.0,
            fixed_max_primitives: None,
            scene_test_vertices: 0,
            scene_test_keeps_cells: false,
            time_by_way_round_m: 0.0,
        }
    }
}

/// `[stages.env.walker]` over the paper's preset.
fn paper_walker<'de, D: serde::Deserializer<'de>>(d: D) -> Result<WalkerSettings, D::Error> {
    WalkerSettings::over(WalkerSettings::PAPER, d)
}

/// Where an episode walks: its walkable map, the obstacle of a box scene, start and goal.
#[derive(Debug, Clone)]
struct Course {
    map: Arc<WalkableMap>,
    obstacle: Option<Obstacle2>,
    /// Obstacles that move, on the episode's clock.
    moving: Vec<MovingObstacle>,
    start: DVec2,
    goal: DVec2,
    /// What was drawn: a box scene, or a pair of a fixed scene.
    box_params: Option<BoxParams>,
    crossing: Option<CrossingParams>,
    rooms: Option<RoomParams>,
    pair: Option<usize>,
    /// Primitives before the episode times out.
    max_primitives: usize,
    /// The scene's 3D SDF, where Eq. 11 is measured.
    sdf: Option<Arc<SceneSdf>>,
    /// The walking distance to the goal, with [`EnvSettings::goal_by_path`] indoors.
    goal_field: Option<Arc<PathField>>,
    /// The walking distance from start to goal, found once when first asked
    /// ([`Course::way_round_m`]).
    way_round: std::sync::OnceLock<Option<f64>>,
}

/// A fixed scene (e.g. the apartment) and the start/goal pairs its episodes walk, in turn.
#[derive(Debug, Clone)]
pub struct FixedScene {
    pub map: Arc<WalkableMap>,
    pub pairs: Vec<StartGoal>,
    /// The scene's 3D SDF, where scene penetration is measured (paper Eq. 11; evaluation
    /// only: posing and looking up every vertex of every frame made the apartment evaluation
    /// about 30× slower, docs/POLICY.md).
    pub sdf: Option<Arc<SceneSdf>>,
}

/// Where an episode walks, for pictures: its map, its still and moving obstacles (on the
/// episode's clock), its start and goal.
#[derive(Debug, Clone)]
pub struct CourseView {
    pub map: Arc<WalkableMap>,
    pub obstacle: Option<Obstacle2>,
    pub moving: Vec<MovingObstacle>,
    pub start: DVec2,
    pub goal: DVec2,
}

/// One episode in progress.
#[derive(Debug, Clone)]
struct Episode {
    id: u64,
    course: Course,
    walker: Walker,
    /// What the walker has seen, where its guide plans on that ([`WalkerSettings::guide_memory`]).
    seen: Option<SeenMap>,
}

impl Course {
    /// Whether the course is indoors: a floor plan or a pair of the fixed scene.
    fn indoors(&self) -> bool {
        self.rooms.is_some() || self.pair.is_some()
    }

    /// The walking distance from the start to the goal round what blocks walking on the map
    /// (indoors only: a box scene's box and a crossing's person are not on the map).
    fn way_round_m(&self) -> Option<f64> {
        *self.way_round.get_or_init(|| {
            if !self.indoors() {
                return None;
            }
            match &self.goal_field {
                Some(f) => f.at(self.start),
                None => PathField::to_goal(&self.map, self.goal)?.at(self.start),
            }
        })
    }

    fn surroundings(&self) -> Surroundings<'_> {
        Surroundings {
            map: &self.map,
            obstacle: self.obstacle.as_ref(),
            moving: &self.moving,
        }
    }
}

/// An episode in progress as data (checkpoints of training).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EpisodeSnapshot {
    id: u64,
    #[serde(default)]
    scene: Option<BoxParams>,
    #[serde(default)]
    crossing: Option<CrossingParams>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rooms: Option<RoomParams>,
    #[serde(default)]
    pair: Option<usize>,
    /// The seed frames' pose (165) and translation (3).
    frames: Vec<Vec<f64>>,
    steps: usize,
    distance_m: f64,
    start_distance_m: f64,
    totals: Totals,
    /// What the walker has seen ([`SeenMap::to_bytes`]), where its guide plans on that.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    seen: Option<Vec<u8>>,
}

impl EpisodeSnapshot {
    /// The seed frames of the episode's next primitive: pose (165) and translation (3) each.
    pub fn seed_frames(&self) -> &[Vec<f64>] {
        &self.frames
    }
}

/// All episodes in progress and the next episode's number.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EnvSnapshot {
    pub episode_base: u64,
    pub next_episode: u64,
    pub episodes: Vec<EpisodeSnapshot>,
}

/// How an episode ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    Success,
    Penetration,
    Timeout,
    /// The decoder produced a non-finite primitive.
    Failure,
}

/// A finished episode.
#[derive(Debug, Clone, Serialize)]
pub struct EpisodeSummary {
    pub id: u64,
    pub ending: Ending,
    pub primitives: usize,
    pub start_distance_m: f64,
    pub final_distance_m: f64,
    /// Sum of rewards.
    pub reward: f64,
    /// Mean foot contact (3-D, Eq. 12) over the primitives.
    pub contact: f64,
    /// Mean cos(view, goal direction) at primitive ends.
    pub view_cos: f64,
    /// cos(view, goal direction) at the end of each primitive, in order.
    pub view_cos_each: Vec<f64>,
    /// Their mean without the arrival (an episode's last primitive when it succeeds), where
    /// the pelvis stands centimetres from the goal and the direction to it is noise; NaN when
    /// the first primitive arrives.
    pub view_cos_walking: f64,
    /// Angle between the view and the direction of travel, each primitive that travelled
    /// (degrees; [`crate::walker::reward::Judged::view_off_travel_rad`]).
    pub view_off_travel_deg: Vec<f64>,
    /// Share of the new frames in which a body marker stood inside the obstacle.
    pub penetration_share: f64,
    /// Horizontal pelvis path length over time (m/s).
    pub speed_m_s: f64,
    /// Share of the new frames penetrating the scene by paper Eq. 11, and the most body
    /// vertices inside it in a frame (0 where the scene has no 3D SDF).
    pub scene_penetration_share: f64,
    pub scene_vertices_inside_max: usize,
    /// New frames whose pelvis path passed over a cell that is not walkable: through a wall,
    /// furniture or a closed doorway ([`crate::walker::reward::path_leaves_floor`]).
    pub pelvis_off_floor_frames: usize,
    /// The pelvis's floor position at the end (m, world).
    pub end_xy: [f64; 2],
    /// The walking distance from the start to the goal round what blocks walking on the
    /// course's map (m; `scene::PathField`: 8-connected 0.1 m cells, a lower bound on a walk
    /// that keeps a body's width off the walls). Indoor courses, when the environment measures
    /// it ([`PolicyEnv::measuring_way_round`]); `None` otherwise or where the goal cannot be
    /// reached on the map.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub way_round_m: Option<f64>,
    /// The mean over its primitives of each one's largest pose embedding norm (EgoGen's
    /// ‖VP‖₂ role, [`crate::walker::PosePrior::embedding_norm`]; comparable with mocap primitives').
    pub pose_norm_max: f64,
}

impl EpisodeSummary {
    /// The summary of a walk that ended.
    pub fn of(id: u64, ending: Ending, w: &Walker) -> Self {
        let n = w.steps.max(1) as f64;
        Self {
            id,
            ending,
            primitives: w.steps,
            start_distance_m: w.start_distance_m,
            final_distance_m: w.distance_m,
            reward: w.totals.reward,
            contact: w.totals.contact / n,
            view_cos: w.totals.view_cos / n,
            view_cos_each: w.totals.view_cos_each.clone(),
            view_cos_walking: mean_before_arrival(&w.totals.view_cos_each, ending),
            view_off_travel_deg: w
                .totals
                .view_off_travel_rad
                .iter()
                .map(|a| a.to_degrees())
                .collect(),
            penetration_share: w.totals.frames_in_obstacle as f64 / w.totals.frames.max(1) as f64,
            speed_m_s: w.speed_m_s(),
            scene_penetration_share: w.totals.scene_penetrating_frames as f64
                / w.totals.frames.max(1) as f64,
            scene_vertices_inside_max: w.totals.scene_vertices_inside_max,
            pelvis_off_floor_frames: w.totals.pelvis_off_floor_frames,
            end_xy: w.view.pelvis.to_array(),
            pose_norm_max: w.totals.pose_norm_max_sum / n,
            way_round_m: None,
        }
    }
}

/// Mean of a measure taken at each primitive's end, without the arrival (the last primitive
/// of an episode that succeeded); NaN when nothing is left.
pub(crate) fn mean_before_arrival(each: &[f64], ending: Ending) -> f64 {
    let walking = match ending {
        Ending::Success => &each[..each.len().saturating_sub(1)],
        _ => each,
    };
    match walking.len() {
        0 => f64::NAN,
        k => walking.iter().sum::<f64>() / k as f64,
    }
}

/// One candidate primitive for one episode, judged but not yet taken.
#[derive(Debug, Clone)]
pub struct Candidate {
    pub env: usize,
    pub latent: Vec<f32>,
    /// `None`: the decoder produced a non-finite primitive.
    pub primitive: Option<DecodedPrimitive>,
    pub judged: Option<Judged>,
    /// The reward as a walker adds it up (0 where not finite).
    pub reward: f64,
    /// The reward as weighed, what a controller ranks candidates by (−∞ where the primitive
    /// did not decode).
    pub score: f64,
}

/// What a step returns.
#[derive(Debug, Clone, Default)]
pub struct StepOutput {
    /// `[B]` rewards.
    pub reward: Vec<f32>,
    /// `[B]`: whether the episode ended with this step (the observation is already the next
    /// episode's).
    pub done: Vec<bool>,
    /// Episodes that ended.
    pub finished: Vec<EpisodeSummary>,
}

/// Why the environment could not be built or stepped.
#[derive(Debug, thiserror::Error)]
pub enum EnvError {
    #[error("the seed bank is empty")]
    NoSeeds,
    #[error("{found} latent values for {envs} environments × {per} candidates × {dim}")]
    LatentShape {
        found: usize,
        envs: usize,
        per: usize,
        dim: usize,
    },
    #[error("environment snapshot: {0}")]
    Snapshot(String),
    #[error("this controller acts through a policy: the environment steps a policy through its batched actor")]
    NeedsPolicy,
    #[error(transparent)]
    Decode(#[from] DecodeError),
}

/// The environment (see the module docs).
pub struct PolicyEnv<'m> {
    model: &'m MotionModel,
    body: &'m BodyContext<'m>,
    bank: &'m SeedBank,
    prior: &'m PosePrior,
    fixed: Option<&'m FixedScene>,
    /// The floor of every crossing scene, built once.
    crossing_floor: Arc<WalkableMap>,
    pub settings: EnvSettings,
    sensor: Sensor,
    foot_markers: Vec<usize>,
    /// Eq. 11 on a vertex subset, where training tests the fixed scene with it.
    scene_test: Option<SceneTest>,
    episodes: Vec<Episode>,
    episode_base: u64,
    next_episode: u64,
    /// Whether finished episodes' summaries carry their way round walls (evaluations).
    measure_way_round: bool,
}

/// The generator of episode `id` under `base`.
fn episode_rng(base: u64, id: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(base.rotate_left(32) ^ id.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// What an environment is built from: the motion model, the body, the seeds episodes start
/// from, the pose prior, and the fixed scene (box scenes, crossings and floor plans when
/// `None`). Training, its validation and the held-out evaluations build theirs from one.
#[derive(Clone, Copy)]
pub struct EnvParts<'m> {
    pub model: &'m MotionModel,
    pub body: &'m BodyContext<'m>,
    pub bank: &'m SeedBank,
    pub prior: &'m PosePrior,
    pub fixed: Option<&'m FixedScene>,
}

impl<'m> EnvParts<'m> {
    /// `envs` episodes at a time under `episode_base` ([`PolicyEnv::with_scene`]).
    pub fn env(
        &self,
        settings: EnvSettings,
        envs: usize,
        episode_base: u64,
    ) -> Result<PolicyEnv<'m>, EnvError> {
        PolicyEnv::with_scene(
            self.model,
            self.body,
            self.bank,
            self.prior,
            self.fixed,
            settings,
            envs,
            episode_base,
        )
    }
}

impl<'m> PolicyEnv<'m> {
    /// `envs` episodes, numbered from 0 under `episode_base`.
    pub fn new(
        model: &'m MotionModel,
        body: &'m BodyContext<'m>,
        bank: &'m SeedBank,
        prior: &'m PosePrior,
        settings: EnvSettings,
        envs: usize,
        episode_base: u64,
    ) -> Result<Self, EnvError> {
        Self::with_scene(model, body, bank, prior, None, settings, envs, episode_base)
    }

    /// The same in a fixed scene (its `settings.scene` unused): episode `n` walks pair
    /// `n mod pairs`.
    #[allow(clippy::too_many_arguments)]
    pub fn with_scene(
        model: &'m MotionModel,
        body: &'m BodyContext<'m>,
        bank: &'m SeedBank,
        prior: &'m PosePrior,
        fixed: Option<&'m FixedScene>,
        settings: EnvSettings,
        envs: usize,
        episode_base: u64,
    ) -> Result<Self, EnvError> {
        if bank.seeds.is_empty() {
            return Err(EnvError::NoSeeds);
        }
        if fixed.is_some_and(|f| f.pairs.is_empty()) {
            return Err(EnvError::Snapshot(
                "the fixed scene has no start/goal pairs".into(),
            ));
        }
        let mut env = Self {
            model,
            body,
            bank,
            prior,
            fixed,
            crossing_floor: Arc::new(CrossingScene::floor(&settings.crossing)),
            settings,
            sensor: Sensor::default(),
            foot_markers: RigGeometry::new(body.model, &body.betas)
                .map_err(DecodeError::from)?
                .foot_markers,
            scene_test: (settings.scene_test_vertices > 0)
                .then(|| SceneTest::new(body.model, settings.scene_test_vertices)),
            episodes: Vec::with_capacity(envs),
            episode_base,
            next_episode: 0,
            measure_way_round: false,
        };
        for _ in 0..envs {
            let e = env.start_episode()?;
            env.episodes.push(e);
        }
        Ok(env)
    }

    /// Observes with `spec` instead of the paper's 32 rays (a policy's own sensing:
    /// [`super::net::ActorCritic::sensing`]).
    pub fn with_sensing(mut self, spec: &SensingSpec) -> Self {
        self.sensor = spec.sensor();
        self
    }

    /// Summaries of finished indoor episodes carry the walking distance from start to goal
    /// round walls ([`EpisodeSummary::way_round_m`]; a few milliseconds per episode, so
    /// evaluations only).
    pub fn measuring_way_round(mut self) -> Self {
        self.measure_way_round = true;
        self
    }

    /// Where the parts of this environment's observations lie.
    pub fn obs_layout(&self) -> ObsLayout {
        ObsLayout {
            sensing_per_frame: self.sensor.dim(),
        }
    }

    /// Number of parallel episodes.
    pub fn len(&self) -> usize {
        self.episodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.episodes.is_empty()
    }

    /// Latent size of the motion model.
    pub fn latent_dim(&self) -> usize {
        self.model.latent_dim()
    }

    /// The reward weights of an episode on `course`.
    fn weights(&self, course: &Course) -> RewardWeights {
        let changes = if course.indoors() {
            &self.settings.indoor_weights
        } else if course.box_params.is_some() {
            &self.settings.box_weights
        } else {
            return self.settings.weights;
        };
        changes.applied_to(self.settings.weights)
    }

    fn box_course(&self, scene: BoxScene) -> Course {
        Course {
            map: Arc::new(scene.map),
            obstacle: Some(scene.obstacle),
            moving: Vec::new(),
            start: scene.start,
            goal: scene.goal,
            box_params: Some(scene.params),
            crossing: None,
            rooms: None,
            pair: None,
            max_primitives: self.settings.walker.max_primitives_per_goal,
            sdf: None,
            goal_field: None,
            way_round: Default::default(),
        }
    }

    fn room_course(&self, scene: RoomScene) -> Course {
        self.timed_for_way_round(Course {
            obstacle: None,
            moving: Vec::new(),
            start: scene.start,
            goal: scene.goal,
            box_params: None,
            crossing: None,
            rooms: Some(scene.params),
            pair: None,
            max_primitives: self.settings.rooms.max_primitives,
            sdf: None,
            goal_field: self.goal_field(&scene.map, scene.goal),
            way_round: Default::default(),
            map: Arc::new(scene.map),
        })
    }

    fn crossing_course(&self, scene: CrossingScene) -> Course {
        Course {
            map: self.crossing_floor.clone(),
            obstacle: None,
            moving: scene.movers,
            start: scene.start,
            goal: scene.goal,
            box_params: None,
            crossing: Some(scene.params),
            rooms: None,
            pair: None,
            max_primitives: self.settings.walker.max_primitives_per_goal,
            sdf: None,
            goal_field: None,
            way_round: Default::default(),
        }
    }

    fn fixed_course(&self, f: &FixedScene, pair: usize) -> Course {
        self.timed_for_way_round(Course {
            map: f.map.clone(),
            obstacle: None,
            moving: Vec::new(),
            start: f.pairs[pair].start,
            goal: f.pairs[pair].goal,
            box_params: None,
            crossing: None,
            rooms: None,
            pair: Some(pair),
            max_primitives: self
                .settings
                .fixed_max_primitives
                .unwrap_or(self.settings.walker.max_primitives_per_goal),
            sdf: f.sdf.clone(),
            goal_field: self.goal_field(&f.map, f.pairs[pair].goal),
            way_round: Default::default(),
        })
    }

    /// An indoor course with time for its way round walls, when the settings ask for it
    /// ([`EnvSettings::time_by_way_round_m`]).
    fn timed_for_way_round(&self, mut course: Course) -> Course {
        let per_primitive = self.settings.time_by_way_round_m;
        if per_primitive > 0.0 {
            if let Some(way) = course.way_round_m() {
                let needed = (way / per_primitive).ceil();
                if needed.is_finite() && needed > course.max_primitives as f64 {
                    course.max_primitives = needed as usize;
                }
            }
        }
        course
    }

    /// The walking-distance field of an indoor goal, when the settings ask for one.
    fn goal_field(&self, map: &WalkableMap, goal: DVec2) -> Option<Arc<PathField>> {
        self.settings
            .goal_by_path
            .then(|| PathField::to_goal(map, goal).map(Arc::new))
            .flatten()
    }

    /// The course of episode `id`: the next pair of the fixed scene (or, with a fixed share
    /// below 1, a random pair for that share of episodes), else a new floor plan (with the
    /// rooms' share), else a new crossing scene (with the crossing share) or box scene.
    fn draw_course(&self, id: u64, rng: &mut ChaCha8Rng) -> Course {
        let crossing = self.settings.crossing;
        let rooms = self.settings.rooms;
        let share = self.settings.fixed_share;
        match self.fixed {
            // No draw when only the fixed scene is walked: evaluations stay as they were.
            Some(f) if share >= 1.0 => self.fixed_course(f, (id % f.pairs.len() as u64) as usize),
            Some(f) if uniform_open01(rng) < share => {
                self.fixed_course(f, (rng.next_u64() % f.pairs.len() as u64) as usize)
            }
            // No draw when there are no floor plans: runs without them stay as they were.
            _ if rooms.share > 0.0 && uniform_open01(rng) < rooms.share => {
                self.room_course(RoomScene::sample(&rooms, rng))
            }
            // No draw when there are no crossings: box-only runs stay as they were.
            _ if crossing.share > 0.0 && uniform_open01(rng) < crossing.share => {
                self.crossing_course(CrossingScene::sample(&crossing, rng))
            }
            _ => self.box_course(BoxScene::sample(&self.settings.scene, rng)),
        }
    }

    fn start_episode(&mut self) -> Result<Episode, DecodeError> {
        let id = self.next_episode;
        self.next_episode += 1;
        let mut rng = episode_rng(self.episode_base, id);
        let rest_pelvis = self.body.shaped.rest_joints[joint::PELVIS];
        let mut tries = 0;
        loop {
            let scene = self.draw_course(id, &mut rng);
            let floor_z = scene.map.floor_z_m;
            let (frames, floor) =
                &self.bank.seeds[(rng.next_u64() % self.bank.seeds.len() as u64) as usize];
            let to_goal = scene.goal - scene.start;
            let jitter = self.settings.seed_yaw_jitter_rad * (2.0 * uniform_open01(&mut rng) - 1.0);
            let facing = to_goal.y.atan2(to_goal.x) + jitter;
            let seed = place_seed(frames, *floor, scene.start, facing, floor_z, rest_pelvis);
            let view = SeedView::new(self.body, seed)?;
            // As EgoGen's reset: no blocked cell under the seed body.
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for m in view.markers.iter().flatten() {
                lo = lo.min(DVec2::new(m.x, m.y));
                hi = hi.max(DVec2::new(m.x, m.y));
            }
            tries += 1;
            if tries < MAX_RESET_TRIES
                && blocked_cells_in_box(&scene.map, (lo + hi) * 0.5, (hi - lo) * 0.5, 0.0) > 0
            {
                continue;
            }
            let walker = Walker::new(view, scene.goal);
            let seen = self.remembers(&scene).then(|| {
                let mut seen = SeenMap::unseen(&scene.map);
                walker.look(
                    &memory_scan(&self.sensor),
                    &scene.map,
                    scene.obstacle.as_slice(),
                    &mut seen,
                );
                seen
            });
            return Ok(Episode {
                id,
                walker,
                course: scene,
                seen,
            });
        }
    }

    /// Observations of all episodes, `[B × D]` ([`Self::obs_layout`]).
    pub fn observations(&self) -> Vec<f32> {
        let d = self.obs_layout().dim();
        let mut out = vec![0f32; self.episodes.len() * d];
        out.par_chunks_mut(d)
            .zip(&self.episodes)
            .for_each(|(o, e)| self.observe_into(e, o));
        out
    }

    /// The guide's lookahead on a course (0: unguided).
    fn guide_lookahead_m(&self, course: &Course) -> f64 {
        if self.settings.guide_indoors_only && !course.indoors() {
            0.0
        } else {
            self.settings.walker.guide_lookahead_m
        }
    }

    /// Whether the walker of a course remembers what it sees: its guide plans on it.
    fn remembers(&self, course: &Course) -> bool {
        self.settings.walker.guide_memory && self.guide_lookahead_m(course) > 0.0
    }

    fn observe_into(&self, e: &Episode, out: &mut [f32]) {
        let w = &e.walker;
        let goal = guide_aim_remembered(
            e.seen.as_ref(),
            &e.course.map,
            e.course.obstacle.as_slice(),
            w.view.pelvis,
            e.course.goal,
            &Guide {
                lookahead_m: self.guide_lookahead_m(&e.course),
                ..self.settings.walker.guide()
            },
        );
        let t0_s = frame_time_s(w.steps, 0);
        let (around, ahead) = self.seen_around(e, t0_s);
        let around = Surroundings {
            moving: ahead.as_deref().unwrap_or(around.moving),
            ..around
        };
        w.observe_into(
            self.body,
            &self.sensor,
            goal,
            &around,
            t0_s,
            1.0 - w.steps as f64 / e.course.max_primitives as f64,
            out,
        );
    }

    /// Decodes `per` candidate latents for every episode (`[B × per × L]`, episode-major) in
    /// one batch and judges them; nothing changes until [`Self::commit`].
    pub fn propose(&self, latents: &[f32], per: usize) -> Result<Vec<Candidate>, EnvError> {
        let l = self.latent_dim();
        let b = self.episodes.len();
        if latents.len() != b * per * l {
            return Err(EnvError::LatentShape {
                found: latents.len(),
                envs: b,
                per,
                dim: l,
            });
        }
        let seeds: Vec<PrimitiveSeed> = self
            .episodes
            .iter()
            .flat_map(|e| std::iter::repeat_n(e.walker.view.seed.clone(), per))
            .collect();
        let zs: Vec<Vec<f32>> = latents.chunks(l).map(<[f32]>::to_vec).collect();
        let decoded = self.model.decode_each(self.body, &seeds, &zs)?;
        decoded
            .into_par_iter()
            .zip(zs)
            .enumerate()
            .map(|(i, (d, latent))| {
                let env = i / per.max(1);
                let e = &self.episodes[env];
                match d {
                    Ok(p) => {
                        let (j, reward) = self.judge(e).judge(self.body, &p, &self.situation(e))?;
                        Ok(Candidate {
                            env,
                            latent,
                            primitive: Some(p),
                            judged: Some(j),
                            score: reward,
                            reward: finite_reward(reward),
                        })
                    }
                    Err(DecodeError::NonFinite { .. }) => Ok(Candidate {
                        env,
                        latent,
                        primitive: None,
                        judged: None,
                        reward: 0.0,
                        score: f64::NEG_INFINITY,
                    }),
                    Err(e) => Err(EnvError::Decode(e)),
                }
            })
            .collect()
    }

    /// The judge of an episode's primitives: the environment's limits, the course's weights,
    /// its scene test.
    fn judge<'a>(&'a self, e: &'a Episode) -> Judge<'a> {
        let scene = match (e.course.sdf.as_deref(), &self.scene_test) {
            // Training: the fast test decides (beside the cells, if kept).
            (Some(sdf), Some(test)) => SceneCheck::Fast {
                sdf,
                test,
                keeps_cells: self.settings.scene_test_keeps_cells,
            },
            // Evaluation: every vertex of every frame, measured.
            (Some(sdf), None) => SceneCheck::Measure { sdf },
            (None, _) => SceneCheck::Cells,
        };
        Judge {
            limits: Limits {
                success_m: self
                    .settings
                    .arrival_m
                    .unwrap_or(self.settings.walker.success_m),
                penetration_cells: self.settings.penetration_cells,
                people_every_frame: self.settings.people_every_frame,
                box_every_frame: self.settings.box_every_frame,
                scene_every_frame: self.settings.walker.scene_every_frame,
            },
            weights: self.weights(&e.course),
            primitives_left: e.course.max_primitives.saturating_sub(e.walker.steps + 1),
            foot_markers: &self.foot_markers,
            prior: self.prior,
            scene,
            no_progress_through_walls: self.settings.no_progress_through_walls,
        }
    }

    /// Where an episode's walker stands before its next primitive.
    fn situation<'a>(&self, e: &'a Episode) -> Situation<'a> {
        Situation {
            goal_field: e.course.goal_field.as_deref(),
            ..e.walker.situation(
                &e.course.surroundings(),
                e.course.goal,
                frame_time_s(e.walker.steps, 0),
            )
        }
    }

    /// The candidate each episode takes of `candidates` (`per` each, episode-major, as
    /// [`Self::propose`] made them), by the one rule every walker chooses by
    /// (`walker::step::choose_primitive`, no redraws); an episode none of whose candidates
    /// decoded takes its first (and fails).
    pub fn choose(&self, candidates: Vec<Candidate>) -> Result<Vec<Candidate>, EnvError> {
        let mut per_episode: Vec<Vec<Candidate>> =
            (0..self.episodes.len()).map(|_| Vec::new()).collect();
        for c in candidates {
            per_episode[c.env].push(c);
        }
        per_episode
            .into_iter()
            .enumerate()
            .map(|(env, mut candidates)| {
                let e = &self.episodes[env];
                let first_failed = candidates
                    .iter()
                    .position(|c| c.primitive.is_none())
                    .map(|k| candidates[k].clone());
                let proposals: Vec<Proposal> = candidates
                    .drain(..)
                    .filter_map(|c| {
                        Some(Proposal {
                            latent: c.latent,
                            primitive: c.primitive?,
                            judged: c.judged?,
                            reward: c.reward,
                            score: c.score,
                        })
                    })
                    .collect();
                let (judge, situation) = (self.judge(e), self.situation(e));
                let ctx = StepContext {
                    model: self.model,
                    body: self.body,
                    seed: &e.walker.view.seed,
                    judge: &judge,
                    situation: &situation,
                    pelvis: e.walker.view.pelvis,
                };
                match choose_primitive(&ctx, proposals, None)? {
                    Some(c) => Ok(Candidate {
                        env,
                        latent: c.latent,
                        primitive: Some(c.primitive),
                        judged: Some(c.judged),
                        reward: c.reward,
                        score: c.reward,
                    }),
                    None => first_failed.ok_or(EnvError::LatentShape {
                        found: 0,
                        envs: self.episodes.len(),
                        per: 0,
                        dim: self.latent_dim(),
                    }),
                }
            })
            .collect()
    }

    /// Takes one candidate per episode (in episode order), ends and restarts the episodes that
    /// are over.
    pub fn commit(&mut self, chosen: Vec<Candidate>) -> Result<StepOutput, EnvError> {
        let mut out = StepOutput {
            reward: Vec::with_capacity(chosen.len()),
            done: Vec::with_capacity(chosen.len()),
            finished: Vec::new(),
        };
        let scan = memory_scan(&self.sensor);
        for (i, c) in chosen.into_iter().enumerate() {
            debug_assert_eq!(c.env, i);
            let max_primitives = self.episodes[i].course.max_primitives;
            let terminate_on_penetration = self.settings.terminate_on_penetration;
            let e = &mut self.episodes[i];
            let w = &mut e.walker;
            let ending = match (c.primitive, c.judged) {
                (Some(p), Some(j)) => {
                    w.advance(&p, &j, c.reward);
                    if let Some(seen) = &mut e.seen {
                        w.look(&scan, &e.course.map, e.course.obstacle.as_slice(), seen);
                    }
                    if j.success {
                        Some(Ending::Success)
                    } else if j.penetrated && terminate_on_penetration {
                        Some(Ending::Penetration)
                    } else if w.steps >= max_primitives {
                        let within = self.settings.arrival_m.is_some()
                            && w.distance_m < self.settings.walker.success_m;
                        Some(if within {
                            Ending::Success
                        } else {
                            Ending::Timeout
                        })
                    } else {
                        None
                    }
                }
                _ => {
                    w.fail(c.reward);
                    Some(Ending::Failure)
                }
            };
            out.reward.push(c.reward as f32);
            out.done.push(ending.is_some());
            if let Some(ending) = ending {
                let e = &self.episodes[i];
                let mut summary = EpisodeSummary::of(e.id, ending, &e.walker);
                if self.measure_way_round {
                    summary.way_round_m = e.course.way_round_m();
                }
                out.finished.push(summary);
                self.episodes[i] = self.start_episode()?;
            }
        }
        Ok(out)
    }

    /// One step of every episode by a controller of the walker layer (`controllers[i]` for
    /// the walker of episode slot `i`, each proposing as a take's person does, drawing from
    /// `rng` in episode order), its proposals decoded in one batch, scored by the controller
    /// and chosen as [`Self::choose`] does. Every controller proposes as many latents.
    pub(crate) fn step_with(
        &mut self,
        controllers: &mut [Box<dyn Controller + '_>],
        rng: &mut ChaCha8Rng,
    ) -> Result<StepOutput, EnvError> {
        let l = self.latent_dim();
        let mut latents = Vec::new();
        let mut per = None;
        for (e, controller) in self.episodes.iter().zip(controllers.iter_mut()) {
            let w = &e.walker;
            let t0_s = frame_time_s(w.steps, 0);
            let (around, ahead) = self.seen_around(e, t0_s);
            let around = Surroundings {
                moving: ahead.as_deref().unwrap_or(around.moving),
                ..around
            };
            let sight = Sight {
                walker: w,
                body: self.body,
                sensor: &self.sensor,
                around: &around,
                standing: e.course.obstacle.as_slice(),
                goal: e.course.goal,
                t0_s,
                time_left: 1.0 - w.steps as f64 / e.course.max_primitives as f64,
                settings: &self.settings.walker,
                latent_dim: l,
            };
            let proposed = controller.propose(&sight, rng);
            let n = proposed.latents.len();
            if *per.get_or_insert(n) != n {
                return Err(EnvError::LatentShape {
                    found: n * l,
                    envs: self.episodes.len(),
                    per: per.unwrap_or(0),
                    dim: l,
                });
            }
            latents.extend(proposed.latents.into_iter().flatten());
        }
        let mut candidates = self.propose(&latents, per.unwrap_or(1))?;
        for c in &mut candidates {
            if let (Some(p), Some(j)) = (&c.primitive, &c.judged) {
                c.score = controllers[c.env].score(p, j, c.score);
            }
        }
        let chosen = self.choose(candidates)?;
        self.commit(chosen)
    }

    /// The others as an episode's walker sees them at `t0_s`: the course's surroundings, and
    /// where [`WalkerSettings::anticipate_people`] says, the moving people where they will
    /// stand when the primitive ends.
    fn seen_around<'a>(
        &self,
        e: &'a Episode,
        t0_s: f64,
    ) -> (Surroundings<'a>, Option<Vec<MovingObstacle>>) {
        let around = e.course.surroundings();
        let ahead = (self.settings.walker.anticipate_people && !around.moving.is_empty())
            .then(|| seen_ahead(around.moving, t0_s).collect());
        (around, ahead)
    }

    /// One primitive per episode from `latents` (`[B × L]`).
    pub fn step(&mut self, latents: &[f32]) -> Result<StepOutput, EnvError> {
        let c = self.propose(latents, 1)?;
        let chosen = self.choose(c)?;
        self.commit(chosen)
    }

    /// The episodes in progress as data.
    pub fn snapshot(&self) -> EnvSnapshot {
        EnvSnapshot {
            episode_base: self.episode_base,
            next_episode: self.next_episode,
            episodes: self
                .episodes
                .iter()
                .map(|e| EpisodeSnapshot {
                    id: e.id,
                    scene: e.course.box_params,
                    crossing: e.course.crossing.clone(),
                    rooms: e.course.rooms.clone(),
                    pair: e.course.pair,
                    frames: e
                        .walker
                        .view
                        .seed
                        .frames
                        .iter()
                        .map(|f| f.pose.iter().copied().chain(f.transl.to_array()).collect())
                        .collect(),
                    steps: e.walker.steps,
                    distance_m: e.walker.distance_m,
                    start_distance_m: e.walker.start_distance_m,
                    totals: e.walker.totals.clone(),
                    seen: e.seen.as_ref().map(SeenMap::to_bytes),
                })
                .collect(),
        }
    }

    /// Continues from a snapshot of an environment of the same settings and size.
    pub fn restore(&mut self, snap: &EnvSnapshot) -> Result<(), EnvError> {
        if snap.episodes.len() != self.episodes.len() || snap.episode_base != self.episode_base {
            return Err(EnvError::Snapshot(format!(
                "{} episodes under base {} saved, {} under base {} here",
                snap.episodes.len(),
                snap.episode_base,
                self.episodes.len(),
                self.episode_base
            )));
        }
        let mut episodes = Vec::with_capacity(snap.episodes.len());
        for s in &snap.episodes {
            if s.frames.len() != SEED_FRAMES || s.frames.iter().any(|f| f.len() != POSE_DIM + 3) {
                return Err(EnvError::Snapshot(format!(
                    "episode {}: seed frames of the wrong size",
                    s.id
                )));
            }
            let frames: [BodyParams; SEED_FRAMES] = std::array::from_fn(|k| {
                let f = &s.frames[k];
                BodyParams {
                    pose: std::array::from_fn(|i| f[i]),
                    transl: Vec3::new(f[POSE_DIM], f[POSE_DIM + 1], f[POSE_DIM + 2]),
                    ..BodyParams::default()
                }
            });
            let only_fixed = self.fixed.is_some() && self.settings.fixed_share >= 1.0;
            let course = match (
                s.scene,
                s.crossing.clone(),
                s.rooms.clone(),
                s.pair,
                self.fixed,
            ) {
                (Some(p), None, None, None, _) if !only_fixed => {
                    self.box_course(BoxScene::build(&self.settings.scene, p))
                }
                (None, Some(c), None, None, _) if !only_fixed => {
                    self.crossing_course(CrossingScene::build(&self.settings.crossing, c))
                }
                (None, None, Some(r), None, _) if !only_fixed => {
                    self.room_course(RoomScene::build(&self.settings.rooms, r))
                }
                (None, None, None, Some(pair), Some(f)) if pair < f.pairs.len() => {
                    self.fixed_course(f, pair)
                }
                _ => {
                    return Err(EnvError::Snapshot(format!(
                        "episode {}: its scene is not of this environment's kind",
                        s.id
                    )))
                }
            };
            let floor_z = course.map.floor_z_m;
            let view = SeedView::new(self.body, PrimitiveSeed { frames, floor_z })?;
            let remembers = self.remembers(&course);
            let seen = match (&s.seen, remembers) {
                (Some(bytes), true) => {
                    Some(SeenMap::from_bytes(&course.map, bytes).ok_or_else(|| {
                        EnvError::Snapshot(format!(
                            "episode {}: its memory does not fit its map",
                            s.id
                        ))
                    })?)
                }
                (None, false) => None,
                _ => {
                    return Err(EnvError::Snapshot(format!(
                        "episode {}: saved {} a memory, its walker here {}",
                        s.id,
                        if s.seen.is_some() { "with" } else { "without" },
                        if remembers { "remembers" } else { "does not" }
                    )))
                }
            };
            episodes.push(Episode {
                id: s.id,
                seen,
                course,
                walker: Walker {
                    view,
                    steps: s.steps,
                    distance_m: s.distance_m,
                    start_distance_m: s.start_distance_m,
                    totals: s.totals.clone(),
                },
            });
        }
        self.episodes = episodes;
        self.next_episode = snap.next_episode;
        Ok(())
    }

    /// Each episode in progress: its id and its pelvis's floor position (m, world).
    pub fn pelvis_positions(&self) -> Vec<(u64, DVec2)> {
        self.episodes
            .iter()
            .map(|e| (e.id, e.walker.view.pelvis))
            .collect()
    }

    /// Where episode `i` (of those in progress) walks, for pictures.
    pub fn course_view(&self, i: usize) -> CourseView {
        let c = &self.episodes[i].course;
        CourseView {
            map: c.map.clone(),
            obstacle: c.obstacle,
            moving: c.moving.clone(),
            start: c.start,
            goal: c.goal,
        }
    }

    /// Ids of the episodes in progress.
    pub fn episode_ids(&self) -> Vec<u64> {
        self.episodes.iter().map(|e| e.id).collect()
    }
}
