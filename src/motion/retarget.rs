//! Retargeting a CMU-skeleton BVH clip onto the SMPL-X body joints of a body model.
//!
//! Both skeletons rest with y up, z forward and the body's left at +x. For each SMPL-X body
//! joint mapped to a CMU joint, the CMU joint's world rotation is transferred, after a per-bone
//! rest correction: the minimal rotation taking the SMPL-X rest bone (joint → child) onto the
//! CMU rest bone, so that differences between the two rest poses (CMU's splayed legs, bone
//! directions) do not become pose. Local rotations follow from the world rotations. The root
//! path is scaled by the ratio of leg lengths and put in the z-up world (`world = Rx(90°)·body`,
//! so the body faces −y), and the clip is lifted so its lowest foot joint stands at the height
//! it has above the soles in the rest pose.

use std::f64::consts::FRAC_PI_2;

use super::bvh::BvhClip;
use super::MotionSequence;
use crate::body::skeleton::NUM_BODY_JOINTS;
use crate::body::{joint, BodyModel, PARENTS, POSE_DIM};
use crate::math::{axis_angle_to_matrix, matrix_to_axis_angle, Mat3, Vec3};

/// SMPL-X body joint ← CMU joint, and the SMPL-X child that defines its bone (if any).
pub(crate) const CMU_TO_SMPLX: [(usize, &str, Option<usize>); NUM_BODY_JOINTS] = [
    (joint::PELVIS, "Hips", None),
    (joint::LEFT_HIP, "LeftUpLeg", Some(joint::LEFT_KNEE)),
    (joint::RIGHT_HIP, "RightUpLeg", Some(joint::RIGHT_KNEE)),
    (3, "LowerBack", None),
    (joint::LEFT_KNEE, "LeftLeg", Some(joint::LEFT_ANKLE)),
    (joint::RIGHT_KNEE, "RightLeg", Some(joint::RIGHT_ANKLE)),
    (6, "Spine", None),
    (joint::LEFT_ANKLE, "LeftFoot", Some(joint::LEFT_FOOT)),
    (joint::RIGHT_ANKLE, "RightFoot", Some(joint::RIGHT_FOOT)),
    (9, "Spine1", None),
    (joint::LEFT_FOOT, "LeftToeBase", None),
    (joint::RIGHT_FOOT, "RightToeBase", None),
    (joint::NECK, "Neck1", Some(joint::HEAD)),
    (13, "LeftShoulder", Some(joint::LEFT_SHOULDER)),
    (14, "RightShoulder", Some(joint::RIGHT_SHOULDER)),
    (joint::HEAD, "Head", None),
    (joint::LEFT_SHOULDER, "LeftArm", Some(joint::LEFT_ELBOW)),
    (joint::RIGHT_SHOULDER, "RightArm", Some(joint::RIGHT_ELBOW)),
    (joint::LEFT_ELBOW, "LeftForeArm", Some(joint::LEFT_WRIST)),
    (joint::RIGHT_ELBOW, "RightForeArm", Some(joint::RIGHT_WRIST)),
    (joint::LEFT_WRIST, "LeftHand", None),
    (joint::RIGHT_WRIST, "RightHand", None),
];

/// CMU metres per file unit (the cgspeed conversion's scale).
pub(crate) const CMU_UNIT_M: f64 = 0.056444;

