//! Seats found in a scene: upward-facing surfaces at sitting height, flat and large enough to
//! sit on, with room above them and free walkable floor in front — from the geometry alone,
//! then confirmed or refused by what the file calls the object (`chair`, `sofa`, `bed` … are
//! seats; `table`, `shelf`, `cabinet` … are not). Each seat is a place to sit: where the pelvis
//! goes, which way the seated person faces, the walkable point in front where they stand
//! before sitting down. A long sofa or a bed gives several places, spaced apart. A chair
//! pulled up to a table, with no free floor in front of it, gives a place on the chair pulled
//! out (`chair_pull`).

use super::chair_pull::{chair_facing, pulled_out_chairs, ChairNeeds, Pull, PulledChair};
use super::object_class::ObjectClass;
use glam::DVec2;
use std::f64::consts::FRAC_1_SQRT_2;

use super::floor::UP_FACING_MIN_NZ;
use super::mesh::{ObjectId, SceneMesh};
use super::walkable::{clip_z, convex_overlaps_rect, WalkableMap};

/// Knobs of the seat finder (docs/ACTIVITIES.md "Seats").
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SeatSettings {
    /// Lowest and highest seat surface over the floor (m).
    pub height_m: (f64, f64),
    /// Free space a seat needs above its surface (m): shelves and the inside of cabinets have
    /// a board above them.
    pub headroom_m: f64,
    /// How far a place to sit must lie inside the surface's edge on every side (m): half the
    /// width of a seat.
    pub min_half_width_m: f64,
    /// Farthest a sitting pelvis sits behind the seat's front edge (m).
    pub max_depth_m: f64,
    /// Where the person stands before sitting down: this far in front of the front edge (m),
    /// on walkable floor.
    pub stand_off_m: f64,
    /// Free floor round the standing point (m to the nearest non-walkable cell).
    pub stand_clearance_m: f64,
    /// Places on one surface (a sofa, a bed) lie at least this far apart (m).
    pub spacing_m: f64,
}

impl Default for SeatSettings {
    fn default() -> Self {
        Self {
            height_m: (0.35, 0.75),
            headroom_m: 0.5,
            min_half_width_m: 0.12,
            max_depth_m: 0.45,
            stand_off_m: 0.35,
            stand_clearance_m: 0.2,
            spacing_m: 0.6,
        }
    }
}

/// What the file says an object is, as far as sitting goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum SeatNaming {
    /// Its name or label names a seat (`chair`, `sofa`, `bed` …).
    Named,
    /// Its name says nothing either way: a seat by its shape alone.
    Shape,
}

/// Whether an object's name (else its label) makes it a seat (`Some(true)`: a chair, a sofa,
/// a bed …), something else one does not sit on (`Some(false)`: a table, a shelf, a floor …;
/// [`ObjectClass`]), or says nothing either way.
pub(crate) fn seat_by_name(name: &str, label: Option<&str>) -> Option<bool> {
    ObjectClass::named(name, label).map(ObjectClass::is_seat)
}

/// One place to sit.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct Seat {
    /// Where the seated pelvis goes (horizontal, m).
    pub pelvis_xy: [f64; 2],
    /// Which way a seated person faces (rad from +x): towards the free floor in front.
    pub facing_rad: f64,
    /// Height of the seat surface over the floor under the standing point (m).
    pub height_m: f64,
    /// World height of the seat surface (m).
    pub surface_z_m: f64,
    /// Walkable point in front of the seat where a person stands before sitting down.
    pub stand_xy: [f64; 2],
    /// How far the pelvis sits behind the seat's front edge (m).
    pub depth_m: f64,
    /// Something higher (a backrest, a wall) right behind the place.
    pub backed: bool,
    /// The object whose surface it is, and its name.
    #[serde(skip)]
    pub object: ObjectId,
    pub object_name: String,
    pub naming: SeatNaming,
    /// Map cells of the seat's surface (what a seated body may touch beside the floor), in
    /// ascending order.
    #[serde(skip)]
    pub cells: Vec<usize>,
    /// For a chair pulled up to a table or desk: how it is pulled out to sit on
    /// ([`super::chair_pull`]); the place, surface and cells are the pulled chair's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pull: Option<Pull>,
    /// For a chair pulled out: the place on it pulled [`super::chair_pull::MORE_KNEE_ROOM_M`]
    /// or more farther, where that works too (for a body too large for the first).
    #[serde(skip)]
    pub longer: Option<Box<Seat>>,
}

