//! The vectorised locomotion environment: `B` episodes stepped together, one primitive each
//! per step, all decoded in one batch. The same code serves training, the sampling controller
//! and evaluation.
//!
//! An episode (EgoGen's box environment): a [`BoxScene`] — or, for a configured share of
//! episodes, a [`CrossingScene`], where another person crosses the path as a moving 2D box
//! that the rays see and the penetration test counts, on the episode's clock — a mocap seed
//! (two frames of a training primitive) placed at the start facing the goal within ±`seed_yaw_jitter_rad`,
//! the floor at z = 0. A step decodes the latent, judges the primitive ([`super::reward`]),
//! and ends the episode on success, on penetration (when `terminate_on_penetration`), on a
//! non-finite primitive, or after `max_primitives` (a timeout is terminal, as in EgoGen).
//! Finished episodes are replaced by the next episode at once; episode `n` of an
//! environment with `episode_base` b is drawn from a generator seeded by `(b, n)` alone, so
//! runs are deterministic and held-out bases never meet training ones.
//!
//! Observation per episode ([`OBS_DIM`] values, EgoGen's layout): for each of the two seed
//! frames the 67 markers in the seed's canonical frame and the unit vectors from each marker
//! to the goal (2 × 67 × 6); the 32-ray scan of both seed frames (2 × 32,
//! −1 + 2·hit/7 m); `1/(1 + d)` of the horizontal pelvis–goal distance; `1 − t/T`.

use std::sync::Arc;

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::box_scene::{BoxParams, BoxScene, BoxSceneSettings};
use super::crossing_scene::{CrossingParams, CrossingScene, CrossingSettings};
use super::pose_prior::PosePrior;
use super::reward::{judge, Judged, Limits, RewardWeights, Situation};
use crate::body::{joint, BodyParams, NUM_MARKERS, POSE_DIM};
use crate::math::random::uniform_open01;
use crate::math::{Affine3, Mat3, Vec3};
use crate::motion::cvae::data::PrimitiveSet;
use crate::motion::cvae::features::{frame_params, FRAME_DIM};
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::rig::RigGeometry;
use crate::motion::cvae::{
    BodyContext, CanonicalSeed, DecodedPrimitive, MotionModel, PrimitiveSeed,
};
use crate::motion::primitive::{canonical_frame, PRIMITIVE_FRAMES, PRIMITIVE_RATE_HZ, SEED_FRAMES};
use crate::scene::{blocked_cells_in_box, MovingObstacle, Obstacle2, StartGoal, WalkableMap};
use crate::sensing::{EgoPose2, EgoSensor, RayScan, RayScanSettings, SensingWorld};

/// Seed placements tried before an episode starts even with blocked cells under the body
/// (a start too near a wall for every seed).
const MAX_RESET_TRIES: usize = 100;

/// Values per seed frame of the marker state: 67 canonical positions and 67 goal directions.
pub const STATE_FRAME_DIM: usize = NUM_MARKERS * 6;
/// Rays per seed frame.
pub const RAYS: usize = 32;
/// Observation length.
pub const OBS_DIM: usize = SEED_FRAMES * (STATE_FRAME_DIM + RAYS) + 2;
/// Offset of the ray scans in an observation.
pub const OBS_RAYS_OFFSET: usize = SEED_FRAMES * STATE_FRAME_DIM;
/// Offset of `1/(1 + d)`; `1 − t/T` follows it.
pub const OBS_DIST_OFFSET: usize = OBS_RAYS_OFFSET + SEED_FRAMES * RAYS;

/// Settings of the environment (defaults: EgoGen's box pretraining).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvSettings {
    pub scene: BoxSceneSettings,
    /// Crossing scenes (another person walking across the path) and their share of episodes.
    pub crossing: CrossingSettings,
    pub weights: RewardWeights,
    /// Success radius around the goal (m, horizontal; EgoGen's 0.1).
    pub success_m: f64,
    /// Primitives before the episode times out (EgoGen's box scenes: 11).
    pub max_primitives: usize,
    /// End the episode when the body penetrates (fine-tuning).
    pub terminate_on_penetration: bool,
    /// Blocked cells in the body's 2D box beyond which it penetrates (paper Eq. 7: 3).
    pub penetration_cells: usize,
    /// Largest angle between the seed's facing and the goal direction (rad; EgoGen's box
    /// environment: 0.2π).
    pub seed_yaw_jitter_rad: f64,
}

