//! The sampling controller over the batched environment: the no-training baseline beside the
//! policy. Every episode's walker steps with the walker layer's sampling controller — the one
//! a take's people step with (`walker::ControllerSpec::Sampling`): `k` latents drawn from
//! N(0, I) (episode by episode from one generator), decoded and judged by the environment's
//! own reward (one primitive of lookahead), the best taken by the one rule every walker
//! chooses by. `k` is the speed/accuracy knob: one step costs `k` decodes per episode; `k = 1`
//! is the plain random walk. [`controller_step`] steps any controller of the walker layer
//! that needs no policy (the path follower too).

use rand_chacha::ChaCha8Rng;

use super::env::{EnvError, PolicyEnv, StepOutput};
use crate::walker::ControllerSpec;

/// One step of every episode with the best of `k` random latents.
#[cfg(test)]
pub(crate) fn sampling_step(
    env: &mut PolicyEnv,
    k: usize,
    rng: &mut ChaCha8Rng,
) -> Result<StepOutput, EnvError> {
    controller_step(env, ControllerSpec::Sampling { k }, rng)
}

/// One step of every episode with a controller of the walker layer built from `spec` (one per
/// episode, built anew every step: these keep nothing from step to step). A controller that
/// acts through a policy is refused (the batched actor steps the policy).
pub(crate) fn controller_step(
    env: &mut PolicyEnv,
    spec: ControllerSpec,
    rng: &mut ChaCha8Rng,
) -> Result<StepOutput, EnvError> {
    let mut controllers = (0..env.len())
        .map(|_| spec.build(None).ok_or(EnvError::NeedsPolicy))
        .collect::<Result<Vec<_>, _>>()?;
    env.step_with(&mut controllers, rng)
}
