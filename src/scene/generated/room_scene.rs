//! Procedural floor plans: a dwelling drawn anew for every episode, so that a policy can learn
//! to find its way through rooms and doorways without walking one apartment over and over, and
//! be tested in a scene it never saw.
//!
//! A plan is a rectangle of U(`size_m`) × U(`size_m`) m ringed by an outer wall, split into
//! U(`rooms`) rooms by binary space partition: the largest room is cut across its longer side
//! at U(`min_room_m`, side − `min_room_m`) by a wall `wall_m` thick with one doorway
//! U(`door_m`) wide, kept 0.3 m from the wall's ends; a wall never ends in another's doorway.
//! Furniture — U(`furniture`) boxes of sides U(`furniture_side_m`), three in four square to the
//! walls, the rest at a random yaw — stands in random rooms, clear of every doorway by
//! `door_clearance_m`. The start and goal lie on cells at least `clearance_m` from anything
//! blocked, in the same connected floor, U(`distance_m`) apart in a straight line (often in
//! different rooms). Only the 0.1 m walkable map is built, ringed by a wall of blocked cells:
//! the rays and Eq. 7's blocked cells read it as they read a box scene's.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;
use serde::{Deserialize, Serialize};

use crate::math::random::{uniform_in, uniform_open01};
use crate::scene::{Obstacle2, WalkableMap};

/// Floor plans drawn before a scene is kept even without a start/goal pair in range (a plan
/// where furniture cut the floor into small pieces).
const MAX_PLAN_TRIES: usize = 50;

/// How floor plans are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RoomSettings {
    /// Share of the episodes outside the fixed scene that walk a floor plan (0: none); the
    /// crossing share applies to the rest.
    pub share: f64,
    /// Range of each side of the dwelling (m).
    pub size_m: (f64, f64),
    /// Range of the number of rooms (inner walls + 1).
    pub rooms: (usize, usize),
    /// Least side of a room (m); a room too small to cut stays whole.
    pub min_room_m: f64,
    /// Thickness of inner walls (m).
    pub wall_m: f64,
    /// Range of doorway widths (m).
    pub door_m: (f64, f64),
    /// Range of the number of furniture boxes.
    pub furniture: (usize, usize),
    /// Range of a box's side lengths (m).
    pub furniture_side_m: (f64, f64),
    /// Least distance from a doorway's centre to furniture (m).
    pub door_clearance_m: f64,
    /// Least distance from the start and goal to anything blocked (m).
    pub clearance_m: f64,
    /// Range of the straight-line start–goal distance (m).
    pub distance_m: (f64, f64),
    /// Cell size of the walkable map (m).
    pub cell_m: f64,
    /// Primitives before an episode times out (EgoGen's apartment: 13).
    pub max_primitives: usize,
}

impl Default for RoomSettings {
    fn default() -> Self {
        Self {
            share: 0.0,
            size_m: (5.0, 10.0),
            rooms: (2, 4),
            min_room_m: 2.0,
            wall_m: 0.15,
            door_m: (0.8, 1.1),
            furniture: (2, 6),
            furniture_side_m: (0.4, 1.6),
            door_clearance_m: 0.9,
            clearance_m: 0.4,
            distance_m: (2.0, 7.0),
            cell_m: 0.1,
            max_primitives: 13,
        }
    }
}

impl RoomSettings {
    /// Whether the ranges can be drawn from: shares in [0, 1], MIN ≤ MAX, positive sizes, a
    /// room count ≥ 1, at least one 0.1 m of floor per room.
    pub(crate) fn is_valid(&self) -> bool {
        let range = |(lo, hi): (f64, f64)| lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi;
        (0.0..=1.0).contains(&self.share)
            && range(self.size_m)
            && range(self.door_m)
            && range(self.furniture_side_m)
            && range(self.distance_m)
            && (1..=self.rooms.1).contains(&self.rooms.0)
            && self.furniture.0 <= self.furniture.1
            && self.min_room_m.is_finite()
            && self.min_room_m > 0.0
            && self.wall_m.is_finite()
            && self.wall_m > 0.0
            && self.door_clearance_m.is_finite()
            && self.door_clearance_m >= 0.0
            && self.clearance_m.is_finite()
            && self.clearance_m >= 0.0
            && self.cell_m.is_finite()
            && self.cell_m > 0.0
            && self.size_m.1 / self.cell_m <= 1000.0
            && self.max_primitives >= 1
    }
}

/// An inner wall: along x (`along_x`, at y = `at_m`) or along y (at x = `at_m`), from `from_m`
/// to `to_m` on its own axis, with a doorway of `door_width_m` centred at `door_m`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    pub along_x: bool,
    pub at_m: f64,
    pub from_m: f64,
    pub to_m: f64,
    pub door_m: f64,
    pub door_width_m: f64,
}

