//! Inside the walls: the cells a scene encloses (rays that meet a wall all round, the hollow
//! of closed objects), and the map its people walk, restricted to them.

use glam::DVec2;

use super::WalkableMap;
use crate::scene::mesh::SceneMesh;
use crate::scene::sdf2d::signed_distance;

impl WalkableMap {
    /// The walkable cells inside the walls: those from which at least `min_enclosed` of 32
    /// horizontal rays, evenly around, meet something that blocks walking (a wall, furniture)
    /// before they leave the grid. The ground around a building sees open space on one side
    /// (about half its rays escape); a room sees walls all round but through its doors and
    /// openings. `None` when no cell is enclosed (an open floor).
    pub(crate) fn indoor_cells(&self, min_enclosed: f64) -> Option<Vec<bool>> {
        const RAYS: usize = 32;
        let dirs: Vec<DVec2> = (0..RAYS)
            .map(|k| DVec2::from_angle(std::f64::consts::TAU * k as f64 / RAYS as f64))
            .collect();
        let step = 0.5 * self.cell_m;
        let max_steps = (2.0 * (self.nx + self.ny) as f64) as usize;
        let inside: Vec<bool> = (0..self.nx * self.ny)
            .map(|k| {
                if !self.walkable[k] {
                    return false;
                }
                let start = self.centre(k % self.nx, k / self.nx);
                let hits = dirs
                    .iter()
                    .filter(|&&d| {
                        (1..max_steps).find_map(|s| {
                            match self.cell_of(start + d * (s as f64 * step)) {
                                None => Some(false),
                                Some((i, j)) if self.occupied[j * self.nx + i] => Some(true),
                                Some(_) => None,
                            }
                        }) == Some(true)
                    })
                    .count();
                hits as f64 >= min_enclosed * RAYS as f64
            })
            .collect();
        inside.iter().any(|&i| i).then_some(inside)
    }

    /// The map with every walkable cell outside `region` blocked, as a wall would block it:
    /// signed distances and components are those of the smaller floor. Agents that sense this
    /// map see the ground around a building as blocked and stay inside its walls.
    pub(crate) fn restricted_to(&self, region: &[bool]) -> WalkableMap {
        assert_eq!(
            region.len(),
            self.nx * self.ny,
            "region must have nx·ny cells"
        );
        let mut map = self.clone();
        for k in 0..self.nx * self.ny {
            if map.walkable[k] && !region[k] {
                map.walkable[k] = false;
                map.occupied[k] = true;
            }
        }
        map.sdf_m = signed_distance(&map.walkable, map.nx, map.ny, map.cell_m);
        map.component.fill(0);
        map.label_components();
        map
    }

    /// Cells whose centre, at height `z_of(cell)`, lies inside a closed object: the vertical line
    /// through it crosses that object's surface an odd number of times both above and below
    /// `z`. The hollow inside of a wall modelled as a closed box has no triangle in the body's
    /// height range, and would otherwise be floor; an open surface (a ceiling plane, a floor
    /// slab below) fails one side of the test and encloses nothing.
    pub(super) fn enclosed_cells(
        &self,
        mesh: &SceneMesh,
        z_of: impl Fn(usize) -> f64,
    ) -> Vec<bool> {
        let mut enclosed = vec![false; self.nx * self.ny];
        let mut by_object: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
        for (t, o) in mesh.triangle_object.iter().enumerate() {
            by_object.entry(o.0).or_default().push(t);
        }
        // Rays off the grid's lines and diagonals, so that they miss shared edges and vertices
        // of grid-aligned geometry.
        let jitter = DVec2::new(0.000_618_034, 0.000_414_214) * self.cell_m;
        for tris in by_object.values() {
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for &t in tris {
                for v in mesh.triangle(t) {
                    lo = lo.min(DVec2::new(v.x, v.y));
                    hi = hi.max(DVec2::new(v.x, v.y));
                }
            }
            let (ri, rj) = self.cell_range(lo, hi);
            if ri.is_empty() || rj.is_empty() {
                continue;
            }
            let w = ri.len();
            // Crossing parity above (bit 0) and below (bit 1) per cell of the object's box.
            let mut parity = vec![0u8; w * rj.len()];
            for &t in tris {
                self.for_cells_under(mesh.triangle(t), jitter, |k, tz| {
                    let (i, j) = (k % self.nx, k / self.nx);
                    parity[(j - rj.start) * w + (i - ri.start)] ^= if tz > z_of(k) { 1 } else { 2 };
                });
            }
            for j in rj.clone() {
                for i in ri.clone() {
                    if parity[(j - rj.start) * w + (i - ri.start)] == 3 {
                        enclosed[j * self.nx + i] = true;
                    }
                }
            }
        }
        enclosed
    }
}

