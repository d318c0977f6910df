//! PPO training of the actor-critic in the box environment (paper Tab. S3), in stages
//! (pretraining: penetration weight 1, no penetration termination; fine-tuning: 0.1, strict
//! termination), resumable exactly from atomic checkpoints.
//!
//! One update: every environment takes `steps_per_env` steps with actions sampled from the
//! policy (one batched network forward and one batched decode per step); advantages by GAE
//! (a timeout ends an episode, as in EgoGen); then `epochs` passes over the batch in shuffled
//! minibatches: clipped surrogate (advantages normalised per minibatch), value loss without
//! clipping, entropy bonus, optionally a penalty on KL(π ‖ N(0, I)), gradients clipped to `max_grad_norm` on their global norm (burn
//! clips per tensor, so the norm is computed here), AdamW. A pass stops early when the
//! approximate KL between the old and new policy exceeds `target_kl`.
//!
//! Every `eval_every_updates` the policy runs `eval_episodes` validation episodes (their own
//! episode base, neither training's nor the held-out test's); the weights with the best
//! validation return of the last stage are written to `weights_out` (EgoGen selects by test
//! reward and KL(π ‖ N(0, I)): with `select_max_prior_kl`, only among validations whose mean
//! KL is at most that), the last weights of every stage beside them
//! (`<weights>.<stage>.last.safetensors`).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::module::{AutodiffModule, ModuleVisitor, Param};
use burn::optim::{AdamWConfig, GradientsParams, Optimizer};
use burn::prelude::*;
use burn::tensor::backend::AutodiffBackend;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

use super::env::{EnvError, EnvParts, EnvSettings, EnvSnapshot, PolicyEnv};
use super::net::{entropy, kl_to_standard, log_prob, ActorCritic, PolicyArch};
use super::weights::{load_policy, save_policy};
use crate::motion::cvae::checkpoint::{self, CheckpointState};
use crate::motion::cvae::train::{normal_samples, TrainBackend, TrainError};
use crate::motion::cvae::weights::WeightsError;

/// PPO settings (paper Tab. S3 and EgoGen's box run by default).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PpoSettings {
    /// Environments stepped together.
    pub envs: usize,
    /// Steps of every environment per update (EgoGen: 1024 transitions from 256 envs).
    pub steps_per_env: usize,
    pub minibatch: usize,
    /// Passes over each batch ("repeat").
    pub epochs: usize,
    pub learning_rate: f64,
    pub weight_decay: f64,
    pub gamma: f64,
    pub gae_lambda: f64,
    pub clip: f64,
    pub value_coef: f64,
    pub entropy_coef: f64,
    /// Weight of the mean KL(π(·|s) ‖ N(0, I)) in the loss: keeps the latents where the motion
    /// model was trained (GAMMA's policy regulariser). 0 leaves them unbounded.
    pub prior_kl_coef: f64,
    /// Largest global gradient norm.
    pub max_grad_norm: f64,
    /// Stop a pass when the approximate KL(old ‖ new) exceeds this.
    pub target_kl: f64,
}

impl Default for PpoSettings {
    fn default() -> Self {
        Self {
            envs: 256,
            steps_per_env: 4,
            minibatch: 256,
            epochs: 1,
            learning_rate: 3e-4,
            weight_decay: 0.01,
            gamma: 0.99,
            gae_lambda: 0.95,
            clip: 0.1,
            value_coef: 1.0,
            entropy_coef: 0.01,
            prior_kl_coef: 0.0,
            max_grad_norm: 0.1,
            target_kl: 0.02,
        }
    }
}

/// One training stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StagePlan {
    pub name: String,
    /// Environment steps of the stage.
    pub env_steps: usize,
    pub env: EnvSettings,
}

