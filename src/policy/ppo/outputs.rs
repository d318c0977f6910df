//! What a training run writes and refuses: its log (started, truncated on resume, appended),
//! the stages' last weights beside the weights, the starting weights, and the stop when a loss
//! or a weight goes non-finite; the conversions of environment and weights errors.

use std::io::Write;
use std::path::{Path, PathBuf};

use burn::module::{ModuleVisitor, Param};
use burn::prelude::*;

use super::{PolicyTrainPlan, UpdateLog};
use crate::motion::cvae::train::{TrainBackend, TrainError};
use crate::motion::cvae::weights::WeightsError;
use crate::policy::env::EnvError;
use crate::policy::net::ActorCritic;
use crate::policy::weights::load_policy;

pub(super) fn stage_last_path(weights_out: &Path, stage: &str) -> PathBuf {
    let mut name = weights_out
        .file_stem()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".{stage}.last.safetensors"));
    weights_out.with_file_name(name)
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
pub(super) fn check_finite<B: Backend>(
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
pub(super) fn initial_policy(
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
pub(super) fn start_log(log: &Path, force: bool) -> Result<(), TrainError> {
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

pub(super) fn env_error(e: EnvError) -> TrainError {
    TrainError::Data(format!("environment: {e}"))
}

pub(super) fn weights_error(e: WeightsError) -> TrainError {
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

pub(super) fn truncate_log(path: &Path, bytes: u64) -> Result<(), TrainError> {
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

pub(super) fn append_log(path: &Path, log: &UpdateLog) -> Result<(), TrainError> {
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

/// Refuses a new run over weights an earlier run left at the plan's outputs.
pub(super) fn refuse_earlier_weights(plan: &PolicyTrainPlan) -> Result<(), TrainError> {
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
    Ok(())
}
