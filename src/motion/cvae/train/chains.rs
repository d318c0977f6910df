//! The losses of a training batch of chains: each primitive decoded from the seed the one
//! before leaves (the mocap's own seed, optionally noised, or a drawn one), and the prior
//! phase's chains from random latents kept upright.

use burn::prelude::*;
use burn::tensor::backend::AutodiffBackend;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;

use super::PriorPlan;
use crate::math::random::normal_samples;
use crate::motion::cvae::data::{PrimitiveSet, PRIMITIVE_VALUES};
use crate::motion::cvae::features::FRAME_DIM;
use crate::motion::cvae::loss::{
    pelvis_and_trunk, pose_frames, primitive_loss, prior_loss, LossWeights, PlausibleRange,
};
use crate::motion::cvae::measure::{decode_raw, UPRIGHT_PELVIS_M};
use crate::motion::cvae::net::PrimitiveVae;
use crate::motion::cvae::rollout::next_seed;
use crate::motion::cvae::tensor_body::TensorRig;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};

/// A random batch of items of `set` as `[B, K, T, F]` features and `[B, K]` floors.
pub(super) fn batch<B: Backend>(
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
pub(crate) fn chain_loss<B: Backend>(
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
pub(super) fn chain_loss_from<B: Backend>(
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
pub(super) fn prior_chain_loss<B: AutodiffBackend>(
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