impl Wall {
    /// The doorway's centre.
    pub(crate) fn door_centre(&self) -> DVec2 {
        if self.along_x {
            DVec2::new(self.door_m, self.at_m)
        } else {
            DVec2::new(self.at_m, self.door_m)
        }
    }

    /// Whether a point lies in the wall (`half_m` either side of its line), not in its doorway.
    fn blocks(&self, p: DVec2, half_m: f64) -> bool {
        let (along, across) = if self.along_x { (p.x, p.y) } else { (p.y, p.x) };
        (across - self.at_m).abs() <= half_m
            && (self.from_m..=self.to_m).contains(&along)
            && (along - self.door_m).abs() > self.door_width_m / 2.0
    }
}

/// A furniture box: centre, half extents along its own axes, yaw (rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Furniture {
    pub centre: [f64; 2],
    pub half_extents: [f64; 2],
    pub yaw_rad: f64,
}

impl Furniture {
    pub(crate) fn obstacle(&self) -> Obstacle2 {
        Obstacle2::Box {
            centre: DVec2::from_array(self.centre),
            half_extents: DVec2::from_array(self.half_extents),
            yaw_rad: self.yaw_rad,
        }
    }
}

/// What is drawn for a floor plan: the dwelling's size (centred on the origin), its walls and
/// furniture, the start and the goal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoomParams {
    pub size_m: [f64; 2],
    pub walls: Vec<Wall>,
    pub furniture: Vec<Furniture>,
    pub start: [f64; 2],
    pub goal: [f64; 2],
}

/// One drawn floor plan.
#[derive(Debug, Clone)]
pub struct RoomScene {
    pub map: WalkableMap,
    pub start: DVec2,
    pub goal: DVec2,
    pub params: RoomParams,
}

/// Heights of a floor plan's mesh ([`RoomParams::scene_mesh`], m).
pub(crate) const PLAN_WALL_HEIGHT_M: f64 = 2.5;
pub(crate) const PLAN_FURNITURE_HEIGHT_M: f64 = 0.8;
/// Thickness of the floor slab under the dwelling (its top at z = 0) and of the outer walls.
const PLAN_SLAB_M: f64 = 0.1;

impl RoomParams {
    /// The plan as a scene mesh (metres, z up, floor at z = 0): a floor slab, the outer walls
    /// ([`PLAN_WALL_HEIGHT_M`] high, their inner faces on the dwelling's edge), each inner
    /// wall as boxes either side of its doorway (`wall_m` thick), and the furniture as boxes
    /// [`PLAN_FURNITURE_HEIGHT_M`] high — a multi-room dwelling as a scene file would hold it,
    /// one object per part (`floor`, `outer_wall_k`, `wall_k_a`/`_b`, `furniture_k`).
    pub(crate) fn scene_mesh(&self, settings: &RoomSettings) -> crate::scene::SceneMesh {
        use crate::math::Vec3;
        let mut mesh = crate::scene::SceneMesh::default();
        let half = DVec2::from_array(self.size_m) / 2.0;
        let (h, t) = (PLAN_WALL_HEIGHT_M, PLAN_SLAB_M);
        mesh.add_box(
            "floor",
            Vec3::new(-half.x - t, -half.y - t, -t),
            Vec3::new(half.x + t, half.y + t, 0.0),
        );
        let outer = [
            (
                DVec2::new(-half.x - t, -half.y - t),
                DVec2::new(half.x + t, -half.y),
            ),
            (
                DVec2::new(-half.x - t, half.y),
                DVec2::new(half.x + t, half.y + t),
            ),
            (
                DVec2::new(-half.x - t, -half.y),
                DVec2::new(-half.x, half.y),
            ),
            (DVec2::new(half.x, -half.y), DVec2::new(half.x + t, half.y)),
        ];
        for (k, (lo, hi)) in outer.iter().enumerate() {
            mesh.add_box(
                format!("outer_wall_{k}"),
                Vec3::new(lo.x, lo.y, 0.0),
                Vec3::new(hi.x, hi.y, h),
            );
        }
        let w = settings.wall_m / 2.0;
        for (k, wall) in self.walls.iter().enumerate() {
            let pieces = [
                (wall.from_m, wall.door_m - wall.door_width_m / 2.0),
                (wall.door_m + wall.door_width_m / 2.0, wall.to_m),
            ];
            for ((a, b), side) in pieces.into_iter().zip(["a", "b"]) {
                if b - a <= 0.0 {
                    continue;
                }
                let (lo, hi) = if wall.along_x {
                    (DVec2::new(a, wall.at_m - w), DVec2::new(b, wall.at_m + w))
                } else {
                    (DVec2::new(wall.at_m - w, a), DVec2::new(wall.at_m + w, b))
                };
                mesh.add_box(
                    format!("wall_{k}_{side}"),
                    Vec3::new(lo.x, lo.y, 0.0),
                    Vec3::new(hi.x, hi.y, h),
                );
            }
        }
        for (k, f) in self.furniture.iter().enumerate() {
            mesh.add_turned_box(
                format!("furniture_{k}"),
                DVec2::from_array(f.centre),
                DVec2::from_array(f.half_extents),
                f.yaw_rad,
                (0.0, PLAN_FURNITURE_HEIGHT_M),
            );
        }
        mesh
    }
}

