//! Measurements of a trained model: held-out marker error, foot-contact scores of batches and
//! random-latent chains (the score itself is [`super::contact`]) and long-rollout statistics.

use burn::prelude::*;
use burn::tensor::FloatDType;

pub(crate) use super::contact::contact_terms;
pub(crate) use super::contact::{contact_score, contact_score_horizontal};
use super::data::{PrimitiveSet, PRIMITIVE_VALUES};
use super::features::FRAME_DIM;
use super::loss::pose_frames;
pub(crate) use super::net::decode_raw;
use super::net::PrimitiveVae;
use super::tensor_body::TensorRig;
use crate::motion::primitive::{PRIMITIVE_FRAMES, PRIMITIVE_RATE_HZ, SEED_FRAMES};

/// Items `range` of a single-primitive set as raw features `[B, T, F]` and floors `[B]`.
pub(crate) fn set_batch<B: Backend>(
    set: &PrimitiveSet,
    range: std::ops::Range<usize>,
    device: &B::Device,
) -> (Tensor<B, 3>, Vec<f32>) {
    let items: Vec<usize> = range.collect();
    pick_batch(set, &items, device)
}

/// Items `items` of a single-primitive set as raw features `[B, T, F]` and floors `[B]`.
pub(crate) fn pick_batch<B: Backend>(
    set: &PrimitiveSet,
    items: &[usize],
    device: &B::Device,
) -> (Tensor<B, 3>, Vec<f32>) {
    let mut x = Vec::with_capacity(items.len() * PRIMITIVE_VALUES);
    let mut floors = Vec::with_capacity(items.len());
    for &i in items {
        x.extend_from_slice(set.item(i));
        floors.extend_from_slice(set.floors(i));
    }
    (
        Tensor::from_data(
            TensorData::new(x, [items.len(), PRIMITIVE_FRAMES, FRAME_DIM]),
            device,
        ),
        floors,
    )
}

fn floor_tensor<B: Backend>(floors: &[f32], device: &B::Device) -> Tensor<B, 1> {
    Tensor::from_data(TensorData::new(floors.to_vec(), [floors.len()]), device)
}

/// Posterior mean latents `[B, L]` of raw primitives `[B, T, F]`, in their precision (the
/// network runs in its own).
pub(crate) fn posterior_mean<B: Backend>(net: &PrimitiveVae<B>, x: Tensor<B, 3>) -> Tensor<B, 2> {
    let io = FloatDType::from(x.dtype());
    let dt = FloatDType::from(net.dtype());
    net.encode(net.normalize(x.cast(dt))).0.cast(io)
}

/// Mean marker error (mm) over the decoded frames of every primitive of `set`, each decoded
/// from its own seed and its posterior mean latent.
pub(crate) fn marker_mpjpe_mm<B: Backend>(
    net: &PrimitiveVae<B>,
    rig: &TensorRig<B>,
    set: &PrimitiveSet,
    batch: usize,
) -> f64 {
    let device = net.feature_mean.val().device();
    let mut sum = 0.0;
    let mut count = 0usize;
    for start in (0..set.len()).step_by(batch.max(1)) {
        let end = (start + batch).min(set.len());
        let (x, floors) = set_batch::<B>(set, start..end, &device);
        let mu = posterior_mean(net, x.clone());
        let floor = floor_tensor(&floors, &device);
        let pred = decode_raw(net, x.clone().narrow(1, 0, SEED_FRAMES), floor, mu);
        let n = PRIMITIVE_FRAMES - SEED_FRAMES;
        let pm = pose_frames(rig, pred).markers.narrow(1, SEED_FRAMES, n);
        let gm = pose_frames(rig, x).markers.narrow(1, SEED_FRAMES, n);
        let dist = (pm - gm).square().sum_dim(3).sqrt();
        count += dist.dims().iter().product::<usize>();
        sum += dist.sum().into_scalar().elem::<f64>();
    }
    sum / count.max(1) as f64 * 1000.0
}

