//! A stabilised head: walking people hold their heading steady while the torso sways from side
//! to side with each stride (a real walker's head yaws 1.7° RMS about its path, the decoded
//! body's 6°; docs/MOTION.md, "Head motion"). [`stabilise_head`] turns the neck and head about
//! the vertical so the viewing direction's heading follows its own smoothed course (a
//! zero-phase Gaussian over [`HeadStabiliser::smoothing_s`]: the stride's sway is filtered out,
//! turns are kept and the head starts each turn a little before the body, as people do); the
//! neck takes [`HeadStabiliser::neck_share`] of the turn, the head the rest. The rest of the
//! body is unchanged. Where the viewing direction is near vertical (looking at the floor) the
//! heading is ill-defined and the correction fades out.

use crate::body::{joint, BodyParams, CpfCalibration, PoseError, ShapedBody, PARENTS};
use crate::math::{axis_angle_to_matrix, matrix_to_axis_angle, Mat3, Real};

use super::head_motion::unwrapped_yaw;
use crate::math::gaussian_smooth;

/// How the head is held.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HeadStabiliser {
    /// σ of the Gaussian the heading is smoothed with (s).
    pub smoothing_s: Real,
    /// Share of each correction the neck takes (the head the rest).
    pub neck_share: Real,
    /// Largest correction (rad).
    pub max_correction_rad: Real,
}

impl Default for HeadStabiliser {
    fn default() -> Self {
        Self {
            smoothing_s: 0.45,
            neck_share: 0.4,
            max_correction_rad: 0.5,
        }
    }
}

fn rotation_about_z(angle: Real) -> Mat3 {
    Mat3::from_rotation_z(angle)
}

/// Turns the neck and head of `frames` (a body of shape `shaped`, at `rate_hz`) so the CPF's
/// heading follows its smoothed course (the caller poses the frames again for their eye
/// frames and markers).
pub(crate) fn stabilise_head(
    frames: &mut [BodyParams],
    shaped: &ShapedBody,
    cpf: &CpfCalibration,
    rate_hz: Real,
    settings: &HeadStabiliser,
) -> Result<(), PoseError> {
    let neck = joint::NECK;
    let head = joint::HEAD;
    let spine3 = PARENTS[neck].expect("the neck has a parent");
    let mut parents = Vec::with_capacity(frames.len());
    let mut heads = Vec::with_capacity(frames.len());
    for f in frames.iter() {
        let sk = shaped.skeleton(&f.pose, f.transl)?;
        parents.push((
            sk.world_from_joint[spine3].matrix3,
            sk.world_from_joint[neck].matrix3,
        ));
        heads.push(cpf.world_from_cpf(&sk));
    }
    let yaw = unwrapped_yaw(&heads);
    let target = gaussian_smooth(&yaw, settings.smoothing_s * rate_hz);
    for (f, frame) in frames.iter_mut().enumerate() {
        let forward = heads[f].matrix3.z_axis;
        let level = ((forward.truncate().length() - 0.3) / 0.4).clamp(0.0, 1.0);
        let delta = (target[f] - yaw[f])
            .clamp(-settings.max_correction_rad, settings.max_correction_rad)
            * level;
        if delta == 0.0 {
            continue;
        }
        let (spine_world, neck_world) = parents[f];
        for (j, parent_world, angle) in [
            (neck, spine_world, settings.neck_share * delta),
            (head, neck_world, (1.0 - settings.neck_share) * delta),
        ] {
            let local = axis_angle_to_matrix(frame.joint_axis_angle(j));
            let turned = parent_world.transpose() * rotation_about_z(angle) * parent_world * local;
            frame.set_joint_axis_angle(j, matrix_to_axis_angle(turned));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyModel;
    use crate::math::{Affine3, Vec3};
    use std::f64::consts::PI;

    #[test]
    fn a_swaying_torso_keeps_a_steady_head_and_the_rest_of_the_body() {
        let model =
            BodyModel::load(crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz"))
                .unwrap();
        let shaped = model.shape(&[], &[]).unwrap();
        let cpf = CpfCalibration::from_rest_joints(&shaped.rest_joints);
        // The body yaws ±8° at 0.9 Hz about the vertical (global orient about world z: the
        // body frame's y is up in the SMPL-X rest; a z-up world turns it upright first).
        let upright = Mat3::from_rotation_x(PI / 2.0);
        let mut frames: Vec<BodyParams> = (0..200)
            .map(|f| {
                let t = f as Real / 40.0;
                let yaw = 8f64.to_radians() * (2.0 * PI * 0.9 * t).sin();
                let mut b = BodyParams::default();
                b.set_joint_axis_angle(
                    0,
                    matrix_to_axis_angle(Mat3::from_rotation_z(yaw) * upright),
                );
                b.transl = Vec3::new(1.2 * t, 0.0, 0.0);
                b
            })
            .collect();
        let before = frames.clone();
        stabilise_head(&mut frames, &shaped, &cpf, 40.0, &HeadStabiliser::default()).unwrap();
        let heads: Vec<Affine3> = frames
            .iter()
            .map(|f| cpf.world_from_cpf(&shaped.skeleton(&f.pose, f.transl).unwrap()))
            .collect();
        let yaw = unwrapped_yaw(&heads);
        // The body faces −y on average.
        let mid = &yaw[50..150];
        let mean = mid.iter().sum::<Real>() / mid.len() as Real;
        let rms = (mid.iter().map(|y| (y - mean).powi(2)).sum::<Real>() / mid.len() as Real).sqrt();
        // The body sways 5.7° RMS.
        assert!(
            rms.to_degrees() < 1.7,
            "head yaw sway {}°",
            rms.to_degrees()
        );
        for (a, b) in frames.iter().zip(&before) {
            for j in (0..55).filter(|&j| j != joint::NECK && j != joint::HEAD) {
                assert_eq!(a.joint_axis_angle(j), b.joint_axis_angle(j));
            }
            assert_eq!(a.transl, b.transl);
        }
    }
}
