//! Training: single primitives first, then rollout fine-tuning over chains of primitives, each
//! decoded from the previous one's last two frames (gradients flow through the chain), then
//! prior fine-tuning: chains decoded from random latents z ~ N(0, I), as they are used, kept
//! on the floor and upright by losses that need no mocap target and anchored to the root motion
//! the starting weights decode for the same latents, next to the reconstruction of mocap
//! chains. Deterministic for a seed: batches, noise and initial weights all come from it.
//!
//! Here: the loop; `setup` (what training starts from and ends with: the checkpoint resumed,
//! the training and held-out sets, the starting weights, the output folders, and the weights,
//! report and loss log written at the end), `chains` (the losses of a batch of chains),
//! `prior` (the prior phase's terms of a step).

mod chains;
mod prior;
mod setup;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::backend::{Autodiff, Flex};
use burn::grad_clipping::GradientClippingConfig;
use burn::module::AutodiffModule;
use burn::optim::{AdamConfig, GradientsParams, Optimizer};
use burn::prelude::*;
use indicatif::ProgressBar;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use super::checkpoint;
use super::data::{build_set, ClipPart, ContactFilter, PrimitiveSet};
use super::loss::{LossWeights, PlausibleRange, PriorWeights};
use super::net::{ArchConfig, PrimitiveVae};
use super::pool::SeedPool;
use super::tensor_body::{RigGeometry, TensorRig};
pub(crate) use super::train_error::TrainError;
use crate::body::BodyModel;
use crate::motion::primitive::PRIMITIVE_RATE_HZ;
use crate::motion::MotionSequence;

use chains::batch;
pub(crate) use chains::chain_loss;
use prior::{PriorStep, SeedIndex};
use setup::{
    create_output_dirs, finish_training, initial_net, prior_range, restore, training_sets,
    Restored, TrainingSets,
};

/// The loss log gets every this many steps (and each phase's last).
pub(crate) const LOG_EVERY_STEPS: usize = 10;

/// Backend of training (CPU, reverse-mode autodiff).
pub type TrainBackend = Autodiff<Flex>;

/// One clip of the training config.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipSpec {
    pub path: PathBuf,
    /// The whole clip is held out for evaluation.
    pub held_out: bool,
    /// Frames from this time on (s) are held out; earlier ones train.
    pub held_out_from_s: Option<f64>,
}

/// Length of one training phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhasePlan {
    pub steps: usize,
    pub batch_size: usize,
    pub learning_rate: f64,
}

/// The prior fine-tuning phase: each step decodes `phase.batch_size` chains of `primitives`
/// primitives from random latents (gradients through the chain) next to as many mocap chains
/// reconstructed as in the rollout phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PriorPlan {
    pub phase: PhasePlan,
    pub primitives: usize,
    /// Share of the random chains that start where an earlier random chain ended (the others
    /// start from mocap seeds), so that training sees the states long chains reach.
    pub pool_fraction: f64,
    /// Persistent chains of the seed pool (`pool::SeedPool::Slots`); none for the pool of
    /// recent chain ends.
    pub pool_slots: Option<usize>,
    /// The pelvis-height and trunk-lean ranges run between these quantiles of the training
    /// frames (`loss::plausible_range`).
    pub range_quantile: f64,
    /// Overrides the data's steepest trunk lean (degrees from vertical).
    pub trunk_tilt_max_deg: Option<f64>,
    /// Slowest mean pelvis speed over a primitive that passes free (m/s; 0 for no limit).
    pub min_pelvis_speed_m_s: f64,
    pub weights: PriorWeights,
}

