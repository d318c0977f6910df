//! The egocentric camera anchor, CPF ("central pupil frame"), from a posed skeleton.
//!
//! Origin: midpoint of the eye joints 23 and 24. Orientation: from the plane of the two eye
//! bones (head 15 → left eye 23, head 15 → right eye 24). That plane's normal points forward
//! and, because the eyes sit above and in front of the head joint, also tilts down; the tilt the
//! plane has in the rest pose is removed, so an upright neutral head looks level and the CPF of
//! the zero pose has the axes of the SMPL-X body frame.
//!
//! CPF axes (the frame rigs are placed in, `world_from_cam = world_from_cpf · cpf_from_cam`):
//! x towards the wearer's left, y up, z forward (viewing direction).

use super::lbs::PosedSkeleton;
use super::skeleton::{joint, NUM_JOINTS};
use crate::math::{Affine3, Mat3, Vec3};

/// Orthonormal frame of the eye-bone plane: x = right-eye→left-eye, z = plane normal
/// (forward), y = z × x.
fn eye_plane_frame(head: Vec3, left_eye: Vec3, right_eye: Vec3) -> Mat3 {
    let bone_l = left_eye - head;
    let bone_r = right_eye - head;
    let z = bone_l.cross(bone_r).normalize();
    let x0 = left_eye - right_eye;
    let x = (x0 - z * z.dot(x0)).normalize();
    Mat3::from_cols(x, z.cross(x), z)
}

/// The CPF calibration of a body shape: rest-pose eye-plane frame, whose tilt is removed.
#[derive(Debug, Clone, Copy)]
pub struct CpfCalibration {
    /// `eye_plane_from_cpf`: the CPF axes expressed in the rest eye-plane frame.
    eye_plane_from_cpf: Mat3,
}

impl CpfCalibration {
    /// Calibrates from the rest joints of a shaped body.
    pub fn from_rest_joints(rest_joints: &[Vec3; NUM_JOINTS]) -> Self {
        let rest = eye_plane_frame(
            rest_joints[joint::HEAD],
            rest_joints[joint::LEFT_EYE],
            rest_joints[joint::RIGHT_EYE],
        );
        // CPF at rest = body frame axes (identity in the model frame).
        Self {
            eye_plane_from_cpf: rest.transpose(),
        }
    }

    /// Angle (radians) by which the rest eye-plane normal points below the level gaze.
    pub(crate) fn rest_tilt_down_rad(&self) -> f64 {
        // The plane normal in CPF coordinates is the z column of cpf_from_eye_plane.
        let normal_in_cpf = self.eye_plane_from_cpf.transpose().z_axis;
        (-normal_in_cpf.y).atan2(normal_in_cpf.z)
    }

    /// `world_from_cpf` of a posed skeleton.
    pub fn world_from_cpf(&self, skeleton: &PosedSkeleton) -> Affine3 {
        let j = &skeleton.joints;
        let plane = eye_plane_frame(j[joint::HEAD], j[joint::LEFT_EYE], j[joint::RIGHT_EYE]);
        Affine3 {
            matrix3: plane * self.eye_plane_from_cpf,
            translation: (j[joint::LEFT_EYE] + j[joint::RIGHT_EYE]) * 0.5,
        }
    }
}