impl Default for EnvSettings {
    fn default() -> Self {
        Self {
            scene: BoxSceneSettings::default(),
            crossing: CrossingSettings::default(),
            weights: RewardWeights::default(),
            success_m: 0.1,
            max_primitives: 11,
            terminate_on_penetration: false,
            penetration_cells: 3,
            seed_yaw_jitter_rad: 0.2 * std::f64::consts::PI,
        }
    }
}

/// Mocap seeds episodes start from: the first two frames of training primitives, canonical,
/// with the floor height in that frame.
#[derive(Debug, Clone)]
pub struct SeedBank {
    pub seeds: Vec<([BodyParams; SEED_FRAMES], f64)>,
}

impl SeedBank {
    /// The seeds of every primitive of a set.
    pub fn from_set(set: &PrimitiveSet) -> Self {
        let seeds = (0..set.len())
            .map(|i| {
                let v = set.item(i);
                (
                    std::array::from_fn(|k| {
                        frame_params(&v[k * FRAME_DIM..(k + 1) * FRAME_DIM], &[])
                    }),
                    set.floors(i)[0] as f64,
                )
            })
            .collect();
        Self { seeds }
    }

    /// Seeds given in the world (any floor height), canonicalised.
    pub fn from_world_seeds(
        body: &BodyContext,
        seeds: &[PrimitiveSeed],
    ) -> Result<Self, DecodeError> {
        let seeds = seeds
            .iter()
            .map(|s| {
                let c = CanonicalSeed::new(body, s)?;
                let frames: [BodyParams; SEED_FRAMES] =
                    std::array::from_fn(|k| c.frames[k].clone());
                Ok((frames, c.floor as f64))
            })
            .collect::<Result<_, DecodeError>>()?;
        Ok(Self { seeds })
    }
}

/// What an episode's seed frames look like to the observation.
#[derive(Debug, Clone)]
struct SeedView {
    seed: PrimitiveSeed,
    markers: [Vec<Vec3>; SEED_FRAMES],
    world_from_cpf: [Affine3; SEED_FRAMES],
    pelvis: DVec2,
}

/// Running totals of an episode, for its summary.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct Totals {
    reward: f64,
    contact: f64,
    view_cos: f64,
    frames: usize,
    frames_in_obstacle: usize,
    path_m: f64,
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
    pair: Option<usize>,
}

/// A fixed scene (e.g. the apartment) and the start/goal pairs its episodes walk, in turn.
#[derive(Debug, Clone)]
pub struct FixedScene {
    pub map: Arc<WalkableMap>,
    pub pairs: Vec<StartGoal>,
}

/// One episode in progress.
#[derive(Debug, Clone)]
struct Episode {
    id: u64,
    course: Course,
    view: SeedView,
    steps: usize,
    distance_m: f64,
    start_distance_m: f64,
    totals: Totals,
}

/// An episode in progress as data (checkpoints of training).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EpisodeSnapshot {
    id: u64,
    #[serde(default)]
    scene: Option<BoxParams>,
    #[serde(default)]
    crossing: Option<CrossingParams>,
    #[serde(default)]
    pair: Option<usize>,
    /// The seed frames' pose (165) and translation (3).
    frames: Vec<Vec<f64>>,
    steps: usize,
    distance_m: f64,
    start_distance_m: f64,
    totals: Totals,
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
    /// Share of the new frames in which a body marker stood inside the obstacle.
    pub penetration_share: f64,
    /// Horizontal pelvis path length over time (m/s).
    pub speed_m_s: f64,
}

/// One candidate primitive for one episode, judged but not yet taken.
#[derive(Debug, Clone)]
pub struct Candidate {
    pub env: usize,
    pub latent: Vec<f32>,
    /// `None`: the decoder produced a non-finite primitive.
    pub primitive: Option<DecodedPrimitive>,
    pub judged: Option<Judged>,
    pub reward: f64,
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
    scan: RayScan,
    foot_markers: Vec<usize>,
    episodes: Vec<Episode>,
    episode_base: u64,
    next_episode: u64,
}

/// Time (s) of frame `f` of the primitive an episode takes at step `steps`, on the episode's
/// clock (frame 0 of the first seed at 0): moving obstacles are placed at it.
fn frame_time_s(steps: usize, f: usize) -> f64 {
    (steps * (PRIMITIVE_FRAMES - SEED_FRAMES) + f) as f64 / PRIMITIVE_RATE_HZ
}

