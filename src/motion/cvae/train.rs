//! Training: single primitives first, then rollout fine-tuning over chains of primitives, each
//! decoded from the previous one's last two frames (gradients flow through the chain), then
//! prior fine-tuning: chains decoded from random latents z ~ N(0, I), as they are used, kept
//! on the floor and upright by losses that need no mocap target and anchored to the root motion
//! the starting weights decode for the same latents, next to the reconstruction of mocap
//! chains. Deterministic for a seed: batches, noise and initial weights all come from it.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::backend::{Autodiff, Flex};
use burn::grad_clipping::GradientClippingConfig;
use burn::module::AutodiffModule;
use burn::optim::{AdamConfig, GradientsParams, Optimizer};
use burn::prelude::*;
use burn::tensor::backend::AutodiffBackend;
use indicatif::ProgressBar;
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::data::{build_set, ClipPart, ContactFilter, PrimitiveSet, PRIMITIVE_VALUES};
use super::loss::{
    pelvis_and_trunk, plausible_range, pose_frames, primitive_loss, prior_loss, LossWeights,
    PlausibleRange, PriorWeights,
};
use super::measure::{decode_raw, marker_mpjpe_mm, UPRIGHT_PELVIS_M};
use super::net::{ArchConfig, PrimitiveVae};
use super::pool::SeedPool;
use super::rollout::next_seed;
use super::tensor_body::{RigGeometry, TensorRig};
pub use super::train_error::TrainError;
use super::{checkpoint, weights};
use crate::body::BodyModel;
use crate::motion::primitive::{PRIMITIVE_FRAMES, PRIMITIVE_RATE_HZ, SEED_FRAMES};
use crate::motion::MotionSequence;

