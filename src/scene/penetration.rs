//! Body–scene collision terms. Two models, and only the one a scene needs is built:
//! - mesh scenes: 3D SDF at body vertices — count and sum of negative values (paper Eq. 8, 11);
//! - sparse scenes (procedural scenarios): the 2D box test — a body collides when at least 3
//!   non-walkable 0.1 m cells have their centre inside its 2D box (paper Eq. 7).

use glam::DVec2;

use super::sdf3d::SceneSdf;
use super::walkable::WalkableMap;
use crate::math::Vec3;

/// Penetration of a set of body vertices into the scene.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Penetration {
    /// Vertices with negative signed distance.
    pub count: usize,
    /// Sum of the negative signed distances (m, ≤ 0).
    pub sum_negative_m: f64,
}

/// Penetration of `vertices` (world, z up) by SDF lookup.
pub fn sdf_penetration(sdf: &SceneSdf, vertices: &[Vec3]) -> Penetration {
    vertices
        .iter()
        .map(|v| sdf.sample(*v))
        .filter(|d| *d < 0.0)
        .fold(Penetration::default(), |acc, d| Penetration {
            count: acc.count + 1,
            sum_negative_m: acc.sum_negative_m + d,
        })
}

/// Number of non-walkable cells whose centre lies in the oriented 2D box (paper Eq. 7).
pub fn blocked_cells_in_box(
    map: &WalkableMap,
    centre: DVec2,
    half_extents: DVec2,
    yaw_rad: f64,
) -> usize {
    let rot = DVec2::from_angle(yaw_rad);
    let r = half_extents.length();
    let (lo, hi) = (centre - DVec2::splat(r), centre + DVec2::splat(r));
    let to_cell = |p: DVec2| ((p - map.origin) / map.cell_m).floor();
    let (a, b) = (to_cell(lo), to_cell(hi));
    let mut count = 0;
    for j in a.y as i64..=b.y as i64 {
        for i in a.x as i64..=b.x as i64 {
            let c = map.origin + (DVec2::new(i as f64, j as f64) + 0.5) * map.cell_m;
            let along = rot.dot(c - centre);
            let across = rot.perp().dot(c - centre);
            if along.abs() <= half_extents.x && across.abs() <= half_extents.y && map.blocked(i, j)
            {
                count += 1;
            }
        }
    }
    count
}
