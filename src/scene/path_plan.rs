//! Shortest walking paths on a walkable map: A* over its cells (8-connected, octile step
//! costs), keeping `clearance_m` from anything that blocks walking and from extra 2D
//! obstacles (other people, moving boxes where they stand now). The planner of the
//! path-following baseline (`synth::crowd`, steering `path_follow`), in the spirit of
//! GAMMA's and DIMOS's A* paths, and of the guide ([`guide_aim`]) that shows a policy where
//! to head when a wall hides its goal. Also the walking distance to one goal from every cell
//! ([`PathField`], Dijkstra on the same grid without clearance), which a training reward can
//! pay progress along (`EnvSettings::goal_by_path`).

use glam::DVec2;
use pathfinding::prelude::astar;

use super::obstacle::Obstacle2;
use super::walkable::WalkableMap;

/// Clearance of the guide's straight-line test and path (m): a doorway of 0.8 m leaves a
/// lane of 0.2 m.
pub(crate) const GUIDE_CLEARANCE_M: f64 = 0.3;

/// Distance from what blocks walking at which a centred guide's path stops paying for being
/// near it ([`plan_path_centred`]): the middle of a 0.9 m doorway.
pub(crate) const GUIDE_CENTRE_M: f64 = 0.45;

/// Integer costs: one cell straight, √2 diagonal, in thousandths of a cell.
const STRAIGHT: u32 = 1000;
const DIAGONAL: u32 = 1414;

/// A cell's eight neighbours, straight ones first.
const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, 0),
    (1, 0),
    (0, -1),
    (0, 1),
    (-1, -1),
    (-1, 1),
    (1, -1),
    (1, 1),
];

/// The steps from cell `(i, j)` to those of its eight neighbours that `free` allows, with
/// their costs: straight ones, and diagonal ones only where both cells beside the diagonal are
/// free (a step may not cut a blocked corner). `free` is asked about cells off the grid too.
fn steps(
    i: i64,
    j: i64,
    free: impl Fn(i64, i64) -> bool,
) -> impl Iterator<Item = ((i64, i64), u32)> {
    NEIGHBOURS.into_iter().filter_map(move |(di, dj)| {
        let (ni, nj) = (i + di, j + dj);
        let diagonal = di != 0 && dj != 0;
        (free(ni, nj) && (!diagonal || (free(ni, j) && free(i, nj))))
            .then_some(((ni, nj), if diagonal { DIAGONAL } else { STRAIGHT }))
    })
}

/// A planned path: points from the start to the goal (cell centres between them).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PlannedPath {
    pub points: Vec<DVec2>,
    /// Whether the planner found a way; `false`: the straight line from start to goal (the
    /// goal is walled off, or occupied for now).
    pub found: bool,
}

impl PlannedPath {
    /// Length along the path (m).
    #[cfg(test)]
    pub(crate) fn length_m(&self) -> f64 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    /// The point `distance_m` along the path from its start (the goal beyond its end).
    pub(crate) fn point_along(&self, distance_m: f64) -> DVec2 {
        let mut left = distance_m.max(0.0);
        for w in self.points.windows(2) {
            let d = w[0].distance(w[1]);
            if left <= d && d > 0.0 {
                return w[0] + (w[1] - w[0]) * (left / d);
            }
            left -= d;
        }
        *self
            .points
            .last()
            .expect("a path has at least its start and goal")
    }
}

/// Plans from `from` to `to` (see the module docs). The start's own cell is always usable
/// (a body standing near a wall can still leave it); the goal's cell must be free.
pub(crate) fn plan_path(
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    clearance_m: f64,
    from: DVec2,
    to: DVec2,
) -> PlannedPath {
    plan_path_centred(map, obstacles, clearance_m, 0.0, from, to)
}

