//! The walkable map: a 2D grid over the scene (0.1 m cells by default) that marks where a
//! person can stand — floor underneath, nothing between step height and head height — with
//! the 2D signed distance to the nearest non-walkable cell and connected components.

use super::floor::{detect_floor_z, UP_FACING_MIN_NZ};
use super::mesh::SceneMesh;
use super::sdf2d::signed_distance;
use crate::math::Vec3;
use glam::DVec2;

/// Knobs of the walkable map.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WalkableSettings {
    /// Grid cell size (m).
    pub cell_m: f64,
    /// Geometry lower than floor + this (m) is stepped over (rugs, sills).
    pub step_height_m: f64,
    /// Geometry higher than floor + this (m) is walked under (ceilings, lamps).
    pub head_height_m: f64,
    /// Upward-facing triangles within this distance (m) of the floor height count as floor.
    pub floor_tolerance_m: f64,
    /// Walk the floor at this height (m: a building's upper storey) instead of the lowest
    /// floor holding a quarter of the largest floor area.
    pub floor_z_m: Option<f64>,
}

impl Default for WalkableSettings {
    fn default() -> Self {
        Self {
            cell_m: 0.1,
            step_height_m: 0.1,
            head_height_m: 1.8,
            floor_tolerance_m: 0.05,
            floor_z_m: None,
        }
    }
}

/// Grid cells: index `j * nx + i`, cell `(i, j)` covers
/// `[origin.x + i·cell, origin.x + (i+1)·cell) × [origin.y + j·cell, …)`.
#[derive(Debug, Clone)]
pub struct WalkableMap {
    pub origin: DVec2,
    pub cell_m: f64,
    pub nx: usize,
    pub ny: usize,
    pub floor_z_m: f64,
    pub settings: WalkableSettings,
    /// Geometry between step height and head height touches the cell.
    pub occupied: Vec<bool>,
    /// Floor under the cell centre.
    pub has_floor: Vec<bool>,
    /// `has_floor && !occupied`.
    pub walkable: Vec<bool>,
    /// Signed distance (m) to the walkable boundary: > 0 on walkable cells.
    pub sdf_m: Vec<f64>,
    /// 4-connected component of each walkable cell (1-based; 0 = not walkable).
    pub component: Vec<u32>,
}

/// Why no map could be built (the caller adds the file name).
#[derive(Debug, Clone, PartialEq)]
pub enum WalkableError {
    NoFloor,
    NoWalkable {
        floor_z_m: f64,
        lo: f64,
        hi: f64,
    },
    /// The grid would hold more than [`MAX_MAP_CELLS`] cells (or the cell size is not a
    /// positive number).
    TooManyCells {
        nx: f64,
        ny: f64,
        cell_m: f64,
    },
    /// The grid is within [`MAX_MAP_CELLS`] but would not fit in the memory this run may use
    /// (what it needs against the budget, [`crate::memory`]).
    OutOfMemory(String),
}

/// Most cells a walkable map may have (about 1.5 GB with the distance transform's scratch).
pub const MAX_MAP_CELLS: f64 = 5e7;

/// Bytes a map needs per cell, scratch included (flags, signed distance, component, EDT).
pub(crate) const MAP_BYTES_PER_CELL: f64 = 31.0;

