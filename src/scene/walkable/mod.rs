//! The walkable map: a 2D grid over the scene (0.1 m cells by default) that marks where a
//! person can stand — floor underneath, nothing between step height and head height — with
//! the 2D signed distance to the nearest non-walkable cell and connected components.
//! `floors` holds stepped floors (each cell's floor height, ledges too high to step, the
//! smoothed floor a body follows), `indoor` the cells inside the walls and the map restricted
//! to them.

mod floors;
mod indoor;

use super::floor::{detect_floor_z, UP_FACING_MIN_NZ};
use super::mesh::SceneMesh;
use super::sdf2d::signed_distance;
use crate::math::Vec3;
use glam::DVec2;

pub use indoor::indoor_map;

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
    /// Floors that step up or down by at most this (m) from cell to cell are one floor: steps
    /// between rooms, a sunken room, a ramp. Each cell keeps its own floor height (the highest
    /// upward-facing surface within this of a neighbouring cell's floor, reached from the
    /// floor at `floor_z_m`), geometry blocks a cell between its own floor + step and + head
    /// height (the step being the larger of this and `step_height_m`), and a drop deeper than
    /// this blocks like a wall. `None`: one flat floor.
    pub floor_steps_m: Option<f64>,
}

impl Default for WalkableSettings {
    fn default() -> Self {
        Self {
            cell_m: 0.1,
            step_height_m: 0.1,
            head_height_m: 1.8,
            floor_tolerance_m: 0.05,
            floor_z_m: None,
            floor_steps_m: None,
        }
    }
}

impl WalkableSettings {
    /// Geometry lower than a cell's floor + this (m) is stepped over.
    pub(crate) fn stepped_over_m(&self) -> f64 {
        self.step_height_m.max(self.floor_steps_m.unwrap_or(0.0))
    }

    /// What is wrong with the floor a run asks for, if anything: the setting's name
    /// (`floor_z_m`, `floor_steps_m`; a config key's last part, a flag with dashes) and what
    /// was expected. One check for run and synth configs and `egogen scene inspect`.
    pub(crate) fn floor_problem(&self) -> Option<(&'static str, String)> {
        if let Some(z) = self.floor_z_m.filter(|z| !z.is_finite()) {
            return Some((
                "floor_z_m",
                format!("expected a finite height (m), got {z}"),
            ));
        }
        match self.floor_steps_m {
            Some(s) if !(s.is_finite() && s > 0.0 && s <= MAX_FLOOR_STEPS_M) => Some((
                "floor_steps_m",
                format!(
                    "expected the highest step between floors, more than 0 and at most \
                     {MAX_FLOOR_STEPS_M} m, got {s}"
                ),
            )),
            _ => None,
        }
    }
}

/// Highest [`WalkableSettings::floor_steps_m`] a run accepts (m): a step a person takes, not
/// a storey.
pub(crate) const MAX_FLOOR_STEPS_M: f64 = 0.5;

/// With [`WalkableSettings::floor_steps_m`], upward-facing surfaces within this (m) of the
/// floor height are candidates for a cell's floor.
pub(crate) const FLOOR_LEVELS_RANGE_M: f64 = 1.5;

/// A body standing on stepped floors follows the cells' floors averaged within this (m)
/// round its pelvis ([`WalkableMap::floor_under`]): it rises or sinks over about twice this
/// across a step instead of at a cell's edge.
pub(crate) const FLOOR_SMOOTHING_M: f64 = 0.3;

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
    /// Each cell's own floor height (m; NaN without floor) on stepped floors
    /// ([`WalkableSettings::floor_steps_m`]); empty on a flat floor at `floor_z_m`.
    pub floor_m: Vec<f32>,
    /// The floor heights averaged round each cell ([`FLOOR_SMOOTHING_M`]; `floor_z_m` where
    /// no cell within has floor); empty on a flat floor.
    pub floor_smooth_m: Vec<f32>,
    /// Geometry between step height and head height over the cell's floor touches the cell
    /// (or, on stepped floors, the cell stands at the edge of a drop deeper than a step).
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
pub(crate) const MAX_MAP_CELLS: f64 = 5e7;

