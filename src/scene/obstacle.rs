//! Obstacles that move or are not part of the mesh: 2D oriented boxes and circles (other
//! agents' footprints, moving boxes), with straight-line motion.

use glam::DVec2;

/// A 2D obstacle footprint in the world's xy plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Obstacle2 {
    /// Box with centre, half extents (along its own axes) and yaw (rad, about +z).
    Box {
        centre: DVec2,
        half_extents: DVec2,
        yaw_rad: f64,
    },
    /// Disc with centre and radius (m).
    Circle { centre: DVec2, radius_m: f64 },
}

impl Obstacle2 {
    /// The same obstacle moved by `offset`.
    pub(crate) fn translated(self, offset: DVec2) -> Self {
        match self {
            Obstacle2::Box {
                centre,
                half_extents,
                yaw_rad,
            } => Obstacle2::Box {
                centre: centre + offset,
                half_extents,
                yaw_rad,
            },
            Obstacle2::Circle { centre, radius_m } => Obstacle2::Circle {
                centre: centre + offset,
                radius_m,
            },
        }
    }

    /// The same obstacle grown by `margin_m` on every side (a box's corners stay square: the
    /// grown box holds every point within `margin_m` of the box).
    pub(crate) fn grown(self, margin_m: f64) -> Self {
        match self {
            Obstacle2::Box {
                centre,
                half_extents,
                yaw_rad,
            } => Obstacle2::Box {
                centre,
                half_extents: half_extents + DVec2::splat(margin_m),
                yaw_rad,
            },
            Obstacle2::Circle { centre, radius_m } => Obstacle2::Circle {
                centre,
                radius_m: radius_m + margin_m,
            },
        }
    }

    /// The centre of the footprint.
    pub(crate) fn centre(&self) -> DVec2 {
        match *self {
            Obstacle2::Box { centre, .. } | Obstacle2::Circle { centre, .. } => centre,
        }
    }

    /// Whether a point lies inside (boundary included).
    pub(crate) fn contains(&self, p: DVec2) -> bool {
        match *self {
            Obstacle2::Box {
                centre,
                half_extents,
                yaw_rad,
            } => {
                // Farther than the corners: outside, without the rotation's sine and cosine.
                if (p - centre).length_squared() > half_extents.length_squared() {
                    return false;
                }
                let local = DVec2::from_angle(-yaw_rad).rotate(p - centre);
                local.x.abs() <= half_extents.x && local.y.abs() <= half_extents.y
            }
            Obstacle2::Circle { centre, radius_m } => {
                p.distance_squared(centre) <= radius_m * radius_m
            }
        }
    }
}

/// An obstacle as a solid a rendered run draws: a footprint standing on the floor (or moving
/// at constant velocity; zero for a still one), `height_m` tall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObstacleSolid {
    pub motion: MovingObstacle,
    pub height_m: f64,
}

/// An obstacle moving at constant velocity: footprint at time 0, velocity (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MovingObstacle {
    pub at_start: Obstacle2,
    pub velocity_m_per_s: DVec2,
}

impl MovingObstacle {
    /// Footprint at time `t_s`.
    pub(crate) fn at(&self, t_s: f64) -> Obstacle2 {
        self.at_start.translated(self.velocity_m_per_s * t_s)
    }
}