impl WalkableMap {
    /// Builds the map of a scene.
    pub fn build(mesh: &SceneMesh, settings: WalkableSettings) -> Result<Self, WalkableError> {
        let floor_z = match settings.floor_z_m {
            Some(z) => z,
            None => detect_floor_z(mesh).ok_or(WalkableError::NoFloor)?,
        };
        let (lo, hi) = mesh.bounds().ok_or(WalkableError::NoFloor)?;
        let cell = settings.cell_m;
        let origin = DVec2::new(lo.x, lo.y) - DVec2::splat(cell);
        let (fx, fy) = (
            ((hi.x - lo.x) / cell).ceil() + 2.0,
            ((hi.y - lo.y) / cell).ceil() + 2.0,
        );
        if !(cell.is_finite() && cell > 0.0 && fx * fy <= MAX_MAP_CELLS) {
            return Err(WalkableError::TooManyCells {
                nx: fx,
                ny: fy,
                cell_m: cell,
            });
        }
        crate::memory::check_fits(
            &format!("a walkable map of {fx} × {fy} cells of {cell} m"),
            fx * fy * MAP_BYTES_PER_CELL,
        )
        .map_err(WalkableError::OutOfMemory)?;
        let (nx, ny) = (fx as usize, fy as usize);
        let mut map = WalkableMap {
            origin,
            cell_m: cell,
            nx,
            ny,
            floor_z_m: floor_z,
            settings,
            occupied: vec![false; nx * ny],
            has_floor: vec![false; nx * ny],
            walkable: vec![false; nx * ny],
            sdf_m: vec![0.0; nx * ny],
            component: vec![0; nx * ny],
        };
        let (z_lo, z_hi) = (
            floor_z + settings.step_height_m,
            floor_z + settings.head_height_m,
        );
        for t in 0..mesh.triangles.len() {
            let tri = mesh.triangle(t);
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            let is_floor = n.length() > 0.0
                && n.z / n.length() >= UP_FACING_MIN_NZ
                && tri
                    .iter()
                    .all(|p| (p.z - floor_z).abs() <= settings.floor_tolerance_m);
            if is_floor {
                map.mark_floor(tri);
            }
            let poly = clip_z(&clip_z(&tri, z_lo, true), z_hi, false);
            if !poly.is_empty() {
                map.mark_occupied(&poly, DVec2::new(n.x, n.y));
            }
        }
        let enclosed = map.enclosed_cells(mesh, 0.5 * (z_lo + z_hi));
        for k in 0..nx * ny {
            map.walkable[k] = map.has_floor[k] && !map.occupied[k] && !enclosed[k];
        }
        if !map.walkable.iter().any(|&w| w) {
            return Err(WalkableError::NoWalkable {
                floor_z_m: floor_z,
                lo: z_lo,
                hi: z_hi,
            });
        }
        map.sdf_m = signed_distance(&map.walkable, nx, ny, cell);
        map.label_components();
        Ok(map)
    }

    /// A map from a given walkable pattern (row-major, `ny` rows of `nx`), e.g. a floor plan
    /// image; the floor is at z = 0 and occupancy is the complement of `walkable`.
    pub fn from_walkable(
        origin: DVec2,
        cell_m: f64,
        nx: usize,
        ny: usize,
        walkable: Vec<bool>,
    ) -> Self {
        assert_eq!(
            walkable.len(),
            nx * ny,
            "walkable pattern must have nx·ny cells"
        );
        let mut map = WalkableMap {
            origin,
            cell_m,
            nx,
            ny,
            floor_z_m: 0.0,
            settings: WalkableSettings {
                cell_m,
                ..Default::default()
            },
            occupied: walkable.iter().map(|&w| !w).collect(),
            has_floor: vec![true; nx * ny],
            sdf_m: signed_distance(&walkable, nx, ny, cell_m),
            walkable,
            component: vec![0; nx * ny],
        };
        map.label_components();
        map
    }

    /// Cell containing a point, or `None` outside the grid.
    pub fn cell_of(&self, p: DVec2) -> Option<(usize, usize)> {
        let q = (p - self.origin) / self.cell_m;
        (q.x >= 0.0 && q.y >= 0.0 && (q.x as usize) < self.nx && (q.y as usize) < self.ny)
            .then_some((q.x as usize, q.y as usize))
    }

    /// Centre of cell `(i, j)`.
    pub fn centre(&self, i: usize, j: usize) -> DVec2 {
        self.origin + (DVec2::new(i as f64, j as f64) + 0.5) * self.cell_m
    }

    /// Whether cell `(i, j)` blocks walking (cells outside the grid do).
    #[inline]
    pub fn blocked(&self, i: i64, j: i64) -> bool {
        if i < 0 || j < 0 || i >= self.nx as i64 || j >= self.ny as i64 {
            return true;
        }
        !self.walkable[j as usize * self.nx + i as usize]
    }