/// A room of the partition: its corners.
#[derive(Debug, Clone, Copy)]
struct Room {
    lo: DVec2,
    hi: DVec2,
}

impl RoomScene {
    /// Draws a floor plan and a start/goal pair on it with `rng`.
    pub fn sample(settings: &RoomSettings, rng: &mut ChaCha8Rng) -> Self {
        let mut tries = 0;
        loop {
            tries += 1;
            let (size, walls, furniture) = draw_plan(settings, rng);
            let mut params = RoomParams {
                size_m: size.to_array(),
                walls,
                furniture,
                start: [0.0; 2],
                goal: [0.0; 2],
            };
            let map = plan_map(settings, &params);
            let (start, goal) = match draw_pair(settings, &map, rng) {
                Some(pair) => pair,
                // A start and a goal on the floor's two farthest clear cells: an episode
                // still runs (ranges no plan can meet are the config's to fix).
                None if tries >= MAX_PLAN_TRIES => farthest_clear_pair(settings, &map),
                None => continue,
            };
            params.start = start.to_array();
            params.goal = goal.to_array();
            return Self {
                map,
                start,
                goal,
                params,
            };
        }
    }

    /// The scene of drawn parameters.
    pub(crate) fn build(settings: &RoomSettings, params: RoomParams) -> Self {
        Self {
            map: plan_map(settings, &params),
            start: DVec2::from_array(params.start),
            goal: DVec2::from_array(params.goal),
            params,
        }
    }
}

