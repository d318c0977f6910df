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
    pub fn stepped_over_m(&self) -> f64 {
        self.step_height_m.max(self.floor_steps_m.unwrap_or(0.0))
    }

    /// What is wrong with the floor a run asks for, if anything: the setting's name
    /// (`floor_z_m`, `floor_steps_m`; a config key's last part, a flag with dashes) and what
    /// was expected. One check for run and synth configs and `egogen scene inspect`.
    pub fn floor_problem(&self) -> Option<(&'static str, String)> {
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
pub const MAX_FLOOR_STEPS_M: f64 = 0.5;

/// With [`WalkableSettings::floor_steps_m`], upward-facing surfaces within this (m) of the
/// floor height are candidates for a cell's floor.
pub const FLOOR_LEVELS_RANGE_M: f64 = 1.5;

/// A body standing on stepped floors follows the cells' floors averaged within this (m)
/// round its pelvis ([`WalkableMap::floor_under`]): it rises or sinks over about twice this
/// across a step instead of at a cell's edge.
pub const FLOOR_SMOOTHING_M: f64 = 0.3;

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
pub const MAX_MAP_CELLS: f64 = 5e7;

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

    /// Whether the map has one flat floor at `floor_z_m` (not stepped floors).
    pub fn is_flat(&self) -> bool {
        self.floor_m.is_empty()
    }

    /// Floor height (m) of cell `k`: its own on stepped floors (`floor_z_m` where it has
    /// none), else `floor_z_m`.
    pub fn cell_floor_m(&self, k: usize) -> f64 {
        match self.floor_m.get(k) {
            Some(f) if !f.is_nan() => *f as f64,
            _ => self.floor_z_m,
        }
    }

    /// Lowest and highest floor (m, [`Self::cell_floor_m`]) of the cells `counted` keeps;
    /// `None` when it keeps none.
    pub fn floor_range(&self, counted: impl Fn(usize) -> bool) -> Option<(f64, f64)> {
        (0..self.nx * self.ny)
            .filter(|&k| counted(k))
            .map(|k| self.cell_floor_m(k))
            .fold(None, |r, z| {
                Some(r.map_or((z, z), |(a, b): (f64, f64)| (a.min(z), b.max(z))))
            })
    }

    /// Floor height (m) of the cell under `p`, when it has floor ([`Self::cell_floor_m`]).
    pub fn cell_floor_at(&self, p: DVec2) -> Option<f64> {
        let (i, j) = self.cell_of(p)?;
        let k = j * self.nx + i;
        self.has_floor[k].then(|| self.cell_floor_m(k))
    }

    /// Floor height (m) for a body standing at `p`: on stepped floors the cells' floors
    /// averaged within [`FLOOR_SMOOTHING_M`], bilinear between cell centres (the grid's edge
    /// beyond it); `floor_z_m` on a flat floor.
    pub fn floor_under(&self, p: DVec2) -> f64 {
        if self.floor_smooth_m.is_empty() || !p.is_finite() {
            return self.floor_z_m;
        }
        self.bilinear(p, |k| self.floor_smooth_m[k] as f64)
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

    /// Each cell's floor on stepped floors (NaN: none). The upward-facing surfaces over a
    /// cell's centre within [`FLOOR_LEVELS_RANGE_M`] of `floor_z_m` are its candidates; those
    /// within the floor tolerance of `floor_z_m` are reached, and so, breadth first, is every
    /// candidate of a 4-neighbouring cell within `steps_m` of a reached one. A cell stands on
    /// its highest reached candidate: on a platform or a ramp rather than the floor under it,
    /// while a bed or a table top (no chain of steps up to it) or a storey above are not floor.
    fn stepped_floors(&self, mesh: &SceneMesh, steps_m: f64) -> Vec<f32> {
        let (n, z0) = (self.nx * self.ny, self.floor_z_m);
        let mut candidates: Vec<(u32, f32)> = Vec::new();
        for t in 0..mesh.triangles.len() {
            let tri = mesh.triangle(t);
            let nrm = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            if !(nrm.length() > 0.0 && nrm.z / nrm.length() >= UP_FACING_MIN_NZ) {
                continue;
            }
            self.for_cells_under(tri, DVec2::ZERO, |k, z| {
                if (z - z0).abs() <= FLOOR_LEVELS_RANGE_M {
                    candidates.push((k as u32, z as f32));
                }
            });
        }
        candidates.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        candidates.dedup();
        let mut start = vec![0usize; n + 1];
        for &(k, _) in &candidates {
            start[k as usize + 1] += 1;
        }
        for k in 0..n {
            start[k + 1] += start[k];
        }
        let tolerance = self.settings.floor_tolerance_m;
        let mut reached = vec![false; candidates.len()];
        let mut queue: std::collections::VecDeque<usize> = (0..candidates.len())
            .filter(|&c| (candidates[c].1 as f64 - z0).abs() <= tolerance)
            .collect();
        for &c in &queue {
            reached[c] = true;
        }
        while let Some(c) = queue.pop_front() {
            let (k, h) = (candidates[c].0 as usize, candidates[c].1 as f64);
            for m in self.neighbours4(k) {
                for d in start[m]..start[m + 1] {
                    if !reached[d] && (candidates[d].1 as f64 - h).abs() <= steps_m {
                        reached[d] = true;
                        queue.push_back(d);
                    }
                }
            }
        }
        (0..n)
            .map(|k| {
                (start[k]..start[k + 1])
                    .rev()
                    .find(|&c| reached[c])
                    .map_or(f32::NAN, |c| candidates[c].1)
            })
            .collect()
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

    /// Marks the cells a triangle blocks on stepped floors: those whose interior the part of
    /// it between the cell's own floor + `step` and + `head` enters (cells without floor:
    /// over `floor_z_m`). A vertical face on a cell boundary blocks the cell behind it, as
    /// [`Self::mark_occupied`] decides.
    fn mark_occupied_stepped(&mut self, tri: [Vec3; 3], step: f64, head: f64) {
        let nrm = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let normal_xy = DVec2::new(nrm.x, nrm.y).try_normalize();
        let (zmin, zmax) = (
            tri[0].z.min(tri[1].z).min(tri[2].z),
            tri[0].z.max(tri[1].z).max(tri[2].z),
        );
        let lo = tri.iter().fold(DVec2::splat(f64::INFINITY), |a, v| {
            a.min(DVec2::new(v.x, v.y))
        });
        let hi = tri.iter().fold(DVec2::splat(f64::NEG_INFINITY), |a, v| {
            a.max(DVec2::new(v.x, v.y))
        });
        let (ri, rj) = self.cell_range(lo, hi);
        let margin = 1e-9 * self.cell_m;
        for j in rj {
            for i in ri.clone() {
                let k = j * self.nx + i;
                let f = self.cell_floor_m(k);
                if zmax < f + step || zmin > f + head {
                    continue;
                }
                let poly = clip_z(&clip_z(&tri, f + step, true), f + head, false);
                if poly.is_empty() {
                    continue;
                }
                let p: Vec<DVec2> = poly.iter().map(|v| DVec2::new(v.x, v.y)).collect();
                let c_lo = self.origin + DVec2::new(i as f64, j as f64) * self.cell_m;
                let c_hi = c_lo + DVec2::splat(self.cell_m);
                let blocks = convex_overlaps_rect(&p, c_lo, c_hi, margin, false)
                    || match normal_xy {
                        Some(n) => {
                            let nudged: Vec<DVec2> =
                                p.iter().map(|v| *v - n * (1e-6 * self.cell_m)).collect();
                            convex_overlaps_rect(&nudged, c_lo, c_hi, margin, false)
                        }
                        None => convex_overlaps_rect(&p, c_lo, c_hi, 0.0, true),
                    };
                if blocks {
                    self.occupied[k] = true;
                }
            }
        }
    }

    /// On stepped floors, blocks every cell with floor beside a 4-neighbour whose floor lies
    /// more than `steps_m` lower: the edge of a drop is walked as a wall.
    fn mark_ledges(&mut self, steps_m: f64) {
        for k in 0..self.nx * self.ny {
            let h = self.floor_m[k];
            if !h.is_nan()
                && self
                    .neighbours4(k)
                    .any(|m| ((h - self.floor_m[m]) as f64) > steps_m)
            {
                self.occupied[k] = true;
            }
        }
    }

    /// The cells' floors averaged over the cells with floor within [`FLOOR_SMOOTHING_M`]
    /// (a square window, two separable passes); `floor_z_m` where none has.
    fn smoothed_floor(&self) -> Vec<f32> {
        let r = (FLOOR_SMOOTHING_M / self.cell_m).round().max(0.0) as usize;
        let (nx, ny) = (self.nx, self.ny);
        let mut sum: Vec<f64> = self
            .floor_m
            .iter()
            .map(|&f| if f.is_nan() { 0.0 } else { f as f64 })
            .collect();
        let mut count: Vec<f64> = self
            .floor_m
            .iter()
            .map(|f| if f.is_nan() { 0.0 } else { 1.0 })
            .collect();
        let pass = |v: &[f64], along_x: bool| {
            let mut out = vec![0.0; v.len()];
            for j in 0..ny {
                for i in 0..nx {
                    let (c, len) = if along_x { (i, nx) } else { (j, ny) };
                    let (a, b) = (c.saturating_sub(r), (c + r).min(len - 1));
                    out[j * nx + i] = (a..=b)
                        .map(|t| {
                            if along_x {
                                v[j * nx + t]
                            } else {
                                v[t * nx + i]
                            }
                        })
                        .sum();
                }
            }
            out
        };
        for along_x in [true, false] {
            sum = pass(&sum, along_x);
            count = pass(&count, along_x);
        }
        sum.iter()
            .zip(&count)
            .map(|(&s, &c)| {
                if c > 0.0 {
                    (s / c) as f32
                } else {
                    self.floor_z_m as f32
                }
            })
            .collect()
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
        self.bilinear(p, |k| self.sdf_m[k])
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

    /// Cells whose centre, at height `z_of(cell)`, lies inside a closed object: the vertical line
    /// through it crosses that object's surface an odd number of times both above and below
    /// `z`. The hollow inside of a wall modelled as a closed box has no triangle in the body's
    /// height range, and would otherwise be floor; an open surface (a ceiling plane, a floor
    /// slab below) fails one side of the test and encloses nothing.
    fn enclosed_cells(&self, mesh: &SceneMesh, z_of: impl Fn(usize) -> f64) -> Vec<bool> {
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

    /// A 10 × 6 m floor slab (top at z = 0) split by a wall at x = 0 with a 1 m doorway; east
    /// of it a platform 0.15 m high over the whole room (a step up through the doorway); in
    /// the west room a bed 0.5 m high, and a ramp (an open sloped surface over the floor)
    /// from 0 to 0.6 m up to a plateau 0.6 m high that ends in a drop.
    fn stepped_rooms() -> SceneMesh {
        let v = |x: f64, y: f64, z: f64| Vec3::new(x, y, z);
        let mut mesh = SceneMesh::default();
        mesh.add_box("slab", v(-5.0, -3.0, -0.1), v(5.0, 3.0, 0.0));
        mesh.add_box("wall_south", v(-0.1, -3.0, 0.0), v(0.1, -0.5, 2.5));
        mesh.add_box("wall_north", v(-0.1, 0.5, 0.0), v(0.1, 3.0, 2.5));
        mesh.add_box("platform", v(0.1, -3.0, 0.0), v(5.0, 3.0, 0.15));
        mesh.add_box("bed", v(-4.0, 1.0, 0.0), v(-2.0, 2.6, 0.5));
        mesh.add_object(
            "ramp",
            &[
                v(-4.5, -2.5, 0.0),
                v(-2.5, -2.5, 0.6),
                v(-2.5, -1.0, 0.6),
                v(-4.5, -1.0, 0.0),
            ],
            &[[0, 1, 2], [0, 2, 3]],
        );
        mesh.add_box("plateau", v(-2.5, -2.5, 0.0), v(-1.5, -1.0, 0.6));
        mesh
    }

    fn stepped_map(steps: Option<f64>) -> WalkableMap {
        WalkableMap::build(
            &stepped_rooms(),
            WalkableSettings {
                floor_steps_m: steps,
                ..Default::default()
            },
        )
        .unwrap()
    }

    #[test]
    fn a_flat_floor_blocks_a_step_up_and_stepped_floors_walk_it() {
        let p = |x: f64, y: f64| DVec2::new(x, y);
        let flat = stepped_map(None);
        assert!(flat.is_flat() && flat.floor_under(p(3.0, 0.0)) == 0.0);
        assert!(flat.is_walkable_at(p(-1.0, 0.0)) && !flat.is_walkable_at(p(3.0, 0.0)));
        // A step of 0.15 m is more than a 0.1 m step: blocked as before.
        let low = stepped_map(Some(0.1));
        assert!(low.is_walkable_at(p(-1.0, 0.0)) && !low.is_walkable_at(p(3.0, 0.0)));

        let map = stepped_map(Some(0.2));
        assert!(!map.is_flat());
        let floor_at = |x: f64, y: f64| {
            let (i, j) = map.cell_of(p(x, y)).unwrap();
            map.cell_floor_m(j * map.nx + i)
        };
        // Both rooms walked, each on its own floor, one region through the doorway.
        assert!(map.is_walkable_at(p(-1.0, 0.0)) && map.is_walkable_at(p(3.0, 0.0)));
        assert!(floor_at(-1.0, 0.0).abs() < 1e-6);
        assert!((floor_at(3.0, 0.0) - 0.15).abs() < 1e-6);
        let region = |x: f64, y: f64| {
            let (i, j) = map.cell_of(p(x, y)).unwrap();
            map.component[j * map.nx + i]
        };
        assert!(region(-1.0, 0.0) > 0 && region(-1.0, 0.0) == region(3.0, 0.0));
        // The bed is furniture (no step reaches its top), the wall a wall.
        assert!(!map.is_walkable_at(p(-3.0, 1.8)) && floor_at(-3.0, 1.8).abs() < 1e-6);
        assert!(!map.is_walkable_at(p(0.0, 2.0)));
        // Up the ramp onto the plateau, which ends in a drop: its edge blocks like a wall.
        assert!(
            (floor_at(-3.5, -1.75) - 0.3).abs() < 0.03,
            "{}",
            floor_at(-3.5, -1.75)
        );
        assert!(map.is_walkable_at(p(-3.5, -1.75)) && map.is_walkable_at(p(-2.0, -1.75)));
        assert!((floor_at(-2.0, -1.75) - 0.6).abs() < 1e-6);
        assert!(!map.is_walkable_at(p(-1.55, -1.75)), "the plateau's edge");
        assert!(
            !map.is_walkable_at(p(-3.0, -1.05)),
            "the ramp's side, 0.45 m over the floor"
        );
        assert!(
            map.is_walkable_at(p(-3.0, -0.95)),
            "the floor beside the ramp"
        );
        assert!(
            map.is_walkable_at(p(-4.2, -1.05)),
            "the ramp's foot: a step from the floor"
        );
        // A body follows the floor: 0 in the west room, 0.15 m in the east one, rising
        // steadily over the doorway's step.
        assert!(map.floor_under(p(-2.0, 0.0)).abs() < 1e-6);
        assert!((map.floor_under(p(3.0, 0.0)) - 0.15).abs() < 1e-6);
        let across: Vec<f64> = (0..=20)
            .map(|k| map.floor_under(p(-0.5 + 0.05 * k as f64, 0.0)))
            .collect();
        assert!(across.windows(2).all(|w| w[1] >= w[0] - 1e-9), "{across:?}");
        assert!(across.windows(2).all(|w| w[1] - w[0] < 0.03), "{across:?}");
    }

    #[test]
    fn an_open_floor_encloses_nothing() {
        let n = 50;
        let map = WalkableMap::from_walkable(DVec2::ZERO, 0.1, n, n, vec![true; n * n]);
        assert!(map.indoor_cells(0.75).is_none());
    }
}