/// [`plan_path`], a step onto a cell closer than [`GUIDE_CENTRE_M`] to what blocks walking
/// costing more, by up to `centre_weight` times its length at the clearance (in proportion to
/// how far short of [`GUIDE_CENTRE_M`] the cell falls): the path keeps to the middle of a 0.9 m
/// doorway or a corridor instead of grazing its side at the clearance, where a body's swinging
/// hands brush the frame. 0: [`plan_path`]. The octile heuristic stays admissible (steps only
/// cost more).
pub(crate) fn plan_path_centred(
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    clearance_m: f64,
    centre_weight: f64,
    from: DVec2,
    to: DVec2,
) -> PlannedPath {
    plan_path_weighted(map, obstacles, clearance_m, centre_weight, None, from, to)
}

/// [`plan_path_centred`], a step onto cell `k` (row-major, as the map's cells) costing
/// `extra[k]` times its length more besides: a planner's dislike of some ground (a guide on
/// memory, of cells the walker never saw: [`Guide::unknown_cost`]). `None` or all zeros:
/// [`plan_path_centred`]. The heuristic stays admissible (steps only cost more).
pub(crate) fn plan_path_weighted(
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    clearance_m: f64,
    centre_weight: f64,
    extra: Option<&[f32]>,
    from: DVec2,
    to: DVec2,
) -> PlannedPath {
    let straight = PlannedPath {
        points: vec![from, to],
        found: false,
    };
    let (Some(start), Some(goal)) = (map.cell_of(from), map.cell_of(to)) else {
        return straight;
    };
    debug_assert!(extra.is_none_or(|e| e.len() == map.nx * map.ny));
    let extra = extra.filter(|e| e.len() == map.nx * map.ny);
    let grown: Vec<Obstacle2> = obstacles.iter().map(|o| o.grown(clearance_m)).collect();
    let free = |(i, j): (usize, usize)| {
        let k = j * map.nx + i;
        (i, j) == start
            || (map.walkable[k]
                && map.sdf_m[k] >= clearance_m
                && !grown.iter().any(|o| o.contains(map.centre(i, j))))
    };
    if !free(goal) {
        return straight;
    }
    let octile = |(i, j): &(usize, usize)| {
        let dx = i.abs_diff(goal.0) as u32;
        let dy = j.abs_diff(goal.1) as u32;
        let (lo, hi) = (dx.min(dy), dx.max(dy));
        DIAGONAL * lo + STRAIGHT * (hi - lo)
    };
    let centre_m = GUIDE_CENTRE_M.max(clearance_m);
    let in_grid = |i: i64, j: i64| i >= 0 && j >= 0 && i < map.nx as i64 && j < map.ny as i64;
    let successors = |&(i, j): &(usize, usize)| {
        steps(i as i64, j as i64, |i, j| {
            in_grid(i, j) && free((i as usize, j as usize))
        })
        .map(|((i, j), cost)| {
            let (i, j) = (i as usize, j as usize);
            let short = if centre_m > clearance_m {
                ((centre_m - map.sdf_m[j * map.nx + i]) / (centre_m - clearance_m)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let dislike = extra.map_or(0.0, |e| f64::from(e[j * map.nx + i]));
            (
                (i, j),
                cost + (f64::from(cost) * (centre_weight * short + dislike)).round() as u32,
            )
        })
        .collect::<Vec<_>>()
    };
    match astar(&start, successors, octile, |c| *c == goal) {
        Some((cells, _)) => {
            let mut points = Vec::with_capacity(cells.len() + 1);
            points.push(from);
            points.extend(
                cells
                    .iter()
                    .skip(1)
                    .take(cells.len().saturating_sub(2))
                    .map(|&(i, j)| map.centre(i, j)),
            );
            points.push(to);
            PlannedPath {
                points,
                found: true,
            }
        }
        None => straight,
    }
}

/// Whether the straight way from `a` to `b` stays on walkable ground `clearance_m` from
/// anything blocking and from `obstacles` (points every half cell; the first and last
/// `clearance_m` are not tested, where a body may stand close to a wall).
pub(crate) fn line_is_clear(
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    clearance_m: f64,
    a: DVec2,
    b: DVec2,
) -> bool {
    let length = a.distance(b);
    if length == 0.0 {
        return true;
    }
    let grown: Vec<Obstacle2> = obstacles.iter().map(|o| o.grown(clearance_m)).collect();
    let steps = (length / (0.5 * map.cell_m)).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|k| k as f64 / steps as f64 * length)
        .filter(|&d| d >= clearance_m && d <= length - clearance_m)
        .map(|d| a + (b - a) * (d / length))
        .all(|p| {
            map.is_walkable_at(p)
                && map.sdf_at(p) >= clearance_m
                && !grown.iter().any(|o| o.contains(p))
        })
}

/// How a guide shows a walker the way round what hides its goal (the `guide_*` settings of
/// training, `egogen policy eval`, `egogen synth` and `egogen-run`); its path keeps
/// [`GUIDE_CLEARANCE_M`] from what blocks walking.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Guide {
    /// The aim: the point this far (m) along the planned path; 0: no guide (the goal itself).
    pub lookahead_m: f64,
    /// How strongly the path keeps to the middle of doorways and corridors
    /// ([`plan_path_centred`]); 0: the shortest path at the clearance.
    pub centre_weight: f64,
    /// On the walker's memory (`scene::SeenMap`): a step onto a cell it never saw costs this
    /// many times its length more than one onto a cell seen open — the way round prefers the
    /// doorways its rays looked through to walls it has not seen yet. 0: the unknown taken as
    /// open at no extra cost. Unused on a whole map.
    pub unknown_cost: f64,
}