/// A fixed training scene (e.g. the apartment) and how its start/goal pairs are drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrainScene {
    pub path: PathBuf,
    /// How the file's coordinates become the world's (`[scene] up_axis`, `unit_m`; left out
    /// of the serialised plan when the format's own).
    #[serde(skip_serializing_if = "crate::scene::SceneFrame::is_default")]
    pub frame: crate::scene::SceneFrame,
    pub pairs: usize,
    /// Start–goal distance range (m, horizontal).
    pub pair_distance_m: (f64, f64),
    /// Least distance of a start or goal to anything blocking (m).
    pub clearance_m: f64,
    /// Starts and goals inside the walls only ([`crate::scene::WalkableMap::indoor_cells`]),
    /// the ground around the walls blocked in the map the walker senses
    /// ([`crate::scene::WalkableMap::restricted_to`]).
    pub indoors: bool,
    pub seed: u64,
}

/// Everything a policy training run needs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PolicyTrainPlan {
    pub seed: u64,
    pub body_model: PathBuf,
    pub motion_weights: PathBuf,
    /// The motion training config whose training primitives seed the episodes.
    pub motion_config: PathBuf,
    pub pose_prior: PathBuf,
    pub arch: PolicyArch,
    pub ppo: PpoSettings,
    pub stages: Vec<StagePlan>,
    pub eval_every_updates: usize,
    pub eval_episodes: usize,
    /// Model selection: only validations whose mean KL(π ‖ N(0, I)) is at most this are
    /// candidates (`None`: every validation).
    pub select_max_prior_kl: Option<f64>,
    /// Start from these policy weights (same architecture) instead of a fresh network.
    pub init_weights: Option<PathBuf>,
    /// A fixed scene some episodes walk (each stage's `env.fixed_share`).
    pub scene: Option<TrainScene>,
    pub weights_out: PathBuf,
    pub log_out: PathBuf,
    pub checkpoint_every_s: f64,
}

impl PolicyTrainPlan {
    /// Updates of a stage.
    pub fn updates(&self, stage: usize) -> usize {
        let per = (self.ppo.envs * self.ppo.steps_per_env).max(1);
        self.stages[stage].env_steps.div_ceil(per)
    }
}

/// Episode base of validation episodes.
pub(crate) const VALIDATION_BASE: u64 = 0x7A11_0000;

/// Sum of squares of all gradients of a module.
struct GradSquares<'a, B: AutodiffBackend> {
    grads: &'a GradientsParams,
    sum: f64,
    _b: std::marker::PhantomData<B>,
}

impl<B: AutodiffBackend> ModuleVisitor<B> for GradSquares<'_, B> {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        if let Some(g) = self.grads.get::<B::InnerBackend, D>(param.id) {
            self.sum += g.square().sum().into_scalar().elem::<f64>();
        }
    }
}

/// Scales all gradients of a module.
struct GradScale<'a, B: AutodiffBackend> {
    grads: &'a mut GradientsParams,
    scale: f64,
    _b: std::marker::PhantomData<B>,
}

impl<B: AutodiffBackend> ModuleVisitor<B> for GradScale<'_, B> {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        if let Some(g) = self.grads.remove::<B::InnerBackend, D>(param.id) {
            self.grads.register(param.id, g.mul_scalar(self.scale));
        }
    }
}

/// Clips the gradients of `net` to global norm `max_norm`; returns the norm before clipping.
pub fn clip_global_norm<B: AutodiffBackend, M: AutodiffModule<B>>(
    net: &M,
    grads: &mut GradientsParams,
    max_norm: f64,
) -> f64 {
    let mut sq = GradSquares::<B> {
        grads,
        sum: 0.0,
        _b: std::marker::PhantomData,
    };
    net.visit(&mut sq);
    let norm = sq.sum.sqrt();
    if norm > max_norm && norm.is_finite() {
        let mut scale = GradScale::<B> {
            grads,
            scale: max_norm / norm,
            _b: std::marker::PhantomData,
        };
        net.visit(&mut scale);
    }
    norm
}