    /// Whether a point stands on a walkable cell.
    pub fn is_walkable_at(&self, p: DVec2) -> bool {
        self.cell_of(p)
            .is_some_and(|(i, j)| self.walkable[j * self.nx + i])
    }

    /// Signed distance (m) at a point, bilinear between cell centres. Beyond the grid: the value
    /// at the grid's nearest point less the distance to it (still falling away from the floor).
    pub fn sdf_at(&self, p: DVec2) -> f64 {
        if self.cell_of(p).is_none() {
            if !p.is_finite() {
                return f64::NEG_INFINITY;
            }
            let size = DVec2::new(self.nx as f64, self.ny as f64) * self.cell_m;
            let inner = 1e-9 * self.cell_m;
            let nearest = p.clamp(self.origin + inner, self.origin + size - inner);
            return self.sdf_at(nearest) - p.distance(nearest);
        }
        let q = (p - self.origin) / self.cell_m - 0.5;
        let (i0, j0) = (q.x.floor(), q.y.floor());
        let (fx, fy) = (q.x - i0, q.y - j0);
        let get = |i: f64, j: f64| {
            let (i, j) = (
                (i as i64).clamp(0, self.nx as i64 - 1),
                (j as i64).clamp(0, self.ny as i64 - 1),
            );
            self.sdf_m[j as usize * self.nx + i as usize]
        };
        let a = get(i0, j0) * (1.0 - fx) + get(i0 + 1.0, j0) * fx;
        let b = get(i0, j0 + 1.0) * (1.0 - fx) + get(i0 + 1.0, j0 + 1.0) * fx;
        a * (1.0 - fy) + b * fy
    }