use super::features::FRAME_DIM;

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
        let name = spec
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let n = seq.len();
        let split = match (spec.held_out, spec.held_out_from_s) {
            (true, _) => 0,
            (false, Some(t)) => ((t * PRIMITIVE_RATE_HZ).round() as usize).min(n),
            (false, None) => n,
        };
        let part = |frames| ClipPart {
            name: name.clone(),
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

/// A random batch of items of `set` as `[B, K, T, F]` features and `[B, K]` floors.
fn batch<B: Backend>(
    set: &PrimitiveSet,
    size: usize,
    rng: &mut ChaCha8Rng,
    device: &B::Device,
) -> (Tensor<B, 4>, Tensor<B, 2>) {
    let k = set.chain_len;
    let mut x = Vec::with_capacity(size * k * PRIMITIVE_VALUES);
    let mut floors = Vec::with_capacity(size * k);
    for _ in 0..size {
        let i = (rng.next_u64() % set.len() as u64) as usize;
        x.extend_from_slice(set.item(i));
        floors.extend_from_slice(set.floors(i));
    }
    (
        Tensor::from_data(
            TensorData::new(x, [size, k, PRIMITIVE_FRAMES, FRAME_DIM]),
            device,
        ),
        Tensor::from_data(TensorData::new(floors, [size, k]), device),
    )
}

/// Loss of a batch of chains `[B, K, T, F]`: every primitive after the first is decoded from
/// the seed that the previous decoded primitive leaves. With `seed_noise` > 0 the first seed
/// is offset by Gaussian noise (the same for both seed frames) of that many feature standard
/// deviations while the targets stay the mocap's: the decoder cannot recognise a clip by its
/// seed alone, and learns to bring a body that is off the data back onto it.
pub fn chain_loss<B: Backend>(
    net: &PrimitiveVae<B>,
    rig: &TensorRig<B>,
    weights: &LossWeights,
    x: Tensor<B, 4>,
    floors: Tensor<B, 2>,
    seed_noise: f64,
    rng: &mut ChaCha8Rng,
) -> (Tensor<B, 1>, Vec<(&'static str, f64)>) {
    let [b, _, t, f] = x.dims();
    let mut seed = x
        .clone()
        .narrow(1, 0, 1)
        .reshape([b, t, f])
        .narrow(1, 0, SEED_FRAMES);
    if seed_noise > 0.0 {
        let noise = Tensor::<B, 3>::from_data(
            TensorData::new(normal_samples(rng, b * f), [b, 1, f]),
            &x.device(),
        );
        let std = net.feature_std.val().detach().reshape([1, 1, f]);
        seed = seed + noise.mul(std).mul_scalar(seed_noise);
    }
    let floor = floors.clone().narrow(1, 0, 1).reshape([b]);
    chain_loss_from(net, rig, weights, seed, floor, x, floors, rng)
}

/// [`chain_loss`] of chains whose first primitive is decoded from `seed` `[B, S, F]` over
/// canonical floors `floor` `[B]` instead of the mocap's own seed.
#[allow(clippy::too_many_arguments)]
fn chain_loss_from<B: Backend>(
    net: &PrimitiveVae<B>,
    rig: &TensorRig<B>,
    weights: &LossWeights,
    mut seed: Tensor<B, 3>,
    mut pred_floor: Tensor<B, 1>,
    x: Tensor<B, 4>,
    floors: Tensor<B, 2>,
    rng: &mut ChaCha8Rng,
) -> (Tensor<B, 1>, Vec<(&'static str, f64)>) {
    let [b, k, t, f] = x.dims();
    let device = x.device();
    let latent = net.latent_dim();
    let mut total: Option<Tensor<B, 1>> = None;
    let mut parts: Vec<(&'static str, f64)> = Vec::new();
    for c in 0..k {
        let target = x.clone().narrow(1, c, 1).reshape([b, t, f]);
        let target_floor = floors.clone().narrow(1, c, 1).reshape([b]);
        let (mu, logvar) = net.encode(net.normalize(target.clone()));
        let eps = Tensor::<B, 2>::from_data(
            TensorData::new(normal_samples(rng, b * latent), [b, latent]),
            &device,
        );
        let z = mu.clone() + logvar.clone().mul_scalar(0.5).exp() * eps;
        let full = decode_raw(net, seed.clone(), pred_floor.clone(), z);
        let terms = primitive_loss(
            rig,
            weights,
            full.clone(),
            target,
            pred_floor.clone(),
            target_floor,
            (mu, logvar),
        );
        total = Some(match total {
            Some(t) => t + terms.total,
            None => terms.total,
        });
        add_parts(&mut parts, terms.parts, k);
        if c + 1 < k {
            let (next, height) = next_seed(rig, full);
            seed = next;
            pred_floor = pred_floor - height;
        }
    }
    let total = total.expect("at least one primitive").div_scalar(k as f64);
    (total, parts)
}

/// Loss of `seed.dims()[0]` chains of `primitives` primitives decoded from random latents,
/// starting from raw seeds `[B, S, F]` over canonical floors `[B]`. Also returns the chains'
/// ends (`[B × S × F]` seeds, `[B]` floors) and whether each end is still upright
/// ([`UPRIGHT_PELVIS_M`] and a trunk within [`POOL_TRUNK_TILT_MAX_DEG`] of vertical) — a
/// persistent pool drops the others.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn prior_chain_loss<B: AutodiffBackend>(
    net: &PrimitiveVae<B>,
    anchor_net: Option<&PrimitiveVae<B::InnerBackend>>,
    rig: &TensorRig<B>,
    plan: &PriorPlan,
    range: &PlausibleRange,
    mut seed: Tensor<B, 3>,
    mut floor: Tensor<B, 1>,
    rng: &mut ChaCha8Rng,
) -> (
    Tensor<B, 1>,
    Vec<(&'static str, f64)>,
    (Vec<f32>, Vec<f32>, Vec<bool>),
) {
    let [b, _, _] = seed.dims();
    let k = plan.primitives;
    let device = seed.device();
    let latent = net.latent_dim();
    let mut total: Option<Tensor<B, 1>> = None;
    let mut parts: Vec<(&'static str, f64)> = Vec::new();
    let mut upright = Vec::new();
    for c in 0..k {
        let z = Tensor::<B, 2>::from_data(
            TensorData::new(normal_samples(rng, b * latent), [b, latent]),
            &device,
        );
        let anchor = anchor_net.map(|a| {
            Tensor::from_inner(decode_raw(
                a,
                seed.clone().inner(),
                floor.clone().inner(),
                z.clone().inner(),
            ))
        });
        let full = decode_raw(net, seed, floor.clone(), z);
        let terms = prior_loss(
            rig,
            &plan.weights,
            range,
            full.clone(),
            floor.clone(),
            anchor,
        );
        total = Some(match total {
            Some(t) => t + terms.total,
            None => terms.total,
        });
        add_parts(&mut parts, terms.parts, k);
        if c + 1 == k {
            upright = upright_at_end(rig, full.clone(), floor.clone());
        }
        let (next, height) = next_seed(rig, full);
        seed = next;
        floor = floor - height;
    }
    let seeds: Vec<f32> = seed.into_data().convert::<f32>().to_vec().expect("f32");
    let floors: Vec<f32> = floor.into_data().convert::<f32>().to_vec().expect("f32");
    let total = total.expect("at least one primitive").div_scalar(k as f64);
    (total, parts, (seeds, floors, upright))
}

/// Trunk lean (degrees from vertical, pelvis → neck) beyond which a persistent pool drops a
/// chain's end: the body is falling.
pub(crate) const POOL_TRUNK_TILT_MAX_DEG: f64 = 60.0;

/// Whether the last frame of each primitive (raw features `[B, T, F]` over floors `[B]`) is
/// upright (see [`prior_chain_loss`]).
fn upright_at_end<B: Backend>(
    rig: &TensorRig<B>,
    x: Tensor<B, 3>,
    floor: Tensor<B, 1>,
) -> Vec<bool> {
    let t = x.dims()[1];
    let (height, up) = pelvis_and_trunk(&pose_frames(rig, x.narrow(1, t - 1, 1)), floor);
    let height: Vec<f32> = height.into_data().convert::<f32>().to_vec().expect("f32");
    let up: Vec<f32> = up.into_data().convert::<f32>().to_vec().expect("f32");
    let up_min = POOL_TRUNK_TILT_MAX_DEG.to_radians().cos();
    height
        .iter()
        .zip(&up)
        .map(|(&h, &u)| UPRIGHT_PELVIS_M.contains(&(h as f64)) && u as f64 >= up_min)
        .collect()
}

/// How much the floor height counts when matching seeds ([`SeedIndex`]): its normalised
/// difference is scaled by this, so it weighs as much as a few dozen pose features.
const SEED_MATCH_FLOOR_SCALE: f32 = 8.0;

/// The first seeds of a chain set, normalised, for finding the mocap chain that starts nearest
/// a seed a random chain reached (the `prior.loss.recovery` target).
struct SeedIndex {
    keys: Vec<f32>,
    mean: Vec<f32>,
    std: Vec<f32>,
    floor_mean_std: [f32; 2],
}

impl SeedIndex {
    fn new<B: Backend>(set: &PrimitiveSet, net: &PrimitiveVae<B>) -> Self {
        let values = |p: &burn::module::Param<Tensor<B, 1>>| -> Vec<f32> {
            p.val().into_data().convert::<f32>().to_vec().expect("f32")
        };
        let fl = values(&net.floor_mean_std);
        let mut index = Self {
            keys: Vec::new(),
            mean: values(&net.feature_mean),
            std: values(&net.feature_std),
            floor_mean_std: [fl[0], fl[1]],
        };
        for i in 0..set.len() {
            let key = index.key(&set.item(i)[..SEED_FRAMES * FRAME_DIM], set.floors(i)[0]);
            index.keys.extend(key);
        }
        index
    }

    fn key(&self, seed: &[f32], floor: f32) -> Vec<f32> {
        let mut key: Vec<f32> = seed
            .iter()
            .enumerate()
            .map(|(j, v)| (v - self.mean[j % FRAME_DIM]) / self.std[j % FRAME_DIM])
            .collect();
        key.push(
            SEED_MATCH_FLOOR_SCALE * (floor - self.floor_mean_std[0]) / self.floor_mean_std[1],
        );
        key
    }

    /// Index of the chain whose first seed is nearest (squared distance of the keys).
    fn nearest(&self, seed: &[f32], floor: f32) -> usize {
        let key = self.key(seed, floor);
        let distance =
            |c: &[f32]| -> f32 { c.iter().zip(&key).map(|(a, b)| (a - b) * (a - b)).sum() };
        self.keys
            .chunks_exact(key.len())
            .map(distance)
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(i, _)| i)
    }
}

/// The recovery batch: `size` seeds random chains ended in (`[B, S, F]`, floors `[B]`) and, as
/// targets, the mocap chains of `set` that start nearest them (`[B, K, T, F]`, floors `[B, K]`).
#[allow(clippy::type_complexity)]
fn recovery_batch<B: Backend>(
    set: &PrimitiveSet,
    index: &SeedIndex,
    pool: &SeedPool,
    size: usize,
    rng: &mut ChaCha8Rng,
    device: &B::Device,
) -> (Tensor<B, 3>, Tensor<B, 1>, Tensor<B, 4>, Tensor<B, 2>) {
    let k = set.chain_len;
    let mut seeds = Vec::with_capacity(size * SEED_FRAMES * FRAME_DIM);
    let mut seed_floors = Vec::with_capacity(size);
    let mut x = Vec::with_capacity(size * k * PRIMITIVE_VALUES);
    let mut floors = Vec::with_capacity(size * k);
    for _ in 0..size {
        let Some(pooled) = pool.sample(rng) else {
            break;
        };
        let i = index.nearest(&pooled.frames, pooled.floor);
        seeds.extend_from_slice(&pooled.frames);
        seed_floors.push(pooled.floor);
        x.extend_from_slice(set.item(i));
        floors.extend_from_slice(set.floors(i));
    }
    let size = seed_floors.len();
    (
        Tensor::from_data(
            TensorData::new(seeds, [size, SEED_FRAMES, FRAME_DIM]),
            device,
        ),
        Tensor::from_data(TensorData::new(seed_floors, [size]), device),
        Tensor::from_data(
            TensorData::new(x, [size, k, PRIMITIVE_FRAMES, FRAME_DIM]),
            device,
        ),
        Tensor::from_data(TensorData::new(floors, [size, k]), device),
    )
}

/// Adds the mean over `k` primitives of loss terms to `parts` (matched by position).
fn add_parts<B: Backend>(
    parts: &mut Vec<(&'static str, f64)>,
    terms: Vec<(&'static str, Tensor<B, 1>)>,
    k: usize,
) {
    for (i, (name, v)) in terms.into_iter().enumerate() {
        let v = v.into_scalar().elem::<f64>() / k as f64;
        match parts.get_mut(i) {
            Some(p) => p.1 += v,
            None => parts.push((name, v)),
        }
    }
}

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
    let started = Instant::now();
    let ckpt_dir = checkpoint::checkpoint_dir(&plan.weights_out);
    checkpoint::check_resume(&ckpt_dir, resume)?;
    let fingerprint = checkpoint::plan_fingerprint(plan);
    let device = Default::default();
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
    let log_io = |source| TrainError::Io {
        path: plan.log_out.clone(),
        source,
    };
    let Restored {
        net: resumed_net,
        optim: mut restored_optim,
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

    let prior_steps = plan.prior.map_or(0, |p| p.phase.steps);
    let total_steps = plan.primitive.steps + plan.rollout.steps + prior_steps;
    let bar = match show_progress {
        true => crate::progress::progress_bar(
            "egogen train primitive",
            "training",
            "steps",
            total_steps as u64,
            resume_at.2 as u64,
        ),
        false => ProgressBar::hidden(),
    };
    let range = match plan.prior {
        Some(prior) => Some(prior_range(
            plan, &prior, &singles, &geo, &mut log, !resume,
        )?),
        None => None,
    };
    // The starting weights, frozen, for `prior.loss.anchor`.
    let anchor_net = match plan.prior {
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
    };
    let mut pool =
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
            // Cosine decay to a tenth of the phase's rate.
            let progress = step as f64 / phase_plan.steps as f64;
            let lr = phase_plan.learning_rate
                * (0.1 + 0.45 * (1.0 + (std::f64::consts::PI * progress).cos()));
            let mut weights = plan.loss;
            if plan.kl_warmup_steps > 0 {
                weights.kl *= (global_step as f64 / plan.kl_warmup_steps as f64).min(1.0);
            }
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
            let mut line = serde_json::json!({
                "phase": phase,
                "step": step,
                "lr": lr,
                "loss": value,
                "elapsed_s": elapsed_before_s + started.elapsed().as_secs_f64(),
            });
            for (name, v) in &parts {
                line[*name] = serde_json::json!(v);
            }
            if step % LOG_EVERY_STEPS == 0 || step + 1 == phase_plan.steps {
                log_line(&mut log, &line, &plan.log_out)?;
            }
            bar.set_message(format!("{phase} loss {value:.4}"));
            bar.inc(1);
            global_step += 1;
            let done = step + 1 == phase_plan.steps;
            if !done && last_checkpoint.elapsed().as_secs_f64() >= plan.checkpoint_every_s {
                let (rng_seed_hex, rng_stream, rng_word_pos) = checkpoint::rng_position(&rng);
                let state = checkpoint::CheckpointState {
                    plan_sha256: fingerprint.clone(),
                    phase: phase_index,
                    step: step + 1,
                    global_step,
                    last_loss: final_loss,
                    elapsed_s: elapsed_before_s + started.elapsed().as_secs_f64(),
                    rng_seed_hex,
                    rng_stream,
                    rng_word_pos,
                    net_file: String::new(),
                    optim_file: None,
                    extra_file: None,
                    log_bytes: std::fs::metadata(&plan.log_out).map_err(log_io)?.len(),
                    sha256: Default::default(),
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

/// One step's prior-phase terms: chains from the seed pool scored by the prior loss, the
/// pool updated with their ends, and the recovery term from seeds near the pool's where the
/// plan weights it.
struct PriorStep<'a> {
    net: &'a PrimitiveVae<TrainBackend>,
    anchor_net: Option<&'a PrimitiveVae<Flex>>,
    rig: &'a TensorRig<TrainBackend>,
    prior: &'a PriorPlan,
    range: &'a PlausibleRange,
    set: &'a PrimitiveSet,
    seed_index: Option<&'a SeedIndex>,
    weights: &'a LossWeights,
    batch_size: usize,
}

impl PriorStep<'_> {
    /// `loss` with the terms added (in this order: prior, recovery), each term named in
    /// `parts`.
    fn add_to(
        &self,
        mut loss: Tensor<TrainBackend, 1>,
        parts: &mut Vec<(&'static str, f64)>,
        pool: &mut SeedPool,
        rng: &mut ChaCha8Rng,
        device: &burn::tensor::Device<TrainBackend>,
    ) -> Tensor<TrainBackend, 1> {
        let prior = self.prior;
        let draw = pool.draw(self.set, prior.pool_fraction, self.batch_size, rng);
        let b = draw.len();
        let seed = Tensor::from_data(
            TensorData::new(draw.seeds.clone(), [b, SEED_FRAMES, FRAME_DIM]),
            device,
        );
        let floor = Tensor::from_data(TensorData::new(draw.floors.clone(), [b]), device);
        let (prior_total, prior_parts, (ends, end_floors, upright)) = prior_chain_loss(
            self.net,
            self.anchor_net,
            self.rig,
            prior,
            self.range,
            seed,
            floor,
            rng,
        );
        loss = loss + prior_total;
        parts.extend(prior_parts);
        let depth_mean = draw.depths.iter().sum::<usize>() as f64 / b.max(1) as f64;
        let depth_max = draw.depths.iter().copied().max().unwrap_or(0);
        parts.push(("pool_depth_mean", depth_mean));
        parts.push(("pool_depth_max", depth_max as f64));
        parts.push((
            "pool_upright_share",
            upright.iter().filter(|&&u| u).count() as f64 / b.max(1) as f64,
        ));
        let keep = match pool {
            SeedPool::Recent(_) => vec![true; b],
            SeedPool::Slots(_) => upright,
        };
        pool.accept(&draw, &ends, &end_floors, &keep, prior.primitives);
        if let Some(index) = self.seed_index {
            let (seed, floor, x, floors) =
                recovery_batch::<TrainBackend>(self.set, index, pool, self.batch_size, rng, device);
            if floor.dims()[0] > 0 {
                let (recovery, _) = chain_loss_from(
                    self.net,
                    self.rig,
                    self.weights,
                    seed,
                    floor,
                    x,
                    floors,
                    rng,
                );
                parts.push(("recovery", recovery.clone().into_scalar().elem::<f64>()));
                loss = loss + recovery.mul_scalar(prior.weights.recovery);
            }
        }
        loss
    }
}

/// Where a run starts: from nothing, or (`resume`) from the checkpoint — the network, the
/// optimiser of the phase under way, the generator and the pool as the checkpoint left them,
/// and the log cut back to what the run had logged then.
struct Restored {
    net: Option<PrimitiveVae<TrainBackend>>,
    optim: Option<PrimitiveOptimizer>,
    pool: Option<SeedPool>,
    elapsed_before_s: f64,
    /// Phase, step in it, global step, last loss.
    at: (usize, usize, usize, f64),
    log: std::io::BufWriter<std::fs::File>,
}

/// The optimiser every phase uses ([`new_optimizer`]).
type PrimitiveOptimizer = burn::optim::adaptor::OptimizerAdaptor<
    burn::optim::Adam,
    PrimitiveVae<TrainBackend>,
    TrainBackend,
>;

fn restore(
    plan: &TrainPlan,
    resume: bool,
    ckpt_dir: &Path,
    fingerprint: &str,
    net: &PrimitiveVae<TrainBackend>,
    rng: &mut ChaCha8Rng,
    device: &burn::tensor::Device<TrainBackend>,
) -> Result<Restored, TrainError> {
    let log_io = |source| TrainError::Io {
        path: plan.log_out.clone(),
        source,
    };
    let mut restored = Restored {
        net: None,
        optim: None,
        pool: None,
        elapsed_before_s: 0.0,
        at: (0, 0, 0, f64::NAN),
        log: std::io::BufWriter::new(
            match resume {
                true => std::fs::OpenOptions::new().append(true).open(&plan.log_out),
                false => std::fs::File::create(&plan.log_out),
            }
            .map_err(log_io)?,
        ),
    };
    if resume {
        let r = checkpoint::load(ckpt_dir, fingerprint, net.clone(), new_optimizer, device)?;
        restored.net = Some(r.net);
        restored.optim = r.optim;
        restored.pool = r.extra;
        *rng = r.rng;
        restored.elapsed_before_s = r.state.elapsed_s;
        restored.at = (
            r.state.phase,
            r.state.step,
            r.state.global_step,
            r.state.last_loss,
        );
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(&plan.log_out)
            .map_err(log_io)?;
        f.set_len(r.state.log_bytes).map_err(log_io)?;
    }
    Ok(restored)
}

/// The primitives a run trains on: single primitives, chains of `rollout_primitives` (for the
/// rollout and prior phases) and the held-out single primitives.
struct TrainingSets {
    singles: PrimitiveSet,
    chains: PrimitiveSet,
    held: PrimitiveSet,
}

fn training_sets(plan: &TrainPlan, model: &BodyModel) -> Result<TrainingSets, TrainError> {
    let (train_parts, held_parts) = load_clips(plan)?;
    let filter = plan
        .min_contact_score
        .map(|s| ContactFilter::new(model, s, plan.contact_context_frames))
        .transpose()?;
    let f = filter.as_ref();
    let singles = build_set(&train_parts, 1, plan.stride_frames, plan.mirror, model, f)?;
    let needs_chains = plan.rollout.steps > 0 || plan.prior.is_some();
    let chains = if needs_chains {
        build_set(
            &train_parts,
            plan.rollout_primitives,
            plan.stride_frames,
            plan.mirror,
            model,
            f,
        )?
    } else {
        PrimitiveSet::new(plan.rollout_primitives)
    };
    let held = build_set(&held_parts, 1, plan.stride_frames, false, model, f)?;
    if singles.is_empty() {
        return Err(TrainError::Data(
            "no training primitive: every clip is held out or shorter than 20 frames".into(),
        ));
    }
    if needs_chains && chains.is_empty() {
        return Err(TrainError::Data(format!(
            "rollout: no clip part holds {} chained primitives",
            plan.rollout_primitives
        )));
    }
    Ok(TrainingSets {
        singles,
        chains,
        held,
    })
}

/// The network training starts from: `init_weights` (of the plan's architecture), or a new
/// one normalised by the single primitives' statistics.
fn initial_net(
    plan: &TrainPlan,
    singles: &PrimitiveSet,
    device: &burn::tensor::Device<TrainBackend>,
) -> Result<PrimitiveVae<TrainBackend>, TrainError> {
    let stats = singles.input_stats(1e-3);
    match &plan.init_weights {
        None => Ok(plan.arch.init(&stats, device)),
        Some(path) => {
            let (arch, net) = weights::load(path, device)?;
            if arch != plan.arch {
                return Err(TrainError::Data(format!(
                    "init weights {}: architecture {arch:?}, the config asks for {:?}",
                    path.display(),
                    plan.arch
                )));
            }
            Ok(net)
        }
    }
}

fn create_output_dirs(plan: &TrainPlan) -> Result<(), TrainError> {
    for out in [&plan.log_out, &plan.weights_out] {
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| TrainError::Io {
                path: dir.into(),
                source,
            })?;
        }
    }
    Ok(())
}

/// The plausible range the prior phase holds random chains to (from the single primitives and
/// the prior's settings); logged when `log_it` (a fresh run; a resumed log has it).
fn prior_range(
    plan: &TrainPlan,
    prior: &PriorPlan,
    singles: &PrimitiveSet,
    geo: &RigGeometry,
    log: &mut impl Write,
    log_it: bool,
) -> Result<PlausibleRange, TrainError> {
    let mut r = training_range(singles, geo, prior.range_quantile);
    if let Some(deg) = prior.trunk_tilt_max_deg {
        r.trunk_up_min = deg.to_radians().cos();
    }
    r.pelvis_speed_min = prior.min_pelvis_speed_m_s;
    let line = serde_json::json!({
        "phase": "prior_range",
        "pelvis_m": [r.pelvis_m.0, r.pelvis_m.1],
        "trunk_up_min": r.trunk_up_min,
        "pelvis_speed_min": r.pelvis_speed_min,
    });
    if log_it {
        log_line(log, &line, &plan.log_out)?;
    }
    Ok(r)
}

/// Scores the trained network on the held-out primitives, logs the run's summary, writes the
/// weights and removes the checkpoint that has served.
fn finish_training(
    plan: &TrainPlan,
    inference: &PrimitiveVae<Flex>,
    geo: &RigGeometry,
    sets: &TrainingSets,
    log: &mut impl Write,
    seconds: f64,
    final_loss: f64,
) -> Result<TrainReport, TrainError> {
    let held_out_mpjpe_mm = if sets.held.is_empty() {
        None
    } else {
        let irig = TensorRig::new(geo, &Default::default());
        Some(marker_mpjpe_mm(inference, &irig, &sets.held, 256))
    };
    let summary = serde_json::json!({
        "phase": "done",
        "seconds": seconds,
        "held_out_marker_mpjpe_mm": held_out_mpjpe_mm,
        "train_primitives": sets.singles.len(),
        "train_chains": sets.chains.len(),
        "held_out_primitives": sets.held.len(),
    });
    log_line(log, &summary, &plan.log_out)?;
    weights::save(inference, &plan.arch, &plan.weights_out)?;
    let ckpt_dir = checkpoint::checkpoint_dir(&plan.weights_out);
    if ckpt_dir.exists() {
        std::fs::remove_dir_all(&ckpt_dir).map_err(|source| TrainError::Io {
            path: ckpt_dir.clone(),
            source,
        })?;
    }
    Ok(TrainReport {
        train_primitives: sets.singles.len(),
        train_chains: sets.chains.len(),
        held_out_primitives: sets.held.len(),
        seconds,
        final_loss,
        held_out_mpjpe_mm,
    })
}

/// Range of pelvis heights and trunk lean over the frames of a single-primitive set.
fn training_range(set: &PrimitiveSet, geo: &RigGeometry, q: f64) -> PlausibleRange {
    let device = Default::default();
    let rig = TensorRig::<Flex>::new(geo, &device);
    let (x, floors) = super::measure::set_batch::<Flex>(set, 0..set.len(), &device);
    let floor = Tensor::from_data(TensorData::new(floors.clone(), [floors.len()]), &device);
    plausible_range(&rig, x, floor, q)
}

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