/// One update's log line.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct UpdateLog {
    pub stage: String,
    pub update: usize,
    pub env_steps: usize,
    pub wall_s: f64,
    /// Mean reward per step of the batch.
    pub step_reward: f64,
    /// Episodes that ended during the update: count, mean return, success share, mean length.
    pub episodes: usize,
    pub episode_return: f64,
    pub success_rate: f64,
    pub episode_length: f64,
    /// Mean KL(π(·|s) ‖ N(0, I)) over the batch's states.
    pub kl_prior: f64,
    /// Approximate KL(old ‖ new) of the last minibatch, and minibatches run.
    pub approx_kl: f64,
    pub minibatches: usize,
    pub policy_loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
    pub grad_norm: f64,
    pub clip_fraction: f64,
    /// Seconds in the environment (decode, markers, sensing, reward), in the policy forward
    /// of collection, and in the update.
    pub env_s: f64,
    pub forward_s: f64,
    pub update_s: f64,
    /// Validation: mean return, success share, mean KL to the prior (only on eval updates).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub validation: Option<Validation>,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub(crate) struct Validation {
    pub episode_return: f64,
    pub success_rate: f64,
    pub kl_prior: f64,
    pub final_distance_m: f64,
}

/// State a checkpoint carries besides the network and optimiser.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct RunState {
    env: EnvSnapshot,
    best_validation_return: Option<f64>,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct PolicyTrainReport {
    pub updates: usize,
    pub env_steps: usize,
    pub seconds: f64,
    pub best_validation_return: Option<f64>,
    pub parameters: usize,
}

fn to_tensor<B: Backend>(v: Vec<f32>, shape: [usize; 2], device: &B::Device) -> Tensor<B, 2> {
    Tensor::from_data(TensorData::new(v, shape), device)
}

fn values<B: Backend, const D: usize>(t: Tensor<B, D>) -> Vec<f32> {
    t.into_data().to_vec().expect("f32 tensor")
}

/// Policy actions for observations: sampled (with `rng`) or the mean; with log-probabilities,
/// values and KL to N(0, I).
pub fn act<B: Backend>(
    net: &ActorCritic<B>,
    obs: Vec<f32>,
    rng: Option<&mut ChaCha8Rng>,
    device: &B::Device,
) -> (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>) {
    let d = net.obs_layout().dim();
    let b = obs.len() / d;
    let out = net.forward(to_tensor(obs, [b, d], device));
    let actions = draw(out.mean.clone(), out.logvar.clone(), rng, device);
    let logp = values(log_prob(
        actions.clone(),
        out.mean.clone(),
        out.logvar.clone(),
    ));
    let kl = values(kl_to_standard(out.mean, out.logvar));
    (values(actions), logp, values(out.value), kl)
}

/// Policy actions for observations, sampled (with `rng`) or the mean: [`act`]'s actions, the
/// same numbers from the same draws, without the critic, log-probabilities or KL (what
/// steering needs).
pub fn actions<B: Backend>(
    net: &ActorCritic<B>,
    obs: Vec<f32>,
    rng: Option<&mut ChaCha8Rng>,
    device: &B::Device,
) -> Vec<f32> {
    let d = net.obs_layout().dim();
    let b = obs.len() / d;
    let (mean, logvar) = net.actor_forward(to_tensor(obs, [b, d], device));
    values(draw(mean, logvar, rng, device))
}

/// Actions `[B, L]` from the policy's distribution: `mean + exp(logvar / 2) · ε` with ε drawn
/// from `rng`, or the mean without one.
fn draw<B: Backend>(
    mean: Tensor<B, 2>,
    logvar: Tensor<B, 2>,
    rng: Option<&mut ChaCha8Rng>,
    device: &B::Device,
) -> Tensor<B, 2> {
    match rng {
        Some(rng) => {
            let [b, l] = mean.dims();
            let eps = to_tensor(normal_samples(rng, b * l), [b, l], device);
            mean + logvar.mul_scalar(0.5).exp() * eps
        }
        None => mean,
    }
}

/// The policy's action distribution for one observation: `(mean, standard deviation)`, `[L]`
/// each, for drawing several actions from one forward pass.
pub fn action_distribution<B: Backend>(
    net: &ActorCritic<B>,
    obs: Vec<f32>,
    device: &B::Device,
) -> (Vec<f32>, Vec<f32>) {
    let d = net.obs_layout().dim();
    let (mean, logvar) = net.actor_forward(to_tensor(obs, [1, d], device));
    (values(mean), values(logvar.mul_scalar(0.5).exp()))
}