/// Where a walker at `at` bound for `goal` should head, by `guide`: the goal itself while the
/// straight way to it is clear ([`line_is_clear`] at [`GUIDE_CLEARANCE_M`]) and, where
/// `dislike` makes some ground dearer (a half cell on cell `k` costing `1 + dislike[k]`), no
/// dearer than the path planned on it; otherwise the point `guide.lookahead_m` along the path
/// planned around what blocks it ([`plan_path_weighted`]; pure pursuit), or the goal when no
/// path is found. A lookahead of 0 (no guide) gives the goal. Stateless: the path is planned
/// anew from where the walker stands.
pub(crate) fn guide_aim(
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    at: DVec2,
    goal: DVec2,
    guide: &Guide,
    dislike: Option<&[f32]>,
) -> DVec2 {
    if !(guide.lookahead_m > 0.0) {
        return goal;
    }
    let clear = line_is_clear(map, obstacles, GUIDE_CLEARANCE_M, at, goal);
    if clear && dislike.is_none() {
        return goal;
    }
    let path = plan_path_weighted(
        map,
        obstacles,
        GUIDE_CLEARANCE_M,
        guide.centre_weight,
        dislike,
        at,
        goal,
    );
    // A clear straight way no dearer than the planned one (a disliked stretch on it not worth
    // a detour): the goal itself.
    let straight_is_cheaper = || {
        let d = dislike.unwrap_or_default();
        weighted_length(map, d, &[at, goal]) <= weighted_length(map, d, &path.points)
    };
    if path.found && !(clear && straight_is_cheaper()) {
        path.point_along(guide.lookahead_m)
    } else {
        goal
    }
}

/// The length of a polyline with each stretch of it weighed by the ground it crosses: a half
/// cell on cell `k` counts `1 + dislike[k]` times (1 off the grid or where `dislike` is empty).
fn weighted_length(map: &WalkableMap, dislike: &[f32], points: &[DVec2]) -> f64 {
    let weight = |p: DVec2| {
        map.cell_of(p)
            .and_then(|(i, j)| dislike.get(j * map.nx + i))
            .map_or(1.0, |&c| 1.0 + f64::from(c))
    };
    points
        .windows(2)
        .map(|w| {
            let length = w[0].distance(w[1]);
            let n = (length / (0.5 * map.cell_m)).ceil().max(1.0) as usize;
            (0..n)
                .map(|k| weight(w[0].lerp(w[1], (k as f64 + 0.5) / n as f64)))
                .sum::<f64>()
                * (length / n as f64)
        })
        .sum()
}

/// Walking distance to one goal from every cell of a map: Dijkstra from the goal's cell over
/// walkable cells (8-connected, octile steps, no cut corners), for a reward that pays the
/// progress a walk makes along the way round walls rather than straight at the goal.
#[derive(Debug, Clone)]
pub struct PathField {
    origin: DVec2,
    cell_m: f64,
    nx: usize,
    ny: usize,
    /// Metres from the cell's centre to the goal; infinite where the goal cannot be reached.
    distance_m: Vec<f32>,
}