/// The generator of episode `id` under `base`.
fn episode_rng(base: u64, id: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(base.rotate_left(32) ^ id.wrapping_mul(0x9E37_79B9_7F4A_7C15))
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
            scan: RayScan::new(RayScanSettings::default()),
            foot_markers: RigGeometry::new(body.model, &body.betas)
                .map_err(DecodeError::from)?
                .foot_markers,
            episodes: Vec::with_capacity(envs),
            episode_base,
            next_episode: 0,
        };
        for _ in 0..envs {
            let e = env.start_episode()?;
            env.episodes.push(e);
        }
        Ok(env)
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

    fn view_of(&self, seed: PrimitiveSeed) -> Result<SeedView, DecodeError> {
        let mut markers: [Vec<Vec3>; SEED_FRAMES] = Default::default();
        let mut cpf = [Affine3::IDENTITY; SEED_FRAMES];
        let mut pelvis = DVec2::ZERO;
        for (k, f) in seed.frames.iter().enumerate() {
            let mf = self
                .body
                .shaped
                .marker_frame(&f.pose, f.transl, &self.body.marker_ids)?;
            cpf[k] = self.body.cpf.world_from_cpf(&mf.skeleton);
            if k == 0 {
                let p = mf.skeleton.joints[joint::PELVIS];
                pelvis = DVec2::new(p.x, p.y);
            }
            markers[k] = mf.markers;
        }
        Ok(SeedView {
            seed,
            markers,
            world_from_cpf: cpf,
            pelvis,
        })
    }

    fn box_course(scene: BoxScene) -> Course {
        Course {
            map: Arc::new(scene.map),
            obstacle: Some(scene.obstacle),
            moving: Vec::new(),
            start: scene.start,
            goal: scene.goal,
            box_params: Some(scene.params),
            crossing: None,
            pair: None,
        }
    }

    fn crossing_course(floor: &Arc<WalkableMap>, scene: CrossingScene) -> Course {
        Course {
            map: floor.clone(),
            obstacle: None,
            moving: vec![scene.mover],
            start: scene.start,
            goal: scene.goal,
            box_params: None,
            crossing: Some(scene.params),
            pair: None,
        }
    }

    fn fixed_course(f: &FixedScene, pair: usize) -> Course {
        Course {
            map: f.map.clone(),
            obstacle: None,
            moving: Vec::new(),
            start: f.pairs[pair].start,
            goal: f.pairs[pair].goal,
            box_params: None,
            crossing: None,
            pair: Some(pair),
        }
    }

    /// The course of episode `id`: the next pair of the fixed scene, or a new crossing scene
    /// (with the crossing share) or box scene.
    fn draw_course(&self, id: u64, rng: &mut ChaCha8Rng) -> Course {
        let crossing = self.settings.crossing;
        match self.fixed {
            Some(f) => Self::fixed_course(f, (id % f.pairs.len() as u64) as usize),
            // No draw when there are no crossings: box-only runs stay as they were.
            None if crossing.share > 0.0 && uniform_open01(rng) < crossing.share => {
                Self::crossing_course(&self.crossing_floor, CrossingScene::sample(&crossing, rng))
            }
            None => Self::box_course(BoxScene::sample(&self.settings.scene, rng)),
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
            // Canonical seeds face +y.
            let yaw = to_goal.y.atan2(to_goal.x) - std::f64::consts::FRAC_PI_2 + jitter;
            let world_from_canon = Affine3 {
                matrix3: Mat3::from_rotation_z(yaw),
                translation: Vec3::new(scene.start.x, scene.start.y, floor_z - floor),
            };
            let seed = PrimitiveSeed {
                frames: std::array::from_fn(|k| {
                    frames[k].moved_rigidly(world_from_canon, rest_pelvis)
                }),
                floor_z,
            };
            let view = self.view_of(seed)?;
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
            let distance_m = view.pelvis.distance(scene.goal);
            return Ok(Episode {
                id,
                course: scene,
                view,
                steps: 0,
                distance_m,
                start_distance_m: distance_m,
                totals: Totals::default(),
            });
        }
    }

    /// Observations of all episodes, `[B × OBS_DIM]`.
    pub fn observations(&self) -> Vec<f32> {
        let mut out = vec![0f32; self.episodes.len() * OBS_DIM];
        out.par_chunks_mut(OBS_DIM)
            .zip(&self.episodes)
            .for_each(|(o, e)| self.observe_into(e, o));
        out
    }

    fn observe_into(&self, e: &Episode, out: &mut [f32]) {
        let goal = Vec3::new(e.course.goal.x, e.course.goal.y, 0.0);
        // The canonical frame of the seed; with hips vertical (never in a walking seed) the
        // world frame at the pelvis stands in.
        let joints0 = self
            .body
            .shaped
            .skeleton(&e.view.seed.frames[0].pose, e.view.seed.frames[0].transl)
            .map(|s| s.joints.to_vec());
        let world_from_canon = joints0
            .ok()
            .and_then(|j| canonical_frame(&j).ok())
            .unwrap_or(Affine3::from_translation(Vec3::new(
                e.view.pelvis.x,
                e.view.pelvis.y,
                0.0,
            )));
        let canon_from_world = world_from_canon.inverse();
        for (k, markers) in e.view.markers.iter().enumerate() {
            let o = &mut out[k * STATE_FRAME_DIM..(k + 1) * STATE_FRAME_DIM];
            for (i, m) in markers.iter().enumerate() {
                let c = canon_from_world.transform_point3(*m);
                let g = goal.with_z(m.z);
                let d = canon_from_world.transform_vector3((g - *m).normalize_or_zero());
                o[3 * i..3 * i + 3].copy_from_slice(&[c.x as f32, c.y as f32, c.z as f32]);
                let j = 3 * NUM_MARKERS + 3 * i;
                o[j..j + 3].copy_from_slice(&[d.x as f32, d.y as f32, d.z as f32]);
            }
        }
        for (k, cpf) in e.view.world_from_cpf.iter().enumerate() {
            let t = frame_time_s(e.steps, k);
            let moving: Vec<Obstacle2> = e.course.moving.iter().map(|m| m.at(t)).collect();
            let world = SensingWorld {
                map: &e.course.map,
                obstacles: &moving,
            };
            let at = OBS_RAYS_OFFSET + k * RAYS;
            self.scan.observe_into(
                &world,
                EgoPose2::from_world_from_cpf(cpf),
                &mut out[at..at + RAYS],
            );
        }
        out[OBS_DIST_OFFSET] = (1.0 / (1.0 + e.distance_m)) as f32;
        out[OBS_DIST_OFFSET + 1] =
            (1.0 - e.steps as f64 / self.settings.max_primitives as f64) as f32;
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
            .flat_map(|e| std::iter::repeat_n(e.view.seed.clone(), per))
            .collect();
        let zs: Vec<Vec<f32>> = latents.chunks(l).map(<[f32]>::to_vec).collect();
        let decoded = self.model.decode_each(self.body, &seeds, &zs)?;
        let limits = Limits {
            success_m: self.settings.success_m,
            penetration_cells: self.settings.penetration_cells,
        };
        decoded
            .into_par_iter()
            .zip(zs)
            .enumerate()
            .map(|(i, (d, latent))| {
                let env = i / per.max(1);
                let e = &self.episodes[env];
                match d {
                    Ok(p) => {
                        let s = Situation {
                            map: &e.course.map,
                            obstacle: e.course.obstacle.as_ref(),
                            moving: &e.course.moving,
                            t0_s: frame_time_s(e.steps, 0),
                            goal: e.course.goal,
                            distance_m: e.distance_m,
                        };
                        let j = judge(&p, &s, &self.foot_markers, self.prior, &limits);
                        let reward = j.terms.total(&self.settings.weights);
                        Ok(Candidate {
                            env,
                            latent,
                            primitive: Some(p),
                            judged: Some(j),
                            reward: if reward.is_finite() { reward } else { 0.0 },
                        })
                    }
                    Err(DecodeError::NonFinite { .. }) => Ok(Candidate {
                        env,
                        latent,
                        primitive: None,
                        judged: None,
                        reward: 0.0,
                    }),
                    Err(e) => Err(EnvError::Decode(e)),
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
        for (i, c) in chosen.into_iter().enumerate() {
            debug_assert_eq!(c.env, i);
            let max_primitives = self.settings.max_primitives;
            let terminate_on_penetration = self.settings.terminate_on_penetration;
            let e = &mut self.episodes[i];
            e.steps += 1;
            e.totals.reward += c.reward;
            let ending = match (c.primitive, c.judged) {
                (Some(p), Some(j)) => {
                    let first = p.joints[SEED_FRAMES - 1][joint::PELVIS];
                    let mut path = 0.0;
                    let mut prev = DVec2::new(first.x, first.y);
                    for f in &p.joints[SEED_FRAMES..] {
                        let q = DVec2::new(f[joint::PELVIS].x, f[joint::PELVIS].y);
                        path += q.distance(prev);
                        prev = q;
                    }
                    e.totals.path_m += path;
                    e.totals.contact += j.contact;
                    e.totals.view_cos += j.view_cos;
                    e.totals.frames += p.joints.len() - SEED_FRAMES;
                    e.totals.frames_in_obstacle += j.frames_in_obstacle;
                    e.distance_m = j.distance_m;
                    let seed = p.next_seed();
                    e.view = SeedView {
                        pelvis: prev,
                        markers: std::array::from_fn(|k| {
                            p.markers[p.markers.len() - SEED_FRAMES + k].clone()
                        }),
                        world_from_cpf: std::array::from_fn(|k| {
                            p.world_from_cpf[p.world_from_cpf.len() - SEED_FRAMES + k]
                        }),
                        seed,
                    };
                    // The pelvis of the new seed's first frame.
                    let p0 = p.joints[p.joints.len() - SEED_FRAMES][joint::PELVIS];
                    e.view.pelvis = DVec2::new(p0.x, p0.y);
                    if j.success {
                        Some(Ending::Success)
                    } else if j.penetrated && terminate_on_penetration {
                        Some(Ending::Penetration)
                    } else if e.steps >= max_primitives {
                        Some(Ending::Timeout)
                    } else {
                        None
                    }
                }
                _ => Some(Ending::Failure),
            };
            out.reward.push(c.reward as f32);
            out.done.push(ending.is_some());
            if let Some(ending) = ending {
                let e = &self.episodes[i];
                let n = e.steps.max(1) as f64;
                out.finished.push(EpisodeSummary {
                    id: e.id,
                    ending,
                    primitives: e.steps,
                    start_distance_m: e.start_distance_m,
                    final_distance_m: e.distance_m,
                    reward: e.totals.reward,
                    contact: e.totals.contact / n,
                    view_cos: e.totals.view_cos / n,
                    penetration_share: e.totals.frames_in_obstacle as f64
                        / e.totals.frames.max(1) as f64,
                    speed_m_s: e.totals.path_m
                        / (e.totals.frames.max(1) as f64
                            / crate::motion::primitive::PRIMITIVE_RATE_HZ),
                });
                self.episodes[i] = self.start_episode()?;
            }
        }
        Ok(out)
    }

    /// One primitive per episode from `latents` (`[B × L]`).
    pub fn step(&mut self, latents: &[f32]) -> Result<StepOutput, EnvError> {
        let c = self.propose(latents, 1)?;
        self.commit(c)
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
                    crossing: e.course.crossing,
                    pair: e.course.pair,
                    frames: e
                        .view
                        .seed
                        .frames
                        .iter()
                        .map(|f| f.pose.iter().copied().chain(f.transl.to_array()).collect())
                        .collect(),
                    steps: e.steps,
                    distance_m: e.distance_m,
                    start_distance_m: e.start_distance_m,
                    totals: e.totals.clone(),
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
            let course = match (s.scene, s.crossing, s.pair, self.fixed) {
                (Some(p), None, None, None) => {
                    Self::box_course(BoxScene::build(&self.settings.scene, p))
                }
                (None, Some(c), None, None) => Self::crossing_course(
                    &self.crossing_floor,
                    CrossingScene::build(&self.settings.crossing, c),
                ),
                (None, None, Some(pair), Some(f)) if pair < f.pairs.len() => {
                    Self::fixed_course(f, pair)
                }
                _ => {
                    return Err(EnvError::Snapshot(format!(
                        "episode {}: its scene is not of this environment's kind",
                        s.id
                    )))
                }
            };
            let floor_z = course.map.floor_z_m;
            let view = self.view_of(PrimitiveSeed { frames, floor_z })?;
            episodes.push(Episode {
                id: s.id,
                course,
                view,
                steps: s.steps,
                distance_m: s.distance_m,
                start_distance_m: s.start_distance_m,
                totals: s.totals.clone(),
            });
        }
        self.episodes = episodes;
        self.next_episode = snap.next_episode;
        Ok(())
    }

    /// Ids of the episodes in progress.
    pub fn episode_ids(&self) -> Vec<u64> {
        self.episodes.iter().map(|e| e.id).collect()
    }
}
