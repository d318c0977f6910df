//! What a walker has seen of a walkable map: the cells its rays crossed (open) and the cells
//! they ended on (blocked), every other cell unknown. A guide plans on it with the unknown
//! taken as open ([`SeenMap::believed`]; optimistic planning, as frontier explorers and D* Lite
//! navigators plan): it heads round the walls the walker has seen, never round walls it has not,
//! and plans anew as it sees more; a step onto ground never seen may cost more than one onto
//! ground seen open ([`Guide::unknown_cost`]), so that the way round prefers the doorways the
//! rays have looked through. The walker's memory of a dwelling it walks for the first time, in
//! place of the whole map a guide would otherwise be given.

use glam::DVec2;

use super::obstacle::Obstacle2;
use super::path_plan::{guide_aim, Guide};
use super::walkable::WalkableMap;

/// Where a walker at `at` bound for `goal` should head ([`guide_aim`] by `guide`): planned on
/// its memory when it keeps one — what stands is there where its rays met it, so `obstacles`
/// are not added; ground never seen costs [`Guide::unknown_cost`] more — otherwise on the
/// whole `map` round `obstacles`.
pub(crate) fn guide_aim_remembered(
    seen: Option<&SeenMap>,
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    at: DVec2,
    goal: DVec2,
    guide: &Guide,
) -> DVec2 {
    match seen {
        Some(seen) if guide.lookahead_m > 0.0 => {
            let dislike =
                (guide.unknown_cost > 0.0).then(|| seen.unknown_costs(guide.unknown_cost));
            guide_aim(&seen.believed(), &[], at, goal, guide, dislike.as_deref())
        }
        _ => guide_aim(map, obstacles, at, goal, guide, None),
    }
}

/// What is known of one cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
enum Seen {
    Unknown = 0,
    Open = 1,
    Blocked = 2,
}

/// A walker's memory of a map's grid (same origin, cell size and extent as the map it walks).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SeenMap {
    origin: DVec2,
    cell_m: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Seen>,
}

impl SeenMap {
    /// Nothing seen yet of `map`'s grid.
    pub(crate) fn unseen(map: &WalkableMap) -> Self {
        Self {
            origin: map.origin,
            cell_m: map.cell_m,
            nx: map.nx,
            ny: map.ny,
            cells: vec![Seen::Unknown; map.nx * map.ny],
        }
    }

    fn index(&self, p: DVec2) -> Option<usize> {
        let q = (p - self.origin) / self.cell_m;
        (q.x >= 0.0 && q.y >= 0.0 && (q.x as usize) < self.nx && (q.y as usize) < self.ny)
            .then(|| q.y as usize * self.nx + q.x as usize)
    }

    /// Records one ray from `origin` along the unit `dir`: the cells it crosses before
    /// `hit_m` are open, the cell it enters at `hit_m` blocked; with no hit, open up to
    /// `max_m`. The latest ray decides a cell (a person who stood there and left is forgotten
    /// once a ray crosses the cell again). Points off the grid are not kept.
    pub(crate) fn record_ray(&mut self, origin: DVec2, dir: DVec2, hit_m: Option<f64>, max_m: f64) {
        if !(origin.is_finite() && dir.is_finite()) {
            return;
        }
        let end = hit_m.unwrap_or(max_m).clamp(0.0, max_m.max(0.0));
        let step = 0.25 * self.cell_m;
        let mut t = 0.0;
        while t < end {
            if let Some(k) = self.index(origin + dir * t) {
                self.cells[k] = Seen::Open;
            }
            t += step;
        }
        if let Some(hit) = hit_m {
            if let Some(k) = self.index(origin + dir * (hit + 0.01 * self.cell_m)) {
                self.cells[k] = Seen::Blocked;
            }
        }
    }

    /// The map as the walker believes it: every cell walkable but those seen blocked (cells
    /// off the grid block, as on every map).
    pub(crate) fn believed(&self) -> WalkableMap {
        let mut map = WalkableMap::from_walkable(
            self.origin,
            self.cell_m,
            self.nx,
            self.ny,
            self.cells.iter().map(|&c| c != Seen::Blocked).collect(),
        );
        // Nothing seen blocked: no boundary to measure from; the grid's diagonal stands in for
        // the infinite distance (bilinear reads of infinity give NaN).
        let far = (self.nx as f64).hypot(self.ny as f64) * self.cell_m;
        map.sdf_m
            .iter_mut()
            .filter(|d| !d.is_finite())
            .for_each(|d| *d = far);
        map
    }

