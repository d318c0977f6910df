//! Acting with the burn actor-critic: actions sampled or the mean, with the log-probabilities,
//! values and KL to N(0, I) training needs, and the action distribution for one observation.

use burn::prelude::*;
use rand_chacha::ChaCha8Rng;

use crate::motion::cvae::train::normal_samples;
use crate::policy::net::{kl_to_standard, log_prob, ActorCritic};

pub(super) fn to_tensor<B: Backend>(
    v: Vec<f32>,
    shape: [usize; 2],
    device: &B::Device,
) -> Tensor<B, 2> {
    Tensor::from_data(TensorData::new(v, shape), device)
}

pub(super) fn values<B: Backend, const D: usize>(t: Tensor<B, D>) -> Vec<f32> {
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
