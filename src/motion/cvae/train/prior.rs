//! The prior phase's terms of a step: chains from the seed pool scored by the prior loss, and
//! the recovery term from the mocap seeds nearest the pool's.

use burn::backend::Flex;
use burn::prelude::*;
use rand_chacha::ChaCha8Rng;

use super::chains::{chain_loss_from, prior_chain_loss};
use super::{PriorPlan, TrainBackend};
use crate::motion::cvae::data::{PrimitiveSet, PRIMITIVE_VALUES};
use crate::motion::cvae::features::FRAME_DIM;
use crate::motion::cvae::loss::{LossWeights, PlausibleRange};
use crate::motion::cvae::net::PrimitiveVae;
use crate::motion::cvae::pool::SeedPool;
use crate::motion::cvae::tensor_body::TensorRig;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};

/// How much the floor height counts when matching seeds ([`SeedIndex`]): its normalised
/// difference is scaled by this, so it weighs as much as a few dozen pose features.
const SEED_MATCH_FLOOR_SCALE: f32 = 8.0;

/// The first seeds of a chain set, normalised, for finding the mocap chain that starts nearest
/// a seed a random chain reached (the `prior.loss.recovery` target).
pub(super) struct SeedIndex {
    keys: Vec<f32>,
    mean: Vec<f32>,
    std: Vec<f32>,
    floor_mean_std: [f32; 2],
}

impl SeedIndex {
    pub(super) fn new<B: Backend>(set: &PrimitiveSet, net: &PrimitiveVae<B>) -> Self {
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

/// One step's prior-phase terms: chains from the seed pool scored by the prior loss, the
/// pool updated with their ends, and the recovery term from seeds near the pool's where the
/// plan weights it.
pub(super) struct PriorStep<'a> {
    pub(super) net: &'a PrimitiveVae<TrainBackend>,
    pub(super) anchor_net: Option<&'a PrimitiveVae<Flex>>,
    pub(super) rig: &'a TensorRig<TrainBackend>,
    pub(super) prior: &'a PriorPlan,
    pub(super) range: &'a PlausibleRange,
    pub(super) set: &'a PrimitiveSet,
    pub(super) seed_index: Option<&'a SeedIndex>,
    pub(super) weights: &'a LossWeights,
    pub(super) batch_size: usize,
}

impl PriorStep<'_> {
    /// `loss` with the terms added (in this order: prior, recovery), each term named in
    /// `parts`.
    pub(super) fn add_to(
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
