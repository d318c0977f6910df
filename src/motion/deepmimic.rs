//! DeepMimic motion clips (`humanoid3d_*.txt`, `walker/*.txt` in PyPI `pybullet`'s
//! `pybullet_data/data/motions/`, zlib licence) retargeted onto the body model.
//!
//! Frame layout (44 numbers): duration (s), root position (3, metres), then rotations —
//! quaternions `w x y z` for root, chest, neck, right hip, right ankle, right shoulder, left hip,
//! left ankle, left shoulder, and one angle (rad, about the joint's z axis) for each knee and
//! elbow: `dt | root p | root q | chest q | neck q | r hip q | r knee | r ankle q | r shoulder q |
//! r elbow | l hip q | l knee | l ankle q | l shoulder q | l elbow`.
//! The humanoid (`pybullet_data/humanoid/humanoid.urdf`, loaded at scale 0.25) is y up, faces +x,
//! its right side at +z; it rests with arms hanging down. Its chest rotation is spread evenly
//! over SMPL-X's three spine joints; collars, head, wrists and feet keep their parents' rotation.

use std::path::Path;

use glam::DQuat;

use super::retarget::{rotation_between, sequence_from_body_rotations};
use super::MotionSequence;
use crate::body::skeleton::NUM_BODY_JOINTS;
use crate::body::{joint, BodyModel};
use crate::math::{axis_angle_to_matrix, Mat3, Vec3};

/// Rest offsets of the humanoid (URDF units × 0.25 = metres), humanoid axes.
const SCALE: f64 = 0.25;
const KNEE: [f64; 3] = [0.0, -1.686184, 0.0];
const ANKLE: [f64; 3] = [0.0, -1.639480, 0.0];
const TOE: [f64; 3] = [0.18, -0.09, 0.0];
const ELBOW: [f64; 3] = [0.0, -1.099152, 0.0];
const WRIST: [f64; 3] = [0.0, -1.035788, 0.0];

/// Humanoid axes → SMPL-X body axes: forward +x → +z, up +y → +y, right +z → −x.
fn to_body() -> Mat3 {
    Mat3::from_cols(Vec3::Z, Vec3::Y, -Vec3::X)
}

fn v(a: [f64; 3]) -> Vec3 {
    Vec3::from_array(a) * SCALE
}

/// Where each quaternion (`w x y z`) starts in a frame, and whose rotation it is.
const QUATERNIONS: [(usize, &str); 9] = [
    (4, "root"),
    (8, "chest"),
    (12, "neck"),
    (16, "right hip"),
    (21, "right ankle"),
    (25, "right shoulder"),
    (30, "left hip"),
    (35, "left ankle"),
    (39, "left shoulder"),
];

/// A quaternion shorter than this has no direction to normalise to.
const MIN_QUATERNION_LENGTH: f64 = 1e-6;

/// What went wrong reading a DeepMimic clip.
#[derive(Debug, thiserror::Error)]
pub enum DeepMimicError {
    #[error("DeepMimic clip {path}: {message}")]
    Invalid { path: String, message: String },
}

#[derive(serde::Deserialize)]
struct ClipFile {
    #[serde(rename = "Frames")]
    frames: Vec<Vec<f64>>,
}

