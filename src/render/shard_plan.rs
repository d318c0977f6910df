//! From a posed sequence to what one shard's Blender worker needs: camera pose keys at
//! sub-frames around each rendered frame, raw output names, Blender's frame rate. Planning
//! only; nothing here runs Blender.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use glam::DQuat;

use crate::math::Affine3;
use crate::render::camera_setup::camera_keys;
use crate::render::protocol::{ShardCamera, ShardFrame};
use crate::render::render_camera::RenderCamera;

/// Segmentation ids: scene objects are numbered from 1 (see `scene::ObjectId`); agent `k` is
/// `AGENT_ID_BASE + k`.
pub(crate) const AGENT_ID_BASE: u32 = 1000;

/// Segmentation ids of the objects people pick up: `HELD_OBJECT_ID_BASE + k`, in the take's
/// order (by person, then pick-up).
pub(crate) const HELD_OBJECT_ID_BASE: u32 = 2000;

/// Blender stores a frame rate as `fps / fps_base` with an integer `fps`.
pub(crate) fn blender_fps(rate_hz: f64) -> (u32, f64) {
    let fps = rate_hz.round().max(1.0) as u32;
    (fps, fps as f64 / rate_hz)
}

/// The pose at a fractional frame, interpolated between per-frame poses (rotation slerp,
/// translation lerp), held constant outside the sequence.
pub(crate) fn pose_at(poses: &[Affine3], frame: f64) -> Affine3 {
    let last = poses.len() - 1;
    let t = frame.clamp(0.0, last as f64);
    let i = (t.floor() as usize).min(last);
    let a = t - i as f64;
    if a == 0.0 || i == last {
        return poses[i];
    }
    let (p, q) = (poses[i], poses[i + 1]);
    let r = DQuat::from_mat3(&p.matrix3).slerp(DQuat::from_mat3(&q.matrix3), a);
    Affine3 {
        matrix3: glam::DMat3::from_quat(r),
        translation: p.translation.lerp(q.translation, a),
    }
}

/// Cycles' deformation motion steps for a body whose vertex cache holds
/// `cache_samples_per_frame` samples a frame, under a shutter open `shutter_frames` frames:
/// the fewest with Cycles' time samples (`2^steps + 1` across the shutter, evenly) at least
/// as dense as the cache's. Cycles moves vertices linearly between its samples and the cache
/// plays linearly between its own, so more steps only repeat what the cache's samples already
/// say, at the price of an evaluation and a sync of every body per extra sample and frame.
/// With the default shutter (½ frame) and cache (4 samples a frame) that is 1 step, 3 time
/// samples, each on one of the cache's.
pub(crate) fn deform_motion_steps(shutter_frames: f64, cache_samples_per_frame: u32) -> u32 {
    let intervals = (shutter_frames.max(0.0) * cache_samples_per_frame as f64 - 1e-9).ceil();
    let mut steps = 1;
    // Cycles keeps at most 129 time samples (2^7 + 1).
    while steps < 7 && f64::from(1u32 << steps) < intervals {
        steps += 1;
    }
    steps
}

/// Which raw renders a frame needs (`render::passes::Passes` decides).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RawRenders {
    /// The blurred colour render.
    pub colour: bool,
    /// The unblurred ground-truth render.
    pub ground_truth: bool,
}

/// The raw renders of a frame under `raw_dir` (colour, ground truth), each where asked.
pub(crate) fn raw_frame_paths(
    raw_dir: &Path,
    camera: &str,
    frame: u32,
    renders: RawRenders,
) -> (Option<PathBuf>, Option<PathBuf>) {
    let dir = raw_dir.join(camera);
    (
        renders
            .colour
            .then(|| dir.join(format!("rgb_{frame:05}.exr"))),
        renders
            .ground_truth
            .then(|| dir.join(format!("gt_{frame:05}.exr"))),
    )
}

/// A shard camera rendering `frames` of a sequence whose per-frame OpenCV poses are
/// `world_from_cam`. Pose keys are placed every `1 / keys_per_frame` frames from
/// `frame_step` frames before to `frame_step` after each rendered frame (the shutter interval
/// and the motion vectors' neighbours: the previous and next saved frame), inside the sequence.
pub(crate) fn shard_camera(
    name: &str,
    render: &RenderCamera,
    world_from_cam: &[Affine3],
    frames: &[u32],
    keys_per_frame: u32,
    frame_step: u32,
    raw_dir: &Path,
    renders: RawRenders,
) -> ShardCamera {
    let s = keys_per_frame.max(1) as i64;
    let step = frame_step.max(1) as i64;
    let last = (world_from_cam.len() as i64 - 1) * s;
    let ticks: BTreeSet<i64> = frames
        .iter()
        .flat_map(|&f| (f as i64 - step) * s..=(f as i64 + step) * s)
        .filter(|&k| (0..=last).contains(&k))
        .collect();
    let poses: Vec<(f64, Affine3)> = ticks
        .iter()
        .map(|&k| {
            let t = k as f64 / s as f64;
            (t, pose_at(world_from_cam, t))
        })
        .collect();
    ShardCamera {
        name: name.into(),
        lens: render.lens(),
        clip_start_m: 0.01,
        keys: camera_keys(&poses),
        frames: frames
            .iter()
            .map(|&frame| {
                let (rgb_exr, ground_truth_exr) = raw_frame_paths(raw_dir, name, frame, renders);
                ShardFrame {
                    frame,
                    rgb_exr,
                    ground_truth_exr,
                }
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::deform_motion_steps;

    #[test]
    fn motion_steps_are_as_dense_as_the_cache_and_no_denser() {
        // 2^steps + 1 time samples across the shutter against shutter × samples + 1 of the cache.
        assert_eq!(deform_motion_steps(0.5, 4), 1); // 3 against 3 (the default run)
        assert_eq!(deform_motion_steps(1.0, 4), 2); // 5 against 5
        assert_eq!(deform_motion_steps(1.0, 8), 3); // 9 against 9
        assert_eq!(deform_motion_steps(0.5, 5), 2); // 5 against 3.5: never sparser
        assert_eq!(deform_motion_steps(0.25, 4), 1); // 3 against 2
        assert_eq!(deform_motion_steps(0.0, 4), 1); // no blur: Cycles' least
        assert_eq!(deform_motion_steps(1.0, 1000), 7); // Cycles' most: 129 samples
        for spf in 1..=64 {
            for tenth in 0..=10 {
                let shutter = tenth as f64 / 10.0;
                let steps = deform_motion_steps(shutter, spf);
                let cycles = f64::from(1u32 << steps);
                assert!(steps == 7 || cycles >= shutter * spf as f64 - 1e-9);
                assert!(steps == 1 || cycles / 2.0 < shutter * spf as f64 - 1e-9);
            }
        }
    }
}