    /// The walkable cells inside the walls: those from which at least `min_enclosed` of 32
    /// horizontal rays, evenly around, meet something that blocks walking (a wall, furniture)
    /// before they leave the grid. The ground around a building sees open space on one side
    /// (about half its rays escape); a room sees walls all round but through its doors and
    /// openings. `None` when no cell is enclosed (an open floor).
    pub fn indoor_cells(&self, min_enclosed: f64) -> Option<Vec<bool>> {
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
    pub fn restricted_to(&self, region: &[bool]) -> WalkableMap {
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

    /// Number of walkable cells.
    pub fn walkable_count(&self) -> usize {
        self.walkable.iter().filter(|&&w| w).count()
    }

    fn cell_range(&self, lo: DVec2, hi: DVec2) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let a = ((lo - self.origin) / self.cell_m).floor().max(DVec2::ZERO);
        let b = ((hi - self.origin) / self.cell_m).floor();
        let i1 = (b.x.max(-1.0) as i64 + 1).clamp(0, self.nx as i64) as usize;
        let j1 = (b.y.max(-1.0) as i64 + 1).clamp(0, self.ny as i64) as usize;
        ((a.x as usize).min(i1)..i1, (a.y as usize).min(j1)..j1)
    }

    /// Cells whose centre, at height `z`, lies inside a closed object: the vertical line
    /// through it crosses that object's surface an odd number of times both above and below
    /// `z`. The hollow inside of a wall modelled as a closed box has no triangle in the body's
    /// height range, and would otherwise be floor; an open surface (a ceiling plane, a floor
    /// slab below) fails one side of the test and encloses nothing.
    fn enclosed_cells(&self, mesh: &SceneMesh, z: f64) -> Vec<bool> {
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
                let tri = mesh.triangle(t);
                let p = tri.map(|v| DVec2::new(v.x, v.y));
                let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
                if area == 0.0 {
                    continue;
                }
                let (tlo, thi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
                let (ti, tj) = self.cell_range(tlo, thi);
                for j in tj {
                    for i in ti.clone() {
                        let c = self.centre(i, j) + jitter;
                        let b = [
                            (p[2] - p[1]).perp_dot(c - p[1]) / area,
                            (p[0] - p[2]).perp_dot(c - p[2]) / area,
                            (p[1] - p[0]).perp_dot(c - p[0]) / area,
                        ];
                        if b.iter().any(|&x| x < 0.0) {
                            continue;
                        }
                        let tz = b[0] * tri[0].z + b[1] * tri[1].z + b[2] * tri[2].z;
                        parity[(j - rj.start) * w + (i - ri.start)] ^= if tz > z { 1 } else { 2 };
                    }
                }
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

    fn mark_floor(&mut self, tri: [Vec3; 3]) {
        let p = tri.map(|v| DVec2::new(v.x, v.y));
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        let (ri, rj) = self.cell_range(lo, hi);
        let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        if area == 0.0 {
            return;
        }
        for j in rj {
            for i in ri.clone() {
                let c = self.centre(i, j);
                let w = [
                    (p[1] - p[0]).perp_dot(c - p[0]),
                    (p[2] - p[1]).perp_dot(c - p[1]),
                    (p[0] - p[2]).perp_dot(c - p[2]),
                ];
                if w.iter().all(|&x| x * area >= 0.0) {
                    self.has_floor[j * self.nx + i] = true;
                }
            }
        }
    }

    /// Marks cells whose interior the polygon's footprint enters (touching a cell's boundary
    /// does not count, so grid-aligned boxes mark exactly the cells they cover). A vertical
    /// face lying exactly on a cell boundary enters no cell: it marks the cells behind it
    /// (against its normal `normal_xy`), or, without a usable normal, the cells it touches.
    fn mark_occupied(&mut self, poly: &[Vec3], normal_xy: DVec2) {
        let p: Vec<DVec2> = poly.iter().map(|v| DVec2::new(v.x, v.y)).collect();
        if self.mark_footprint(&p, false) {
            return;
        }
        if let Some(n) = normal_xy.try_normalize() {
            let nudged: Vec<DVec2> = p.iter().map(|v| *v - n * (1e-6 * self.cell_m)).collect();
            if self.mark_footprint(&nudged, false) {
                return;
            }
        }
        self.mark_footprint(&p, true);
    }

    /// Marks cells the convex footprint overlaps (`closed`: touching counts); returns whether
    /// any cell was marked.
    fn mark_footprint(&mut self, p: &[DVec2], closed: bool) -> bool {
        let lo = p.iter().fold(DVec2::splat(f64::INFINITY), |a, b| a.min(*b));
        let hi = p
            .iter()
            .fold(DVec2::splat(f64::NEG_INFINITY), |a, b| a.max(*b));
        let (ri, rj) = self.cell_range(lo, hi);
        let margin = if closed { 0.0 } else { 1e-9 * self.cell_m };
        let mut any = false;
        for j in rj {
            for i in ri.clone() {
                let c_lo = self.origin + DVec2::new(i as f64, j as f64) * self.cell_m;
                if convex_overlaps_rect(p, c_lo, c_lo + DVec2::splat(self.cell_m), margin, closed) {
                    self.occupied[j * self.nx + i] = true;
                    any = true;
                }
            }
        }
        any
    }

    fn label_components(&mut self) {
        let mut next = 0u32;
        let mut stack = Vec::new();
        for start in 0..self.nx * self.ny {
            if !self.walkable[start] || self.component[start] != 0 {
                continue;
            }
            next += 1;
            self.component[start] = next;
            stack.push(start);
            while let Some(k) = stack.pop() {
                let (i, j) = (k % self.nx, k / self.nx);
                let nbrs = [
                    (i.wrapping_sub(1), j),
                    (i + 1, j),
                    (i, j.wrapping_sub(1)),
                    (i, j + 1),
                ];
                for (a, b) in nbrs {
                    if a < self.nx && b < self.ny {
                        let n = b * self.nx + a;
                        if self.walkable[n] && self.component[n] == 0 {
                            self.component[n] = next;
                            stack.push(n);
                        }
                    }
                }
            }
        }
    }
}

/// Sutherland–Hodgman clip of a polygon against `z ≥ z0` (`keep_above`) or `z ≤ z0`.
fn clip_z(poly: &[Vec3], z0: f64, keep_above: bool) -> Vec<Vec3> {
    let inside = |p: &Vec3| if keep_above { p.z >= z0 } else { p.z <= z0 };
    let mut out = Vec::with_capacity(poly.len() + 2);
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        match (inside(&a), inside(&b)) {
            (true, true) => out.push(b),
            (true, false) => out.push(a + (b - a) * ((z0 - a.z) / (b.z - a.z))),
            (false, true) => {
                out.push(a + (b - a) * ((z0 - a.z) / (b.z - a.z)));
                out.push(b);
            }
            (false, false) => {}
        }
    }
    out
}

/// Separating-axis test between a convex polygon (possibly degenerate: a segment or a point)
/// and the rectangle `[lo, hi]`. `closed`: touching counts as overlap. Otherwise the shapes
/// must overlap by more than `margin` along every axis (interiors meet).
fn convex_overlaps_rect(p: &[DVec2], lo: DVec2, hi: DVec2, margin: f64, closed: bool) -> bool {
    let separated = |amax: f64, bmin: f64| {
        if closed {
            amax < bmin
        } else {
            amax <= bmin + margin
        }
    };
    let (plo, phi) = p.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(a, b), v| (a.min(*v), b.max(*v)),
    );
    if separated(phi.x, lo.x)
        || separated(hi.x, plo.x)
        || separated(phi.y, lo.y)
        || separated(hi.y, plo.y)
    {
        return false;
    }
    let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    for k in 0..p.len() {
        let e = p[(k + 1) % p.len()] - p[k];
        if e.length_squared() < 1e-24 {
            continue;
        }
        let axis = e.perp().normalize();
        let proj = |v: &DVec2| axis.dot(*v);
        let (pmin, pmax) = p
            .iter()
            .map(proj)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        let (rmin, rmax) = corners
            .iter()
            .map(proj)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        if separated(pmax, rmin) || separated(rmax, pmin) {
            return false;
        }
    }
    true
}

/// Share of a cell's rays that must meet something for it to count as inside the walls.
pub const MIN_ENCLOSED: f64 = 0.75;

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