/// Runs validation episodes with the sampled policy.
fn validate(
    net: &ActorCritic<<TrainBackend as AutodiffBackend>::InnerBackend>,
    parts: &EnvParts,
    settings: EnvSettings,
    episodes: usize,
    seed: u64,
) -> Result<Validation, EnvError> {
    let device = Default::default();
    let envs = episodes.clamp(1, 64);
    let mut env = parts
        .env(settings, envs, VALIDATION_BASE)?
        .with_sensing(&net.sensing());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut kl_sum = 0.0;
    let mut kl_n = 0usize;
    let (summaries, _) = super::held_out::run_episodes(
        &mut env,
        episodes,
        |e| {
            let (a, _, _, kl) = act(net, e.observations(), Some(&mut rng), &device);
            kl_sum += kl.iter().map(|&x| x as f64).sum::<f64>();
            kl_n += kl.len();
            e.step(&a)
        },
        |_| {},
    )?;
    let n = summaries.len().max(1) as f64;
    Ok(Validation {
        episode_return: summaries.iter().map(|s| s.reward).sum::<f64>() / n,
        success_rate: summaries
            .iter()
            .filter(|s| s.ending == super::env::Ending::Success)
            .count() as f64
            / n,
        kl_prior: kl_sum / kl_n.max(1) as f64,
        final_distance_m: summaries.iter().map(|s| s.final_distance_m).sum::<f64>() / n,
    })
}

fn stage_last_path(weights_out: &Path, stage: &str) -> PathBuf {
    let mut name = weights_out
        .file_stem()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".{stage}.last.safetensors"));
    weights_out.with_file_name(name)
}

