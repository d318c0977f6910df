//! Whole jobs the `egogen policy` commands run: fitting and checking the pose prior, and
//! evaluating a controller (the policy or the sampling controller) on held-out episodes. Each takes loaded parts and
//! returns a report; the binary only parses arguments and prints.

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};
use serde::Serialize;

use crate::body::BodyParams;
use crate::math::Quantiles;
use crate::math::{axis_angle_to_matrix, matrix_to_axis_angle, Vec3};
use crate::motion::cvae::data::PrimitiveSet;
use crate::motion::cvae::features::{frame_params, FRAME_DIM};
use crate::motion::cvae::train::normal_samples;
use crate::motion::cvae::MotionModel;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};
use crate::policy::env::{EnvParts, EnvSettings, PolicyEnv};
use crate::policy::held_out::{run_episodes, EvalReport, HELD_OUT_BASE};
use crate::policy::sampling::controller_step;
use crate::walker::pose_prior::{prior_values, PosePrior, PRIOR_DIM};

/// Frames of every primitive of a set, as poses.
/// Every primitive of a set as its frames' body parameters (no shape).
pub(crate) fn set_frames(set: &PrimitiveSet) -> Vec<Vec<BodyParams>> {
    (0..set.len())
        .map(|i| {
            set.item(i)
                .chunks(FRAME_DIM)
                .map(|f| frame_params(f, &[]))
                .collect()
        })
        .collect()
}

/// Joints bent in the "broken pose" check: hips, knees, spine, shoulders, elbows.
const BENT_JOINTS: [usize; 9] = [1, 2, 3, 4, 5, 16, 17, 18, 19];

/// Per-primitive mean scores of three groups, and how many of each exceed the limit.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct PriorSeparation {
    pub plausible_max_nll: f64,
    pub held_out_mocap: Quantiles,
    pub random_latent: Quantiles,
    pub bent_joint: Quantiles,
    pub held_out_mocap_implausible_share: f64,
    pub random_latent_implausible_share: f64,
    pub bent_joint_implausible_share: f64,
    /// The scores themselves, for histograms (`tools/plot_pose_prior.py`).
    pub scores: PriorScores,
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct PriorScores {
    pub held_out_mocap: Vec<f64>,
    pub random_latent: Vec<f64>,
    pub bent_joint: Vec<f64>,
}