impl Seat {
    pub(crate) fn pelvis(&self) -> DVec2 {
        DVec2::from_array(self.pelvis_xy)
    }

    pub(crate) fn stand(&self) -> DVec2 {
        DVec2::from_array(self.stand_xy)
    }
}

impl SeatSettings {
    /// What a chair needs of its place, for [`super::chair_pull`].
    fn chair_needs(&self) -> ChairNeeds {
        ChairNeeds {
            height_m: self.height_m,
            headroom_m: self.headroom_m,
            min_half_width_m: self.min_half_width_m,
            stand_clearance_m: self.stand_clearance_m,
        }
    }
}

/// Directions a seat's front is looked for in.
const DIRECTIONS: usize = 16;

/// The places to sit in `mesh` over its walkable `map` (see the module docs), in a
/// deterministic order (by object, then position).
pub(crate) fn find_seats(
    mesh: &SceneMesh,
    map: &WalkableMap,
    settings: &SeatSettings,
) -> Vec<Seat> {
    let (mut top, top_object) = sitting_height_tops(mesh, map, settings);
    let high = clear_room_above(mesh, map, settings, &mut top);
    let refused: Vec<bool> = mesh
        .objects
        .iter()
        .map(|o| seat_by_name(&o.name, o.label.as_deref()) == Some(false))
        .collect();
    for k in 0..top.len() {
        let refused_object = (top_object[k] as usize)
            .checked_sub(1)
            .is_none_or(|o| refused.get(o).copied().unwrap_or(true));
        if refused_object {
            top[k] = f64::NAN;
        }
    }
    let (region, regions) = surfaces(map, &top, &top_object);
    // Places on each surface: inside its edge, the front edge near, free floor beyond it.
    let cell = map.cell_m;
    let in_region = |p: DVec2, id: usize| {
        map.cell_of(p)
            .is_some_and(|(i, j)| region[j * map.nx + i] == id)
    };
    let walkable_at = |p: DVec2| {
        map.cell_of(p)
            .is_some_and(|(i, j)| map.walkable[j * map.nx + i])
    };
    // Distance along `d` from `p` to leaving the surface, marched in half cells.
    let edge = |p: DVec2, d: DVec2, id: usize, most: f64| {
        let mut s = 0.0;
        while s <= most {
            if !in_region(p + d * s, id) {
                return Some(s);
            }
            s += 0.5 * cell;
        }
        None
    };
    let mut seats = Vec::new();
    for (r, cells) in regions.iter().enumerate() {
        let id = r + 1;
        let mut spots: Vec<(bool, f64, f64, usize, DVec2, f64)> = Vec::new();
        for &k in cells {
            let c = map.centre(k % map.nx, k / map.nx);
            // Inside the edge by half a seat's width on every side.
            let inside = (0..DIRECTIONS).all(|a| {
                let d = DVec2::from_angle(std::f64::consts::TAU * a as f64 / DIRECTIONS as f64);
                in_region(c + d * settings.min_half_width_m, id)
            });
            if !inside {
                continue;
            }
            for a in 0..DIRECTIONS {
                let d = DVec2::from_angle(std::f64::consts::TAU * a as f64 / DIRECTIONS as f64);
                let Some(e) = edge(c, d, id, settings.max_depth_m) else {
                    continue;
                };
                let stand = c + d * (e + settings.stand_off_m);
                let room = map.cell_of(stand).is_some_and(|(i, j)| {
                    let m = j * map.nx + i;
                    map.walkable[m] && map.sdf_m[m] >= settings.stand_clearance_m
                });
                // From the edge to the standing point: walkable floor, or nothing higher
                // than the seat's own front (its frame, a lip).
                let lip = top[k] + 0.1;
                let steps = (settings.stand_off_m / (0.5 * cell)).ceil() as usize;
                let clear = (0..=steps).all(|s| {
                    let q = c + d * (e + settings.stand_off_m * s as f64 / steps as f64);
                    walkable_at(q)
                        || map
                            .cell_of(q)
                            .is_some_and(|(i, j)| high[j * map.nx + i] <= lip)
                });
                if !(room && clear) {
                    continue;
                }
                let back = edge(c, -d, id, 2.0).unwrap_or(2.0);
                let behind = c - d * (back + 0.5 * cell);
                let backed = map
                    .cell_of(behind)
                    .is_some_and(|(i, j)| high[j * map.nx + i] > top[k] + 0.15);
                let depth_miss = (e - 0.5 * settings.max_depth_m).abs();
                spots.push((backed, depth_miss, e, k, d, d.y.atan2(d.x)));
            }
        }
        // Backed places first, then those at a natural depth; then spaced apart.
        spots.sort_by(|a, b| {
            b.0.cmp(&a.0)
                .then(a.1.total_cmp(&b.1))
                .then(a.3.cmp(&b.3))
                .then(a.5.total_cmp(&b.5))
        });
        let mut chosen: Vec<DVec2> = Vec::new();
        let object = top_object[cells[0]];
        for (backed, _, e, k, d, facing) in spots {
            let c = map.centre(k % map.nx, k / map.nx);
            if chosen.iter().any(|p| p.distance(c) < settings.spacing_m) {
                continue;
            }
            chosen.push(c);
            let Some(o) = (object as usize)
                .checked_sub(1)
                .and_then(|o| mesh.objects.get(o))
            else {
                continue;
            };
            let stand = c + d * (e + settings.stand_off_m);
            let floor = map.floor_under(stand);
            seats.push(Seat {
                pelvis_xy: c.to_array(),
                facing_rad: facing,
                height_m: top[k] - floor,
                surface_z_m: top[k],
                stand_xy: stand.to_array(),
                depth_m: e,
                backed,
                object: o.id,
                object_name: o.name.clone(),
                naming: match seat_by_name(&o.name, o.label.as_deref()) {
                    Some(true) => SeatNaming::Named,
                    _ => SeatNaming::Shape,
                },
                cells: {
                    let mut sorted = cells.clone();
                    sorted.sort_unstable();
                    sorted
                },
                pull: None,
                longer: None,
            });
        }
    }
    with_chairs_by_their_backs(mesh, map, settings, seats)
}

