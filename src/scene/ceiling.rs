//! Whether a scene has a ceiling, and the one egogen adds when it has none: many scanned and
//! modelled interiors are open at the top, and a head-mounted camera looking up would see the
//! empty world instead of a room.

use super::floor::{detect_floor_z, UP_FACING_MIN_NZ};
use super::mesh::SceneMesh;

/// Horizontal faces above this height over the floor count as ceiling (m).
pub const CEILING_MIN_HEIGHT_M: f64 = 2.0;

/// A ceiling to add: a rectangle over the scene's extent at the top of its walls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AddedCeiling {
    pub z_m: f64,
    pub min_xy: [f64; 2],
    pub max_xy: [f64; 2],
}

/// Areas (m²) of the floor (up-facing faces at the floor height) and of the ceiling
/// (down-facing faces at least [`CEILING_MIN_HEIGHT_M`] above the floor).
pub fn floor_and_ceiling_m2(mesh: &SceneMesh, floor_z: f64) -> (f64, f64) {
    let (mut floor, mut ceiling) = (0.0, 0.0);
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let n = (b - a).cross(c - a);
        let area = 0.5 * n.length();
        if area <= 0.0 {
            continue;
        }
        let nz = n.z / (2.0 * area);
        let z = (a.z + b.z + c.z) / 3.0;
        if nz >= UP_FACING_MIN_NZ && (z - floor_z).abs() < 0.05 {
            floor += area;
        } else if nz <= -UP_FACING_MIN_NZ && z >= floor_z + CEILING_MIN_HEIGHT_M {
            ceiling += area;
        }
    }
    (floor, ceiling)
}

/// The ceiling to add to a scene whose ceiling covers less than half its floor: at the
/// scene's highest point (the top of its walls), over its horizontal extent. `None` when the
/// scene has a ceiling, no floor, or nothing rises [`CEILING_MIN_HEIGHT_M`] above the floor.
pub fn ceiling_to_add(mesh: &SceneMesh) -> Option<AddedCeiling> {
    let floor_z = detect_floor_z(mesh)?;
    let (lo, hi) = mesh.bounds()?;
    let (floor, ceiling) = floor_and_ceiling_m2(mesh, floor_z);
    (floor > 0.0 && ceiling < 0.5 * floor && hi.z >= floor_z + CEILING_MIN_HEIGHT_M).then_some(
        AddedCeiling {
            z_m: hi.z,
            min_xy: [lo.x, lo.y],
            max_xy: [hi.x, hi.y],
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn quad(m: &mut SceneMesh, z: f64, up: bool) {
        let base = m.vertices.len() as u32;
        m.vertices.extend([
            Vec3::new(0.0, 0.0, z),
            Vec3::new(4.0, 0.0, z),
            Vec3::new(4.0, 4.0, z),
            Vec3::new(0.0, 4.0, z),
        ]);
        let (a, b) = if up {
            ([0, 1, 2], [0, 2, 3])
        } else {
            ([0, 2, 1], [0, 3, 2])
        };
        for t in [a, b] {
            m.triangles.push(t.map(|i| base + i));
            m.triangle_object.push(crate::scene::ObjectId(0));
        }
    }

    #[test]
    fn an_open_room_gets_a_ceiling_and_a_closed_one_does_not() {
        let mut open = SceneMesh::default();
        quad(&mut open, 0.0, true);
        // A wall top at 2.5 m (a thin up-facing strip stands in for the walls' height).
        open.vertices.push(Vec3::new(0.0, 0.0, 2.5));
        open.vertices.push(Vec3::new(0.1, 0.0, 2.5));
        open.vertices.push(Vec3::new(0.1, 0.1, 2.5));
        open.triangles.push([4, 5, 6]);
        open.triangle_object.push(crate::scene::ObjectId(0));
        let added = ceiling_to_add(&open).expect("no ceiling: one is added");
        assert_eq!(added.z_m, 2.5);
        assert_eq!((added.min_xy, added.max_xy), ([0.0, 0.0], [4.0, 4.0]));
        let mut closed = open.clone();
        quad(&mut closed, 2.5, false);
        assert_eq!(floor_and_ceiling_m2(&closed, 0.0), (16.0, 16.0));
        assert!(ceiling_to_add(&closed).is_none());
    }
}
