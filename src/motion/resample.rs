//! Changing a sequence's frame rate (rotation slerp, translation lerp) and mirroring it left ↔
//! right (augmentation).

use glam::DQuat;

use super::MotionSequence;
use crate::body::{BodyModel, NUM_JOINTS, POSE_DIM};
use crate::math::{axis_angle_to_matrix, matrix_to_axis_angle, Mat3, Vec3};

/// Resamples to `rate_hz`: frame `k` at time `k / rate_hz`, up to the last source frame.
/// Integer ratios (120 → 40 Hz) pick source frames exactly.
pub(crate) fn resample(seq: &MotionSequence, rate_hz: f64) -> MotionSequence {
    let n_in = seq.len();
    let duration = (n_in.saturating_sub(1)) as f64 / seq.frame_rate_hz;
    let n_out = (duration * rate_hz + 1e-9).floor() as usize + 1;
    let quats: Vec<[DQuat; NUM_JOINTS]> = seq
        .poses
        .iter()
        .map(|p| {
            std::array::from_fn(|j| {
                DQuat::from_mat3(&axis_angle_to_matrix(Vec3::new(
                    p[3 * j],
                    p[3 * j + 1],
                    p[3 * j + 2],
                )))
            })
        })
        .collect();
    let mut out = MotionSequence {
        frame_rate_hz: rate_hz,
        poses: Vec::with_capacity(n_out),
        trans: Vec::with_capacity(n_out),
        ..seq.clone()
    };
    for k in 0..n_out {
        let src = k as f64 / rate_hz * seq.frame_rate_hz;
        let i0 = (src.floor() as usize).min(n_in - 1);
        let a = src - i0 as f64;
        if a < 1e-9 || i0 + 1 >= n_in {
            out.poses.push(seq.poses[i0]);
            out.trans.push(seq.trans[i0]);
            continue;
        }
        let mut pose = [0.0; POSE_DIM];
        for j in 0..NUM_JOINTS {
            let q = quats[i0][j].slerp(quats[i0 + 1][j], a);
            pose[3 * j..3 * j + 3]
                .copy_from_slice(&matrix_to_axis_angle(Mat3::from_quat(q)).to_array());
        }
        out.poses.push(pose);
        out.trans.push(seq.trans[i0].lerp(seq.trans[i0 + 1], a));
    }
    out
}

/// Left ↔ right joint pairs of SMPL-X.
fn mirrored_joint(j: usize) -> usize {
    match j {
        1 | 4 | 7 | 10 | 13 | 16 | 18 | 20 => j + 1,
        2 | 5 | 8 | 11 | 14 | 17 | 19 | 21 => j - 1,
        23 => 24,
        24 => 23,
        25..=39 => j + 15,
        40..=54 => j - 15,
        _ => j,
    }
}

/// The sequence mirrored through the world plane x = 0 (z-up world): left and right joints
/// swap, body-frame rotations are reflected through the body's sagittal plane (x → −x).
pub(crate) fn mirror(
    seq: &MotionSequence,
    model: &BodyModel,
) -> Result<MotionSequence, crate::body::PoseError> {
    let m = Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
    let j0 = model.rest_joints(&seq.betas, &[])?[0];
    let reflect = |p: &[f64; POSE_DIM]| {
        let mut out = [0.0; POSE_DIM];
        for j in 0..NUM_JOINTS {
            let r = axis_angle_to_matrix(Vec3::new(p[3 * j], p[3 * j + 1], p[3 * j + 2]));
            // Reflection on both sides keeps a rotation: world x ↔ −x and body x ↔ −x.
            let r = m * r * m;
            let t = mirrored_joint(j);
            out[3 * t..3 * t + 3].copy_from_slice(&matrix_to_axis_angle(r).to_array());
        }
        out
    };
    let poses = seq.poses.iter().map(reflect).collect();
    // Posed pelvis = J0 + transl; mirror it, then re-root on the (mirrored-shape) rest pelvis.
    let trans = seq.trans.iter().map(|t| m * (*t + j0) - j0).collect();
    Ok(MotionSequence {
        poses,
        trans,
        ..seq.clone()
    })
}