    /// The extra cost of a step onto each cell, row-major as the map's cells: `weight` where
    /// nothing was seen, 0 elsewhere ([`Guide::unknown_cost`]).
    fn unknown_costs(&self, weight: f64) -> Vec<f32> {
        self.cells
            .iter()
            .map(|&c| {
                if c == Seen::Unknown {
                    weight as f32
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Cells seen open and seen blocked.
    #[cfg(test)]
    pub(crate) fn seen_cells(&self) -> (usize, usize) {
        let count = |s: Seen| self.cells.iter().filter(|&&c| c == s).count();
        (count(Seen::Open), count(Seen::Blocked))
    }

    /// The memory as bytes, one a cell (0 unknown, 1 open, 2 blocked), row-major: what a
    /// checkpoint keeps.
    pub(crate) fn to_bytes(&self) -> Vec<u8> {
        self.cells.iter().map(|&c| c as u8).collect()
    }

    /// A memory of `map`'s grid from [`Self::to_bytes`]; `None` when the bytes do not fit
    /// the grid.
    pub(crate) fn from_bytes(map: &WalkableMap, bytes: &[u8]) -> Option<Self> {
        let mut seen = Self::unseen(map);
        if bytes.len() != seen.cells.len() {
            return None;
        }
        for (c, &b) in seen.cells.iter_mut().zip(bytes) {
            *c = match b {
                0 => Seen::Unknown,
                1 => Seen::Open,
                2 => Seen::Blocked,
                _ => return None,
            };
        }
        Some(seen)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6 × 4 m room split by a wall at x = 3 m with a 1 m doorway at its top (y 3–4 m).
    fn split_room() -> WalkableMap {
        let (nx, ny) = (60, 40);
        let walkable = (0..nx * ny)
            .map(|k| {
                let (i, j) = (k % nx, k / nx);
                !((29..31).contains(&i) && j < 30)
            })
            .collect();
        WalkableMap::from_walkable(DVec2::ZERO, 0.1, nx, ny, walkable)
    }

    fn look(seen: &mut SeenMap, map: &WalkableMap, at: DVec2, heading: f64) {
        for k in 0..32 {
            let a = heading - std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * k as f64 / 31.0;
            let dir = DVec2::from_angle(a);
            // The first blocked cell along the ray, marched in hundredths of a cell.
            let hit = (0..7000)
                .map(|k| k as f64 * 0.001)
                .find(|&t| !map.is_walkable_at(at + dir * t));
            seen.record_ray(at, dir, hit, 7.0);
        }
    }

    /// A guide 2 m ahead on the shortest path, unknown ground costing `unknown_cost` more.
    fn guide(unknown_cost: f64) -> Guide {
        Guide {
            lookahead_m: 2.0,
            centre_weight: 0.0,
            unknown_cost,
        }
    }

    #[test]
    fn a_guide_that_dislikes_the_unknown_keeps_to_ground_seen_open() {
        // A 6 × 4 m floor, open but for a wall along its top edge; the walker has seen only a
        // way round by the top (up, across, down), not the straight way from (1, 1) to (5, 1).
        let walkable = (0..2400).map(|k| k / 60 < 39).collect();
        let map = WalkableMap::from_walkable(DVec2::ZERO, 0.1, 60, 40, walkable);
        let (at, goal) = (DVec2::new(1.0, 1.0), DVec2::new(5.0, 1.0));
        let mut seen = SeenMap::unseen(&map);
        let corners = [at, DVec2::new(1.0, 3.5), DVec2::new(5.0, 3.5), goal];
        for w in corners.windows(2) {
            let d = w[1] - w[0];
            seen.record_ray(w[0], d.normalize(), None, d.length());
        }
        let aim_with = |seen: &SeenMap, cost: f64| {
            guide_aim_remembered(Some(seen), &map, &[], at, goal, &guide(cost))
        };
        // Taken as open, the unknown straight way is the shortest: the goal itself.
        assert_eq!(aim_with(&seen, 0.0), goal);
        // Four times dearer, the 4 m unknown straight way (20 m) loses to the 9 m seen round
        // the top: the aim is up the seen way.
        let aim = aim_with(&seen, 4.0);
        assert!(aim.y > 2.5 && (aim.x - 1.0).abs() < 0.3, "aim {aim}");
        // A little dearer, the straight way still wins: the goal itself.
        assert_eq!(aim_with(&seen, 0.1), goal);
        // Once the straight way has been seen open (all but the goal's own cell), the planned
        // way keeps to it and the goal itself is aimed at.
        seen.record_ray(at, DVec2::X, None, 4.0);
        assert_eq!(aim_with(&seen, 4.0), goal);
        // On the whole map the cost changes nothing.
        let whole = guide_aim_remembered(None, &map, &[], at, goal, &guide(4.0));
        assert_eq!(whole, goal);
    }

    #[test]
    fn a_guide_on_what_was_seen_goes_round_seen_walls_only() {
        let map = split_room();
        let (at, goal) = (DVec2::new(1.0, 1.0), DVec2::new(5.0, 1.0));
        let mut seen = SeenMap::unseen(&map);
        // Nothing seen: the goal straight ahead, through the wall the walker has not seen.
        let aim = guide_aim(&seen.believed(), &[], at, goal, &guide(0.0), None);
        assert_eq!(aim, goal);
        // Looking at the wall: round its end seen open at the top, not through it.
        look(&mut seen, &map, at, 0.0);
        let (open, blocked) = seen.seen_cells();
        assert!(open > 100 && blocked > 5, "{open} open, {blocked} blocked");
        let aim = guide_aim(&seen.believed(), &[], at, goal, &guide(0.0), None);
        assert!(aim != goal && aim.y > at.y + 0.5, "aim {aim}");
        // The whole map's guide agrees on the side.
        let full = guide_aim(&map, &[], at, goal, &guide(0.0), None);
        assert!((aim - full).length() < 0.8, "{aim} against {full}");
        // A memory survives its bytes.
        let back = SeenMap::from_bytes(&map, &seen.to_bytes()).unwrap();
        assert_eq!(back, seen);
        assert!(SeenMap::from_bytes(&map, &[0; 3]).is_none());
        assert!(SeenMap::from_bytes(&map, &vec![7; 2400]).is_none());
    }
}