/// The dwelling's size, its inner walls and its furniture.
fn draw_plan(settings: &RoomSettings, rng: &mut ChaCha8Rng) -> (DVec2, Vec<Wall>, Vec<Furniture>) {
    let size = DVec2::new(
        uniform_in(rng, settings.size_m.0, settings.size_m.1),
        uniform_in(rng, settings.size_m.0, settings.size_m.1),
    );
    let count = draw_count(settings.rooms, rng);
    let mut rooms = vec![Room {
        lo: -size / 2.0,
        hi: size / 2.0,
    }];
    let mut walls = Vec::new();
    let min = settings.min_room_m + settings.wall_m / 2.0;
    while rooms.len() < count {
        // The largest room that can still be cut, across its longer side.
        let Some((index, room)) = rooms
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, r)| (r.hi - r.lo).max_element() >= 2.0 * min)
            .max_by(|(_, a), (_, b)| {
                let area = |r: &Room| (r.hi - r.lo).x * (r.hi - r.lo).y;
                area(a).total_cmp(&area(b))
            })
        else {
            break;
        };
        let side = room.hi - room.lo;
        let along_x = side.y >= side.x;
        let (cut_lo, cut_hi, span_lo, span_hi) = if along_x {
            (room.lo.y, room.hi.y, room.lo.x, room.hi.x)
        } else {
            (room.lo.x, room.hi.x, room.lo.y, room.hi.y)
        };
        // Where the new wall ends it meets the walls that bound its room: not in their
        // doorways (with a wall's thickness to spare).
        let meets_doorway = |at: f64| {
            walls.iter().any(|w: &Wall| {
                w.along_x != along_x
                    && ((w.at_m - span_lo).abs() < 1e-9 || (w.at_m - span_hi).abs() < 1e-9)
                    && (at - w.door_m).abs() < w.door_width_m / 2.0 + settings.wall_m
            })
        };
        let Some(at) = (0..20)
            .map(|_| uniform_in(rng, cut_lo + min, cut_hi - min))
            .find(|&at| !meets_doorway(at))
        else {
            break;
        };
        let width = uniform_in(rng, settings.door_m.0, settings.door_m.1)
            .min(span_hi - span_lo - 0.6)
            .max(0.0);
        let door = uniform_in(
            rng,
            span_lo + 0.3 + width / 2.0,
            span_hi - 0.3 - width / 2.0,
        );
        walls.push(Wall {
            along_x,
            at_m: at,
            from_m: span_lo,
            to_m: span_hi,
            door_m: door,
            door_width_m: width,
        });
        let (mut a, mut b) = (room, room);
        if along_x {
            a.hi.y = at;
            b.lo.y = at;
        } else {
            a.hi.x = at;
            b.lo.x = at;
        }
        rooms[index] = a;
        rooms.push(b);
    }
    let doors: Vec<DVec2> = walls.iter().map(Wall::door_centre).collect();
    let mut furniture = Vec::new();
    for _ in 0..draw_count(settings.furniture, rng) {
        for _ in 0..20 {
            let room = rooms[(rng.next_u64() % rooms.len() as u64) as usize];
            let (lo, hi) = settings.furniture_side_m;
            let half = DVec2::new(uniform_in(rng, lo, hi), uniform_in(rng, lo, hi)) / 2.0;
            let yaw = if uniform_open01(rng) < 0.75 {
                if rng.next_u64().is_multiple_of(2) {
                    0.0
                } else {
                    std::f64::consts::FRAC_PI_2
                }
            } else {
                uniform_in(rng, 0.0, std::f64::consts::PI)
            };
            // The box's axis-aligned half extents, to keep it inside its room.
            let (s, c) = yaw.sin_cos();
            let bound = DVec2::new(
                (c * half.x).abs() + (s * half.y).abs(),
                (s * half.x).abs() + (c * half.y).abs(),
            );
            let inner_lo = room.lo + bound + settings.wall_m / 2.0;
            let inner_hi = room.hi - bound - settings.wall_m / 2.0;
            if inner_lo.x >= inner_hi.x || inner_lo.y >= inner_hi.y {
                continue;
            }
            let centre = DVec2::new(
                uniform_in(rng, inner_lo.x, inner_hi.x),
                uniform_in(rng, inner_lo.y, inner_hi.y),
            );
            let item = Furniture {
                centre: centre.to_array(),
                half_extents: half.to_array(),
                yaw_rad: yaw,
            };
            let grown = item.obstacle().grown(settings.door_clearance_m);
            if doors.iter().any(|&d| grown.contains(d)) {
                continue;
            }
            furniture.push(item);
            break;
        }
    }
    (size, walls, furniture)
}

/// A count drawn uniformly from `lo..=hi`.
fn draw_count((lo, hi): (usize, usize), rng: &mut ChaCha8Rng) -> usize {
    lo + (rng.next_u64() % (hi.saturating_sub(lo) as u64 + 1)) as usize
}

/// The walkable map of a plan: a cell is blocked when its centre lies in a wall (outside its
/// doorway) or in furniture; a ring of blocked cells around the dwelling is its outer wall
/// (so that distances to it count, as to any wall).
fn plan_map(settings: &RoomSettings, params: &RoomParams) -> WalkableMap {
    let size = DVec2::from_array(params.size_m);
    let cell = settings.cell_m;
    let nx = (size.x / cell).round().max(1.0) as usize + 2;
    let ny = (size.y / cell).round().max(1.0) as usize + 2;
    let origin = -DVec2::new(nx as f64, ny as f64) * cell / 2.0;
    let obstacles: Vec<Obstacle2> = params.furniture.iter().map(Furniture::obstacle).collect();
    let walkable = (0..nx * ny)
        .map(|k| {
            let (i, j) = (k % nx, k / nx);
            let c = origin + (DVec2::new(i as f64, j as f64) + 0.5) * cell;
            i > 0
                && j > 0
                && i + 1 < nx
                && j + 1 < ny
                && !params
                    .walls
                    .iter()
                    .any(|w| w.blocks(c, settings.wall_m / 2.0))
                && !obstacles.iter().any(|o| o.contains(c))
        })
        .collect();
    WalkableMap::from_walkable(origin, cell, nx, ny, walkable)
}

/// Cells clear enough to start or end on.
fn clear_cells(settings: &RoomSettings, map: &WalkableMap) -> Vec<usize> {
    (0..map.nx * map.ny)
        .filter(|&k| map.walkable[k] && map.sdf_m[k] >= settings.clearance_m)
        .collect()
}