    /// A 10 m square of ground with a 4 m room in the middle: walls one cell thick, a 1 m
    /// door on the south side.
    fn room_on_ground() -> WalkableMap {
        let n = 100;
        let mut walkable = vec![true; n * n];
        for k in 30..=70 {
            for (i, j) in [(k, 30), (k, 70), (30, k), (70, k)] {
                let door = j == 30 && (45..55).contains(&i);
                if !door {
                    walkable[j * n + i] = false;
                }
            }
        }
        WalkableMap::from_walkable(DVec2::ZERO, 0.1, n, n, walkable)
    }

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

    /// Beyond the grid the distance keeps falling, so "nearer the floor" still means something
    /// for a body that has left the map; NaN stays −∞.
    #[test]
    fn the_distance_falls_on_beyond_the_grid() {
        let closed = {
            let map = room_on_ground();
            let inside = map.indoor_cells(0.75).unwrap();
            map.restricted_to(&inside)
        };
        let p = |x: f64, y: f64| DVec2::new(x, y);
        let edge = closed.sdf_at(p(5.0, 0.0001));
        let (near, far) = (closed.sdf_at(p(5.0, -1.0)), closed.sdf_at(p(5.0, -3.0)));
        assert!(
            edge < 0.0 && near < edge && far < near,
            "{edge} {near} {far}"
        );
        assert!((edge - near - 1.0).abs() < 1e-6 && (near - far - 2.0).abs() < 1e-6);
        assert!(closed.sdf_at(p(-1e12, 1e12)).is_finite());
        assert_eq!(closed.sdf_at(p(f64::NAN, 1.0)), f64::NEG_INFINITY);
    }

    #[test]
    fn an_open_floor_encloses_nothing() {
        let n = 50;
        let map = WalkableMap::from_walkable(DVec2::ZERO, 0.1, n, n, vec![true; n * n]);
        assert!(map.indoor_cells(0.75).is_none());
    }
}
