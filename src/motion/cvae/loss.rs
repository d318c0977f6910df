//! Training losses of the C-VAE: pose (6D), translation, FK markers, marker velocity, foot
//! skating, floor (penetration and contact height), and the robust KL of GAMMA/EgoGen (`sqrt(1 + KL²) − 1`).

use burn::prelude::*;
use serde::{Deserialize, Serialize};

use super::features::TRANSL_OFFSET;
use super::tensor_body::{matrix_to_rot6d, rot6d_to_matrix, TensorRig, BODY_JOINTS};
use crate::motion::primitive::{PRIMITIVE_RATE_HZ, SEED_FRAMES};

/// Weight of each loss term.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LossWeights {
    /// L1 on the 6D rotations of the decoded frames.
    pub pose: f64,
    /// L1 on `transl` (metres).
    pub transl: f64,
    /// L1 on marker positions (metres).
    pub markers: f64,
    /// L1 on marker displacements between frames (metres per frame).
    pub velocity: f64,
    /// Horizontal speed (m/s) of foot markers where the mocap foot is in contact.
    pub skate: f64,
    /// Depth (metres) of foot markers below the floor, plus the error of their height above the
    /// floor where the mocap foot is in contact (this keeps chained primitives on the floor).
    pub floor: f64,
    /// Robust KL of the posterior to N(0, I) (nats).
    pub kl: f64,
}

/// Height above the floor (m) and horizontal speed (m/s) under which a mocap foot marker is in
/// contact, for the skate term.
const CONTACT_HEIGHT_M: f64 = 0.05;
const CONTACT_SPEED_M_PER_S: f64 = 0.3;

/// A posed batch of primitives: `[B, T, ...]`.
#[derive(Debug, Clone)]
pub(crate) struct Posed<B: Backend> {
    /// Gram-Schmidt'ed 6D `[B, T, 22, 6]`.
    pub rot6d: Tensor<B, 4>,
    /// `[B, T, 3]`.
    pub transl: Tensor<B, 3>,
    /// `[B, T, 22, 3]`.
    pub joints: Tensor<B, 4>,
    /// `[B, T, M, 3]`.
    pub markers: Tensor<B, 4>,
}

/// Poses raw features `[B, T, F]`.
pub(crate) fn pose_frames<B: Backend>(rig: &TensorRig<B>, x: Tensor<B, 3>) -> Posed<B> {
    let [b, t, _] = x.dims();
    let rot: Tensor<B, 5> =
        rot6d_to_matrix(
            x.clone()
                .narrow(2, 0, TRANSL_OFFSET)
                .reshape([b, t, BODY_JOINTS, 6]),
        );
    let transl = x.narrow(2, TRANSL_OFFSET, 3);
    let (joints, _, markers) = rig.pose(
        rot.clone().reshape([b * t, BODY_JOINTS, 3, 3]),
        transl.clone().reshape([b * t, 3]),
    );
    let m = rig.num_markers;
    Posed {
        rot6d: matrix_to_rot6d(rot),
        transl,
        joints: joints.reshape([b, t, BODY_JOINTS, 3]),
        markers: markers.reshape([b, t, m, 3]),
    }
}

