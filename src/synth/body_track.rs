//! Poses a body over a motion sequence: joints and `world_from_cpf` per frame, and the hands'
//! landmarks (`body::hand_landmarks`) where its hands move.

use rayon::prelude::*;

use crate::body::hand_landmarks::{hand_landmarks, HandLandmarks, HandTips};
use crate::body::{BodyModel, CpfCalibration, PoseError, NUM_JOINTS};
use crate::math::{Affine3, Vec3};
use crate::motion::MotionSequence;

/// One frame of a tracked body.
#[derive(Debug, Clone)]
pub struct TrackFrame {
    pub joints: [Vec3; NUM_JOINTS],
    pub world_from_cpf: Affine3,
}

/// A body followed through a motion sequence.
#[derive(Debug, Clone)]
pub struct BodyTrack {
    pub frame_rate_hz: f64,
    pub frames: Vec<TrackFrame>,
    /// Both hands' landmarks on every frame, in the world (left, right); `None` when the
    /// motion's hand pose is all zeros (the body model's rest hand throughout: a take with
    /// `[walker] finger_motion = false`, or mocap without fingers).
    pub hands: Option<Vec<[HandLandmarks; 2]>>,
}

/// Joints and CPF for every frame (joints-only fast path; no vertices), and the hands'
/// landmarks from the same skeletons where the hand pose is not all zeros.
pub(crate) fn track_body(
    model: &BodyModel,
    motion: &MotionSequence,
) -> Result<BodyTrack, PoseError> {
    let shaped = model.shape(&motion.betas, &[])?;
    let calibration = CpfCalibration::from_rest_joints(&shaped.rest_joints);
    let moves = motion
        .poses
        .iter()
        .any(|p| p[75..].iter().any(|&x| x != 0.0));
    let tips = moves.then(|| HandTips::of(model)).transpose()?;
    let tracked = (0..motion.len())
        .into_par_iter()
        .map(|i| {
            let pose = &motion.poses[i];
            let skeleton = shaped.skeleton(pose, motion.trans[i])?;
            let hands = tips
                .as_ref()
                .map(|tips| hand_landmarks(&shaped, &skeleton, pose, tips));
            let frame = TrackFrame {
                joints: skeleton.joints,
                world_from_cpf: calibration.world_from_cpf(&skeleton),
            };
            Ok((frame, hands))
        })
        .collect::<Result<Vec<_>, PoseError>>()?;
    let (frames, hands): (Vec<_>, Vec<_>) = tracked.into_iter().unzip();
    Ok(BodyTrack {
        frame_rate_hz: motion.frame_rate_hz,
        frames,
        hands: if moves {
            hands.into_iter().collect()
        } else {
            None
        },
    })
}
