//! Ray against a disc.

use glam::DVec2;

use super::{Ray2, RayTarget};

/// A disc (closed).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Circle {
    pub centre: DVec2,
    pub radius_m: f64,
}

impl RayTarget for Circle {
    fn local_frame(&self) -> (f64, DVec2) {
        (0.0, self.centre)
    }

    fn hit_local(&self, ray: Ray2, max_t: f64) -> Option<f64> {
        let r2 = self.radius_m * self.radius_m;
        let c = ray.origin.length_squared() - r2;
        if c <= 0.0 {
            return Some(0.0);
        }
        let b = ray.origin.dot(ray.dir);
        if b >= 0.0 {
            return None; // outside and pointing away
        }
        // Distance² from the centre to the line, computed without cancellation.
        let closest = ray.origin - ray.dir * b;
        let h = r2 - closest.length_squared();
        if h < 0.0 {
            return None;
        }
        // Smaller root, stable form: t = c / (−b + √h).
        let t = c / (-b + h.sqrt());
        (t <= max_t).then_some(t)
    }
}