/// Trains per the plan; `resume` continues the checkpoint a killed run left (refused when
/// there is none or it belongs to another plan; without `resume` an existing one is refused).
/// A new run refuses weights an earlier run left at the plan's outputs unless `force`; a loss
/// or a weight that goes non-finite stops the run with the update and the term.
pub fn train_policy(
    plan: &PolicyTrainPlan,
    parts: &EnvParts,
    show_progress: bool,
    resume: bool,
    force: bool,
) -> Result<PolicyTrainReport, TrainError> {
    let device = Default::default();
    let ckpt_dir = checkpoint::checkpoint_dir(&plan.weights_out);
    checkpoint::check_resume(&ckpt_dir, resume)?;
    if !resume && !force {
        let stage_outputs = plan
            .stages
            .iter()
            .map(|s| stage_last_path(&plan.weights_out, &s.name));
        for path in std::iter::once(plan.weights_out.clone()).chain(stage_outputs) {
            if path.exists() {
                return Err(TrainError::Data(format!(
                    "{} already exists (an earlier run's weights); not overwriting it: move it \
                     away, name other `output.weights`, or pass --force to replace it and the log",
                    path.display()
                )));
            }
        }
    }
    let fingerprint = checkpoint::plan_fingerprint(plan);
    let ppo = plan.ppo;
    let new_optim = || {
        AdamWConfig::new()
            .with_weight_decay(ppo.weight_decay as f32)
            .init::<TrainBackend, ActorCritic<TrainBackend>>()
    };
    TrainBackend::seed(&device, plan.seed);
    let mut net = initial_policy(plan, &device)?;
    let parameters = net.num_params();
    let mut optim = new_optim();
    let mut rng = ChaCha8Rng::seed_from_u64(plan.seed);
    let (mut stage, mut update, mut global_update, mut elapsed_before) =
        (0usize, 0usize, 0usize, 0.0);
    let mut run_state: Option<RunState> = None;
    if resume {
        let r = checkpoint::load::<TrainBackend, _, _, RunState>(
            &ckpt_dir,
            &fingerprint,
            net.clone(),
            new_optim,
            &device,
        )?;
        net = r.net;
        if let Some(o) = r.optim {
            optim = o;
        }
        rng = r.rng;
        stage = r.state.phase;
        update = r.state.step;
        global_update = r.state.global_step;
        elapsed_before = r.state.elapsed_s;
        run_state = r.extra;
        truncate_log(&plan.log_out, r.state.log_bytes)?;
    } else {
        start_log(&plan.log_out, force)?;
    }
    let mut best = run_state.as_ref().and_then(|s| s.best_validation_return);
    let t0 = Instant::now();
    let elapsed = |t0: &Instant| elapsed_before + t0.elapsed().as_secs_f64();
    let total_updates: usize = (0..plan.stages.len()).map(|s| plan.updates(s)).sum();
    let bar = match show_progress {
        true => crate::progress::progress_bar(
            "egogen train policy",
            "training",
            "updates",
            total_updates as u64,
            global_update as u64,
        ),
        false => indicatif::ProgressBar::hidden(),
    };
    bar.set_position(global_update as u64);
    let mut last_checkpoint = Instant::now();
    let mut env_steps_total = global_update * ppo.envs * ppo.steps_per_env;
    while stage < plan.stages.len() {
        let sp = &plan.stages[stage];
        let mut env = parts
            .env(sp.env, ppo.envs, stage as u64 + 1)
            .map_err(env_error)?
            .with_sensing(&plan.arch.sensing);
        if let Some(s) = run_state.take() {
            env.restore(&s.env).map_err(env_error)?;
        }
        let updates = plan.updates(stage);
        while update < updates {
            let log = one_update(&mut net, &mut optim, &mut env, &ppo, &mut rng, &device)
                .map_err(env_error)?;
            update += 1;
            global_update += 1;
            env_steps_total += ppo.envs * ppo.steps_per_env;
            check_finite(&net, &log, &sp.name, global_update, &plan.weights_out)?;
            let mut log = UpdateLog {
                stage: sp.name.clone(),
                update: global_update,
                env_steps: env_steps_total,
                wall_s: elapsed(&t0),
                ..log
            };
            let last_stage = stage + 1 == plan.stages.len();
            if plan.eval_every_updates > 0
                && (update % plan.eval_every_updates == 0 || update == updates)
            {
                let v = validate(
                    &net.valid(),
                    parts,
                    sp.env,
                    plan.eval_episodes,
                    plan.seed ^ global_update as u64,
                )
                .map_err(env_error)?;
                let eligible = plan.select_max_prior_kl.is_none_or(|m| v.kl_prior <= m);
                if last_stage && eligible && best.is_none_or(|b| v.episode_return > b) {
                    best = Some(v.episode_return);
                    save_policy(&net.valid(), &plan.arch, &plan.weights_out)
                        .map_err(weights_error)?;
                }
                log.validation = Some(v);
            }
            if update == updates {
                save_policy(
                    &net.valid(),
                    &plan.arch,
                    &stage_last_path(&plan.weights_out, &sp.name),
                )
                .map_err(weights_error)?;
            }
            append_log(&plan.log_out, &log)?;
            bar.set_position(global_update as u64);
            bar.set_message(format!(
                "{} r/ep {:.2} success {:.0}% KL {:.1}",
                sp.name,
                log.episode_return,
                100.0 * log.success_rate,
                log.kl_prior
            ));
            let (next_stage, next_update) = if update == updates {
                (stage + 1, 0)
            } else {
                (stage, update)
            };
            let finished = next_stage == plan.stages.len();
            if !finished && (last_checkpoint.elapsed().as_secs_f64() >= plan.checkpoint_every_s) {
                let log_bytes = std::fs::metadata(&plan.log_out)
                    .map(|m| m.len())
                    .unwrap_or(0);
                let (rng_seed_hex, rng_stream, rng_word_pos) = checkpoint::rng_position(&rng);
                let state = CheckpointState {
                    plan_sha256: fingerprint.clone(),
                    phase: next_stage,
                    step: next_update,
                    global_step: global_update,
                    last_loss: log.policy_loss,
                    elapsed_s: elapsed(&t0),
                    rng_seed_hex,
                    rng_stream,
                    rng_word_pos,
                    net_file: String::new(),
                    optim_file: None,
                    extra_file: None,
                    log_bytes,
                    sha256: Default::default(),
                };
                let extra = RunState {
                    // A new stage starts with fresh environments.
                    env: match next_stage == stage {
                        true => env.snapshot(),
                        false => EnvSnapshot {
                            episode_base: u64::MAX,
                            next_episode: 0,
                            episodes: Vec::new(),
                        },
                    },
                    best_validation_return: best,
                };
                checkpoint::save::<TrainBackend, _, _, _>(
                    &ckpt_dir,
                    state,
                    &net,
                    Some(&optim),
                    Some(&extra),
                )?;
                last_checkpoint = Instant::now();
            }
        }
        stage += 1;
        update = 0;
        // A checkpoint at a stage boundary carries no environments.
        run_state = None;
    }
    bar.finish_and_clear();
    if best.is_none() {
        save_policy(&net.valid(), &plan.arch, &plan.weights_out).map_err(weights_error)?;
    }
    let _ = std::fs::remove_dir_all(&ckpt_dir);
    Ok(PolicyTrainReport {
        updates: global_update,
        env_steps: env_steps_total,
        seconds: elapsed(&t0),
        best_validation_return: best,
        parameters,
    })
}

