//! Frame features: what the network reads and writes per frame, and the way back to SMPL-X
//! parameters.
//!
//! One frame is `FRAME_DIM = 22 × 6 + 3` values in the primitive's canonical frame: the 6D
//! rotations (first two matrix columns) of global orient and the 21 body joints, then the smplx
//! `transl` (metres). Hands, jaw and eyes are not modelled and stay at rest.

use crate::body::BodyParams;
use crate::math::rotation::{matrices_to_axis_angles, rot6d_to_matrices};
use crate::math::{axis_angle_to_matrix, matrix_to_rot6d};
use crate::motion::primitive::Primitive;

use super::tensor_body::BODY_JOINTS;

/// Values per frame.
pub const FRAME_DIM: usize = BODY_JOINTS * 6 + 3;
/// Offset of `transl` inside a frame.
pub(crate) const TRANSL_OFFSET: usize = BODY_JOINTS * 6;

/// Features of one frame.
pub fn frame_features(params: &BodyParams) -> [f32; FRAME_DIM] {
    let mut out = [0f32; FRAME_DIM];
    for j in 0..BODY_JOINTS {
        let d6 = matrix_to_rot6d(axis_angle_to_matrix(params.joint_axis_angle(j)));
        for (o, v) in out[6 * j..6 * j + 6].iter_mut().zip(d6) {
            *o = v as f32;
        }
    }
    for c in 0..3 {
        out[TRANSL_OFFSET + c] = params.transl[c] as f32;
    }
    out
}

/// SMPL-X parameters of one frame of features (hands, jaw, eyes at rest).
pub(crate) fn frame_params(features: &[f32], betas: &[f64]) -> BodyParams {
    let mut p = BodyParams {
        betas: betas.to_vec(),
        ..BodyParams::default()
    };
    let d6: [[f64; 6]; BODY_JOINTS] =
        std::array::from_fn(|j| std::array::from_fn(|k| features[6 * j + k] as f64));
    let mut rotations = [crate::math::Mat3::IDENTITY; BODY_JOINTS];
    rot6d_to_matrices(&d6, &mut rotations);
    let mut axis_angles = [crate::math::Vec3::ZERO; BODY_JOINTS];
    matrices_to_axis_angles(&rotations, &mut axis_angles);
    for (j, aa) in axis_angles.into_iter().enumerate() {
        p.set_joint_axis_angle(j, aa);
    }
    p.transl = crate::math::Vec3::new(
        features[TRANSL_OFFSET] as f64,
        features[TRANSL_OFFSET + 1] as f64,
        features[TRANSL_OFFSET + 2] as f64,
    );
    p
}

/// Features of every frame of a primitive, flattened `[frames × FRAME_DIM]`.
pub(crate) fn primitive_features(p: &Primitive) -> Vec<f32> {
    p.frames.iter().flat_map(frame_features).collect()
}