impl PathField {
    /// The field of `goal` on `map`; `None` when the goal lies off the grid or not on a
    /// walkable cell.
    pub(crate) fn to_goal(map: &WalkableMap, goal: DVec2) -> Option<PathField> {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;

        let (gi, gj) = map.cell_of(goal)?;
        if !map.walkable[gj * map.nx + gi] {
            return None;
        }
        let free = |i: i64, j: i64| !map.blocked(i, j);
        let mut cost = vec![u32::MAX; map.nx * map.ny];
        let mut heap = BinaryHeap::new();
        // The goal's cell and its free neighbours start at their straight distance to the goal.
        let to_cost = |d: f64| (d / map.cell_m * STRAIGHT as f64).round() as u32;
        for (di, dj) in std::iter::once((0, 0)).chain(NEIGHBOURS) {
            let (i, j) = (gi as i64 + di, gj as i64 + dj);
            if free(i, j) {
                let c = to_cost(goal.distance(map.centre(i as usize, j as usize)));
                cost[j as usize * map.nx + i as usize] = c;
                heap.push(Reverse((c, i as u32, j as u32)));
            }
        }
        while let Some(Reverse((c, i, j))) = heap.pop() {
            let (i, j) = (i as i64, j as i64);
            if c > cost[j as usize * map.nx + i as usize] {
                continue;
            }
            for ((ni, nj), step) in steps(i, j, free) {
                let next = c + step;
                let k = nj as usize * map.nx + ni as usize;
                if next < cost[k] {
                    cost[k] = next;
                    heap.push(Reverse((next, ni as u32, nj as u32)));
                }
            }
        }
        let distance_m = cost
            .iter()
            .map(|&c| match c {
                u32::MAX => f32::INFINITY,
                c => (c as f64 / STRAIGHT as f64 * map.cell_m) as f32,
            })
            .collect();
        Some(PathField {
            origin: map.origin,
            cell_m: map.cell_m,
            nx: map.nx,
            ny: map.ny,
            distance_m,
        })
    }