/// What went wrong retargeting.
#[derive(Debug, thiserror::Error)]
pub(crate) enum RetargetError {
    #[error("BVH {path}: joint `{name}` missing; the CMU skeleton (cgspeed BVH) is expected")]
    MissingJoint { path: String, name: &'static str },
    #[error(transparent)]
    Pose(#[from] crate::body::PoseError),
}

/// Minimal rotation taking unit direction `from` onto `to`.
pub(crate) fn rotation_between(from: Vec3, to: Vec3) -> Mat3 {
    let (a, b) = (from.normalize(), to.normalize());
    let axis = a.cross(b);
    let s = axis.length();
    let c = a.dot(b);
    if s < 1e-12 {
        return if c > 0.0 {
            Mat3::IDENTITY
        } else {
            axis_angle_to_matrix(a.any_orthonormal_vector() * std::f64::consts::PI)
        };
    }
    axis_angle_to_matrix(axis / s * s.atan2(c))
}

/// Retargets a CMU BVH clip onto `model` (zero betas), at the clip's own frame rate.
pub(crate) fn retarget_cmu(
    clip: &BvhClip,
    model: &BodyModel,
) -> Result<MotionSequence, RetargetError> {
    let path = clip.source.display().to_string();
    let mut cmu_index = [0usize; NUM_BODY_JOINTS];
    for (j, name, _) in CMU_TO_SMPLX {
        cmu_index[j] = clip.joint_index(name).ok_or(RetargetError::MissingJoint {
            path: path.clone(),
            name,
        })?;
    }
    let rest = model.rest_joints(&[], &[])?;
    let cmu_rest = clip.rest_positions();
    // Per-bone corrections: CMU rest bone direction vs SMPL-X rest bone direction.
    let mut correction = [Mat3::IDENTITY; NUM_BODY_JOINTS];
    for (j, _, child) in CMU_TO_SMPLX {
        if let Some(c) = child {
            let cmu_child = CMU_TO_SMPLX
                .iter()
                .find(|(jj, _, _)| *jj == c)
                .map(|(_, n, _)| clip.joint_index(n).unwrap())
                .unwrap();
            correction[j] = rotation_between(
                rest[c] - rest[j],
                cmu_rest[cmu_child] - cmu_rest[cmu_index[j]],
            );
        }
    }
    // Root path scale: our leg length over the CMU leg length (hip → ankle, left side).
    let leg = |a: Vec3, k: Vec3, f: Vec3| (k - a).length() + (f - k).length();
    let ours = leg(
        rest[joint::LEFT_HIP],
        rest[joint::LEFT_KNEE],
        rest[joint::LEFT_ANKLE],
    );
    let theirs = leg(
        cmu_rest[cmu_index[1]],
        cmu_rest[cmu_index[4]],
        cmu_rest[cmu_index[7]],
    );
    let path_scale = ours / theirs;
    let mut world = Vec::with_capacity(clip.frames.len());
    let mut root_path = Vec::with_capacity(clip.frames.len());
    for f in 0..clip.frames.len() {
        let g = clip.global_transforms(f);
        world.push(std::array::from_fn(|j| {
            g[cmu_index[j]].matrix3 * correction[j]
        }));
        root_path.push(g[cmu_index[0]].translation * path_scale);
    }
    sequence_from_body_rotations(&world, &root_path, clip.frame_rate_hz, model)
}

/// Builds a z-up world sequence from per-frame body-frame world rotations of the 22 body
/// joints and the pelvis path (model's body frame, metres): local rotations from the world
/// ones, `world = Rx(90°)·body`, then lifted onto the floor.
pub(crate) fn sequence_from_body_rotations(
    world: &[[Mat3; NUM_BODY_JOINTS]],
    pelvis_path: &[Vec3],
    frame_rate_hz: f64,
    model: &BodyModel,
) -> Result<MotionSequence, RetargetError> {
    let rest_pelvis = model.rest_joints(&[], &[])?[joint::PELVIS];
    let world_from_body = axis_angle_to_matrix(Vec3::X * FRAC_PI_2);
    let mut poses = Vec::with_capacity(world.len());
    let mut trans = Vec::with_capacity(world.len());
    for (w, p) in world.iter().zip(pelvis_path) {
        let mut pose = [0.0; POSE_DIM];
        for j in 0..NUM_BODY_JOINTS {
            let local = match PARENTS[j] {
                None => world_from_body * w[j],
                Some(parent) => w[parent].transpose() * w[j],
            };
            pose[3 * j..3 * j + 3].copy_from_slice(&matrix_to_axis_angle(local).to_array());
        }
        poses.push(pose);
        trans.push(world_from_body.mul_vec3(*p) - rest_pelvis);
    }
    let mut seq = MotionSequence {
        frame_rate_hz,
        betas: Vec::new(),
        gender: "neutral".into(),
        poses,
        trans,
    };
    lift_to_floor(&mut seq, model)?;
    Ok(seq)
}

/// Shifts a z-up sequence vertically so its lowest foot joint (ankle or ball) is as high
/// above z = 0 as it is above the soles in the rest pose.
pub(crate) fn lift_to_floor(
    seq: &mut MotionSequence,
    model: &BodyModel,
) -> Result<(), crate::body::PoseError> {
    let shaped = model.shape(&seq.betas, &[])?;
    let sole_y = shaped.rest_sole_y();
    let feet = [
        joint::LEFT_ANKLE,
        joint::RIGHT_ANKLE,
        joint::LEFT_FOOT,
        joint::RIGHT_FOOT,
    ];
    let rest_clearance = feet
        .iter()
        .map(|&j| shaped.rest_joints[j].y - sole_y)
        .fold(f64::INFINITY, f64::min);
    let mut lowest = f64::INFINITY;
    for (p, t) in seq.poses.iter().zip(&seq.trans) {
        let s = shaped.skeleton(p, *t)?;
        lowest = feet.iter().map(|&j| s.joints[j].z).fold(lowest, f64::min);
    }
    let dz = rest_clearance - lowest;
    for t in &mut seq.trans {
        t.z += dz;
    }
    Ok(())
}