/// Fits the prior on the training primitives' frames (limit at quantile `quantile` of their
/// per-primitive means) and measures how it separates held-out mocap from primitives decoded
/// from random latents (training seeds, z ~ N(0, I)) and from held-out mocap with one joint
/// bent by 90° about a random axis in every frame.
pub(crate) fn fit_pose_prior(
    train: &PrimitiveSet,
    held_out: &PrimitiveSet,
    model: &MotionModel,
    components: usize,
    iterations: usize,
    quantile: f64,
    seed: u64,
    source: &str,
) -> (PosePrior, PriorSeparation) {
    let train_frames = set_frames(train);
    let poses: Vec<[f64; PRIOR_DIM]> = train_frames.iter().flatten().map(prior_values).collect();
    let mut prior = PosePrior::fit(&poses, components, iterations, seed, source);
    let means: Vec<f64> = train_frames
        .iter()
        .map(|f| prior.mean_pose_nll(f))
        .collect();
    prior.set_plausible_limit(&means, quantile);
    let held_frames = set_frames(held_out);
    let mocap: Vec<f64> = held_frames.iter().map(|f| prior.mean_pose_nll(f)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xB0D1);
    let bent: Vec<f64> = held_frames
        .iter()
        .map(|frames| {
            let j = BENT_JOINTS[(rng.next_u64() % BENT_JOINTS.len() as u64) as usize];
            let axis = Vec3::new(
                crate::math::random::standard_normal(&mut rng),
                crate::math::random::standard_normal(&mut rng),
                crate::math::random::standard_normal(&mut rng),
            )
            .normalize();
            let extra = axis_angle_to_matrix(axis * std::f64::consts::FRAC_PI_2);
            let bent: Vec<BodyParams> = frames
                .iter()
                .map(|f| {
                    let mut b = f.clone();
                    let r = extra * axis_angle_to_matrix(f.joint_axis_angle(j));
                    b.set_joint_axis_angle(j, matrix_to_axis_angle(r));
                    b
                })
                .collect();
            prior.mean_pose_nll(&bent)
        })
        .collect();
    // Random latents from training seeds, decoded in batches.
    let l = model.latent_dim();
    let mut random = Vec::with_capacity(train.len());
    for start in (0..train.len()).step_by(256) {
        let end = (start + 256).min(train.len());
        let b = end - start;
        let mut seeds = Vec::with_capacity(b * SEED_FRAMES * FRAME_DIM);
        let mut floors = Vec::with_capacity(b);
        for i in start..end {
            seeds.extend_from_slice(&train.item(i)[..SEED_FRAMES * FRAME_DIM]);
            floors.push(train.floors(i)[0]);
        }
        let z = normal_samples(&mut rng, b * l);
        let out = model.decode_features(&seeds, &floors, &z);
        for p in out.chunks(PRIMITIVE_FRAMES * FRAME_DIM) {
            if p.iter().any(|v| !v.is_finite()) {
                random.push(f64::INFINITY);
                continue;
            }
            let frames: Vec<BodyParams> =
                p.chunks(FRAME_DIM).map(|f| frame_params(f, &[])).collect();
            random.push(prior.mean_pose_nll(&frames));
        }
    }
    let limit = prior.plausible_max_nll;
    let share = |v: &[f64]| v.iter().filter(|x| **x > limit).count() as f64 / v.len().max(1) as f64;
    let sep = PriorSeparation {
        plausible_max_nll: limit,
        held_out_mocap: Quantiles::of(mocap.iter().copied()),
        random_latent: Quantiles::of(random.iter().copied()),
        bent_joint: Quantiles::of(bent.iter().copied()),
        held_out_mocap_implausible_share: share(&mocap),
        random_latent_implausible_share: share(&random),
        bent_joint_implausible_share: share(&bent),
        scores: PriorScores {
            held_out_mocap: mocap,
            random_latent: random,
            bent_joint: bent,
        },
    };
    (prior, sep)
}

/// What chooses the latents in an evaluation.
pub(crate) enum HeldOutController<'a, B: burn::prelude::Backend> {
    /// A controller of the walker layer that needs no policy, as a take's people step with it
    /// (the best of `k` random latents by the reward, the path follower).
    Walker(crate::walker::ControllerSpec),
    /// The trained policy: actions sampled from π (as EgoGen's test collector does) or its
    /// mean.
    Policy {
        net: &'a crate::policy::net::ActorCritic<B>,
        mean_action: bool,
        /// Scale of the sampled actions' standard deviation (1: as trained).
        spread: f32,
    },
}

/// A controller on the first `episodes` held-out episodes, `envs` at a time.
pub(crate) fn evaluate<B: burn::prelude::Backend>(
    parts: &EnvParts,
    settings: EnvSettings,
    controller: &HeldOutController<B>,
    run: (usize, usize, u64),
    progress: impl FnMut(&crate::policy::env::EpisodeSummary),
) -> Result<(EvalReport, Vec<crate::policy::env::EpisodeSummary>), crate::policy::env::EnvError> {
    let (report, summaries, _) =
        evaluate_with_paths(parts, settings, controller, run, 0, progress)?;
    Ok((report, summaries))
}

/// One evaluated episode's walk, for pictures: its course and the pelvis's floor position at
/// its start and after every primitive, and how it ended.
#[derive(Debug, Clone)]
pub(crate) struct EpisodePath {
    pub course: crate::policy::env::CourseView,
    pub pelvis_xy: Vec<glam::DVec2>,
    pub ending: Option<crate::policy::env::Ending>,
}