/// Loss terms of one batch (each a scalar tensor) and their weighted sum.
pub(crate) struct LossTerms<B: Backend> {
    pub total: Tensor<B, 1>,
    /// `(name, unweighted value)` in the order of [`LossWeights`].
    pub parts: Vec<(&'static str, Tensor<B, 1>)>,
}

/// Losses of predicted primitives `pred` against `target` (raw features `[B, T, F]`, the seed
/// frames included), with floors `[B]` in each canonical frame and KL terms `(mu, logvar)`.
pub(crate) fn primitive_loss<B: Backend>(
    rig: &TensorRig<B>,
    weights: &LossWeights,
    pred: Tensor<B, 3>,
    target: Tensor<B, 3>,
    pred_floor: Tensor<B, 1>,
    target_floor: Tensor<B, 1>,
    posterior: (Tensor<B, 2>, Tensor<B, 2>),
) -> LossTerms<B> {
    let [b, t, _] = pred.dims();
    let n = t - SEED_FRAMES;
    let p = pose_frames(rig, pred);
    let g = pose_frames(rig, target.clone());
    let after_seed = |x: Tensor<B, 4>| x.narrow(1, SEED_FRAMES, n);
    let pose = (after_seed(p.rot6d.clone()) - after_seed(g.rot6d))
        .abs()
        .mean();
    let transl = (p.transl.clone().narrow(1, SEED_FRAMES, n) - g.transl.narrow(1, SEED_FRAMES, n))
        .abs()
        .mean();
    let markers = (after_seed(p.markers.clone()) - after_seed(g.markers.clone()))
        .abs()
        .mean();
    let diff = |x: Tensor<B, 4>| x.clone().narrow(1, 1, t - 1) - x.narrow(1, 0, t - 1);
    let pv = diff(p.markers.clone()).narrow(1, SEED_FRAMES - 1, n);
    let gv = diff(g.markers.clone()).narrow(1, SEED_FRAMES - 1, n);
    let velocity = (pv.clone() - gv.clone()).abs().mean();

    // Feet: horizontal speed (m/s) and height above the floor of the foot markers.
    let feet = rig.foot_markers.clone();
    let horizontal_speed = |v: Tensor<B, 4>| {
        v.select(2, feet.clone())
            .narrow(3, 0, 2)
            .square()
            .sum_dim(3)
            .add_scalar(1e-10)
            .sqrt()
            .mul_scalar(PRIMITIVE_RATE_HZ)
    };
    let height = |m: Tensor<B, 4>, floor: Tensor<B, 1>| {
        m.select(2, feet.clone())
            .narrow(1, SEED_FRAMES, n)
            .narrow(3, 2, 1)
            .sub(floor.reshape([b, 1, 1, 1]))
    };
    let g_height = height(g.markers, target_floor);
    let contact = g_height.clone().lower_elem(CONTACT_HEIGHT_M).float().mul(
        horizontal_speed(gv)
            .lower_elem(CONTACT_SPEED_M_PER_S)
            .float(),
    );
    let skate = (horizontal_speed(pv) * contact.clone()).mean();
    let p_height = height(p.markers, pred_floor);
    let floor = p_height.clone().neg().clamp_min(0.0).mean()
        + ((p_height - g_height) * contact).abs().mean();

    let (mu, logvar) = posterior;
    let kl = (mu.square() + logvar.clone().exp() - logvar - 1.0)
        .sum_dim(1)
        .mul_scalar(0.5)
        .mean();
    let robust_kl = kl.clone().square().add_scalar(1.0).sqrt().sub_scalar(1.0);

    let parts = vec![
        ("pose", pose),
        ("transl", transl),
        ("markers", markers),
        ("velocity", velocity),
        ("skate", skate),
        ("floor", floor),
        ("kl", robust_kl),
    ];
    weighted(
        parts,
        &[
            weights.pose,
            weights.transl,
            weights.markers,
            weights.velocity,
            weights.skate,
            weights.floor,
            weights.kl,
        ],
    )
}

/// Loss terms and their sum weighted by `w` (in the same order).
fn weighted<B: Backend>(parts: Vec<(&'static str, Tensor<B, 1>)>, w: &[f64]) -> LossTerms<B> {
    let total = parts
        .iter()
        .zip(w)
        .map(|((_, v), &w)| v.clone().mul_scalar(w))
        .reduce(|a, b| a + b)
        .expect("loss terms");
    LossTerms { total, parts }
}

/// Weights of the losses on primitives decoded from prior latents z ~ N(0, I), which have no
/// mocap target: they only ask for what every plausible primitive has.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorWeights {
    /// `|lowest foot marker − floor − 2 cm|` per frame (m): the first factor of the
    /// foot-contact score (`eval::contact_score`).
    pub contact: f64,
    /// `max(0, slowest foot marker's 3-D speed − 0.075 m/s)` per frame: its second factor.
    pub skate: f64,
    /// Depth of foot markers below the floor (m).
    pub penetration: f64,
    /// Distance (m) of the pelvis height above the floor outside the training data's range.
    pub pelvis: f64,
    /// How far the trunk's up direction (pelvis → neck) leans beyond the training data's
    /// steepest lean (`cos` units).
    pub upright: f64,
    /// How far (m/s) the pelvis's mean horizontal speed over a primitive falls short of
    /// `PlausibleRange::pelvis_speed_min`: the training clips walk and run, so a chain that
    /// slows to a stand leaves the data (0 when absent).
    #[serde(default)]
    pub speed: f64,
    /// Reconstruction (the mocap losses) of the mocap chain whose first seed is nearest a seed
    /// that an earlier random chain ended in, decoded from that seed: a target for the states
    /// long chains reach, away from the mocap (0 when absent).
    #[serde(default)]
    pub recovery: f64,
    /// L1 distance of the decoded root (global-orient 6D and `transl`, m) from what the
    /// starting weights (`init_weights`) decode from the same seed and latent: the fine-tuning
    /// may change how the legs carry the body, not where a latent takes it (0 when absent).
    #[serde(default)]
    pub anchor: f64,
}

/// Ranges of the training data that the prior losses keep decoded primitives inside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PlausibleRange {
    /// Pelvis height above the floor (m).
    pub pelvis_m: (f64, f64),
    /// Smallest vertical component of the unit trunk vector (pelvis → neck).
    pub trunk_up_min: f64,
    /// Slowest mean horizontal pelvis speed over a primitive's decoded frames (m/s).
    pub pelvis_speed_min: f64,
}

