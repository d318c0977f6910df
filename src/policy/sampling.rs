//! The sampling controller: the no-training baseline beside the policy. For every episode,
//! `k` latents drawn from N(0, I) are decoded and judged by the environment's own reward
//! (one primitive of lookahead) and the best is taken. `k` is the speed/accuracy knob: one
//! step costs `k` decodes per episode; `k = 1` is the plain random walk. The best is taken by the
//! one rule every walker chooses by (`walker::step::choose_primitive`).

use rand_chacha::ChaCha8Rng;

use super::env::{EnvError, PolicyEnv, StepOutput};
use crate::motion::cvae::train::normal_samples;

/// One step of every episode with the best of `k` random latents.
pub fn sampling_step(
    env: &mut PolicyEnv,
    k: usize,
    rng: &mut ChaCha8Rng,
) -> Result<StepOutput, EnvError> {
    let k = k.max(1);
    let latents = normal_samples(rng, env.len() * k * env.latent_dim());
    let candidates = env.propose(&latents, k)?;
    let chosen = env.choose(candidates)?;
    env.commit(chosen)
}