/// Contact scores (3-D, horizontal) of a batch of raw primitives `[B, T, F]` with floors `[B]`.
pub(crate) fn contact_scores<B: Backend>(
    rig: &TensorRig<B>,
    x: Tensor<B, 3>,
    floors: &[f32],
) -> Vec<(f64, f64)> {
    let [b, t, _] = x.dims();
    let feet = pose_frames(rig, x)
        .markers
        .select(2, rig.foot_markers.clone());
    let nf = feet.dims()[2];
    let values: Vec<f32> = feet.into_data().to_vec().expect("f32 markers");
    (0..b)
        .map(|i| {
            let frames: Vec<Vec<[f64; 3]>> = (0..t)
                .map(|f| {
                    (0..nf)
                        .map(|k| {
                            let o = ((i * t + f) * nf + k) * 3;
                            [values[o] as f64, values[o + 1] as f64, values[o + 2] as f64]
                        })
                        .collect()
                })
                .collect();
            let floor = floors[i] as f64;
            (
                contact_score(&frames, floor),
                contact_score_horizontal(&frames, floor),
            )
        })
        .collect()
}

/// Foot-contact scores of random latents against the mocap's own.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub(crate) struct ContactReport {
    /// Primitives scored.
    pub count: usize,
    /// Mean score of primitives decoded from real seeds with z ~ N(0, I).
    pub random_latent_mean: f64,
    /// 10th percentile of those scores.
    pub random_latent_p10: f64,
    /// Mean score of the mocap primitives themselves (the ceiling).
    pub mocap_mean: f64,
    /// The same two means with horizontal foot speed (`contact_score_horizontal`, GAMMA's).
    pub random_latent_mean_horizontal: f64,
    pub mocap_mean_horizontal: f64,
    /// Primitives decoded with a non-finite value.
    pub non_finite: usize,
}

/// Scores `count` primitives decoded from the seeds of evenly spread items of `set` with
/// latents drawn by `latents` (`[count × L]`), next to the score of those mocap primitives.
pub(crate) fn random_latent_contact<B: Backend>(
    net: &PrimitiveVae<B>,
    rig: &TensorRig<B>,
    set: &PrimitiveSet,
    latents: &[f32],
) -> ContactReport {
    let device = net.feature_mean.val().device();
    let l = net.latent_dim();
    let count = latents.len() / l;
    let picks: Vec<usize> = (0..count).map(|i| i * set.len() / count.max(1)).collect();
    let (x, floors) = pick_batch::<B>(set, &picks, &device);
    let z = Tensor::from_data(TensorData::new(latents.to_vec(), [count, l]), &device);
    let floor = floor_tensor(&floors, &device);
    let pred = decode_raw(net, x.clone().narrow(1, 0, SEED_FRAMES), floor, z);
    let values: Vec<f32> = pred.clone().into_data().to_vec().expect("f32");
    let per = PRIMITIVE_VALUES;
    let non_finite = (0..count)
        .filter(|i| {
            values[i * per..(i + 1) * per]
                .iter()
                .any(|v| !v.is_finite())
        })
        .count();
    let decoded = contact_scores(rig, pred, &floors);
    let mocap = contact_scores(rig, x, &floors);
    let mean = |v: &[(f64, f64)], pick: fn(&(f64, f64)) -> f64| {
        v.iter().map(pick).sum::<f64>() / v.len().max(1) as f64
    };
    let mut scores: Vec<f64> = decoded.iter().map(|s| s.0).collect();
    scores.sort_by(f64::total_cmp);
    ContactReport {
        count,
        random_latent_mean: mean(&decoded, |s| s.0),
        random_latent_p10: scores.get(count / 10).copied().unwrap_or(f64::NAN),
        mocap_mean: mean(&mocap, |s| s.0),
        random_latent_mean_horizontal: mean(&decoded, |s| s.1),
        mocap_mean_horizontal: mean(&mocap, |s| s.1),
        non_finite,
    }
}