/// `seats` less the places on chairs facing elsewhere than away from their backrest (the free
/// floor at the side of a chair pulled up to a table is no front), with a place on each chair
/// pulled out from its table that has none ([`pulled_out_chairs`]).
fn with_chairs_by_their_backs(
    mesh: &SceneMesh,
    map: &WalkableMap,
    settings: &SeatSettings,
    mut seats: Vec<Seat>,
) -> Vec<Seat> {
    let mut facing_of = std::collections::HashMap::new();
    seats.retain(|s| {
        let facing = *facing_of
            .entry(s.object_name.clone())
            .or_insert_with(|| chair_facing(mesh, map, &settings.chair_needs(), &s.object_name));
        facing.is_none_or(|f| f.dot(DVec2::from_angle(s.facing_rad)) >= FRAC_1_SQRT_2)
    });
    let found: Vec<ObjectId> = seats.iter().map(|s| s.object).collect();
    for c in pulled_out_chairs(mesh, map, &settings.chair_needs(), &found) {
        seats.push(pulled_seat(mesh, map, c));
    }
    seats
}

/// The place to sit on a chair pulled out, with its longer pull's where there is one.
fn pulled_seat(mesh: &SceneMesh, map: &WalkableMap, c: PulledChair) -> Seat {
    let o = &mesh.objects[c.object.0 as usize - 1];
    Seat {
        pelvis_xy: c.pelvis.to_array(),
        facing_rad: c.facing.y.atan2(c.facing.x),
        height_m: c.top_z - map.floor_under(c.stand),
        surface_z_m: c.top_z,
        stand_xy: c.stand.to_array(),
        depth_m: c.depth_m,
        backed: true,
        object: o.id,
        object_name: o.name.clone(),
        naming: match seat_by_name(&o.name, o.label.as_deref()) {
            Some(true) => SeatNaming::Named,
            _ => SeatNaming::Shape,
        },
        cells: c.cells,
        pull: Some(c.pull),
        longer: c.longer.map(|l| Box::new(pulled_seat(mesh, map, *l))),
    }
}