/// Bytes a map needs per cell, scratch included (flags, signed distance, component, EDT).
pub(crate) const MAP_BYTES_PER_CELL: f64 = 31.0;

/// Bytes stepped floors add per cell: its floor and their average (4 + 4), the candidates'
/// index (8), about one candidate (cell and height, 8) and its mark per surface over it, and
/// the averaging's sums and counts (32).
const STEPPED_BYTES_PER_CELL: f64 = 64.0;

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
        // Stepped floors add each cell's floor, its average and the floor candidates.
        let bytes_per_cell = MAP_BYTES_PER_CELL
            + if settings.floor_steps_m.is_some() {
                STEPPED_BYTES_PER_CELL
            } else {
                0.0
            };
        crate::memory::check_fits(
            &format!("a walkable map of {fx} × {fy} cells of {cell} m"),
            fx * fy * bytes_per_cell,
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
            floor_m: Vec::new(),
            floor_smooth_m: Vec::new(),
            occupied: vec![false; nx * ny],
            has_floor: vec![false; nx * ny],
            walkable: vec![false; nx * ny],
            sdf_m: vec![0.0; nx * ny],
            component: vec![0; nx * ny],
        };
        let step = settings.stepped_over_m();
        let head = settings.head_height_m;
        match settings.floor_steps_m {
            None => {
                let (z_lo, z_hi) = (floor_z + step, floor_z + head);
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
            }
            Some(steps_m) => {
                map.floor_m = map.stepped_floors(mesh, steps_m);
                for k in 0..nx * ny {
                    map.has_floor[k] = !map.floor_m[k].is_nan();
                }
                for t in 0..mesh.triangles.len() {
                    map.mark_occupied_stepped(mesh.triangle(t), step, head);
                }
                map.mark_ledges(steps_m);
                map.floor_smooth_m = map.smoothed_floor();
            }
        }
        let mid = 0.5 * (step + head);
        let enclosed = map.enclosed_cells(mesh, |k| map.cell_floor_m(k) + mid);
        for k in 0..nx * ny {
            map.walkable[k] = map.has_floor[k] && !map.occupied[k] && !enclosed[k];
        }
        if !map.walkable.iter().any(|&w| w) {
            return Err(WalkableError::NoWalkable {
                floor_z_m: floor_z,
                lo: floor_z + step,
                hi: floor_z + head,
            });
        }
        map.sdf_m = signed_distance(&map.walkable, nx, ny, cell);
        map.label_components();
        Ok(map)
    }

    /// The 4-neighbours of cell `k` within the grid.
    fn neighbours4(&self, k: usize) -> impl Iterator<Item = usize> {
        let (nx, ny) = (self.nx, self.ny);
        let (i, j) = (k % nx, k / nx);
        [
            (i.wrapping_sub(1), j),
            (i + 1, j),
            (i, j.wrapping_sub(1)),
            (i, j + 1),
        ]
        .into_iter()
        .filter(move |&(a, b)| a < nx && b < ny)
        .map(move |(a, b)| b * nx + a)
    }

    /// `field` bilinear between cell centres at `p` (clamped to the grid's centres).
    fn bilinear(&self, p: DVec2, field: impl Fn(usize) -> f64) -> f64 {
        let q = (p - self.origin) / self.cell_m - 0.5;
        let (i0, j0) = (q.x.floor(), q.y.floor());
        let (fx, fy) = ((q.x - i0).clamp(0.0, 1.0), (q.y - j0).clamp(0.0, 1.0));
        let get = |i: f64, j: f64| {
            let (i, j) = (
                (i as i64).clamp(0, self.nx as i64 - 1),
                (j as i64).clamp(0, self.ny as i64 - 1),
            );
            field(j as usize * self.nx + i as usize)
        };
        let a = get(i0, j0) * (1.0 - fx) + get(i0 + 1.0, j0) * fx;
        let b = get(i0, j0 + 1.0) * (1.0 - fx) + get(i0 + 1.0, j0 + 1.0) * fx;
        a * (1.0 - fy) + b * fy
    }

    /// Calls `f(cell, z)` for every cell whose centre, moved by `offset`, the triangle's
    /// footprint covers, with the triangle's height over that point.
    pub(super) fn for_cells_under(
        &self,
        tri: [Vec3; 3],
        offset: DVec2,
        mut f: impl FnMut(usize, f64),
    ) {
        let p = tri.map(|v| DVec2::new(v.x, v.y));
        let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        if area == 0.0 {
            return;
        }
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        let (ri, rj) = self.cell_range(lo, hi);
        for j in rj {
            for i in ri.clone() {
                let c = self.centre(i, j) + offset;
                let w = [
                    (p[2] - p[1]).perp_dot(c - p[1]),
                    (p[0] - p[2]).perp_dot(c - p[2]),
                    (p[1] - p[0]).perp_dot(c - p[0]),
                ];
                if w.iter().all(|&x| x * area >= 0.0) {
                    let z = (w[0] * tri[0].z + w[1] * tri[1].z + w[2] * tri[2].z) / area;
                    f(j * self.nx + i, z);
                }
            }
        }
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
            floor_m: Vec::new(),
            floor_smooth_m: Vec::new(),
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
    pub(crate) fn blocked(&self, i: i64, j: i64) -> bool {
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
    pub(crate) fn sdf_at(&self, p: DVec2) -> f64 {
        if self.cell_of(p).is_none() {
            if !p.is_finite() {
                return f64::NEG_INFINITY;
            }
            let size = DVec2::new(self.nx as f64, self.ny as f64) * self.cell_m;
            let inner = 1e-9 * self.cell_m;
            let nearest = p.clamp(self.origin + inner, self.origin + size - inner);
            return self.sdf_at(nearest) - p.distance(nearest);
        }
        self.bilinear(p, |k| self.sdf_m[k])
    }

    /// Number of walkable cells.
    pub fn walkable_count(&self) -> usize {
        self.walkable.iter().filter(|&&w| w).count()
    }

    pub(super) fn cell_range(
        &self,
        lo: DVec2,
        hi: DVec2,
    ) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let a = ((lo - self.origin) / self.cell_m).floor().max(DVec2::ZERO);
        let b = ((hi - self.origin) / self.cell_m).floor();
        let i1 = (b.x.max(-1.0) as i64 + 1).clamp(0, self.nx as i64) as usize;
        let j1 = (b.y.max(-1.0) as i64 + 1).clamp(0, self.ny as i64) as usize;
        ((a.x as usize).min(i1)..i1, (a.y as usize).min(j1)..j1)
    }

    fn mark_floor(&mut self, tri: [Vec3; 3]) {
        let mut cells = Vec::new();
        self.for_cells_under(tri, DVec2::ZERO, |k, _| cells.push(k));
        for k in cells {
            self.has_floor[k] = true;
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
                for n in self.neighbours4(k) {
                    if self.walkable[n] && self.component[n] == 0 {
                        self.component[n] = next;
                        stack.push(n);
                    }
                }
            }
        }
    }
}

/// Sutherland–Hodgman clip of a polygon against `z ≥ z0` (`keep_above`) or `z ≤ z0`.
pub(super) fn clip_z(poly: &[Vec3], z0: f64, keep_above: bool) -> Vec<Vec3> {
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
pub(super) fn convex_overlaps_rect(
    p: &[DVec2],
    lo: DVec2,
    hi: DVec2,
    margin: f64,
    closed: bool,
) -> bool {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 m square of ground with a 4 m room in the middle: walls one cell thick, a 1 m
    /// door on the south side.
    pub(super) fn room_on_ground() -> WalkableMap {
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
}