/// Parameters of a module that are not finite (NaN or ±∞).
struct NonFiniteParams {
    count: usize,
}

impl<B: Backend> ModuleVisitor<B> for NonFiniteParams {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        let bad = param.val().is_finite().bool_not().int().sum().into_scalar();
        self.count += bad.elem::<i64>() as usize;
    }
}

/// Stops training when an update's losses or the network's weights are no longer finite (a
/// learning rate far too high, an exploding gradient): nothing non-finite is ever written as
/// weights.
fn check_finite<B: Backend>(
    net: &ActorCritic<B>,
    log: &UpdateLog,
    stage: &str,
    update: usize,
    weights_out: &Path,
) -> Result<(), TrainError> {
    let terms = [
        ("policy loss", log.policy_loss),
        ("value loss", log.value_loss),
        ("entropy", log.entropy),
        ("gradient norm", log.grad_norm),
        ("KL to the prior", log.kl_prior),
    ];
    let mut params = NonFiniteParams { count: 0 };
    net.visit(&mut params);
    let what = match terms.iter().find(|(_, v)| !v.is_finite()) {
        Some((term, v)) => format!("the {term} is {v}"),
        None if params.count > 0 => format!("{} weights are not finite", params.count),
        None => return Ok(()),
    };
    Err(TrainError::Data(format!(
        "stage `{stage}`, update {update}: {what}; training stopped, nothing written to {} \
         after this update: lower `[ppo] learning_rate` or `max_grad_norm` and train again",
        weights_out.display()
    )))
}

/// The network training starts from: `init_weights` (of the plan's architecture), or a new one.
fn initial_policy(
    plan: &PolicyTrainPlan,
    device: &burn::tensor::Device<TrainBackend>,
) -> Result<ActorCritic<TrainBackend>, TrainError> {
    let Some(path) = &plan.init_weights else {
        return Ok(plan.arch.init::<TrainBackend>(device));
    };
    let (arch, init) = load_policy::<TrainBackend>(path, device).map_err(weights_error)?;
    if arch != plan.arch {
        return Err(TrainError::Data(format!(
            "init_weights {}: architecture {arch:?}, the config asks for {:?}",
            path.display(),
            plan.arch
        )));
    }
    Ok(init)
}

/// A new run's empty log (an existing one is refused, not overwritten, unless `force`).
fn start_log(log: &Path, force: bool) -> Result<(), TrainError> {
    if !force {
        refuse_existing_output(log)?;
    }
    if let Some(dir) = log.parent() {
        std::fs::create_dir_all(dir).map_err(|source| TrainError::Io {
            path: dir.into(),
            source,
        })?;
    }
    std::fs::File::create(log).map_err(|source| TrainError::Io {
        path: log.into(),
        source,
    })?;
    Ok(())
}

fn env_error(e: EnvError) -> TrainError {
    TrainError::Data(format!("environment: {e}"))
}

fn weights_error(e: WeightsError) -> TrainError {
    TrainError::Data(e.to_string())
}

fn refuse_existing_output(path: &Path) -> Result<(), TrainError> {
    if path.exists() {
        return Err(TrainError::Data(format!(
            "{} already exists; not overwriting it (move it away, pass --force to replace it, or \
             --resume an interrupted run)",
            path.display()
        )));
    }
    Ok(())
}