/// The highest upward-facing surface at sitting height over each cell (world z; NaN where
/// none), and its object.
fn sitting_height_tops(
    mesh: &SceneMesh,
    map: &WalkableMap,
    settings: &SeatSettings,
) -> (Vec<f64>, Vec<u32>) {
    let n = map.nx * map.ny;
    let floor_at = |k: usize| map.cell_floor_m(k);
    let mut top = vec![f64::NAN; n];
    let mut top_object = vec![0u32; n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let obj = mesh.triangle_object[t];
        let v = tri.map(|i| mesh.vertices[i as usize]);
        let nrm = (v[1] - v[0]).cross(v[2] - v[0]);
        let len = nrm.length();
        if len <= 0.0 || nrm.z / len < UP_FACING_MIN_NZ {
            continue;
        }
        map.for_cells_under(v, DVec2::ZERO, |k, z| {
            let h = z - floor_at(k);
            if h >= settings.height_m.0 && h <= settings.height_m.1 && !(z <= top[k]) {
                top[k] = z;
                top_object[k] = obj.0;
            }
        });
    }
    (top, top_object)
}

/// Clears the tops without room above them (no geometry between the surface + 15 cm — a
/// cushion puffing up is the seat's own — and + headroom over the cell); returns the highest
/// geometry up to 1.2 m over each cell (what stands at a seat's edges).
fn clear_room_above(
    mesh: &SceneMesh,
    map: &WalkableMap,
    settings: &SeatSettings,
    top: &mut [f64],
) -> Vec<f64> {
    let n = map.nx * map.ny;
    // and the highest geometry up to 1.2 m over each cell (what stands at a seat's edges).
    let lo_gap = 0.15;
    let mut high = vec![f64::NEG_INFINITY; n];
    let reach = map.floor_z_m + 1.2;
    for tri in &mesh.triangles {
        let v = tri.map(|i| mesh.vertices[i as usize]);
        let (zmin, zmax) = (
            v[0].z.min(v[1].z).min(v[2].z),
            v[0].z.max(v[1].z).max(v[2].z),
        );
        let lo = DVec2::new(
            v[0].x.min(v[1].x).min(v[2].x),
            v[0].y.min(v[1].y).min(v[2].y),
        );
        let hi = DVec2::new(
            v[0].x.max(v[1].x).max(v[2].x),
            v[0].y.max(v[1].y).max(v[2].y),
        );
        let low_part = clip_z(&clip_z(&v, map.floor_z_m + 0.1, true), reach, false);
        let low_xy: Vec<DVec2> = low_part.iter().map(|q| DVec2::new(q.x, q.y)).collect();
        let low_top = low_part
            .iter()
            .map(|q| q.z)
            .fold(f64::NEG_INFINITY, f64::max);
        let (ri, rj) = map.cell_range(lo, hi);
        for j in rj {
            for i in ri.clone() {
                let k = j * map.nx + i;
                let c_lo = map.origin + DVec2::new(i as f64, j as f64) * map.cell_m;
                let c_hi = c_lo + DVec2::splat(map.cell_m);
                if low_top > high[k] && convex_overlaps_rect(&low_xy, c_lo, c_hi, 0.0, true) {
                    high[k] = low_top;
                }
                let z = top[k];
                if z.is_nan() || zmax < z + lo_gap || zmin > z + settings.headroom_m {
                    continue;
                }
                let part = clip_z(
                    &clip_z(&v, z + lo_gap, true),
                    z + settings.headroom_m,
                    false,
                );
                if part.is_empty() {
                    continue;
                }
                let p: Vec<DVec2> = part.iter().map(|q| DVec2::new(q.x, q.y)).collect();
                if convex_overlaps_rect(&p, c_lo, c_hi, 0.0, true) {
                    top[k] = f64::NAN;
                }
            }
        }
    }
    high
}

