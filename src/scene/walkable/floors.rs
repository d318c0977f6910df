//! Stepped floors of the walkable map (`floor_steps_m`): each cell's floor height, the obstacles
//! over it between step and head height, the ledges too high to step, the smoothed floor a
//! body's height follows, and the floor under any point.

use glam::DVec2;

use super::{clip_z, convex_overlaps_rect, WalkableMap, FLOOR_LEVELS_RANGE_M, FLOOR_SMOOTHING_M};
use crate::math::Vec3;
use crate::scene::floor::UP_FACING_MIN_NZ;
use crate::scene::mesh::SceneMesh;

impl WalkableMap {
    /// Whether the map has one flat floor at `floor_z_m` (not stepped floors).
    pub(crate) fn is_flat(&self) -> bool {
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
    pub(crate) fn floor_range(&self, counted: impl Fn(usize) -> bool) -> Option<(f64, f64)> {
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

    /// Each cell's floor on stepped floors (NaN: none). The upward-facing surfaces over a
    /// cell's centre within [`FLOOR_LEVELS_RANGE_M`] of `floor_z_m` are its candidates; those
    /// within the floor tolerance of `floor_z_m` are reached, and so, breadth first, is every
    /// candidate of a 4-neighbouring cell within `steps_m` of a reached one. A cell stands on
    /// its highest reached candidate: on a platform or a ramp rather than the floor under it,
    /// while a bed or a table top (no chain of steps up to it) or a storey above are not floor.
    pub(super) fn stepped_floors(&self, mesh: &SceneMesh, steps_m: f64) -> Vec<f32> {
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

    /// Marks the cells a triangle blocks on stepped floors: those whose interior the part of
    /// it between the cell's own floor + `step` and + `head` enters (cells without floor:
    /// over `floor_z_m`). A vertical face on a cell boundary blocks the cell behind it, as
    /// [`Self::mark_occupied`] decides.
    pub(super) fn mark_occupied_stepped(&mut self, tri: [Vec3; 3], step: f64, head: f64) {
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
    pub(super) fn mark_ledges(&mut self, steps_m: f64) {
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
    pub(super) fn smoothed_floor(&self) -> Vec<f32> {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::walkable::WalkableSettings;

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
}
