//! The vectorised locomotion environment: `B` episodes stepped together, one primitive each
//! per step, all decoded in one batch. The same code serves training, the sampling controller
//! and evaluation.
//!
//! An episode (EgoGen's box environment): a [`BoxScene`] — or, for configured shares of
//! episodes, a start/goal pair of the fixed scene or of a generated furnished dwelling, a
//! procedural floor plan ([`RoomScene`]: rooms, doorways, furniture) or a
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
//!
//! Here: the environment and its step; `settings` (what an environment is asked for),
//! `course` (where an episode walks, drawn per episode), `summary` (how an episode ended),
//! `snapshot` (episodes in progress as data, for training's checkpoints).

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

mod course;
mod settings;
mod snapshot;
pub(crate) mod summary;

use course::{Course, Episode};
pub(crate) use course::{CourseView, FixedScene};
pub use settings::EnvSettings;
pub(crate) use snapshot::EnvSnapshot;
pub(crate) use summary::{Ending, EpisodeSummary};

/// Seed placements tried before an episode starts even with blocked cells under the body
/// (a start too near a wall for every seed).
const MAX_RESET_TRIES: usize = 100;

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
    /// The training config's generated dwellings, with their pairs.
    dwellings: &'m [FixedScene],
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
pub(crate) struct EnvParts<'m> {
    pub model: &'m MotionModel,
    pub body: &'m BodyContext<'m>,
    pub bank: &'m SeedBank,
    pub prior: &'m PosePrior,
    pub fixed: Option<&'m FixedScene>,
    /// Generated dwellings whose pairs some episodes walk (`[stages.env.dwellings]`; none
    /// outside training).
    pub dwellings: &'m [FixedScene],
}

impl<'m> EnvParts<'m> {
    /// `envs` episodes at a time under `episode_base` ([`PolicyEnv::with_scene`]).
    pub(crate) fn env(
        &self,
        settings: EnvSettings,
        envs: usize,
        episode_base: u64,
    ) -> Result<PolicyEnv<'m>, EnvError> {
        PolicyEnv::build(*self, settings, envs, episode_base)
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
    pub(crate) fn with_scene(
        model: &'m MotionModel,
        body: &'m BodyContext<'m>,
        bank: &'m SeedBank,
        prior: &'m PosePrior,
        fixed: Option<&'m FixedScene>,
        settings: EnvSettings,
        envs: usize,
        episode_base: u64,
    ) -> Result<Self, EnvError> {
        let parts = EnvParts {
            model,
            body,
            bank,
            prior,
            fixed,
            dwellings: &[],
        };
        Self::build(parts, settings, envs, episode_base)
    }

    fn build(
        parts: EnvParts<'m>,
        settings: EnvSettings,
        envs: usize,
        episode_base: u64,
    ) -> Result<Self, EnvError> {
        if parts.bank.seeds.is_empty() {
            return Err(EnvError::NoSeeds);
        }
        let no_pairs = |f: &FixedScene| f.pairs.is_empty();
        if parts.fixed.is_some_and(no_pairs) || parts.dwellings.iter().any(no_pairs) {
            return Err(EnvError::Snapshot(
                "a fixed scene or dwelling has no start/goal pairs".into(),
            ));
        }
        let body = parts.body;
        let mut env = Self {
            model: parts.model,
            body,
            bank: parts.bank,
            prior: parts.prior,
            fixed: parts.fixed,
            dwellings: parts.dwellings,
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
    pub(crate) fn with_sensing(mut self, spec: &SensingSpec) -> Self {
        self.sensor = spec.sensor();
        self
    }

    /// Summaries of finished indoor episodes carry the walking distance from start to goal
    /// round walls ([`EpisodeSummary::way_round_m`]; a few milliseconds per episode, so
    /// evaluations only).
    pub(crate) fn measuring_way_round(mut self) -> Self {
        self.measure_way_round = true;
        self
    }

    /// Where the parts of this environment's observations lie.
    pub(crate) fn obs_layout(&self) -> ObsLayout {
        ObsLayout {
            sensing_per_frame: self.sensor.dim(),
        }
    }

    /// Number of parallel episodes.
    pub(crate) fn len(&self) -> usize {
        self.episodes.len()
    }

    /// Latent size of the motion model.
    pub(crate) fn latent_dim(&self) -> usize {
        self.model.latent_dim()
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
    pub(crate) fn choose(&self, candidates: Vec<Candidate>) -> Result<Vec<Candidate>, EnvError> {
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
    pub(crate) fn commit(&mut self, chosen: Vec<Candidate>) -> Result<StepOutput, EnvError> {
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

    /// Each episode in progress: its id and its pelvis's floor position (m, world).
    pub(crate) fn pelvis_positions(&self) -> Vec<(u64, DVec2)> {
        self.episodes
            .iter()
            .map(|e| (e.id, e.walker.view.pelvis))
            .collect()
    }

    /// Where episode `i` (of those in progress) walks, for pictures.
    pub(crate) fn course_view(&self, i: usize) -> CourseView {
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
    #[cfg(test)]
    pub(crate) fn episode_ids(&self) -> Vec<u64> {
        self.episodes.iter().map(|e| e.id).collect()
    }
}
