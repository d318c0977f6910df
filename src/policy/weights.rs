//! The policy's weights files: which one ships, and loading and saving a policy (its
//! architecture in the file's header, checked before anything is built). Acting (`egogen
//! synth`, `egogen-run`), evaluation and training all read policies through here.

use std::path::{Path, PathBuf};

use burn::prelude::*;

use super::net::{ActorCritic, PolicyArch};
use crate::motion::cvae::weights::{self, WeightsError};

/// Metadata key of the policy architecture in its weights file.
pub(crate) const POLICY_ARCH_KEY: &str = "egogen.policy_arch";

/// The shipped policy (relative to the crate's folder): the box-and-crossing policy of
/// `configs/train_policy.toml`, fine-tuned with apartment episodes
/// (`configs/train_policy_apartment.toml`), then with the pace bonus
/// (`configs/train_policy_pace.toml`), then among crossings of one to four people
/// (`configs/train_policy_crowd.toml`), then with the apartment's doors closed
/// (`configs/train_policy_indoors.toml`), then with procedural floor plans in its mix, a cost
/// for looking off the goal (stronger in box scenes, where feet that skate cost more too) and
/// the box scenes' box tested in every frame (`configs/train_policy_scene_weights.toml`).
pub const SHIPPED_POLICY: &str = "assets/policy/scene_weights/policy.safetensors";

/// The config whose run wrote [`SHIPPED_POLICY`].
pub const SHIPPED_POLICY_CONFIG: &str = "configs/train_policy_scene_weights.toml";

/// Where the shipped policy is.
pub(crate) fn shipped_policy_path() -> PathBuf {
    crate::paths::crate_root().join(SHIPPED_POLICY)
}

/// Loads a policy written by [`save_policy`].
pub fn load_policy<B: Backend>(
    path: &Path,
    device: &B::Device,
) -> Result<(PolicyArch, ActorCritic<B>), WeightsError> {
    let arch: PolicyArch = weights::read_metadata(path, POLICY_ARCH_KEY)?;
    if let Some(problem) = arch.problem() {
        return Err(WeightsError::Store {
            path: path.into(),
            message: format!(
                "its header's `{POLICY_ARCH_KEY}` asks for a network that cannot be built \
                 ({problem}); the file is damaged or not an egogen policy"
            ),
        });
    }
    let weights_bytes = arch.parameter_count() * std::mem::size_of::<f32>() as f64;
    crate::memory::check_fits(
        &format!(
            "the network its header's `{POLICY_ARCH_KEY}` asks for (hidden = {}, \
             residual_blocks = {})",
            arch.hidden, arch.residual_blocks
        ),
        weights_bytes,
    )
    .map_err(|message| WeightsError::Store {
        path: path.into(),
        message,
    })?;
    let mut net = arch.init::<B>(device);
    weights::load_into(path, &mut net, &format!("{arch:?}"))?;
    Ok((arch, net))
}

/// A trained policy that acts in `model`'s latent space, or an error naming the file.
pub(crate) fn load_policy_for(
    path: &Path,
    model: &crate::motion::cvae::MotionModel,
) -> Result<ActorCritic<crate::motion::cvae::infer::InferBackend>, WeightsError> {
    let (arch, net) =
        load_policy::<crate::motion::cvae::infer::InferBackend>(path, &Default::default())?;
    if arch.latent_dim != model.latent_dim() {
        return Err(WeightsError::Store {
            path: path.into(),
            message: format!(
                "the policy acts in {} latent dimensions, the motion model has {}",
                arch.latent_dim,
                model.latent_dim()
            ),
        });
    }
    Ok(net)
}

/// Writes a policy atomically, its architecture in the header.
pub fn save_policy<B: Backend>(
    net: &ActorCritic<B>,
    arch: &PolicyArch,
    path: &Path,
) -> Result<(), WeightsError> {
    weights::save_module(net, POLICY_ARCH_KEY, arch, path)
}
