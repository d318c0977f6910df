//! Training losses of the C-VAE: pose (6D), translation, FK markers, marker velocity, foot
//! skating, floor (penetration and contact height), and the robust KL of GAMMA/EgoGen (`sqrt(1 + KL²) − 1`).

use burn::prelude::*;
use serde::{Deserialize, Serialize};

use super::features::TRANSL_OFFSET;
use super::rig::{matrix_to_rot6d, rot6d_to_matrix, TensorRig, BODY_JOINTS};
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
pub struct Posed<B: Backend> {
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
pub fn pose_frames<B: Backend>(rig: &TensorRig<B>, x: Tensor<B, 3>) -> Posed<B> {
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
pub struct LossTerms<B: Backend> {
    pub total: Tensor<B, 1>,
    /// `(name, unweighted value)` in the order of [`LossWeights`].
    pub parts: Vec<(&'static str, Tensor<B, 1>)>,
}

/// Losses of predicted primitives `pred` against `target` (raw features `[B, T, F]`, the seed
/// frames included), with floors `[B]` in each canonical frame and KL terms `(mu, logvar)`.
pub fn primitive_loss<B: Backend>(
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
    let w = [
        weights.pose,
        weights.transl,
        weights.markers,
        weights.velocity,
        weights.skate,
        weights.floor,
        weights.kl,
    ];
    let total = parts
        .iter()
        .zip(w)
        .map(|((_, v), w)| v.clone().mul_scalar(w))
        .reduce(|a, b| a + b)
        .expect("loss terms");
    LossTerms { total, parts }
}