/// Share of a cell's rays that must meet something for it to count as inside the walls.
pub(crate) const MIN_ENCLOSED: f64 = 0.75;

/// A scene's map as its people walk it: with `indoors`, when the scene encloses anything
/// ([`WalkableMap::indoor_cells`] at [`MIN_ENCLOSED`]), the region inside the walls where
/// starts and goals are drawn, and the map with the ground around the walls blocked
/// ([`WalkableMap::restricted_to`]: without it agents leave through the outer doors); else the
/// map as it is and no region (anywhere walkable).
pub fn indoor_map(map: WalkableMap, indoors: bool) -> (WalkableMap, Option<Vec<bool>>) {
    match indoors.then(|| map.indoor_cells(MIN_ENCLOSED)).flatten() {
        Some(region) => (map.restricted_to(&region), Some(region)),
        None => (map, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::walkable::tests::room_on_ground;

    #[test]
    fn the_inside_of_walls_is_told_from_the_ground_around() {
        let map = room_on_ground();
        let inside = map.indoor_cells(0.75).expect("the room encloses cells");
        let at = |x: f64, y: f64| {
            let (i, j) = map.cell_of(DVec2::new(x, y)).unwrap();
            inside[j * map.nx + i]
        };
        assert!(at(5.0, 5.0), "room centre");
        assert!(at(3.5, 6.5), "room corner");
        assert!(at(5.0, 3.6), "just inside the door");
        assert!(
            !at(1.0, 1.0) && !at(9.0, 5.0) && !at(5.0, 1.5),
            "ground around"
        );
        assert!(!at(5.0, 3.0), "a wall is not inside");
    }

    #[test]
    fn a_map_restricted_to_the_inside_blocks_the_ground_around() {
        let map = room_on_ground();
        let inside = map.indoor_cells(0.75).unwrap();
        let closed = map.restricted_to(&inside);
        let p = |x: f64, y: f64| DVec2::new(x, y);
        assert!(map.is_walkable_at(p(1.0, 1.0)) && !closed.is_walkable_at(p(1.0, 1.0)));
        assert!(
            closed.occupied[closed.nx + 1],
            "the ground around blocks like a wall"
        );
        assert!(closed.is_walkable_at(p(5.0, 5.0)) && closed.is_walkable_at(p(5.0, 3.6)));
        // The door leads nowhere now: one component, and the room's free space ends at it.
        let components: std::collections::BTreeSet<u32> = closed
            .component
            .iter()
            .copied()
            .filter(|&c| c > 0)
            .collect();
        assert_eq!(components.len(), 1);
        assert!(closed.sdf_at(p(5.0, 3.6)) < map.sdf_at(p(5.0, 3.6)));
        assert_eq!(
            closed.walkable_count(),
            inside.iter().filter(|&&x| x).count()
        );
        // Walkable now: exactly the walkable cells of the region.
        assert!((0..map.nx * map.ny).all(|k| closed.walkable[k] == (map.walkable[k] && inside[k])));
    }

    #[test]
    fn an_open_floor_encloses_nothing() {
        let n = 50;
        let map = WalkableMap::from_walkable(DVec2::ZERO, 0.1, n, n, vec![true; n * n]);
        assert!(map.indoor_cells(0.75).is_none());
    }
}
