//! Whether a scene has a ceiling, and the one egogen adds when it has none: many scanned and
//! modelled interiors are open at the top, and a head-mounted camera looking up would see the
//! empty world instead of a room.

use super::floor::{detect_floor_z, UP_FACING_MIN_NZ};
use super::mesh::SceneMesh;

/// Horizontal faces above this height over the floor count as ceiling (m).
pub(crate) const CEILING_MIN_HEIGHT_M: f64 = 2.0;

/// A ceiling to add: a rectangle over the scene's extent at the top of its walls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AddedCeiling {
    pub z_m: f64,
    pub min_xy: [f64; 2],
    pub max_xy: [f64; 2],
}

/// Areas (m²) of the floor (up-facing faces at the floor height) and of the ceiling
/// (down-facing faces at least [`CEILING_MIN_HEIGHT_M`] above the floor).
pub(crate) fn floor_and_ceiling_m2(mesh: &SceneMesh, floor_z: f64) -> (f64, f64) {
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

/// Faces whose normal's vertical part is below this are walls (near-vertical).
const WALL_MAX_NZ: f64 = 0.3;

/// The height of the walls' tops: of the near-vertical faces that reach at least
/// [`CEILING_MIN_HEIGHT_M`] above the floor, the top height (in 1 cm bins) at which the
/// largest area of them ends — walls, not a stair, a lamp or a tall shelf rising above them;
/// `highest` (the scene's top) when there are none.
pub(crate) fn wall_top_z(mesh: &SceneMesh, floor_z: f64, highest: f64) -> f64 {
    let mut tops: std::collections::BTreeMap<i64, (f64, f64)> = Default::default();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let n = (b - a).cross(c - a);
        let area = 0.5 * n.length();
        if !(area > 0.0) || (n.z / (2.0 * area)).abs() >= WALL_MAX_NZ {
            continue;
        }
        let top = a.z.max(b.z).max(c.z);
        if top >= floor_z + CEILING_MIN_HEIGHT_M {
            let bin = tops
                .entry((top * 100.0).round() as i64)
                .or_insert((0.0, top));
            bin.0 += area;
            bin.1 = bin.1.max(top);
        }
    }
    tops.values()
        .max_by(|p, q| p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)))
        .map_or(highest, |&(_, z)| z)
}

/// The ceiling to add to a scene whose ceiling covers less than half its floor: at the top
/// of its walls ([`wall_top_z`]), over its horizontal extent. `None` when the scene has a
/// ceiling, no floor, or nothing rises [`CEILING_MIN_HEIGHT_M`] above the floor.
pub(crate) fn ceiling_to_add(mesh: &SceneMesh) -> Option<AddedCeiling> {
    let floor_z = detect_floor_z(mesh)?;
    let (lo, hi) = mesh.bounds()?;
    let (floor, ceiling) = floor_and_ceiling_m2(mesh, floor_z);
    (floor > 0.0 && ceiling < 0.5 * floor && hi.z >= floor_z + CEILING_MIN_HEIGHT_M).then(|| {
        AddedCeiling {
            z_m: wall_top_z(mesh, floor_z, hi.z),
            min_xy: [lo.x, lo.y],
            max_xy: [hi.x, hi.y],
        }
    })
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

    #[test]
    fn the_ceiling_closes_the_walls_not_a_stair_rising_above_them() {
        // A 4 × 4 m room of 2.5 m walls and a thin stair post to 3.6 m.
        let mut room = SceneMesh::default();
        quad(&mut room, 0.0, true);
        for (x0, y0, x1, y1) in [(0.0f64, 0.0f64, 4.0f64, 0.0f64), (4.0, 0.0, 4.0, 4.0)] {
            room.add_box(
                "wall",
                Vec3::new(x0.min(x1) - 0.05, y0.min(y1) - 0.05, 0.0),
                Vec3::new(x0.max(x1) + 0.05, y0.max(y1) + 0.05, 2.5),
            );
        }
        room.add_box(
            "stair_post",
            Vec3::new(2.0, 2.0, 0.0),
            Vec3::new(2.1, 2.1, 3.6),
        );
        let added = ceiling_to_add(&room).expect("open at the top");
        assert_eq!(added.z_m, 2.5);
        // Walls of the shipped apartment end at its highest point: its ceiling is unchanged.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let apartment = crate::scene::load_scene(
            &root.join("assets/scenes/apartment.glb"),
            Default::default(),
        )
        .unwrap();
        let (_, hi) = apartment.bounds().unwrap();
        assert_eq!(ceiling_to_add(&apartment).unwrap().z_m, hi.z);
    }
}