/// Surfaces: 4-connected cells of one object whose tops differ by under 5 cm — each cell's
/// surface (1-based; 0: none) and each surface's cells.
fn surfaces(map: &WalkableMap, top: &[f64], top_object: &[u32]) -> (Vec<usize>, Vec<Vec<usize>>) {
    let n = map.nx * map.ny;
    let mut region = vec![0usize; n];
    let mut regions: Vec<Vec<usize>> = Vec::new();
    for start in 0..n {
        if top[start].is_nan() || region[start] != 0 {
            continue;
        }
        regions.push(Vec::new());
        let id = regions.len();
        region[start] = id;
        let mut stack = vec![start];
        while let Some(k) = stack.pop() {
            regions[id - 1].push(k);
            let (i, j) = ((k % map.nx) as i64, (k / map.nx) as i64);
            for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let (a, b) = (i + di, j + dj);
                if a < 0 || b < 0 || a >= map.nx as i64 || b >= map.ny as i64 {
                    continue;
                }
                let m = b as usize * map.nx + a as usize;
                if region[m] == 0
                    && !top[m].is_nan()
                    && top_object[m] == top_object[k]
                    && (top[m] - top[k]).abs() < 0.05
                {
                    region[m] = id;
                    stack.push(m);
                }
            }
        }
    }
    (region, regions)
}

/// Small scenes with seats, for tests.
#[cfg(test)]
pub(crate) mod test_scenes {
    use super::*;
    use crate::math::Vec3;

    /// A 6 × 6 m floor with a seat (`name`, its top at `seat_h`, spanning `lo`..`hi`) and
    /// a backrest 5 cm deep and `back_h` high along its −y side.
    pub(crate) fn floor_with_seat(
        name: &str,
        lo: DVec2,
        hi: DVec2,
        seat_h: f64,
        back_h: f64,
    ) -> SceneMesh {
        let mut m = SceneMesh::default();
        m.add_box(
            "floor",
            Vec3::new(-3.0, -3.0, -0.1),
            Vec3::new(3.0, 3.0, 0.0),
        );
        m.add_box(
            name,
            Vec3::new(lo.x, lo.y, 0.0),
            Vec3::new(hi.x, hi.y, seat_h),
        );
        m.add_box(
            name,
            Vec3::new(lo.x, lo.y, seat_h),
            Vec3::new(hi.x, lo.y + 0.05, seat_h + back_h),
        );
        m
    }

    /// A chair (seat at 0.45 m, backrest on its −y side, facing +y) whose front reaches
    /// `under` m under a table 0.8 m deep, 1.2 m wide, 0.75 m high, at `at`.
    pub(crate) fn chair_at_table(at: DVec2, under: f64) -> SceneMesh {
        let mut m = floor_with_seat("chair", at - 0.22, at + 0.22, 0.45, 0.45);
        let edge = at.y + 0.22 - under;
        m.add_box(
            "table",
            Vec3::new(at.x - 0.6, edge, 0.72),
            Vec3::new(at.x + 0.6, edge + 0.8, 0.75),
        );
        for (x, y) in [(-0.55, 0.05), (0.55, 0.05), (-0.55, 0.75), (0.55, 0.75)] {
            m.add_box(
                "table",
                Vec3::new(at.x + x - 0.03, edge + y - 0.03, 0.0),
                Vec3::new(at.x + x + 0.03, edge + y + 0.03, 0.72),
            );
        }
        m
    }