fn truncate_log(path: &Path, bytes: u64) -> Result<(), TrainError> {
    let io = |source| TrainError::Io {
        path: path.into(),
        source,
    };
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(io)?;
    f.set_len(bytes).map_err(io)
}

fn append_log(path: &Path, log: &UpdateLog) -> Result<(), TrainError> {
    let io = |source| TrainError::Io {
        path: path.into(),
        source,
    };
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(path)
        .map_err(io)?;
    let line = serde_json::to_string(log).map_err(|e| TrainError::Data(e.to_string()))?;
    writeln!(f, "{line}").and_then(|_| f.flush()).map_err(io)
}

/// Collects one batch and updates the network on it.
fn one_update<O: Optimizer<ActorCritic<TrainBackend>, TrainBackend>>(
    net: &mut ActorCritic<TrainBackend>,
    optim: &mut O,
    env: &mut PolicyEnv,
    ppo: &PpoSettings,
    rng: &mut ChaCha8Rng,
    device: &burn::tensor::Device<TrainBackend>,
) -> Result<UpdateLog, EnvError> {
    let b = env.len();
    let t_steps = ppo.steps_per_env.max(1);
    let l = env.latent_dim();
    let d = env.obs_layout().dim();
    let mut obs_buf: Vec<f32> = Vec::with_capacity(t_steps * b * d);
    let mut act_buf: Vec<f32> = Vec::with_capacity(t_steps * b * l);
    let (mut logp_buf, mut val_buf, mut rew_buf, mut done_buf) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut env_s, mut forward_s) = (0.0, 0.0);
    let mut kl_sum = 0.0;
    let mut finished = Vec::new();
    let inner = net.valid();
    for _ in 0..t_steps {
        let t = Instant::now();
        let obs = env.observations();
        env_s += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (a, logp, v, kl) = act(&inner, obs.clone(), Some(rng), device);
        forward_s += t.elapsed().as_secs_f64();
        kl_sum += kl.iter().map(|&x| x as f64).sum::<f64>();
        let t = Instant::now();
        let out = env.step(&a)?;
        env_s += t.elapsed().as_secs_f64();
        obs_buf.extend(obs);
        act_buf.extend(a);
        logp_buf.extend(logp);
        val_buf.extend(v);
        rew_buf.extend(out.reward);
        done_buf.extend(out.done);
        finished.extend(out.finished);
    }
    let t = Instant::now();
    let (_, _, last_v, _) = act(&inner, env.observations(), None, device);
    forward_s += t.elapsed().as_secs_f64();
    // GAE over [T × B], row-major by step.
    let n = t_steps * b;
    let mut adv = vec![0f32; n];
    let mut next_adv = vec![0f64; b];
    for step in (0..t_steps).rev() {
        for e in 0..b {
            let i = step * b + e;
            let nonterminal = if done_buf[i] { 0.0 } else { 1.0 };
            let next_v = if step + 1 == t_steps {
                last_v[e]
            } else {
                val_buf[i + b]
            } as f64;
            let delta = rew_buf[i] as f64 + ppo.gamma * next_v * nonterminal - val_buf[i] as f64;
            next_adv[e] = delta + ppo.gamma * ppo.gae_lambda * nonterminal * next_adv[e];
            adv[i] = next_adv[e] as f32;
        }
    }
    let returns: Vec<f32> = adv.iter().zip(&val_buf).map(|(a, v)| a + v).collect();
    // Update.
    let t = Instant::now();
    let mb = ppo.minibatch.clamp(1, n);
    let (
        mut approx_kl,
        mut minibatches,
        mut pl_sum,
        mut vl_sum,
        mut ent_sum,
        mut gn_sum,
        mut cf_sum,
    ) = (0.0, 0usize, 0.0, 0.0, 0.0, 0.0, 0.0);
    'epochs: for _ in 0..ppo.epochs.max(1) {
        let mut order: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let j = (rand_core::Rng::next_u64(rng) % (i as u64 + 1)) as usize;
            order.swap(i, j);
        }
        for chunk in order.chunks(mb) {
            let m = chunk.len();
            let gather = |src: &[f32], width: usize| -> Vec<f32> {
                chunk
                    .iter()
                    .flat_map(|&i| src[i * width..(i + 1) * width].iter().copied())
                    .collect()
            };
            let obs = to_tensor::<TrainBackend>(gather(&obs_buf, d), [m, d], device);
            let acts = to_tensor::<TrainBackend>(gather(&act_buf, l), [m, l], device);
            let old_logp = Tensor::<TrainBackend, 1>::from_data(
                TensorData::new(gather(&logp_buf, 1), [m]),
                device,
            );
            let mut a = gather(&adv, 1);
            let mean = a.iter().map(|&x| x as f64).sum::<f64>() / m as f64;
            let std = (a.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / m as f64).sqrt();
            a.iter_mut()
                .for_each(|x| *x = ((*x as f64 - mean) / (std + 1e-8)) as f32);
            let adv_t = Tensor::<TrainBackend, 1>::from_data(TensorData::new(a, [m]), device);
            let ret = Tensor::<TrainBackend, 1>::from_data(
                TensorData::new(gather(&returns, 1), [m]),
                device,
            );
            let out = net.forward(obs);
            let logp = log_prob(acts, out.mean.clone(), out.logvar.clone());
            let log_ratio = logp.clone() - old_logp;
            let ratio = log_ratio.clone().exp();
            let surr1 = ratio.clone() * adv_t.clone();
            let surr2 = ratio.clone().clamp(1.0 - ppo.clip, 1.0 + ppo.clip) * adv_t;
            let policy_loss = -surr1.min_pair(surr2).mean();
            let value_loss = (out.value - ret).square().mean();
            let ent = entropy(out.logvar.clone()).mean();
            let mut loss = policy_loss.clone() + value_loss.clone().mul_scalar(ppo.value_coef)
                - ent.clone().mul_scalar(ppo.entropy_coef);
            if ppo.prior_kl_coef > 0.0 {
                let kl = kl_to_standard(out.mean, out.logvar).mean();
                loss = loss + kl.mul_scalar(ppo.prior_kl_coef);
            }
            let mut grads = GradientsParams::from_grads(loss.backward(), net);
            let norm = clip_global_norm::<TrainBackend, _>(net, &mut grads, ppo.max_grad_norm);
            *net = optim.step(ppo.learning_rate, net.clone(), grads);
            let lr_values = values(log_ratio.inner());
            approx_kl = -lr_values.iter().map(|&x| x as f64).sum::<f64>() / m as f64;
            cf_sum += values(ratio.inner())
                .iter()
                .filter(|&&r| (r as f64 - 1.0).abs() > ppo.clip)
                .count() as f64
                / m as f64;
            pl_sum += policy_loss.into_scalar().elem::<f64>();
            vl_sum += value_loss.into_scalar().elem::<f64>();
            ent_sum += ent.into_scalar().elem::<f64>();
            gn_sum += norm;
            minibatches += 1;
            if approx_kl > ppo.target_kl {
                break 'epochs;
            }
        }
    }
    let k = minibatches.max(1) as f64;
    let ne = finished.len();
    let nf = ne.max(1) as f64;
    Ok(UpdateLog {
        stage: String::new(),
        update: 0,
        env_steps: 0,
        wall_s: 0.0,
        step_reward: rew_buf.iter().map(|&r| r as f64).sum::<f64>() / n as f64,
        episodes: ne,
        episode_return: finished.iter().map(|s| s.reward).sum::<f64>() / nf,
        success_rate: finished
            .iter()
            .filter(|s| s.ending == super::env::Ending::Success)
            .count() as f64
            / nf,
        episode_length: finished.iter().map(|s| s.primitives as f64).sum::<f64>() / nf,
        kl_prior: kl_sum / n as f64,
        approx_kl,
        minibatches,
        policy_loss: pl_sum / k,
        value_loss: vl_sum / k,
        entropy: ent_sum / k,
        grad_norm: gn_sum / k,
        clip_fraction: cf_sum / k,
        env_s,
        forward_s,
        update_s: t.elapsed().as_secs_f64(),
        validation: None,
    })
}
