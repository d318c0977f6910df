//! The body's vertex cache for rendering: the body posed along a motion at sub-frame times,
//! as the PC2 point cache Blender plays back (`crate::vertex_cache`).

use crate::body::{BodyModel, PoseError, CORRECTIVE_BATCH};
use crate::math::Vec3;
use crate::motion::resample::resample;
use crate::motion::MotionSequence;
use crate::vertex_cache::PointCache;

/// Posed vertices of a motion at `samples_per_frame` evenly spaced times per frame, from frame
/// 0 to the last frame (rotations slerped, translation lerped between frames): sample `k` is
/// the body at frame `k / samples_per_frame`.
pub fn body_cache(
    model: &BodyModel,
    motion: &MotionSequence,
    samples_per_frame: u32,
) -> Result<PointCache, PoseError> {
    let samples_per_frame = samples_per_frame.max(1);
    let dense = resample(motion, motion.frame_rate_hz * samples_per_frame as f64);
    let shaped = model.shape(&motion.betas, &[])?;
    // Batches of frames: pose correctives from one matrix product per batch, frames skinned
    // in parallel (`ShapedBody::pose_sequence`).
    let mut samples: Vec<Vec<[f32; 3]>> = Vec::with_capacity(dense.poses.len());
    for (poses, trans) in dense
        .poses
        .chunks(CORRECTIVE_BATCH)
        .zip(dense.trans.chunks(CORRECTIVE_BATCH))
    {
        for posed in shaped.pose_sequence(poses, trans)? {
            samples.push(posed.vertices.iter().map(|v| to_f32(*v)).collect());
        }
    }
    Ok(PointCache {
        start_frame: 0.0,
        sample_rate: 1.0 / samples_per_frame as f32,
        samples,
    })
}

fn to_f32(v: Vec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}
