//! A posed body's hand landmarks in Project Aria's MPS hand-tracking order (21 per hand:
//! the five fingertips, the wrist, the finger joints, the palm's centre; projectaria-tools'
//! `HandLandmark`), with the wrist's pose and the palm's and wrist's normals MPS writes
//! beside them. The finger joints and the wrist are the skeleton's; a fingertip is the mesh
//! vertex its last bone reaches farthest ([`HandTips`], chosen once per model from its rest
//! vertices and skin weights); the palm's centre is midway between the wrist and the middle
//! finger's knuckle; the normals are the rest hand's (palm −y, fingers along ±x) turned by
//! the wrist.

use super::{joint, BodyModel, PoseError, PosedSkeleton, ShapedBody, POSE_DIM};
use crate::math::{Affine3, Real, Vec3};

/// The landmarks' names, in MPS order (named for readers: the order every landmark array
/// follows).
#[allow(dead_code)]
pub(crate) const HAND_LANDMARKS: [&str; 21] = [
    "thumb_fingertip",
    "index_fingertip",
    "middle_fingertip",
    "ring_fingertip",
    "pinky_fingertip",
    "wrist",
    "thumb_intermediate",
    "thumb_distal",
    "index_proximal",
    "index_intermediate",
    "index_distal",
    "middle_proximal",
    "middle_intermediate",
    "middle_distal",
    "ring_proximal",
    "ring_intermediate",
    "ring_distal",
    "pinky_proximal",
    "pinky_intermediate",
    "pinky_distal",
    "palm_center",
];

/// The wrists (left, right).
const WRISTS: [usize; 2] = [joint::LEFT_WRIST, joint::RIGHT_WRIST];

/// Each finger's three SMPL-X joints (from the palm out), thumb to little finger, of the left
/// hand (the right's are 15 on).
const FINGER_JOINTS: [[usize; 3]; 5] = [
    [37, 38, 39],
    [25, 26, 27],
    [28, 29, 30],
    [34, 35, 36],
    [31, 32, 33],
];

/// A model's fingertip vertices, `[hand][finger]` (thumb to little finger).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct HandTips {
    pub vertices: [[u32; 5]; 2],
}

impl HandTips {
    /// Each finger's tip: of the vertices its last joint moves most, the one farthest along
    /// its last bone (the model's rest shape).
    pub(crate) fn of(model: &BodyModel) -> Result<HandTips, PoseError> {
        let rest = model.rest_joints(&[], &[])?;
        let mut vertices = [[0u32; 5]; 2];
        for (hand, tips) in vertices.iter_mut().enumerate() {
            for (finger, tip) in tips.iter_mut().enumerate() {
                let [_, j2, j3] = FINGER_JOINTS[finger].map(|j| j + 15 * hand);
                let along = (rest[j3] - rest[j2]).normalize();
                *tip = model
                    .skin_weights
                    .iter()
                    .enumerate()
                    .filter(|(_, w)| {
                        w.iter()
                            .max_by(|a, b| a.1.total_cmp(&b.1))
                            .is_some_and(|&(j, _)| j as usize == j3)
                    })
                    .map(|(v, _)| (v as u32, (model.v_template[v] - rest[j3]).dot(along)))
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(v, _)| v)
                    .ok_or_else(|| PoseError::NoFingertip {
                        joint: j3,
                        model: model.source.display().to_string(),
                    })?;
            }
        }
        Ok(HandTips { vertices })
    }
}

/// One hand on one frame, in the frame its points are in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandLandmarks {
    /// In [`HAND_LANDMARKS`] order (m).
    pub points: [Vec3; 21],
    /// The wrist joint's pose (its rotation the wrist's accumulated rotation).
    pub wrist: Affine3,
    /// Out of the palm, unit length: the rest hand's (−y) turned by the wrist.
    pub palm_normal: Vec3,
    /// From the wrist towards the fingers, unit length: the rest hand's (±x) turned by the
    /// wrist.
    pub wrist_normal: Vec3,
}

impl HandLandmarks {
    /// The same hand in another frame: `to_from_this` applied to every point, pose and normal.
    pub(crate) fn moved(&self, to_from_this: Affine3) -> HandLandmarks {
        HandLandmarks {
            points: self.points.map(|p| to_from_this.transform_point3(p)),
            wrist: to_from_this * self.wrist,
            palm_normal: to_from_this.transform_vector3(self.palm_normal),
            wrist_normal: to_from_this.transform_vector3(self.wrist_normal),
        }
    }
}