/// Offset of the lowest foot above the floor that the contact score rewards (m), and the foot
/// speed it lets pass (m/s), as in `eval::contact_score`.
const CONTACT_OFFSET_M: f64 = 0.02;
const SKATE_FREE_M_PER_S: f64 = 0.075;

/// Pelvis heights above the floor and vertical trunk components `[B, T]` of posed frames over
/// floors `[B]`.
pub(crate) fn pelvis_and_trunk<B: Backend>(
    p: &Posed<B>,
    floor: Tensor<B, 1>,
) -> (Tensor<B, 2>, Tensor<B, 2>) {
    let [b, t, _, _] = p.joints.dims();
    let joint = |j: usize| p.joints.clone().narrow(2, j, 1).reshape([b, t, 3]);
    let pelvis = joint(crate::body::joint::PELVIS);
    let trunk = joint(crate::body::joint::NECK) - pelvis.clone();
    let len = trunk.clone().square().sum_dim(2).add_scalar(1e-12).sqrt();
    let up = (trunk.narrow(2, 2, 1) / len).reshape([b, t]);
    let height = pelvis.narrow(2, 2, 1).reshape([b, t]) - floor.reshape([b, 1]);
    (height, up)
}

/// The range of pelvis heights and trunk lean over the frames of raw primitives `[B, T, F]`
/// with floors `[B]` (the training data), between the quantiles `q` and `1 − q` (0 for the
/// whole range: a few frames of bending or crouching then widen it).
pub(crate) fn plausible_range<B: Backend>(
    rig: &TensorRig<B>,
    x: Tensor<B, 3>,
    floor: Tensor<B, 1>,
    q: f64,
) -> PlausibleRange {
    let (height, up) = pelvis_and_trunk(&pose_frames(rig, x), floor);
    let sorted = |t: Tensor<B, 2>| {
        let mut v: Vec<f64> = t
            .into_data()
            .iter::<f64>()
            .filter(|v| v.is_finite())
            .collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let at = |v: &[f64], q: f64| v[((v.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize];
    let (height, up) = (sorted(height), sorted(up));
    PlausibleRange {
        pelvis_m: (at(&height, q), at(&height, 1.0 - q)),
        trunk_up_min: at(&up, q),
        pelvis_speed_min: 0.0,
    }
}

/// Mean L1 distance of the root features (global-orient 6D and `transl`) of the decoded frames
/// of raw primitives `pred` and `anchor` (`[B, T, F]`, the seed first).
pub(crate) fn root_distance<B: Backend>(pred: Tensor<B, 3>, anchor: Tensor<B, 3>) -> Tensor<B, 1> {
    let t = pred.dims()[1];
    let diff = (pred - anchor)
        .narrow(1, SEED_FRAMES, t - SEED_FRAMES)
        .abs();
    let orient = diff.clone().narrow(2, 0, 6).mean();
    let transl = diff.narrow(2, TRANSL_OFFSET, 3).mean();
    orient + transl
}

/// Losses of primitives `pred` (raw features `[B, T, F]`, the seed first) decoded from prior
/// latents over canonical floors `[B]`; `anchor`, the same seeds and latents decoded by the
/// starting weights, for `PriorWeights::anchor` (the term is 0 without it).
pub(crate) fn prior_loss<B: Backend>(
    rig: &TensorRig<B>,
    weights: &PriorWeights,
    range: &PlausibleRange,
    pred: Tensor<B, 3>,
    floor: Tensor<B, 1>,
    anchor: Option<Tensor<B, 3>>,
) -> LossTerms<B> {
    let [b, t, _] = pred.dims();
    let n = t - SEED_FRAMES;
    let anchor = match anchor {
        Some(a) => root_distance(pred.clone(), a),
        None => Tensor::zeros([1], &pred.device()),
    };
    let p = pose_frames(rig, pred);
    let feet = p.markers.clone().select(2, rig.foot_markers.clone()); // [B, T, F, 3]
    let foot_height = feet
        .clone()
        .narrow(1, SEED_FRAMES, n)
        .narrow(3, 2, 1)
        .sub(floor.clone().reshape([b, 1, 1, 1]));
    let lowest = foot_height.clone().min_dim(2); // [B, n, 1, 1]
    let contact = lowest.sub_scalar(CONTACT_OFFSET_M).abs().mean();
    // Central-difference 3-D speed (as the contact score measures it) of frames
    // SEED_FRAMES − 1 .. T − 2, so that every decoded frame but the last, and the seed's last,
    // is scored.
    let c = t - SEED_FRAMES;
    let ahead = feet.clone().narrow(1, SEED_FRAMES, c);
    let behind = feet.narrow(1, SEED_FRAMES - 2, c);
    let speed = (ahead - behind)
        .square()
        .sum_dim(3)
        .add_scalar(1e-10)
        .sqrt()
        .mul_scalar(PRIMITIVE_RATE_HZ / 2.0);
    let skate = speed
        .min_dim(2)
        .sub_scalar(SKATE_FREE_M_PER_S)
        .clamp_min(0.0)
        .mean();
    let penetration = foot_height.neg().clamp_min(0.0).mean();
    let pelvis_path = p
        .joints
        .clone()
        .narrow(2, crate::body::joint::PELVIS, 1)
        .reshape([b, t, 3]);
    let travelled = (pelvis_path.clone().narrow(1, t - 1, 1)
        - pelvis_path.narrow(1, SEED_FRAMES - 1, 1))
    .narrow(2, 0, 2)
    .square()
    .sum_dim(2)
    .add_scalar(1e-10)
    .sqrt()
    .mul_scalar(PRIMITIVE_RATE_HZ / n as f64);
    let speed_short = travelled
        .neg()
        .add_scalar(range.pelvis_speed_min)
        .clamp_min(0.0)
        .mean();
    let (height, up) = pelvis_and_trunk(&p, floor);
    let (height, up) = (
        height.narrow(1, SEED_FRAMES, n),
        up.narrow(1, SEED_FRAMES, n),
    );
    let (lo, hi) = range.pelvis_m;
    let pelvis = (height.clone().neg().add_scalar(lo).clamp_min(0.0)
        + height.sub_scalar(hi).clamp_min(0.0))
    .mean();
    let upright = up
        .neg()
        .add_scalar(range.trunk_up_min)
        .clamp_min(0.0)
        .mean();
    let parts = vec![
        ("prior_contact", contact),
        ("prior_skate", skate),
        ("prior_penetration", penetration),
        ("prior_pelvis", pelvis),
        ("prior_upright", upright),
        ("prior_speed", speed_short),
        ("prior_anchor", anchor),
    ];
    weighted(
        parts,
        &[
            weights.contact,
            weights.skate,
            weights.penetration,
            weights.pelvis,
            weights.upright,
            weights.speed,
            weights.anchor,
        ],
    )
}
