//! Chaining primitives on tensors: the last two decoded frames become the next seed,
//! re-expressed in their own canonical frame (as `primitive::canonical_frame` defines it),
//! differentiably, so rollout training can back-propagate through the chain.
//!
//! Every joint's 6D rotation in the seed is made orthonormal (Gram-Schmidt), as the f64
//! inference path does when it turns decoded features into poses and back: the decoder's raw
//! 6D outputs drift in length, and a seed that carried them would give the network a hidden
//! state that inference does not have. (Measured: weights trained on raw seeds kept 40 of 40
//! random chains upright for 100 primitives when chained on raw seeds, all of which fell
//! between primitives 101 and 118, but only 25 primitives (median) when chained on valid
//! poses.)

use burn::prelude::*;

use super::features::TRANSL_OFFSET;
use super::tensor_body::{matrix_to_rot6d, rot6d_to_matrix, TensorRig, BODY_JOINTS};
use crate::body::joint;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};

/// The next seed `[B, S, F]` from a primitive's raw features `[B, T, F]`, and the height of
/// the new canonical origin in the old canonical frame `[B]` (to carry the floor along:
/// `floor_new = floor_old − height`).
pub(crate) fn next_seed<B: Backend>(
    rig: &TensorRig<B>,
    x: Tensor<B, 3>,
) -> (Tensor<B, 3>, Tensor<B, 1>) {
    let [b, _, f] = x.dims();
    let s = SEED_FRAMES;
    let last = x.narrow(1, PRIMITIVE_FRAMES - s, s);
    let local: Tensor<B, 4> =
        rot6d_to_matrix(
            last.clone()
                .narrow(2, 0, TRANSL_OFFSET)
                .reshape([b * s, BODY_JOINTS, 6]),
        );
    let transl = last.clone().narrow(2, TRANSL_OFFSET, 3).reshape([b * s, 3]);
    let (joints, _, _) = rig.pose(local.clone(), transl.clone());
    let joints = joints.reshape([b, s, BODY_JOINTS, 3]);
    let first = joints.narrow(1, 0, 1).reshape([b, BODY_JOINTS, 3]);
    let pelvis = first.clone().narrow(1, joint::PELVIS, 1).reshape([b, 3]);
    let hips = first.clone().narrow(1, joint::RIGHT_HIP, 1).reshape([b, 3])
        - first.narrow(1, joint::LEFT_HIP, 1).reshape([b, 3]);
    let hx = hips.clone().narrow(1, 0, 1);
    let hy = hips.narrow(1, 1, 1);
    let len = (hx.clone().square() + hy.clone().square())
        .add_scalar(1e-12)
        .sqrt();
    let (cx, cy) = (hx / len.clone(), hy / len);
    let zero = cx.zeros_like();
    let one = zero.clone().add_scalar(1.0);
    // Rows of canon_from_old: x = (cx, cy, 0), y = z × x = (−cy, cx, 0), z = (0, 0, 1).
    let canon_from_old: Tensor<B, 3> = Tensor::stack(
        vec![
            Tensor::cat(vec![cx.clone(), cy.clone(), zero.clone()], 1),
            Tensor::cat(vec![cy.neg(), cx, zero.clone()], 1),
            Tensor::cat(vec![zero.clone(), zero, one], 1),
        ],
        1,
    );
    let rot = canon_from_old.clone().unsqueeze_dim::<4>(1); // [B, 1, 3, 3]
    let orient = local.clone().narrow(1, 0, 1).reshape([b, s, 3, 3]);
    let new_orient: Tensor<B, 3> = matrix_to_rot6d(rot.clone().matmul(orient));
    // Pelvis (= rest pelvis + transl) relative to the new origin, rotated.
    let rel =
        (transl.reshape([b, s, 3]) - pelvis.clone().unsqueeze_dim::<3>(1)).unsqueeze_dim::<4>(3); // [B, S, 3, 1]
    let rest_offset = rig.rest_pelvis().reshape([1, 1, 3, 1]);
    let new_transl = rot
        .matmul(rel + rest_offset.clone())
        .sub(rest_offset)
        .reshape([b, s, 3]);
    let body: Tensor<B, 3> = matrix_to_rot6d(local.clone().narrow(1, 1, BODY_JOINTS - 1));
    let body = body.reshape([b, s, 6 * (BODY_JOINTS - 1)]);
    let seed = Tensor::cat(vec![new_orient, body, new_transl], 2);
    debug_assert_eq!(seed.dims()[2], f);
    let height = pelvis.narrow(1, 2, 1).reshape([b]);
    (seed, height)
}
