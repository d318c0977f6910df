//! Measuring a model's field of view from its valid region (see [`super::Fov`]).

use super::{CameraModel, Fov, Pixel};
use crate::math::{Real, Vec3};

/// Horizontal, vertical and diagonal field of view of any model.
pub(crate) fn measure<C: CameraModel>(cam: &C) -> Fov {
    let res = cam.resolution();
    let diagonal = Pixel::new(res.width_px as Real, res.height_px as Real).normalize();
    Fov {
        horizontal_rad: across(cam, Pixel::X),
        vertical_rad: across(cam, Pixel::Y),
        diagonal_rad: across(cam, diagonal),
    }
}

/// Angle between the rays of the farthest valid pixels from the principal point in
/// directions `+dir` and `-dir`.
fn across<C: CameraModel>(cam: &C, dir: Pixel) -> Real {
    match (edge_ray(cam, dir), edge_ray(cam, -dir)) {
        (Some(a), Some(b)) => a.cross(b).length().atan2(a.dot(b)),
        _ => 0.0,
    }
}

/// Ray of the farthest valid pixel on the half-line from the principal point along `dir`:
/// the sensor edge if it is valid, else the boundary found by bisection (60 halvings), which
/// assumes the valid region is star-shaped around the principal point.
fn edge_ray<C: CameraModel>(cam: &C, dir: Pixel) -> Option<Vec3> {
    let res = cam.resolution();
    let pp = cam.principal_point();
    let ray0 = cam.unproject(pp)?;
    // Distance to the sensor edge [-0.5, size - 0.5] along dir.
    let limit = |c: Real, d: Real, size: u32| -> Real {
        if d > 0.0 {
            (size as Real - 0.5 - c) / d
        } else if d < 0.0 {
            (-0.5 - c) / d
        } else {
            Real::INFINITY
        }
    };
    let t_max = limit(pp.x, dir.x, res.width_px).min(limit(pp.y, dir.y, res.height_px));
    if let Some(ray) = cam.unproject(pp + dir * t_max) {
        return Some(ray);
    }
    let (mut lo, mut hi) = (0.0, t_max);
    let mut best = ray0;
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        match cam.unproject(pp + dir * mid) {
            Some(ray) => {
                lo = mid;
                best = ray;
            }
            None => hi = mid,
        }
    }
    Some(best)
}
