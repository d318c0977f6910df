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
#[cfg(test)]
pub(crate) fn body_cache(
    model: &BodyModel,
    motion: &MotionSequence,
    samples_per_frame: u32,
) -> Result<PointCache, PoseError> {
    body_cache_at(model, motion, samples_per_frame, None)
}

/// The body at some of `body_cache`'s sample times only: `indices` (ascending) into its
/// grid of `samples_per_frame` samples per frame, or all of them with `None`. Sample `j` of
/// the cache is the body at grid time `indices[j] / samples_per_frame` (the same vertices
/// `body_cache` has there).
pub(crate) fn body_cache_at(
    model: &BodyModel,
    motion: &MotionSequence,
    samples_per_frame: u32,
    indices: Option<&[usize]>,
) -> Result<PointCache, PoseError> {
    let samples_per_frame = samples_per_frame.max(1);
    let mut dense = resample(motion, motion.frame_rate_hz * samples_per_frame as f64);
    if let Some(keep) = indices {
        let keep: Vec<usize> = keep
            .iter()
            .copied()
            .filter(|&k| k < dense.poses.len())
            .collect();
        dense.poses = keep.iter().map(|&k| dense.poses[k]).collect();
        dense.trans = keep.iter().map(|&k| dense.trans[k]).collect();
    }
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

/// What a render reads of a body's motion, on the grid of `samples_per_frame` samples per
/// frame: around every rendered frame `f` the shutter's span `f ± shutter_frames / 2`
/// (rounded out to the grid; motion blur samples in it), and the frames `f ± every_n` whose
/// positions the flow pass reads (the previous and next rendered frames, on the ground
/// truth's timeline; the motion's first or last frame where they fall outside its `frames`).
/// Ascending grid indices.
pub(crate) fn rendered_sample_indices(
    rendered: &[u32],
    every_n: u32,
    shutter_frames: f64,
    samples_per_frame: u32,
    frames: usize,
) -> Vec<usize> {
    let s = samples_per_frame.max(1) as usize;
    let last = frames.saturating_sub(1) * s;
    let half = (0.5 * shutter_frames.max(0.0) * s as f64 - 1e-9)
        .ceil()
        .max(0.0) as usize;
    let mut keep = std::collections::BTreeSet::new();
    for &f in rendered {
        let centre = f as usize * s;
        for k in centre.saturating_sub(half)..=(centre + half).min(last) {
            keep.insert(k);
        }
        // A neighbour outside the motion reads its first or last frame (playback holds them).
        let before = (f as usize).saturating_sub(every_n as usize) * s;
        let after = ((f as usize + every_n as usize) * s).min(last);
        keep.insert(before);
        keep.insert(after);
    }
    keep.into_iter().collect()
}

/// Playback keys of a sparse cache: `(frame, sample)` pairs at the ends of every run of
/// consecutive grid `indices`, so that playing the cache linearly between keys reads, at every
/// time inside a run, the sample the full cache reads there. Between runs nothing is
/// rendered.
pub(crate) fn playback_keys(indices: &[usize], samples_per_frame: u32) -> Vec<[f64; 2]> {
    let s = samples_per_frame.max(1) as f64;
    let mut keys = Vec::new();
    let mut j = 0;
    while j < indices.len() {
        let start = j;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        keys.push([indices[start] as f64 / s, start as f64]);
        if j > start {
            keys.push([indices[j] as f64 / s, j as f64]);
        }
        j += 1;
    }
    keys
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sparse_cache_keeps_the_shutter_and_the_flow_neighbours() {
        // Every 4th frame of 13, shutter half a frame, 4 samples a frame.
        let keep = rendered_sample_indices(&[0, 4, 8, 12], 4, 0.5, 4, 13);
        assert_eq!(keep, vec![0, 1, 15, 16, 17, 31, 32, 33, 47, 48]);
        // Past the last rendered frame the flow reads the motion's last frame.
        let longer = rendered_sample_indices(&[0, 4, 8, 12], 4, 0.5, 4, 15);
        assert_eq!(longer[longer.len() - 3..], [48, 49, 56]);
        let keys = playback_keys(&keep, 4);
        assert_eq!(
            keys,
            vec![
                [0.0, 0.0],
                [0.25, 1.0],
                [3.75, 2.0],
                [4.25, 4.0],
                [7.75, 5.0],
                [8.25, 7.0],
                [11.75, 8.0],
                [12.0, 9.0]
            ]
        );
        // No shutter, every frame: every frame's centre, one run.
        let keep = rendered_sample_indices(&[0, 1, 2], 1, 0.0, 3, 3);
        assert_eq!(keep, vec![0, 3, 6]);
        assert_eq!(
            playback_keys(&keep, 3),
            vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]
        );
    }
}