/// A hand's palm centre (`hand` 0: left, 1: right): midway between the wrist and the middle
/// finger's knuckle, in the skeleton's frame.
pub(crate) fn palm_centre(skeleton: &PosedSkeleton, hand: usize) -> Vec3 {
    (skeleton.joints[WRISTS[hand]] + skeleton.joints[FINGER_JOINTS[2][0] + 15 * hand]) * 0.5
}

/// Both hands (left, right) of a body posed as `skeleton` with `pose`, in the skeleton's
/// frame.
pub(crate) fn hand_landmarks(
    shaped: &ShapedBody,
    skeleton: &PosedSkeleton,
    pose: &[Real; POSE_DIM],
    tips: &HandTips,
) -> [HandLandmarks; 2] {
    let tip_ids: Vec<u32> = tips.vertices.iter().flatten().copied().collect();
    let tip_points = shaped.pose_vertices(skeleton, pose, &tip_ids);
    std::array::from_fn(|hand| {
        let wrist = skeleton.joints[WRISTS[hand]];
        let finger = |f: usize, k: usize| skeleton.joints[FINGER_JOINTS[f][k] + 15 * hand];
        let mut points = [Vec3::ZERO; 21];
        for f in 0..5 {
            points[f] = tip_points[5 * hand + f];
        }
        points[5] = wrist;
        points[6] = finger(0, 1);
        points[7] = finger(0, 2);
        for f in 1..5 {
            for k in 0..3 {
                points[8 + 3 * (f - 1) + k] = finger(f, k);
            }
        }
        points[20] = palm_centre(skeleton, hand);
        // The rest hand's palm faces −y and points along ±x (docs/BODY_MODEL.md): turned by
        // the wrist.
        let world_from_wrist = skeleton.world_from_joint[WRISTS[hand]];
        let along = [Vec3::X, -Vec3::X][hand];
        HandLandmarks {
            points,
            wrist: world_from_wrist,
            palm_normal: world_from_wrist.transform_vector3(-Vec3::Y).normalize(),
            wrist_normal: world_from_wrist.transform_vector3(along).normalize(),
        }
    })
}

/// Both hands' landmarks on every frame of a motion (`betas`, per-frame `poses` and
/// translations `trans`) in its world frame, frames in parallel.
pub(crate) fn hand_track(
    model: &BodyModel,
    betas: &[Real],
    poses: &[[Real; POSE_DIM]],
    trans: &[Vec3],
) -> Result<Vec<[HandLandmarks; 2]>, PoseError> {
    use rayon::prelude::*;
    let tips = HandTips::of(model)?;
    let shaped = model.shape(betas, &[])?;
    poses
        .par_iter()
        .zip(trans)
        .map(|(pose, &t)| {
            let skeleton = shaped.skeleton(pose, t)?;
            Ok(hand_landmarks(&shaped, &skeleton, pose, &tips))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyParams;

    #[test]
    fn landmarks_sit_where_a_hand_is() {
        let model = BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap();
        let tips = HandTips::of(&model).unwrap();
        let frame = BodyParams::default();
        let hands = hand_track(&model, &[], &[frame.pose], &[Vec3::ZERO]).unwrap();
        for (hand, h) in hands[0].iter().enumerate() {
            let side = [1.0, -1.0][hand];
            // Out along the arm, fingertips beyond every joint of their finger.
            for f in 0..5 {
                let tip = h.points[f];
                assert!(
                    side * tip.x > side * h.points[5].x + 0.05,
                    "{hand} {f}: {tip}"
                );
            }
            for k in [8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19] {
                let finger = 1 + (k - 8) / 3;
                assert!(
                    side * h.points[finger].x > side * h.points[k].x,
                    "{hand} {k}"
                );
            }
            // A hand is about 19 cm from the wrist to the middle fingertip.
            let span = h.points[2].distance(h.points[5]);
            assert!((0.14..0.24).contains(&span), "{span}");
            assert!((h.palm_normal - -Vec3::Y).length() < 1e-12);
            assert!((h.wrist_normal - Vec3::X * side).length() < 1e-12);
            // The palm's centre lies between the wrist and the knuckles.
            assert!(side * h.points[20].x > side * h.points[5].x);
            assert!(side * h.points[20].x < side * h.points[11].x);
        }
        // Tips differ per finger and hand.
        let all: std::collections::BTreeSet<u32> =
            tips.vertices.iter().flatten().copied().collect();
        assert_eq!(all.len(), 10);
        // Moved to another frame, everything follows.
        let to = Affine3::from_rotation_translation(
            glam::DQuat::from_rotation_z(0.7),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let moved = hands[0][0].moved(to);
        assert!((moved.points[3] - to.transform_point3(hands[0][0].points[3])).length() < 1e-12);
        assert!((moved.palm_normal.length() - 1.0).abs() < 1e-12);
    }
}
