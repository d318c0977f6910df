//! 2D ray casting: a ray type, the obstacle trait (local-space hit, world hit derived), and one
//! file per target: `grid` (the DDA through the walkable map's cells, for static geometry),
//! `circle` (a disc), `oriented_box` (an oriented box, by the slab method).

pub(crate) mod circle;
pub(crate) mod grid;
pub(crate) mod oriented_box;

use glam::DVec2;

use crate::scene::Obstacle2;

/// A 2D ray: `origin + t·dir`, `dir` of unit length (callers normalise), `t ≥ 0` in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Ray2 {
    pub origin: DVec2,
    pub dir: DVec2,
}

/// Something a ray can hit, described in its own local frame.
pub(crate) trait RayTarget {
    /// `world_from_local` rotation angle (rad) and translation of the target's frame.
    fn local_frame(&self) -> (f64, DVec2);
    /// First `t` in `[0, max_t]` where the local ray meets the closed shape; `Some(0)` when the
    /// origin is inside.
    fn hit_local(&self, ray: Ray2, max_t: f64) -> Option<f64>;
    /// The same, for a world-space ray (distances are preserved by the rigid change of frame).
    fn hit_in_world(&self, ray: Ray2, max_t: f64) -> Option<f64> {
        let (angle, t) = self.local_frame();
        let inv = DVec2::from_angle(-angle);
        self.hit_local(
            Ray2 {
                origin: inv.rotate(ray.origin - t),
                dir: inv.rotate(ray.dir),
            },
            max_t,
        )
    }
}

/// First hit of a ray on a 2D obstacle footprint, within `max_t`.
pub(crate) fn hit_obstacle(obstacle: &Obstacle2, ray: Ray2, max_t: f64) -> Option<f64> {
    match *obstacle {
        Obstacle2::Box {
            centre,
            half_extents,
            yaw_rad,
        } => oriented_box::OrientedBox {
            centre,
            half_extents,
            yaw_rad,
        }
        .hit_in_world(ray, max_t),
        Obstacle2::Circle { centre, radius_m } => {
            circle::Circle { centre, radius_m }.hit_in_world(ray, max_t)
        }
    }
}