/// Reads a humanoid3d clip and retargets it onto `model` at the clip's frame rate.
pub fn import_deepmimic(path: &Path, model: &BodyModel) -> Result<MotionSequence, DeepMimicError> {
    let bad = |message: String| DeepMimicError::Invalid {
        path: path.display().to_string(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("cannot read ({e})")))?;
    let clip: ClipFile = serde_json::from_str(&text)
        .map_err(|e| bad(format!("not a DeepMimic motion file ({e})")))?;
    if clip.frames.is_empty() {
        return Err(bad("no frames".into()));
    }
    if let Some((i, f)) = clip.frames.iter().enumerate().find(|(_, f)| f.len() != 44) {
        return Err(bad(format!(
            "frame {i} has {} numbers, expected 44 (humanoid3d layout)",
            f.len()
        )));
    }
    if let Some(i) = clip
        .frames
        .iter()
        .position(|f| f.iter().any(|x| !x.is_finite()))
    {
        return Err(bad(format!("frame {i} holds a non-finite value")));
    }
    let dt = clip.frames[0][0];
    if !(dt > 0.0 && (1.0 / dt).is_finite()) {
        return Err(bad(format!(
            "frame duration must be positive and give a finite frame rate, found {dt}"
        )));
    }
    for (i, f) in clip.frames.iter().enumerate() {
        if let Some((at, joint)) = QUATERNIONS.iter().find(|(at, _)| {
            let len = DQuat::from_xyzw(f[at + 1], f[at + 2], f[at + 3], f[*at]).length();
            !(len.is_finite() && len > MIN_QUATERNION_LENGTH)
        }) {
            return Err(bad(format!(
                "frame {i}: the {joint} rotation (numbers {at}–{}) is not a rotation: expected a quaternion w x y z of length near 1",
                at + 3
            )));
        }
    }
    let c = to_body();
    let conv = |r: Mat3| c * r * c.transpose();
    let quat = |f: &[f64], i: usize| {
        conv(Mat3::from_quat(
            DQuat::from_xyzw(f[i + 1], f[i + 2], f[i + 3], f[i]).normalize(),
        ))
    };
    let hinge = |a: f64| conv(axis_angle_to_matrix(Vec3::Z * a));

    // Rest bones of both skeletons (body axes), and per-bone corrections.
    let rest = model
        .rest_joints(&[], &[])
        .map_err(|e| bad(format!("retargeting: {e}")))?;
    let dm_bone = |j: usize| -> Option<Vec3> {
        let d = match j {
            joint::RIGHT_HIP | joint::LEFT_HIP => KNEE,
            joint::RIGHT_KNEE | joint::LEFT_KNEE => ANKLE,
            joint::RIGHT_ANKLE | joint::LEFT_ANKLE => TOE,
            joint::RIGHT_SHOULDER | joint::LEFT_SHOULDER => ELBOW,
            joint::RIGHT_ELBOW | joint::LEFT_ELBOW => WRIST,
            joint::NECK => [0.0, 1.0, 0.0],
            _ => return None,
        };
        Some(c * v(d))
    };
    let child = |j: usize| match j {
        joint::LEFT_HIP => joint::LEFT_KNEE,
        joint::RIGHT_HIP => joint::RIGHT_KNEE,
        joint::LEFT_KNEE => joint::LEFT_ANKLE,
        joint::RIGHT_KNEE => joint::RIGHT_ANKLE,
        joint::LEFT_ANKLE => joint::LEFT_FOOT,
        joint::RIGHT_ANKLE => joint::RIGHT_FOOT,
        joint::LEFT_SHOULDER => joint::LEFT_ELBOW,
        joint::RIGHT_SHOULDER => joint::RIGHT_ELBOW,
        joint::LEFT_ELBOW => joint::LEFT_WRIST,
        joint::RIGHT_ELBOW => joint::RIGHT_WRIST,
        _ => joint::HEAD, // neck
    };
    let correction: [Mat3; NUM_BODY_JOINTS] = std::array::from_fn(|j| {
        dm_bone(j).map_or(Mat3::IDENTITY, |d| {
            rotation_between(rest[child(j)] - rest[j], d)
        })
    });
    let dm_leg = v(KNEE).length() + v(ANKLE).length();
    let our_leg = (rest[joint::LEFT_KNEE] - rest[joint::LEFT_HIP]).length()
        + (rest[joint::LEFT_ANKLE] - rest[joint::LEFT_KNEE]).length();
    let path_scale = our_leg / dm_leg;

    let mut world = Vec::with_capacity(clip.frames.len());
    let mut path_body = Vec::with_capacity(clip.frames.len());
    for f in &clip.frames {
        let root = quat(f, 4);
        let chest_local = quat(f, 8);
        let chest = root * chest_local;
        let neck = chest * quat(f, 12);
        let (r_hip, l_hip) = (root * quat(f, 16), root * quat(f, 30));
        let (r_knee, l_knee) = (r_hip * hinge(f[20]), l_hip * hinge(f[34]));
        let (r_ankle, l_ankle) = (r_knee * quat(f, 21), l_knee * quat(f, 35));
        let (r_sh, l_sh) = (chest * quat(f, 25), chest * quat(f, 39));
        let (r_el, l_el) = (r_sh * hinge(f[29]), l_sh * hinge(f[43]));
        // Spine: the chest's local rotation split in three equal steps.
        let step =
            Mat3::from_quat(DQuat::IDENTITY.slerp(DQuat::from_mat3(&chest_local), 1.0 / 3.0));
        let spine1 = root * step;
        let spine2 = spine1 * step;
        let spine3 = spine2 * step;
        let mut w = [Mat3::IDENTITY; NUM_BODY_JOINTS];
        w[joint::PELVIS] = root;
        w[3] = spine1;
        w[6] = spine2;
        w[9] = spine3;
        w[13] = spine3;
        w[14] = spine3;
        w[joint::NECK] = neck * correction[joint::NECK];
        w[joint::HEAD] = w[joint::NECK];
        w[joint::LEFT_HIP] = l_hip * correction[joint::LEFT_HIP];
        w[joint::RIGHT_HIP] = r_hip * correction[joint::RIGHT_HIP];
        w[joint::LEFT_KNEE] = l_knee * correction[joint::LEFT_KNEE];
        w[joint::RIGHT_KNEE] = r_knee * correction[joint::RIGHT_KNEE];
        w[joint::LEFT_ANKLE] = l_ankle * correction[joint::LEFT_ANKLE];
        w[joint::RIGHT_ANKLE] = r_ankle * correction[joint::RIGHT_ANKLE];
        w[joint::LEFT_FOOT] = w[joint::LEFT_ANKLE];
        w[joint::RIGHT_FOOT] = w[joint::RIGHT_ANKLE];
        w[joint::LEFT_SHOULDER] = l_sh * correction[joint::LEFT_SHOULDER];
        w[joint::RIGHT_SHOULDER] = r_sh * correction[joint::RIGHT_SHOULDER];
        w[joint::LEFT_ELBOW] = l_el * correction[joint::LEFT_ELBOW];
        w[joint::RIGHT_ELBOW] = r_el * correction[joint::RIGHT_ELBOW];
        w[joint::LEFT_WRIST] = w[joint::LEFT_ELBOW];
        w[joint::RIGHT_WRIST] = w[joint::RIGHT_ELBOW];
        world.push(w);
        path_body.push(c * Vec3::new(f[1], f[2], f[3]) * path_scale);
    }
    // Durations like 0.033332 mean 30 Hz: snap rates within 0.1 % of an integer.
    let rate = 1.0 / dt;
    let rate = if (rate - rate.round()).abs() < 1e-3 * rate {
        rate.round()
    } else {
        rate
    };
    sequence_from_body_rotations(&world, &path_body, rate, model)
        .map_err(|e| bad(format!("retargeting: {e}")))
}
