//! Motion primitives (paper): 20 frames = 0.5 s at 40 fps, the first 2 the seed, each in its
//! own canonical frame (GAMMA/EgoGen): origin at the pelvis of the first frame, x along
//! left hip → right hip made horizontal, z world up, y = z × x (forward).

use super::MotionSequence;
use crate::body::{joint, BodyModel, BodyParams, PoseError};
use crate::math::{Affine3, Mat3, Vec3};

/// Frames per primitive.
pub(crate) const PRIMITIVE_FRAMES: usize = 20;
/// Seed frames at the start of each primitive.
pub const SEED_FRAMES: usize = 2;
/// New frames per primitive (the seed frames are the previous primitive's last).
pub const NEW_FRAMES: usize = PRIMITIVE_FRAMES - SEED_FRAMES;
/// Frame rate of primitives (Hz).
pub(crate) const PRIMITIVE_RATE_HZ: f64 = 40.0;

/// A primitive expressed in its canonical frame.
#[derive(Debug, Clone)]
pub struct Primitive {
    /// Maps canonical coordinates to the world.
    pub world_from_canon: Affine3,
    /// Body parameters of each frame, in canonical coordinates.
    pub frames: Vec<BodyParams>,
}

/// Why no canonical frame exists.
#[derive(Debug, thiserror::Error)]
pub enum PrimitiveError {
    #[error("the hip line is vertical (|horizontal part| = {0:.2e} m): no canonical frame")]
    VerticalHips(f64),
    #[error(transparent)]
    Pose(#[from] PoseError),
}

/// Canonical frame from posed joints (z-up world).
pub(crate) fn canonical_frame(joints: &[Vec3]) -> Result<Affine3, PrimitiveError> {
    let hips = joints[joint::RIGHT_HIP] - joints[joint::LEFT_HIP];
    let horizontal = Vec3::new(hips.x, hips.y, 0.0);
    let len = horizontal.length();
    if len < 1e-6 {
        return Err(PrimitiveError::VerticalHips(len));
    }
    let x = horizontal / len;
    let z = Vec3::Z;
    let y = z.cross(x);
    Ok(Affine3 {
        matrix3: Mat3::from_cols(x, y, z),
        translation: joints[joint::PELVIS],
    })
}

/// Expresses `PRIMITIVE_FRAMES` frames of `seq` starting at `start` in their canonical frame.
pub(crate) fn canonicalize(
    seq: &MotionSequence,
    start: usize,
    model: &BodyModel,
) -> Result<Primitive, PrimitiveError> {
    let shaped = model.shape(&seq.betas, &[])?;
    let first = shaped.skeleton(&seq.poses[start], seq.trans[start])?;
    let world_from_canon = canonical_frame(&first.joints)?;
    let canon_from_world = world_from_canon.inverse();
    let rest_pelvis = shaped.rest_joints[joint::PELVIS];
    let frames = (start..start + PRIMITIVE_FRAMES)
        .map(|f| seq.frame(f).moved_rigidly(canon_from_world, rest_pelvis))
        .collect();
    Ok(Primitive {
        world_from_canon,
        frames,
    })
}

/// All primitives of a sequence, starting every `stride` frames.
#[cfg(test)]
pub(crate) fn extract_primitives(
    seq: &MotionSequence,
    stride: usize,
    model: &BodyModel,
) -> Result<Vec<Primitive>, PrimitiveError> {
    if seq.len() < PRIMITIVE_FRAMES {
        return Ok(Vec::new());
    }
    (0..=seq.len() - PRIMITIVE_FRAMES)
        .step_by(stride.max(1))
        .map(|s| canonicalize(seq, s, model))
        .collect()
}

impl Primitive {
    /// The frames moved back to the world.
    pub(crate) fn to_world(&self, model: &BodyModel) -> Result<Vec<BodyParams>, PoseError> {
        let betas = self
            .frames
            .first()
            .map(|f| f.betas.clone())
            .unwrap_or_default();
        let rest_pelvis = model.rest_joints(&betas, &[])?[joint::PELVIS];
        Ok(self
            .frames
            .iter()
            .map(|f| f.moved_rigidly(self.world_from_canon, rest_pelvis))
            .collect())
    }
}