/// Records the walks of the episodes numbered below `count` as an evaluation steps.
struct PathRecorder {
    count: u64,
    paths: std::collections::BTreeMap<u64, EpisodePath>,
}

impl PathRecorder {
    /// Before a step: every episode in progress not seen yet starts its path. Returns the
    /// ids of the episodes in progress.
    fn before(&mut self, env: &PolicyEnv) -> Vec<u64> {
        let now = env.pelvis_positions();
        for (i, &(id, xy)) in now.iter().enumerate() {
            if id < self.count && !self.paths.contains_key(&id) {
                let course = env.course_view(i);
                self.paths.insert(
                    id,
                    EpisodePath {
                        course,
                        pelvis_xy: vec![xy],
                        ending: None,
                    },
                );
            }
        }
        now.into_iter().map(|(id, _)| id).collect()
    }

    /// After a step: where the walkers now stand (a finished walk's end from its summary).
    fn after(&mut self, env: &PolicyEnv, ids_before: &[u64], out: &crate::policy::env::StepOutput) {
        let now = env.pelvis_positions();
        for (k, &id) in ids_before.iter().enumerate() {
            if !out.done[k] {
                if let Some(p) = self.paths.get_mut(&id) {
                    p.pelvis_xy.push(now[k].1);
                }
            }
        }
        for s in &out.finished {
            if let Some(p) = self.paths.get_mut(&s.id) {
                p.pelvis_xy.push(glam::DVec2::from_array(s.end_xy));
                p.ending = Some(s.ending);
            }
        }
    }
}

/// [`evaluate`], keeping the walks of the first `paths` episodes ([`EpisodePath`], by id).
pub(crate) fn evaluate_with_paths<B: burn::prelude::Backend>(
    parts: &EnvParts,
    settings: EnvSettings,
    controller: &HeldOutController<B>,
    (episodes, envs, seed): (usize, usize, u64),
    paths: usize,
    progress: impl FnMut(&crate::policy::env::EpisodeSummary),
) -> Result<
    (
        EvalReport,
        Vec<crate::policy::env::EpisodeSummary>,
        Vec<EpisodePath>,
    ),
    crate::policy::env::EnvError,
> {
    let t0 = std::time::Instant::now();
    let mut env = parts
        .env(settings, envs.clamp(1, episodes.max(1)), HELD_OUT_BASE)?
        .measuring_way_round();
    if let HeldOutController::Policy { net, .. } = controller {
        env = env.with_sensing(&net.sensing());
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // The policy acts through its f32 actor (burn's actions, bit for bit, without the cost
    // per tensor operation).
    let actor = match controller {
        HeldOutController::Policy { net, .. } => Some(crate::policy::Actor::of(*net)),
        HeldOutController::Walker(_) => None,
    };
    let mut recorder = PathRecorder {
        count: paths as u64,
        paths: Default::default(),
    };
    let (summaries, steps) = run_episodes(
        &mut env,
        episodes,
        |e| {
            let ids = (paths > 0).then(|| recorder.before(e));
            let out = match controller {
                HeldOutController::Walker(spec) => controller_step(e, *spec, &mut rng),
                HeldOutController::Policy {
                    mean_action,
                    spread,
                    ..
                } => {
                    let actor = actor.as_ref().expect("made above for the policy");
                    let rng = (!mean_action).then_some(&mut rng);
                    let a = actor.actions_with_spread(&e.observations(), rng, *spread);
                    e.step(&a)
                }
            }?;
            if let Some(ids) = ids {
                recorder.after(e, &ids, &out);
            }
            Ok(out)
        },
        progress,
    )?;
    Ok((
        EvalReport::of(&summaries, steps, t0.elapsed().as_secs_f64()),
        summaries,
        recorder.paths.into_values().collect(),
    ))
}
