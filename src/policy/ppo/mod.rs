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
//!
//! This file holds the settings, the plans and the training loop; `act` acts with the burn
//! network, `update` is one update, `outputs` what a run writes and refuses.

mod act;
mod outputs;
mod update;

use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::module::AutodiffModule;
use burn::optim::AdamWConfig;
use burn::prelude::*;
use burn::tensor::backend::AutodiffBackend;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

pub use act::{act, action_distribution, actions};
use outputs::{
    append_log, check_finite, env_error, initial_policy, refuse_earlier_weights, stage_last_path,
    start_log, truncate_log, weights_error,
};
pub use update::clip_global_norm;
use update::one_update;

use super::env::{EnvError, EnvParts, EnvSettings, EnvSnapshot, PolicyEnv};
use super::net::{ActorCritic, PolicyArch};
use super::weights::save_policy;
use crate::motion::cvae::checkpoint::{self, CheckpointState};
use crate::motion::cvae::train::{TrainBackend, TrainError};

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
    /// Generated dwellings whose pairs some episodes walk (each stage's `env.dwellings`), one
    /// scene each (the config's `[dwellings]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dwellings: Vec<TrainScene>,
    pub weights_out: PathBuf,
    pub log_out: PathBuf,
    pub checkpoint_every_s: f64,
}

impl PolicyTrainPlan {
    /// Updates of a stage.
    pub(crate) fn updates(&self, stage: usize) -> usize {
        let per = (self.ppo.envs * self.ppo.steps_per_env).max(1);
        self.stages[stage].env_steps.div_ceil(per)
    }
}

/// Episode base of validation episodes.
pub(crate) const VALIDATION_BASE: u64 = 0x7A11_0000;

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
pub(crate) struct PolicyTrainReport {
    pub updates: usize,
    pub env_steps: usize,
    pub seconds: f64,
    pub best_validation_return: Option<f64>,
    pub parameters: usize,
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

/// Trains per the plan; `resume` continues the checkpoint a killed run left (refused when
/// there is none or it belongs to another plan; without `resume` an existing one is refused).
/// A new run refuses weights an earlier run left at the plan's outputs unless `force`; a loss
/// or a weight that goes non-finite stops the run with the update and the term.
pub(crate) fn train_policy(
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
        refuse_earlier_weights(plan)?;
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
    let bar = progress_bar(show_progress, total_updates, global_update);
    bar.set_position(global_update as u64);
    let mut last_checkpoint = Instant::now();
    let mut env_steps_total = global_update * ppo.envs * ppo.steps_per_env;
    while stage < plan.stages.len() {
        let sp = &plan.stages[stage];
        let mut env = stage_env(plan, parts, stage, run_state.take())?;
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
                let v =
                    validate_update(plan, parts, sp, &net, global_update, last_stage, &mut best)?;
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
                let state = checkpoint_state(
                    &fingerprint,
                    &plan.log_out,
                    &rng,
                    [next_stage, next_update, global_update],
                    log.policy_loss,
                    elapsed(&t0),
                );
                let extra = run_state_at(&env, next_stage == stage, best);
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

/// The progress bar of a run of `total_updates` updates, `global_update` of them done.
fn progress_bar(
    show_progress: bool,
    total_updates: usize,
    global_update: usize,
) -> indicatif::ProgressBar {
    match show_progress {
        true => crate::progress::progress_bar(
            "egogen train policy",
            "training",
            "updates",
            total_updates as u64,
            global_update as u64,
        ),
        false => indicatif::ProgressBar::hidden(),
    }
}

/// The environments of `stage`, restored to a checkpoint's when it carries them.
fn stage_env<'m>(
    plan: &PolicyTrainPlan,
    parts: &EnvParts<'m>,
    stage: usize,
    run_state: Option<RunState>,
) -> Result<PolicyEnv<'m>, TrainError> {
    let sp = &plan.stages[stage];
    let mut env = parts
        .env(sp.env, plan.ppo.envs, stage as u64 + 1)
        .map_err(env_error)?
        .with_sensing(&plan.arch.sensing);
    if let Some(s) = run_state {
        env.restore(&s.env).map_err(env_error)?;
    }
    Ok(env)
}

/// Validates the policy after an update of stage `sp`; the best eligible validation of the last
/// stage saves the weights.
fn validate_update(
    plan: &PolicyTrainPlan,
    parts: &EnvParts,
    sp: &StagePlan,
    net: &ActorCritic<TrainBackend>,
    global_update: usize,
    last_stage: bool,
    best: &mut Option<f64>,
) -> Result<Validation, TrainError> {
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
        *best = Some(v.episode_return);
        save_policy(&net.valid(), &plan.arch, &plan.weights_out).map_err(weights_error)?;
    }
    Ok(v)
}

/// A checkpoint's state: the run resumes at `[stage, update, global update]` with `rng` where
/// it is now and the log cut to its present length.
fn checkpoint_state(
    fingerprint: &str,
    log_out: &Path,
    rng: &ChaCha8Rng,
    [phase, step, global_step]: [usize; 3],
    last_loss: f64,
    elapsed_s: f64,
) -> CheckpointState {
    let log_bytes = std::fs::metadata(log_out).map(|m| m.len()).unwrap_or(0);
    let (rng_seed_hex, rng_stream, rng_word_pos) = checkpoint::rng_position(rng);
    CheckpointState {
        plan_sha256: fingerprint.to_string(),
        phase,
        step,
        global_step,
        last_loss,
        elapsed_s,
        rng_seed_hex,
        rng_stream,
        rng_word_pos,
        net_file: String::new(),
        optim_file: None,
        extra_file: None,
        log_bytes,
        sha256: Default::default(),
    }
}

/// What a checkpoint carries besides the network: `env`'s episodes when the stage goes on
/// (`same_stage`), and the best validation return so far.
fn run_state_at(env: &PolicyEnv, same_stage: bool, best: Option<f64>) -> RunState {
    RunState {
        // A new stage starts with fresh environments.
        env: match same_stage {
            true => env.snapshot(),
            false => EnvSnapshot {
                episode_base: u64::MAX,
                next_episode: 0,
                episodes: Vec::new(),
            },
        },
        best_validation_return: best,
    }
}