    /// Walking distance (m) from a point to the goal, bilinear between the four nearest cell
    /// centres that reach the goal; `None` where none of them does.
    pub(crate) fn at(&self, p: DVec2) -> Option<f64> {
        if !p.is_finite() {
            return None;
        }
        let q = (p - self.origin) / self.cell_m - DVec2::splat(0.5);
        let (i0, j0) = (q.x.floor(), q.y.floor());
        let (fx, fy) = (q.x - i0, q.y - j0);
        let (mut sum, mut weight) = (0.0, 0.0);
        for (di, dj, w) in [
            (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
            (1.0, 0.0, fx * (1.0 - fy)),
            (0.0, 1.0, (1.0 - fx) * fy),
            (1.0, 1.0, fx * fy),
        ] {
            let (i, j) = (i0 + di, j0 + dj);
            if i < 0.0 || j < 0.0 || i >= self.nx as f64 || j >= self.ny as f64 || w <= 0.0 {
                continue;
            }
            let d = self.distance_m[j as usize * self.nx + i as usize];
            if d.is_finite() {
                sum += w * d as f64;
                weight += w;
            }
        }
        (weight > 0.0).then(|| sum / weight)
    }

    /// The way to the goal from a point: the unit direction in which the walking distance
    /// falls fastest (central differences over one cell); `None` where it cannot be told.
    pub(crate) fn way_at(&self, p: DVec2) -> Option<DVec2> {
        let h = self.cell_m;
        let dx = self.at(p + DVec2::X * h)? - self.at(p - DVec2::X * h)?;
        let dy = self.at(p + DVec2::Y * h)? - self.at(p - DVec2::Y * h)?;
        let down = -DVec2::new(dx, dy);
        (down.length() > 1e-9).then(|| down.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 m × 3 m room split by a wall at x = 2 m with a doorway at its top end.
    fn split_room() -> WalkableMap {
        let (nx, ny, cell) = (40usize, 30usize, 0.1);
        let walkable: Vec<bool> = (0..nx * ny)
            .map(|k| {
                let (i, j) = (k % nx, k / nx);
                !(i == 20 && j < 24)
            })
            .collect();
        WalkableMap::from_walkable(DVec2::ZERO, cell, nx, ny, walkable)
    }

    /// Where a path crosses the line x = `x` (m), by linear interpolation between its points.
    fn crossing_y(path: &PlannedPath, x: f64) -> f64 {
        let w = path
            .points
            .windows(2)
            .find(|w| (w[0].x - x) * (w[1].x - x) <= 0.0 && w[0].x != w[1].x)
            .expect("the path crosses the line");
        w[0].y + (w[1].y - w[0].y) * (x - w[0].x) / (w[1].x - w[0].x)
    }

    #[test]
    fn a_centred_path_passes_a_doorway_in_its_middle() {
        // A 6 m × 4 m room split at x = 3 m by a wall with a 0.9 m doorway, y in [1.5, 2.4].
        let (nx, ny, cell) = (60usize, 40usize, 0.1);
        let walkable: Vec<bool> = (0..nx * ny)
            .map(|k| {
                let (i, j) = (k % nx, k / nx);
                i != 30 || (15..24).contains(&j)
            })
            .collect();
        let map = WalkableMap::from_walkable(DVec2::ZERO, cell, nx, ny, walkable);
        // From low on one side to high on the other: the shortest way grazes the doorway's
        // lower frame at the clearance, the centred one keeps to its middle (y = 1.95).
        let (from, to) = (DVec2::new(1.0, 0.5), DVec2::new(5.0, 3.5));
        let shortest = plan_path(&map, &[], GUIDE_CLEARANCE_M, from, to);
        let centred = plan_path_centred(&map, &[], GUIDE_CLEARANCE_M, 2.0, from, to);
        assert!(shortest.found && centred.found);
        let middle = 1.95;
        let (y_short, y_centred) = (crossing_y(&shortest, 3.05), crossing_y(&centred, 3.05));
        assert!(
            (y_centred - middle).abs() < 0.1,
            "centred crosses at {y_centred}"
        );
        assert!(
            (y_short - middle).abs() > (y_centred - middle).abs() + 0.05,
            "shortest at {y_short}, centred at {y_centred}"
        );
        // A little longer, never much: the detour is inside the doorway's approach.
        assert!(centred.length_m() >= shortest.length_m() - 1e-9);
        assert!(centred.length_m() < shortest.length_m() + 0.5);
        // Weight 0 is the shortest path itself.
        assert_eq!(
            plan_path_centred(&map, &[], GUIDE_CLEARANCE_M, 0.0, from, to),
            shortest
        );
    }

    #[test]
    fn the_walking_distance_goes_round_the_wall_and_points_to_the_doorway() {
        let map = split_room();
        let goal = DVec2::new(3.0, 0.5);
        let field = PathField::to_goal(&map, goal).expect("the goal stands on the floor");
        assert!(field.at(goal).unwrap() < 0.1);
        // Across the wall: 2 m apart in a straight line, about 1.9 + 2 + 1.9 m round it.
        let start = DVec2::new(1.0, 0.5);
        let round = field.at(start).unwrap();
        assert!(round > 4.5 && round < 6.0, "{round}");
        // The way from the start leads up, to the doorway, not across the wall to the goal.
        let way = field.way_at(start).unwrap();
        assert!(way.y > 0.9, "{way:?}");
        // Beside the goal, in its own half, the way leads at it.
        let way = field.way_at(DVec2::new(3.0, 1.5)).unwrap();
        assert!(way.y < -0.9, "{way:?}");
        // Off the grid and on the wall's cells: no distance there, but beside it there is.
        assert!(field.at(DVec2::new(-5.0, 0.5)).is_none());
        assert!(field.at(DVec2::new(2.05, 0.5)).is_some());
        assert!(PathField::to_goal(&map, DVec2::new(2.05, 0.5)).is_none());
    }
}