    /// A chair 0.5 m square (seat at `seat_h`, a backrest on its −y side) at (x, y).
    pub(crate) fn room_with_chair(seat_h: f64, x: f64, y: f64, name: &str) -> SceneMesh {
        let c = DVec2::new(x, y);
        floor_with_seat(name, c - 0.25, c + 0.25, seat_h, 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::test_scenes::{chair_at_table, floor_with_seat, room_with_chair};
    use super::*;
    use crate::math::Vec3;
    use crate::scene::walkable::WalkableSettings;

    fn map(mesh: &SceneMesh) -> WalkableMap {
        WalkableMap::build(mesh, WalkableSettings::default()).unwrap()
    }

    #[test]
    fn a_chair_is_a_seat_facing_away_from_its_back() {
        for seat_h in [0.36, 0.45, 0.74] {
            let mesh = room_with_chair(seat_h, 0.52, -0.33, "chair");
            let seats = find_seats(&mesh, &map(&mesh), &SeatSettings::default());
            assert_eq!(seats.len(), 1, "seat at {seat_h} m: {seats:?}");
            let s = &seats[0];
            assert!((s.height_m - seat_h).abs() < 1e-9);
            assert!(s.backed);
            assert_eq!(s.naming, SeatNaming::Named);
            // Faces +y, away from the backrest.
            assert!(
                (s.facing_rad - std::f64::consts::FRAC_PI_2).abs() < 0.4,
                "{s:?}"
            );
            assert!(s.stand()[1] > -0.33 + 0.25, "{s:?}");
            assert!((s.pelvis() - DVec2::new(0.52, -0.33)).length() < 0.25);
        }
    }

    #[test]
    fn too_low_too_high_named_otherwise_or_covered_is_no_seat() {
        for (seat_h, name) in [(0.3, "chair"), (0.8, "chair"), (0.45, "low table")] {
            let mesh = room_with_chair(seat_h, 0.0, 0.0, name);
            assert!(find_seats(&mesh, &map(&mesh), &SeatSettings::default()).is_empty());
        }
        // A shelf board 0.4 m above the surface.
        let mut mesh = room_with_chair(0.45, 0.0, 0.0, "box");
        mesh.add_box(
            "box",
            Vec3::new(-0.25, -0.25, 0.85),
            Vec3::new(0.25, 0.25, 0.87),
        );
        assert!(find_seats(&mesh, &map(&mesh), &SeatSettings::default()).is_empty());
        // Without the board, an unnamed box is a seat by its shape.
        let mesh = room_with_chair(0.45, 0.0, 0.0, "box");
        let seats = find_seats(&mesh, &map(&mesh), &SeatSettings::default());
        assert_eq!(seats.len(), 1);
        assert_eq!(seats[0].naming, SeatNaming::Shape);
    }

    #[test]
    fn a_chair_against_the_map_edge_has_no_front_there() {
        // The backrest against the room's −y edge: the only front is +y, into the room.
        let mesh = room_with_chair(0.45, 0.0, -2.7, "chair");
        let seats = find_seats(&mesh, &map(&mesh), &SeatSettings::default());
        assert_eq!(seats.len(), 1);
        assert!(seats[0].stand()[1] > -2.7);
        // Facing a wall 0.3 m away: nowhere to stand.
        let mut mesh = room_with_chair(0.45, 0.0, 0.0, "chair");
        mesh.add_box("wall", Vec3::new(-1.0, 0.45, 0.0), Vec3::new(1.0, 0.6, 2.5));
        mesh.add_box(
            "wall",
            Vec3::new(-0.45, -0.5, 0.0),
            Vec3::new(-0.3, 0.5, 2.5),
        );
        mesh.add_box("wall", Vec3::new(0.3, -0.5, 0.0), Vec3::new(0.45, 0.5, 2.5));
        assert!(find_seats(&mesh, &map(&mesh), &SeatSettings::default()).is_empty());
    }

    #[test]
    fn a_seat_named_in_another_language_is_a_seat_by_its_shape() {
        for name in ["Stuhl_3", "椅子", "chaise.001", "кресло"] {
            let mesh = room_with_chair(0.45, 0.3, 0.2, name);
            let seats = find_seats(&mesh, &map(&mesh), &SeatSettings::default());
            assert_eq!(seats.len(), 1, "{name}: {seats:?}");
            assert_eq!(seats[0].object_name, name);
            assert_eq!(seats[0].naming, SeatNaming::Shape, "{name}");
            assert!(seats[0].backed, "{name}");
        }
        // A refusing word in English still refuses, whatever else the name holds.
        let mesh = room_with_chair(0.45, 0.3, 0.2, "Regal shelf");
        assert!(find_seats(&mesh, &map(&mesh), &SeatSettings::default()).is_empty());
    }

    #[test]
    fn a_chair_under_a_table_is_pulled_out_away_from_it_far_from_the_origin_too() {
        let seats = |mesh: &SceneMesh| find_seats(mesh, &map(mesh), &SeatSettings::default());
        for at in [DVec2::new(0.1, -0.3), DVec2::new(-1.7, 1.2)] {
            // Its seat half and fully under the table top.
            for under in [0.15, 0.3, 0.44] {
                let mesh = chair_at_table(at, under);
                let map = map(&mesh);
                let found = seats(&mesh);
                assert_eq!(found.len(), 1, "{at} {under}: {found:?}");
                let s = &found[0];
                let pull = s.pull.as_ref().expect("pulled out");
                // Faces the table (+y), pulled back (−y) far enough to sit in front of it.
                assert!(
                    (s.facing_rad - std::f64::consts::FRAC_PI_2).abs() < 0.2,
                    "{s:?}"
                );
                assert!(
                    pull.offset_m[1] < -0.15 && pull.offset_m[0].abs() < 0.05,
                    "{s:?}"
                );
                assert!((s.height_m - 0.45).abs() < 1e-6);
                // The walk ends on walkable floor with room; the step in crosses free floor.
                assert!(map.is_walkable_at(s.stand()), "{s:?}");
                let feet = s.pelvis() + DVec2::Y * crate::scene::chair_pull::STAND_IN_FRONT_M;
                assert!(pull.frees(&map, feet), "{s:?}");
                assert!(s.stand().distance(feet) <= crate::scene::chair_pull::MAX_STEP_IN_M + 1e-9);
                // The pulled seat is clear of the table top.
                assert!(s.pelvis().y < at.y + 0.22 - under - 0.1, "{s:?}");
                // Its longer pull (for knees that would enter the table) is the same chair
                // pulled at least MORE_KNEE_ROOM_M farther the same way, a place of its own
                // with free floor to step in, and has no longer pull of its own.
                let longer = s.longer.as_deref().expect("a longer pull");
                let more = longer.pull.as_ref().expect("pulled out");
                let length = |p: &Pull| DVec2::from_array(p.offset_m).length();
                let extra = length(more) - length(pull);
                assert!(
                    extra >= crate::scene::chair_pull::MORE_KNEE_ROOM_M - 1e-9
                        && more.offset_m[1] < pull.offset_m[1]
                        && more.offset_m[0].abs() < 0.05,
                    "{s:?}"
                );
                assert!((longer.pelvis() - s.pelvis()).length() >= extra - 1e-9);
                assert_eq!(longer.object, s.object);
                let feet = longer.pelvis() + DVec2::Y * crate::scene::chair_pull::STAND_IN_FRONT_M;
                assert!(more.frees(&map, feet) && map.is_walkable_at(longer.stand()));
                assert!(longer.longer.is_none());
            }
        }
    }

    #[test]
    fn a_chair_at_a_table_with_a_wall_behind_it_is_not_sat_on() {
        let seats = |mesh: &SceneMesh| find_seats(mesh, &map(mesh), &SeatSettings::default());
        let at = DVec2::new(0.0, 0.0);
        let mut mesh = chair_at_table(at, 0.3);
        // A wall 5 cm behind the backrest: no room to pull the chair out.
        mesh.add_box(
            "wall",
            Vec3::new(-2.0, at.y - 0.37, 0.0),
            Vec3::new(2.0, at.y - 0.27, 2.5),
        );
        let found = seats(&mesh);
        assert!(found.is_empty(), "{found:?}");
        // A stool or a box without a backrest has no front to pull it out by.
        let mut mesh = floor_with_seat("stool", at - 0.2, at + 0.2, 0.6, 0.0);
        mesh.add_box(
            "counter",
            Vec3::new(-0.6, 0.0, 0.9),
            Vec3::new(0.6, 0.7, 0.95),
        );
        assert!(seats(&mesh).iter().all(|s| s.pull.is_none()));
    }

    #[test]
    fn a_long_sofa_gives_places_spaced_apart() {
        let m = floor_with_seat(
            "sofa",
            DVec2::new(-1.0, -0.4),
            DVec2::new(1.0, 0.3),
            0.45,
            0.45,
        );
        let seats = find_seats(&m, &map(&m), &SeatSettings::default());
        assert!(seats.len() >= 3, "{seats:?}");
        for (a, s) in seats.iter().enumerate() {
            assert!(s.backed);
            for t in &seats[a + 1..] {
                assert!(s.pelvis().distance(t.pelvis()) >= 0.6 - 1e-9);
            }
        }
    }
}