/// How much the latent moves a primitive: over `seeds` evenly spread items of `set`, each
/// decoded with `draws` latents z ~ N(0, I) from `latents` (`[seeds × draws × L]`), the root
/// mean square distance (mm) of the last frame's markers from their mean over the draws.
pub fn latent_spread_mm<B: Backend>(
    net: &PrimitiveVae<B>,
    rig: &TensorRig<B>,
    set: &PrimitiveSet,
    draws: usize,
    latents: &[f32],
) -> f64 {
    let device = net.feature_mean.val().device();
    let l = net.latent_dim();
    let count = latents.len() / l;
    let seeds = count / draws.max(1);
    let picks: Vec<usize> = (0..seeds * draws)
        .map(|i| (i / draws) * set.len() / seeds.max(1))
        .collect();
    let (x, floors) = pick_batch::<B>(set, &picks, &device);
    let z = Tensor::from_data(
        TensorData::new(latents[..picks.len() * l].to_vec(), [picks.len(), l]),
        &device,
    );
    let pred = decode_raw(
        net,
        x.narrow(1, 0, SEED_FRAMES),
        floor_tensor(&floors, &device),
        z,
    );
    let last = pose_frames(rig, pred)
        .markers
        .narrow(1, PRIMITIVE_FRAMES - 1, 1);
    let m = last.dims()[2];
    let last = last.reshape([seeds, draws, m, 3]);
    let mean = last.clone().mean_dim(1);
    let sq = (last - mean).square().sum_dim(3).mean();
    sq.into_scalar().elem::<f64>().sqrt() * 1000.0
}

/// Pelvis heights above the floor (m) counted as upright for [`ChainReport`].
pub(crate) const UPRIGHT_PELVIS_M: std::ops::Range<f64> = 0.5..1.3;

/// Distance (m) of the lowest foot marker from the floor within which [`ChainReport`] counts a
/// frame as standing on the floor.
pub(crate) const FOOT_ON_FLOOR_M: f64 = 0.1;

/// Mean horizontal pelvis speed over a primitive (m/s) from which [`ChainReport`] counts it as
/// moving.
pub(crate) const MOVING_M_PER_S: f64 = 0.2;

/// Statistics of one long chain of primitives decoded from random latents.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub(crate) struct ChainReport {
    pub primitives: usize,
    /// Decoded frames (18 per primitive).
    pub frames: usize,
    /// Primitives decoded before the pelvis first leaves the human range of heights above the
    /// floor, `UPRIGHT_PELVIS_M` (all of them when it never does).
    pub upright_primitives: usize,
    /// World pelvis height range (m).
    pub pelvis_z_min_m: f64,
    pub pelvis_z_max_m: f64,
    /// Largest deviation of a body bone's length from its rest length (m).
    pub bone_length_max_dev_m: f64,
    /// Largest orthonormality error `max |RᵀR − I|` of the canonical frames.
    pub canonical_orthonormality_max_err: f64,
    /// Height of the lowest foot marker above the floor (m): mean, min, max over frames.
    pub lowest_foot_mean_m: f64,
    pub lowest_foot_min_m: f64,
    pub lowest_foot_max_m: f64,
    /// Share of frames whose lowest foot marker is within `FOOT_ON_FLOOR_M` of the floor.
    pub feet_on_floor_share: f64,
    /// Mean foot-contact score of the chain's primitives (f64 markers).
    pub contact_mean: f64,
    /// Horizontal distance of the pelvis from start to end (m).
    pub displacement_m: f64,
    /// Mean horizontal pelvis speed (m/s) over the chain (path length over time).
    pub pelvis_speed_mean_m_s: f64,
    /// Share of primitives whose pelvis moves at [`MOVING_M_PER_S`] or faster (walking rather
    /// than standing).
    pub moving_share: f64,
    /// Latents drawn per primitive, the most plausible kept (`sampler::BestOfK`; 1 for plain
    /// random latents).
    pub candidates: usize,
    /// Candidates dropped because they decoded to non-finite values.
    pub non_finite_candidates: usize,
    /// Wall time of decoding and posing (s).
    pub seconds: f64,
}

