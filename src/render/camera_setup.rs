//! From egogen cameras (OpenCV frame, pinhole intrinsics in pixels) to Blender camera
//! parameters (matrix_world in Blender's camera axes, lens in mm, shift).

use glam::DQuat;

use crate::math::{Affine3, Mat3, Vec3};
use crate::render::protocol::PoseKey;

/// Blender's camera axes expressed in the OpenCV camera frame: x right, y up, z backwards
/// (`opencv_from_blender = diag(1, −1, −1)`).
pub(crate) fn world_from_blender_cam(world_from_cam_opencv: Affine3) -> Affine3 {
    let flip = Mat3::from_diagonal(Vec3::new(1.0, -1.0, -1.0));
    Affine3 {
        matrix3: world_from_cam_opencv.matrix3 * flip,
        translation: world_from_cam_opencv.translation,
    }
}

/// Blender lens for a pinhole camera with square pixels: (focal_mm, sensor_width_mm, shift_x,
/// shift_y) with the sensor fitted horizontally. Shifts are in units of the larger image side,
/// as Blender defines them; +y shift moves the image content down, so the principal point's
/// vertical offset (pixels, y down) changes sign.
pub(crate) fn blender_lens(
    width_px: u32,
    height_px: u32,
    f_px: f64,
    cx: f64,
    cy: f64,
) -> (f64, f64, f64, f64) {
    let sensor = 36.0;
    let (w, h) = (width_px as f64, height_px as f64);
    let side = w.max(h);
    let focal_mm = f_px * sensor / w;
    let shift_x = -(cx - w / 2.0) / side;
    let shift_y = (cy - h / 2.0) / side;
    (focal_mm, sensor, shift_x, shift_y)
}

/// Pose keys for Blender from OpenCV `world_from_cam` poses at (sub)frames, quaternion signs
/// kept continuous so Blender's linear interpolation takes the short way.
pub(crate) fn camera_keys(poses: &[(f64, Affine3)]) -> Vec<PoseKey> {
    let mut keys: Vec<PoseKey> = Vec::with_capacity(poses.len());
    let mut last: Option<DQuat> = None;
    for &(frame, world_from_cam) in poses {
        let blender = world_from_blender_cam(world_from_cam);
        let mut q = DQuat::from_mat3(&blender.matrix3).normalize();
        if last.is_some_and(|l| l.dot(q) < 0.0) {
            q = -q;
        }
        last = Some(q);
        keys.push(PoseKey {
            frame,
            location: blender.translation.to_array(),
            rotation_wxyz: [q.w, q.x, q.y, q.z],
        });
    }
    keys
}
