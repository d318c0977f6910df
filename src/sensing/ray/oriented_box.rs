//! Ray against an oriented box (slab method in the box frame).

use glam::DVec2;

use super::{Ray2, RayTarget};

/// A box (closed) with centre, half extents along its axes and yaw.
#[derive(Debug, Clone, Copy)]
pub(crate) struct OrientedBox {
    pub centre: DVec2,
    pub half_extents: DVec2,
    pub yaw_rad: f64,
}

impl RayTarget for OrientedBox {
    fn local_frame(&self) -> (f64, DVec2) {
        (self.yaw_rad, self.centre)
    }

    fn hit_local(&self, ray: Ray2, max_t: f64) -> Option<f64> {
        slab_hit(ray, -self.half_extents, self.half_extents, max_t)
    }
}

/// First `t ∈ [0, max_t]` where the ray meets the closed axis-aligned box `[lo, hi]`.
pub(crate) fn slab_hit(ray: Ray2, lo: DVec2, hi: DVec2, max_t: f64) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, max_t);
    for axis in 0..2 {
        let (o, d, l, h) = (ray.origin[axis], ray.dir[axis], lo[axis], hi[axis]);
        if d == 0.0 {
            if o < l || o > h {
                return None;
            }
            continue;
        }
        let (a, b) = ((l - o) / d, (h - o) / d);
        let (near, far) = if a <= b { (a, b) } else { (b, a) };
        t0 = t0.max(near);
        t1 = t1.min(far);
        if t0 > t1 {
            return None;
        }
    }
    Some(t0)
}
