//! One PPO update: a batch collected from every environment, advantages by GAE, then the
//! passes over shuffled minibatches with the gradients clipped on their global norm.

use std::time::Instant;

use burn::module::{AutodiffModule, ModuleVisitor, Param};
use burn::optim::{GradientsParams, Optimizer};
use burn::prelude::*;
use burn::tensor::backend::AutodiffBackend;
use rand_chacha::ChaCha8Rng;

use super::act::{act, to_tensor, values};
use super::{PpoSettings, UpdateLog};
use crate::motion::cvae::train::TrainBackend;
use crate::policy::env::{EnvError, EpisodeSummary, PolicyEnv};
use crate::policy::net::{entropy, kl_to_standard, log_prob, ActorCritic};

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

/// Collects one batch and updates the network on it.
pub(super) fn one_update<O: Optimizer<ActorCritic<TrainBackend>, TrainBackend>>(
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
    let rollout = collect(net, env, t_steps, rng, device)?;
    let n = t_steps * b;
    let adv = advantages(
        ppo,
        t_steps,
        b,
        &rollout.rew_buf,
        &rollout.val_buf,
        &rollout.done_buf,
        &rollout.last_v,
    );
    let returns: Vec<f32> = adv
        .iter()
        .zip(&rollout.val_buf)
        .map(|(a, v)| a + v)
        .collect();
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
            let obs = to_tensor::<TrainBackend>(gather(&rollout.obs_buf, d), [m, d], device);
            let acts = to_tensor::<TrainBackend>(gather(&rollout.act_buf, l), [m, l], device);
            let old_logp = Tensor::<TrainBackend, 1>::from_data(
                TensorData::new(gather(&rollout.logp_buf, 1), [m]),
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
    let ne = rollout.finished.len();
    let nf = ne.max(1) as f64;
    Ok(UpdateLog {
        stage: String::new(),
        update: 0,
        env_steps: 0,
        wall_s: 0.0,
        step_reward: rollout.rew_buf.iter().map(|&r| r as f64).sum::<f64>() / n as f64,
        episodes: ne,
        episode_return: rollout.finished.iter().map(|s| s.reward).sum::<f64>() / nf,
        success_rate: rollout
            .finished
            .iter()
            .filter(|s| s.ending == crate::policy::env::Ending::Success)
            .count() as f64
            / nf,
        episode_length: rollout
            .finished
            .iter()
            .map(|s| s.primitives as f64)
            .sum::<f64>()
            / nf,
        kl_prior: rollout.kl_sum / n as f64,
        approx_kl,
        minibatches,
        policy_loss: pl_sum / k,
        value_loss: vl_sum / k,
        entropy: ent_sum / k,
        grad_norm: gn_sum / k,
        clip_fraction: cf_sum / k,
        env_s: rollout.env_s,
        forward_s: rollout.forward_s,
        update_s: t.elapsed().as_secs_f64(),
        validation: None,
    })
}

/// One update's batch, `[T × B]` row-major by step: observations, actions, their
/// log-probabilities and values, rewards and episode ends; the episodes that ended, the values of
/// the last observations, and the seconds and KL sum of collecting it.
struct Rollout {
    obs_buf: Vec<f32>,
    act_buf: Vec<f32>,
    logp_buf: Vec<f32>,
    val_buf: Vec<f32>,
    rew_buf: Vec<f32>,
    done_buf: Vec<bool>,
    finished: Vec<EpisodeSummary>,
    last_v: Vec<f32>,
    env_s: f64,
    forward_s: f64,
    kl_sum: f64,
}

/// Every environment takes `t_steps` steps with actions sampled from the policy.
fn collect(
    net: &ActorCritic<TrainBackend>,
    env: &mut PolicyEnv,
    t_steps: usize,
    rng: &mut ChaCha8Rng,
    device: &burn::tensor::Device<TrainBackend>,
) -> Result<Rollout, EnvError> {
    let b = env.len();
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
    Ok(Rollout {
        obs_buf,
        act_buf,
        logp_buf,
        val_buf,
        rew_buf,
        done_buf,
        finished,
        last_v,
        env_s,
        forward_s,
        kl_sum,
    })
}

/// Advantages by GAE over `[T × B]` (a timeout ends an episode).
fn advantages(
    ppo: &PpoSettings,
    t_steps: usize,
    b: usize,
    rew_buf: &[f32],
    val_buf: &[f32],
    done_buf: &[bool],
    last_v: &[f32],
) -> Vec<f32> {
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
    adv
}
