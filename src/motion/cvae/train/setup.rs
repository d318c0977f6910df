//! What training starts from and ends with: the checkpoint resumed, the training and held-out
//! sets, the starting weights, the output folders, the prior's plausible range, and the
//! weights, report and loss log written at the end.

use std::io::Write;
use std::path::Path;

use burn::backend::Flex;
use burn::prelude::*;
use rand_chacha::ChaCha8Rng;

use super::{
    load_clips, log_line, new_optimizer, PrimitiveOptimizer, PriorPlan, TrainBackend, TrainPlan,
    TrainReport,
};
use crate::body::BodyModel;
use crate::motion::cvae::data::{build_set, ContactFilter, PrimitiveSet};
use crate::motion::cvae::loss::{plausible_range, PlausibleRange};
use crate::motion::cvae::measure::marker_mpjpe_mm;
use crate::motion::cvae::net::PrimitiveVae;
use crate::motion::cvae::pool::SeedPool;
use crate::motion::cvae::tensor_body::{RigGeometry, TensorRig};
use crate::motion::cvae::train_error::TrainError;
use crate::motion::cvae::{checkpoint, weights};

/// Where a run starts: from nothing, or (`resume`) from the checkpoint — the network, the
/// optimiser of the phase under way, the generator and the pool as the checkpoint left them,
/// and the log cut back to what the run had logged then.
pub(super) struct Restored {
    pub(super) net: Option<PrimitiveVae<TrainBackend>>,
    pub(super) optim: Option<PrimitiveOptimizer>,
    pub(super) pool: Option<SeedPool>,
    pub(super) elapsed_before_s: f64,
    /// Phase, step in it, global step, last loss.
    pub(super) at: (usize, usize, usize, f64),
    pub(super) log: std::io::BufWriter<std::fs::File>,
}

pub(super) fn restore(
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
pub(super) struct TrainingSets {
    pub(super) singles: PrimitiveSet,
    pub(super) chains: PrimitiveSet,
    pub(super) held: PrimitiveSet,
}

pub(super) fn training_sets(
    plan: &TrainPlan,
    model: &BodyModel,
) -> Result<TrainingSets, TrainError> {
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
pub(super) fn initial_net(
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

pub(super) fn create_output_dirs(plan: &TrainPlan) -> Result<(), TrainError> {
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
pub(super) fn prior_range(
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
pub(super) fn finish_training(
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
    let (x, floors) = crate::motion::cvae::measure::set_batch::<Flex>(set, 0..set.len(), &device);
    let floor = Tensor::from_data(TensorData::new(floors.clone(), [floors.len()]), &device);
    plausible_range(&rig, x, floor, q)
}
