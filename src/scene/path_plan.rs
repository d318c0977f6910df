//! Shortest walking paths on a walkable map: A* over its cells (8-connected, octile step
//! costs), keeping `clearance_m` from anything that blocks walking and from extra 2D
//! obstacles (other people, moving boxes where they stand now). The planner of the
//! path-following baseline (`synth::crowd`, steering `path_follow`), in the spirit of
//! GAMMA's and DIMOS's A* paths, and of the guide ([`guide_aim`]) that shows a policy where
//! to head when a wall hides its goal.

use glam::DVec2;
use pathfinding::prelude::astar;

use super::obstacle::Obstacle2;
use super::walkable::WalkableMap;

/// Clearance of the guide's straight-line test and path (m): a doorway of 0.8 m leaves a
/// lane of 0.2 m.
pub const GUIDE_CLEARANCE_M: f64 = 0.3;

/// Integer costs: one cell straight, √2 diagonal, in thousandths of a cell.
const STRAIGHT: u32 = 1000;
const DIAGONAL: u32 = 1414;

/// A planned path: points from the start to the goal (cell centres between them).
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedPath {
    pub points: Vec<DVec2>,
    /// Whether the planner found a way; `false`: the straight line from start to goal (the
    /// goal is walled off, or occupied for now).
    pub found: bool,
}

impl PlannedPath {
    /// Length along the path (m).
    pub fn length_m(&self) -> f64 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    /// The point `distance_m` along the path from its start (the goal beyond its end).
    pub fn point_along(&self, distance_m: f64) -> DVec2 {
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
pub fn plan_path(
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    clearance_m: f64,
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
    let successors = |&(i, j): &(usize, usize)| {
        let mut next = Vec::with_capacity(8);
        for (di, dj) in [
            (-1i64, 0i64),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (-1, 1),
            (1, -1),
            (1, 1),
        ] {
            let (ni, nj) = (i as i64 + di, j as i64 + dj);
            if ni < 0 || nj < 0 || ni >= map.nx as i64 || nj >= map.ny as i64 {
                continue;
            }
            let c = (ni as usize, nj as usize);
            // A diagonal step may not cut a blocked corner.
            let corner_free =
                di == 0 || dj == 0 || (free((ni as usize, j)) && free((i, nj as usize)));
            if free(c) && corner_free {
                next.push((
                    c,
                    if di != 0 && dj != 0 {
                        DIAGONAL
                    } else {
                        STRAIGHT
                    },
                ));
            }
        }
        next
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
pub fn line_is_clear(
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

/// Where a walker at `at` bound for `goal` should head: the goal itself while the straight
/// way to it is clear ([`line_is_clear`]); otherwise the point `lookahead_m` along the
/// shortest path planned around what blocks it (pure pursuit), or the goal when no path is
/// found. A lookahead of 0 (no guide) gives the goal. Stateless: the path is planned anew
/// from where the walker stands.
pub fn guide_aim(
    map: &WalkableMap,
    obstacles: &[Obstacle2],
    clearance_m: f64,
    at: DVec2,
    goal: DVec2,
    lookahead_m: f64,
) -> DVec2 {
    if !(lookahead_m > 0.0) || line_is_clear(map, obstacles, clearance_m, at, goal) {
        return goal;
    }
    let path = plan_path(map, obstacles, clearance_m, at, goal);
    if path.found {
        path.point_along(lookahead_m)
    } else {
        goal
    }
}