/// A checked training run (see `cli::train` for the config file).
#[derive(Debug, Clone, PartialEq)]
pub struct TrainPlan {
    pub seed: u64,
    pub body_model: PathBuf,
    pub clips: Vec<ClipSpec>,
    /// Frames between the starts of consecutive training primitives.
    pub stride_frames: usize,
    /// Add the left-right mirrored clips.
    pub mirror: bool,
    /// Keep only primitives whose mocap foot-contact score reaches this (`data::ContactFilter`).
    pub min_contact_score: Option<f64>,
    /// Primitives starting within this many frames of one that fails the contact filter are
    /// dropped too (`data::ContactFilter`).
    pub contact_context_frames: usize,
    pub arch: ArchConfig,
    pub loss: LossWeights,
    /// Steps over which the KL weight ramps up from 0.
    pub kl_warmup_steps: usize,
    /// Noise on the first seed of mocap chains, in feature standard deviations
    /// ([`chain_loss`]; 0 for none).
    pub seed_noise: f64,
    pub primitive: PhasePlan,
    pub rollout: PhasePlan,
    /// Primitives per rollout chain.
    pub rollout_primitives: usize,
    /// Prior fine-tuning after the rollout phase (none when absent).
    pub prior: Option<PriorPlan>,
    /// Start from these weights (same architecture) instead of a fresh network; their input
    /// normalisation is kept.
    pub init_weights: Option<PathBuf>,
    pub weights_out: PathBuf,
    pub log_out: PathBuf,
    /// Seconds between checkpoints (`checkpoint::checkpoint_dir(weights_out)`); 0 writes one
    /// after every step.
    pub checkpoint_every_s: f64,
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct TrainReport {
    pub train_primitives: usize,
    pub train_chains: usize,
    pub held_out_primitives: usize,
    pub seconds: f64,
    pub final_loss: f64,
    pub held_out_mpjpe_mm: Option<f64>,
}

/// Loads the clips of a plan and splits them into training and held-out parts.
pub(crate) fn load_clips(plan: &TrainPlan) -> Result<(Vec<ClipPart>, Vec<ClipPart>), TrainError> {
    let mut train = Vec::new();
    let mut held_out = Vec::new();
    for spec in &plan.clips {
        let seq = MotionSequence::read(&spec.path)?;
        if (seq.frame_rate_hz - PRIMITIVE_RATE_HZ).abs() > 1e-6 {
            return Err(TrainError::Data(format!(
                "clip {}: {} Hz, expected {PRIMITIVE_RATE_HZ} Hz (resample it with `egogen motion import --rate-hz 40`)",
                spec.path.display(),
                seq.frame_rate_hz
            )));
        }
        let n = seq.len();
        let split = match (spec.held_out, spec.held_out_from_s) {
            (true, _) => 0,
            (false, Some(t)) => ((t * PRIMITIVE_RATE_HZ).round() as usize).min(n),
            (false, None) => n,
        };
        let part = |frames| ClipPart {
            seq: seq.clone(),
            frames,
        };
        if split > 0 {
            train.push(part(0..split));
        }
        if split < n {
            held_out.push(part(split..n));
        }
    }
    Ok((train, held_out))
}

pub use crate::math::random::normal_samples;

/// Writes one JSON line to the loss log at `path`, flushed, so that the log can be followed
/// during a run.
fn log_line(log: &mut impl Write, line: &serde_json::Value, path: &Path) -> Result<(), TrainError> {
    writeln!(log, "{line}")
        .and_then(|_| log.flush())
        .map_err(|source| TrainError::Io {
            path: path.into(),
            source,
        })
}

/// The optimiser every phase starts with (Adam, gradients clipped to norm 1 per tensor).
fn new_optimizer() -> PrimitiveOptimizer {
    AdamConfig::new()
        .with_grad_clipping(Some(GradientClippingConfig::Norm(1.0)))
        .init::<TrainBackend, PrimitiveVae<TrainBackend>>()
}

/// Trains per the plan and writes weights and the loss log, with a checkpoint every
/// `plan.checkpoint_every_s`; `resume` continues from the checkpoint an interrupted run left
/// (refused when there is none, or when it belongs to another plan). Without `resume`, an
/// existing checkpoint is refused rather than overwritten.
pub fn train(
    plan: &TrainPlan,
    show_progress: bool,
    resume: bool,
) -> Result<TrainReport, TrainError> {
    let Started {
        started,
        ckpt_dir,
        fingerprint,
        device,
        geo,
        sets: TrainingSets {
            singles,
            chains,
            held,
        },
        mut rng,
        rig,
        mut net,
        mut restored_optim,
        mut pool,
        elapsed_before_s,
        resume_at,
        mut log,
        bar,
        range,
        anchor_net,
        seed_index,
    } = start_training(plan, show_progress, resume)?;
    let log_io = |source| TrainError::Io {
        path: plan.log_out.clone(),
        source,
    };
    let (resume_phase, resume_step, mut global_step, mut final_loss) = resume_at;
    bar.set_position(global_step as u64);
    let mut last_checkpoint = Instant::now();
    let prior_phase = plan.prior.map(|p| p.phase).unwrap_or(PhasePlan {
        steps: 0,
        batch_size: 1,
        learning_rate: 0.0,
    });
    for (phase_index, (phase, phase_plan, set)) in [
        ("primitive", plan.primitive, &singles),
        ("rollout", plan.rollout, &chains),
        ("prior", prior_phase, &chains),
    ]
    .into_iter()
    .enumerate()
    {
        if phase_plan.steps == 0 || phase_index < resume_phase {
            continue;
        }
        let first_step = if phase_index == resume_phase {
            resume_step
        } else {
            0
        };
        let mut optim = match restored_optim.take() {
            Some(o) if phase_index == resume_phase => o,
            _ => new_optimizer(),
        };
        for step in first_step..phase_plan.steps {
            let (lr, weights) = step_rates(plan, &phase_plan, step, global_step);
            let (x, floors) = batch::<TrainBackend>(set, phase_plan.batch_size, &mut rng, &device);
            let (mut loss, mut parts) =
                chain_loss(&net, &rig, &weights, x, floors, plan.seed_noise, &mut rng);
            if let (true, Some(prior), Some(range)) = (phase == "prior", &plan.prior, &range) {
                let step = PriorStep {
                    net: &net,
                    anchor_net: anchor_net.as_ref(),
                    rig: &rig,
                    prior,
                    range,
                    set,
                    seed_index: seed_index.as_ref(),
                    weights: &weights,
                    batch_size: phase_plan.batch_size,
                };
                loss = step.add_to(loss, &mut parts, &mut pool, &mut rng, &device);
            }
            let value = loss.clone().into_scalar().elem::<f64>();
            if !value.is_finite() {
                return Err(TrainError::Diverged {
                    phase,
                    step,
                    loss: value,
                });
            }
            let grads = GradientsParams::from_grads(loss.backward(), &net);
            net = optim.step(lr, net, grads);
            final_loss = value;
            let elapsed_s = elapsed_before_s + started.elapsed().as_secs_f64();
            let line = step_line(phase, step, lr, value, elapsed_s, &parts);
            if step % LOG_EVERY_STEPS == 0 || step + 1 == phase_plan.steps {
                log_line(&mut log, &line, &plan.log_out)?;
            }
            bar.set_message(format!("{phase} loss {value:.4}"));
            bar.inc(1);
            global_step += 1;
            let done = step + 1 == phase_plan.steps;
            if !done && last_checkpoint.elapsed().as_secs_f64() >= plan.checkpoint_every_s {
                let state = checkpoint::CheckpointState {
                    plan_sha256: fingerprint.clone(),
                    phase: phase_index,
                    step: step + 1,
                    global_step,
                    last_loss: final_loss,
                    elapsed_s: elapsed_before_s + started.elapsed().as_secs_f64(),
                    ..checkpoint_state(&rng, &plan.log_out, log_io)?
                };
                let pool = (phase == "prior").then_some(&pool);
                checkpoint::save::<TrainBackend, _, _, _>(
                    &ckpt_dir,
                    state,
                    &net,
                    Some(&optim),
                    pool,
                )?;
                last_checkpoint = Instant::now();
            }
        }
    }
    bar.finish_and_clear();
    let sets = TrainingSets {
        singles,
        chains,
        held,
    };
    let seconds = elapsed_before_s + started.elapsed().as_secs_f64();
    finish_training(
        plan,
        &net.valid(),
        &geo,
        &sets,
        &mut log,
        seconds,
        final_loss,
    )
}

/// Everything training starts from: the sets, the rig, the starting (or checkpoint's) weights
/// and optimiser, the random stream, the loss log, the progress bar, and what the prior phase
/// reads (the plausible range, the frozen anchor, the seed index).
struct Started {
    started: Instant,
    ckpt_dir: PathBuf,
    fingerprint: String,
    device: Device<TrainBackend>,
    geo: RigGeometry,
    sets: TrainingSets,
    rng: ChaCha8Rng,
    rig: TensorRig<TrainBackend>,
    net: PrimitiveVae<TrainBackend>,
    restored_optim: Option<PrimitiveOptimizer>,
    pool: SeedPool,
    elapsed_before_s: f64,
    resume_at: (usize, usize, usize, f64),
    log: std::io::BufWriter<std::fs::File>,
    bar: ProgressBar,
    range: Option<PlausibleRange>,
    anchor_net: Option<PrimitiveVae<Flex>>,
    seed_index: Option<SeedIndex>,
}

/// Loads and checks everything before the first step, in this order: the checkpoint folder
/// (refused as [`train`] says), the body, the sets, the seeded backend and random stream, the
/// starting weights, the output folders, the checkpoint resumed, the plausible range, the
/// frozen anchor and the seed index (both from the starting weights).
fn start_training(
    plan: &TrainPlan,
    show_progress: bool,
    resume: bool,
) -> Result<Started, TrainError> {
    let started = Instant::now();
    let ckpt_dir = checkpoint::checkpoint_dir(&plan.weights_out);
    checkpoint::check_resume(&ckpt_dir, resume)?;
    let fingerprint = checkpoint::plan_fingerprint(plan);
    let device: Device<TrainBackend> = Default::default();
    let model = BodyModel::load(&plan.body_model)?;
    let geo = RigGeometry::new(&model, &[])?;
    let TrainingSets {
        singles,
        chains,
        held,
    } = training_sets(plan, &model)?;
    TrainBackend::seed(&device, plan.seed);
    let mut rng = ChaCha8Rng::seed_from_u64(plan.seed);
    let rig = TensorRig::<TrainBackend>::new(&geo, &device);
    let mut net = initial_net(plan, &singles, &device)?;
    create_output_dirs(plan)?;
    let Restored {
        net: resumed_net,
        optim: restored_optim,
        pool: restored_pool,
        elapsed_before_s,
        at: resume_at,
        log,
    } = restore(
        plan,
        resume,
        &ckpt_dir,
        &fingerprint,
        &net,
        &mut rng,
        &device,
    )?;
    let mut log = log;

    let bar = training_bar(plan, show_progress, resume_at.2);
    let range = match plan.prior {
        Some(prior) => Some(prior_range(
            plan, &prior, &singles, &geo, &mut log, !resume,
        )?),
        None => None,
    };
    let anchor_net = anchor_net(plan, &net)?;
    let pool =
        restored_pool.unwrap_or_else(|| SeedPool::new(plan.prior.and_then(|p| p.pool_slots)));
    let seed_index = plan
        .prior
        .filter(|p| p.weights.recovery > 0.0 && p.phase.steps > 0)
        .map(|_| SeedIndex::new(&chains, &net));
    // The frozen anchor and the seed index above come from the starting weights; training
    // continues from the checkpoint's.
    if let Some(n) = resumed_net {
        net = n;
    }
    Ok(Started {
        started,
        ckpt_dir,
        fingerprint,
        device,
        geo,
        sets: TrainingSets {
            singles,
            chains,
            held,
        },
        rng,
        rig,
        net,
        restored_optim,
        pool,
        elapsed_before_s,
        resume_at,
        log,
        bar,
        range,
        anchor_net,
        seed_index,
    })
}

/// The progress bar over every phase's steps (hidden without `show_progress`), at `done`.
fn training_bar(plan: &TrainPlan, show_progress: bool, done: usize) -> ProgressBar {
    let prior_steps = plan.prior.map_or(0, |p| p.phase.steps);
    let total_steps = plan.primitive.steps + plan.rollout.steps + prior_steps;
    match show_progress {
        true => crate::progress::progress_bar(
            "egogen train primitive",
            "training",
            "steps",
            total_steps as u64,
            done as u64,
        ),
        false => ProgressBar::hidden(),
    }
}

/// The starting weights, frozen, for `prior.loss.anchor` (refused without `init_weights`).
fn anchor_net(
    plan: &TrainPlan,
    net: &PrimitiveVae<TrainBackend>,
) -> Result<Option<PrimitiveVae<Flex>>, TrainError> {
    Ok(match plan.prior {
        Some(p) if p.weights.anchor > 0.0 && p.phase.steps > 0 => {
            if plan.init_weights.is_none() {
                return Err(TrainError::Data(
                    "prior.loss.anchor needs init_weights: the weights it keeps random latents near"
                        .into(),
                ));
            }
            Some(net.valid())
        }
        _ => None,
    })
}

/// A step's learning rate (cosine decay to a tenth of the phase's rate) and loss weights (the
/// KL term warmed up over `kl_warmup_steps`).
fn step_rates(
    plan: &TrainPlan,
    phase_plan: &PhasePlan,
    step: usize,
    global_step: usize,
) -> (f64, LossWeights) {
    // Cosine decay to a tenth of the phase's rate.
    let progress = step as f64 / phase_plan.steps as f64;
    let lr =
        phase_plan.learning_rate * (0.1 + 0.45 * (1.0 + (std::f64::consts::PI * progress).cos()));
    let mut weights = plan.loss;
    if plan.kl_warmup_steps > 0 {
        weights.kl *= (global_step as f64 / plan.kl_warmup_steps as f64).min(1.0);
    }
    (lr, weights)
}

/// A step's line of the loss log: phase, step, rate, loss, time, and each named loss term.
fn step_line(
    phase: &str,
    step: usize,
    lr: f64,
    value: f64,
    elapsed_s: f64,
    parts: &[(&'static str, f64)],
) -> serde_json::Value {
    let mut line = serde_json::json!({
        "phase": phase,
        "step": step,
        "lr": lr,
        "loss": value,
        "elapsed_s": elapsed_s,
    });
    for (name, v) in parts {
        line[*name] = serde_json::json!(v);
    }
    line
}

/// A checkpoint's state as far as the random stream and the loss log give it (the rng's
/// position, the log's length); the caller fills in where training is.
fn checkpoint_state(
    rng: &ChaCha8Rng,
    log_out: &Path,
    log_io: impl Fn(std::io::Error) -> TrainError,
) -> Result<checkpoint::CheckpointState, TrainError> {
    let (rng_seed_hex, rng_stream, rng_word_pos) = checkpoint::rng_position(rng);
    Ok(checkpoint::CheckpointState {
        plan_sha256: String::new(),
        phase: 0,
        step: 0,
        global_step: 0,
        last_loss: 0.0,
        elapsed_s: 0.0,
        rng_seed_hex,
        rng_stream,
        rng_word_pos,
        net_file: String::new(),
        optim_file: None,
        extra_file: None,
        log_bytes: std::fs::metadata(log_out).map_err(log_io)?.len(),
        sha256: Default::default(),
    })
}

/// The optimiser every phase uses ([`new_optimizer`]).
type PrimitiveOptimizer = burn::optim::adaptor::OptimizerAdaptor<
    burn::optim::Adam,
    PrimitiveVae<TrainBackend>,
    TrainBackend,
>;

/// Clip parts of a plan as sets for evaluation: `(train, held_out)` single primitives, no
/// mirroring, filtered by contact score (without context) when `filtered`, so that held-out
/// numbers stay comparable across `data.contact_context_s`.
pub fn evaluation_sets(
    plan: &TrainPlan,
    model: &BodyModel,
    filtered: bool,
) -> Result<(PrimitiveSet, PrimitiveSet), TrainError> {
    let (train, held) = load_clips(plan)?;
    let filter = match (filtered, plan.min_contact_score) {
        (true, Some(s)) => Some(ContactFilter::new(model, s, 0)?),
        _ => None,
    };
    Ok((
        build_set(&train, 1, plan.stride_frames, false, model, filter.as_ref())?,
        build_set(&held, 1, plan.stride_frames, false, model, filter.as_ref())?,
    ))
}

/// Default path of the shipped weights, relative to the crate root.
pub(crate) const SHIPPED_WEIGHTS: &str = "assets/motion/primitive_cvae.safetensors";

/// The shipped weights' path.
pub fn shipped_weights_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(SHIPPED_WEIGHTS)
}