/// Chains `primitives` primitives from `seed`, each the most plausible of `sampler.candidates`
/// decoded from latents z ~ N(0, I) drawn from `rng`, returning the statistics and the decoded
/// primitives.
pub(crate) fn long_rollout(
    model: &super::MotionModel,
    body: &super::BodyContext,
    seed: super::PrimitiveSeed,
    primitives: usize,
    sampler: &super::sampler::BestOfK,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Result<(ChainReport, Vec<super::DecodedPrimitive>), super::infer::DecodeError> {
    use crate::body::PARENTS;
    use crate::math::rotation::orthonormality_error;
    let started = std::time::Instant::now();
    let rest = body.shaped.rest_joints;
    let foot = super::tensor_body::RigGeometry::new(body.model, &body.betas)?.foot_markers;
    let mut seed = seed;
    let mut out = Vec::with_capacity(primitives);
    let mut r = ChainReport {
        primitives,
        frames: 0,
        upright_primitives: 0,
        pelvis_z_min_m: f64::INFINITY,
        pelvis_z_max_m: f64::NEG_INFINITY,
        bone_length_max_dev_m: 0.0,
        canonical_orthonormality_max_err: 0.0,
        lowest_foot_mean_m: 0.0,
        lowest_foot_min_m: f64::INFINITY,
        lowest_foot_max_m: f64::NEG_INFINITY,
        feet_on_floor_share: 0.0,
        contact_mean: 0.0,
        displacement_m: 0.0,
        pelvis_speed_mean_m_s: 0.0,
        moving_share: 0.0,
        candidates: sampler.candidates,
        non_finite_candidates: 0,
        seconds: 0.0,
    };
    let mut upright = true;
    for _ in 0..primitives {
        let step = sampler.next(model, body, &seed, rng)?;
        r.non_finite_candidates += step.non_finite_candidates;
        let p = step.primitive;
        r.canonical_orthonormality_max_err = r
            .canonical_orthonormality_max_err
            .max(orthonormality_error(p.primitive.world_from_canon.matrix3));
        let feet: Vec<Vec<[f64; 3]>> = p
            .markers
            .iter()
            .map(|m| foot.iter().map(|&k| m[k].to_array()).collect())
            .collect();
        r.contact_mean += contact_score(&feet, p.floor_z);
        for f in SEED_FRAMES..PRIMITIVE_FRAMES {
            let joints = &p.joints[f];
            r.frames += 1;
            upright &= UPRIGHT_PELVIS_M.contains(&(joints[0].z - p.floor_z));
            r.pelvis_z_min_m = r.pelvis_z_min_m.min(joints[0].z);
            r.pelvis_z_max_m = r.pelvis_z_max_m.max(joints[0].z);
            for j in 1..super::tensor_body::BODY_JOINTS {
                let parent = PARENTS[j].unwrap_or(0);
                let posed = joints[j].distance(joints[parent]);
                let rest_len = rest[j].distance(rest[parent]);
                r.bone_length_max_dev_m = r.bone_length_max_dev_m.max((posed - rest_len).abs());
            }
            let lowest = feet[f].iter().map(|q| q[2]).fold(f64::INFINITY, f64::min) - p.floor_z;
            r.lowest_foot_mean_m += lowest;
            r.lowest_foot_min_m = r.lowest_foot_min_m.min(lowest);
            r.lowest_foot_max_m = r.lowest_foot_max_m.max(lowest);
            if lowest.abs() <= FOOT_ON_FLOOR_M {
                r.feet_on_floor_share += 1.0;
            }
        }
        if upright {
            r.upright_primitives += 1;
        }
        let (a, b) = (
            p.joints[SEED_FRAMES - 1][0],
            p.joints[PRIMITIVE_FRAMES - 1][0],
        );
        let path = b.truncate().distance(a.truncate());
        r.pelvis_speed_mean_m_s += path;
        if path * PRIMITIVE_RATE_HZ / (PRIMITIVE_FRAMES - SEED_FRAMES) as f64 >= MOVING_M_PER_S {
            r.moving_share += 1.0;
        }
        seed = p.next_seed();
        out.push(p);
    }
    r.contact_mean /= primitives.max(1) as f64;
    r.moving_share /= primitives.max(1) as f64;
    r.pelvis_speed_mean_m_s /=
        (primitives * (PRIMITIVE_FRAMES - SEED_FRAMES)).max(1) as f64 / PRIMITIVE_RATE_HZ;
    r.lowest_foot_mean_m /= r.frames.max(1) as f64;
    r.feet_on_floor_share /= r.frames.max(1) as f64;
    if let (Some(a), Some(b)) = (out.first(), out.last()) {
        let (a, b) = (a.joints[0][0], b.joints[PRIMITIVE_FRAMES - 1][0]);
        r.displacement_m = b.truncate().distance(a.truncate());
    }
    r.seconds = started.elapsed().as_secs_f64();
    Ok((r, out))
}