/// A start and a goal on clear cells of one connected floor, their distance in range.
fn draw_pair(
    settings: &RoomSettings,
    map: &WalkableMap,
    rng: &mut ChaCha8Rng,
) -> Option<(DVec2, DVec2)> {
    let cells = clear_cells(settings, map);
    if cells.is_empty() {
        return None;
    }
    let centre = |k: usize| map.centre(k % map.nx, k / map.nx);
    let (lo, hi) = settings.distance_m;
    for _ in 0..200 {
        let s = cells[(rng.next_u64() % cells.len() as u64) as usize];
        let g = cells[(rng.next_u64() % cells.len() as u64) as usize];
        let d = centre(s).distance(centre(g));
        if map.component[s] == map.component[g] && (lo..=hi).contains(&d) {
            return Some((centre(s), centre(g)));
        }
    }
    None
}

/// The two clear cells of one floor farthest apart (the grid's two corners' nearest clear
/// cells when no cell is clear enough: a degenerate plan still yields an episode).
fn farthest_clear_pair(settings: &RoomSettings, map: &WalkableMap) -> (DVec2, DVec2) {
    let cells = clear_cells(settings, map);
    let centre = |k: usize| map.centre(k % map.nx, k / map.nx);
    let walkable: Vec<usize> = (0..map.nx * map.ny).filter(|&k| map.walkable[k]).collect();
    let pool = if cells.is_empty() { &walkable } else { &cells };
    let Some(&first) = pool.first() else {
        return (map.centre(0, 0), map.centre(map.nx - 1, map.ny - 1));
    };
    let far = pool
        .iter()
        .copied()
        .filter(|&k| map.component[k] == map.component[first])
        .max_by(|&a, &b| {
            centre(a)
                .distance(centre(first))
                .total_cmp(&centre(b).distance(centre(first)))
        })
        .unwrap_or(first);
    (centre(first), centre(far))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;

    #[test]
    fn plans_are_drawn_deterministically_and_rebuild_from_their_parameters() {
        let settings = RoomSettings {
            share: 1.0,
            ..RoomSettings::default()
        };
        for seed in 0..50 {
            let a = RoomScene::sample(&settings, &mut ChaCha8Rng::seed_from_u64(seed));
            let b = RoomScene::sample(&settings, &mut ChaCha8Rng::seed_from_u64(seed));
            assert_eq!(a.params, b.params);
            let rebuilt = RoomScene::build(&settings, a.params.clone());
            assert_eq!(rebuilt.map.walkable, a.map.walkable);
            // Start and goal: clear, on one floor, in range.
            let clear = |p: DVec2| a.map.sdf_at(p) >= settings.clearance_m - 0.05;
            assert!(clear(a.start) && clear(a.goal), "seed {seed}");
            let (i, j) = a.map.cell_of(a.start).unwrap();
            let (k, l) = a.map.cell_of(a.goal).unwrap();
            assert_eq!(
                a.map.component[j * a.map.nx + i],
                a.map.component[l * a.map.nx + k]
            );
            let d = a.start.distance(a.goal);
            assert!((settings.distance_m.0..=settings.distance_m.1).contains(&d));
            assert!(
                (settings.rooms.0 - 1..settings.rooms.1).contains(&a.params.walls.len()),
                "{} walls",
                a.params.walls.len()
            );
        }
    }

    #[test]
    fn walls_block_but_their_doorways_do_not_and_furniture_keeps_clear_of_doorways() {
        let settings = RoomSettings::default();
        let mut walls = 0;
        for seed in 0..200 {
            let s = RoomScene::sample(&settings, &mut ChaCha8Rng::seed_from_u64(seed));
            for w in &s.params.walls {
                walls += 1;
                let door = w.door_centre();
                // The doorway is open across its width (but for the cells its edges cut).
                let along = if w.along_x { DVec2::X } else { DVec2::Y };
                for k in -4..=4 {
                    let p = door + along * (k as f64 / 4.0) * (w.door_width_m / 2.0 - 0.1);
                    assert!(
                        s.map.is_walkable_at(p),
                        "seed {seed}: doorway blocked at {p}"
                    );
                }
                // Halfway between the doorway's edge and the wall's nearer end: blocked.
                let side = if w.door_m - w.from_m < w.to_m - w.door_m {
                    (w.from_m + w.door_m - w.door_width_m / 2.0) / 2.0
                } else {
                    (w.to_m + w.door_m + w.door_width_m / 2.0) / 2.0
                };
                let p = if w.along_x {
                    DVec2::new(side, w.at_m)
                } else {
                    DVec2::new(w.at_m, side)
                };
                assert!(!s.map.is_walkable_at(p), "seed {seed}: wall open at {p}");
                for f in &s.params.furniture {
                    assert!(
                        !f.obstacle().grown(settings.door_clearance_m).contains(door),
                        "seed {seed}: furniture in a doorway"
                    );
                }
            }
        }
        assert!(walls >= 200, "{walls} walls in 200 plans");
    }
}
