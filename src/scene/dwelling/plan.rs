//! A dwelling's floor plan: its rooms drawn from the room program (a living room, a kitchen,
//! a hall, a bathroom and 1–3 bedrooms, each of an area drawn from its range), laid out as a
//! squarified treemap of a rectangle (every room a rectangle close to square, snapped to the
//! centimetre), the walls on the rooms' edges, one door per room joining the rooms as a tree
//! grown from the living room (through the living room or hall where it can, a bedroom only
//! where nothing else borders), and windows in the outer walls.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;
use serde::Serialize;

use super::draw;
use super::DwellingSettings;
use crate::math::random::uniform_open01;

/// Least distance of a door's jamb from the end of the wall it is cut into, beyond the
/// crossing wall's half thickness (m).
const DOOR_END_MARGIN_M: f64 = 0.12;
/// Least distance of a window from a corner or another window (m).
const WINDOW_MARGIN_M: f64 = 0.4;
/// Height of a doorway (m).
pub(crate) const DOOR_HEIGHT_M: f64 = 2.05;
/// Sill of a bathroom's window (m).
const BATHROOM_SILL_M: f64 = 1.3;

/// What a room is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RoomKind {
    Living,
    Kitchen,
    Hall,
    Bathroom,
    Bedroom,
}

impl RoomKind {
    pub(crate) fn name(self) -> &'static str {
        match self {
            RoomKind::Living => "living",
            RoomKind::Kitchen => "kitchen",
            RoomKind::Hall => "hall",
            RoomKind::Bathroom => "bathroom",
            RoomKind::Bedroom => "bedroom",
        }
    }

    /// Rooms a door may lead through (a corridor, an open living room).
    fn is_passage(self) -> bool {
        matches!(self, RoomKind::Living | RoomKind::Hall)
    }
}

/// One room: an axis-aligned rectangle from wall centre to wall centre.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Room {
    pub kind: RoomKind,
    /// `living`, `kitchen`, `bedroom_2` …: unique in the dwelling.
    pub name: String,
    pub min: [f64; 2],
    pub max: [f64; 2],
}

impl Room {
    pub(crate) fn min(&self) -> DVec2 {
        DVec2::from_array(self.min)
    }
    pub(crate) fn max(&self) -> DVec2 {
        DVec2::from_array(self.max)
    }
    pub(crate) fn area_m2(&self) -> f64 {
        let s = self.max() - self.min();
        s.x * s.y
    }
}

/// A straight wall: the line x = `at` (`vertical`) or y = `at`, from `from` to `to` along it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WallLine {
    pub vertical: bool,
    pub at: f64,
    pub from: f64,
    pub to: f64,
    /// On the dwelling's outline (thicker, with windows).
    pub outer: bool,
}

impl WallLine {
    /// The point `s` along the line.
    pub(crate) fn point(&self, s: f64) -> DVec2 {
        if self.vertical {
            DVec2::new(self.at, s)
        } else {
            DVec2::new(s, self.at)
        }
    }
}

/// A doorway between two rooms.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Door {
    /// Index of its wall in [`FloorPlan::walls`].
    pub wall: usize,
    /// Its span along the wall (m).
    pub from: f64,
    pub to: f64,
    /// The rooms it joins (indices into [`FloorPlan::rooms`]).
    pub rooms: [usize; 2],
    /// A leaf standing open at right angles into the second room, hinged at `from` (true) or
    /// `to`; none: an open doorway.
    pub leaf_at_from: Option<bool>,
}

/// A window in an outer wall.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Window {
    pub wall: usize,
    pub from: f64,
    pub to: f64,
    pub sill_m: f64,
    pub top_m: f64,
    pub room: usize,
}

/// Rooms, walls, doors and windows of one dwelling (z up, metres, the outline from (0, 0)).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloorPlan {
    pub size_m: [f64; 2],
    pub ceiling_m: f64,
    pub wall_m: f64,
    pub outer_wall_m: f64,
    pub rooms: Vec<Room>,
    pub walls: Vec<WallLine>,
    pub doors: Vec<Door>,
    pub windows: Vec<Window>,
}

impl FloorPlan {
    /// The room's floor inside its walls: its rectangle less half of each wall's thickness.
    pub fn interior(&self, room: usize) -> (DVec2, DVec2) {
        let r = &self.rooms[room];
        let size = DVec2::from_array(self.size_m);
        let half = |on_outline: bool| {
            0.5 * if on_outline {
                self.outer_wall_m
            } else {
                self.wall_m
            }
        };
        let lo = DVec2::new(
            r.min[0] + half(r.min[0] <= 0.0),
            r.min[1] + half(r.min[1] <= 0.0),
        );
        let hi = DVec2::new(
            r.max[0] - half(r.max[0] >= size.x),
            r.max[1] - half(r.max[1] >= size.y),
        );
        (lo, hi)
    }

    /// The room holding `p`, if any.
    pub(crate) fn room_at(&self, p: DVec2) -> Option<usize> {
        self.rooms
            .iter()
            .position(|r| p.cmpge(r.min()).all() && p.cmple(r.max()).all())
    }

    /// Thickness of a wall.
    pub(crate) fn thickness(&self, wall: &WallLine) -> f64 {
        if wall.outer {
            self.outer_wall_m
        } else {
            self.wall_m
        }
    }
}

/// Draws a floor plan; `None` when this draw's rooms do not fit the rules (a room narrower
/// than `min_room_side_m`, two rooms that must be joined with too short a wall between them):
/// the caller draws again.
pub(crate) fn draw_plan(settings: &DwellingSettings, rng: &mut ChaCha8Rng) -> Option<FloorPlan> {
    let mut program = vec![
        (RoomKind::Living, draw(rng, settings.living_m2)),
        (RoomKind::Kitchen, draw(rng, settings.kitchen_m2)),
        (RoomKind::Hall, draw(rng, settings.hall_m2)),
        (RoomKind::Bathroom, draw(rng, settings.bathroom_m2)),
    ];
    let (lo, hi) = settings.bedrooms;
    let bedrooms = lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize;
    for _ in 0..bedrooms {
        program.push((RoomKind::Bedroom, draw(rng, settings.bedroom_m2)));
    }
    // Largest first, as the treemap wants; equal areas in program order.
    program.sort_by(|a, b| b.1.total_cmp(&a.1));
    let total: f64 = program.iter().map(|p| p.1).sum();
    let aspect = draw(rng, settings.aspect);
    let (w, d) = ((total * aspect).sqrt(), (total / aspect).sqrt());
    let (w, d) = (snap(w), snap(d));
    let areas: Vec<f64> = program.iter().map(|p| p.1 * w * d / total).collect();
    let rects = squarify(&areas, DVec2::ZERO, DVec2::new(w, d));
    let (flip_x, flip_y) = (rng.next_u64() % 2 == 1, rng.next_u64() % 2 == 1);
    let mut counts = std::collections::BTreeMap::new();
    let mut rooms = Vec::with_capacity(program.len());
    for ((kind, _), (a, b)) in program.iter().zip(rects) {
        let (mut a, mut b) = (a.to_array().map(snap), b.to_array().map(snap));
        if flip_x {
            (a[0], b[0]) = (snap(w - b[0]), snap(w - a[0]));
        }
        if flip_y {
            (a[1], b[1]) = (snap(d - b[1]), snap(d - a[1]));
        }
        let side = (b[0] - a[0]).min(b[1] - a[1]);
        if side < settings.min_room_side_m {
            return None;
        }
        let n: &mut usize = counts.entry(*kind).or_default();
        *n += 1;
        let name = match kind {
            RoomKind::Bedroom => format!("bedroom_{n}"),
            _ => kind.name().to_string(),
        };
        rooms.push(Room {
            kind: *kind,
            name,
            min: a,
            max: b,
        });
    }
    let mut plan = FloorPlan {
        size_m: [w, d],
        ceiling_m: draw(rng, settings.ceiling_m),
        wall_m: settings.wall_m,
        outer_wall_m: settings.outer_wall_m,
        walls: wall_lines(&rooms, w, d),
        rooms,
        doors: Vec::new(),
        windows: Vec::new(),
    };
    plan.doors = draw_doors(&plan, settings, rng)?;
    plan.windows = draw_windows(&plan, settings, rng);
    Some(plan)
}

/// To the centimetre.
fn snap(x: f64) -> f64 {
    (x * 100.0).round() / 100.0
}

/// Squarified treemap (Bruls, Huizing and van Wijk 2000): `areas` (largest first, summing to
/// the rectangle's area) as rectangles in the same order.
fn squarify(areas: &[f64], lo: DVec2, hi: DVec2) -> Vec<(DVec2, DVec2)> {
    let worst = |row: &[f64], side: f64| {
        let s: f64 = row.iter().sum();
        row.iter()
            .map(|&r| (side * side * r / (s * s)).max(s * s / (side * side * r)))
            .fold(0.0, f64::max)
    };
    let (mut lo, hi) = (lo, hi);
    let mut out = Vec::with_capacity(areas.len());
    let mut i = 0;
    while i < areas.len() {
        let size = hi - lo;
        let side = size.x.min(size.y);
        let mut end = i + 1;
        while end < areas.len() && worst(&areas[i..=end], side) <= worst(&areas[i..end], side) {
            end += 1;
        }
        let last_row = end == areas.len();
        let s: f64 = areas[i..end].iter().sum();
        if size.x >= size.y {
            // A column at the left, as wide as the row's area needs.
            let col = if last_row { size.x } else { s / size.y };
            let mut y = lo.y;
            for k in i..end {
                let top = if k + 1 == end {
                    hi.y
                } else {
                    y + areas[k] / col
                };
                out.push((DVec2::new(lo.x, y), DVec2::new(lo.x + col, top)));
                y = top;
            }
            lo.x += col;
        } else {
            let row = if last_row { size.y } else { s / size.x };
            let mut x = lo.x;
            for k in i..end {
                let right = if k + 1 == end {
                    hi.x
                } else {
                    x + areas[k] / row
                };
                out.push((DVec2::new(x, lo.y), DVec2::new(right, lo.y + row)));
                x = right;
            }
            lo.y += row;
        }
        i = end;
    }
    out
}

/// The walls: every room edge, merged along each line.
fn wall_lines(rooms: &[Room], w: f64, d: f64) -> Vec<WallLine> {
    let mut edges: Vec<(bool, f64, f64, f64)> = Vec::new();
    for r in rooms {
        edges.push((true, r.min[0], r.min[1], r.max[1]));
        edges.push((true, r.max[0], r.min[1], r.max[1]));
        edges.push((false, r.min[1], r.min[0], r.max[0]));
        edges.push((false, r.max[1], r.min[0], r.max[0]));
    }
    edges.sort_by(|a, b| {
        (a.0, a.1, a.2)
            .partial_cmp(&(b.0, b.1, b.2))
            .expect("finite coordinates")
    });
    let mut lines: Vec<WallLine> = Vec::new();
    for (vertical, at, from, to) in edges {
        if let Some(last) = lines.last_mut() {
            if last.vertical == vertical && last.at == at && from <= last.to + 1e-9 {
                last.to = last.to.max(to);
                continue;
            }
        }
        let outer = if vertical {
            at <= 0.0 || at >= w
        } else {
            at <= 0.0 || at >= d
        };
        lines.push(WallLine {
            vertical,
            at,
            from,
            to,
            outer,
        });
    }
    lines
}

/// The wall two rooms share: (vertical, at, from, to), if their edges touch over a length.
fn shared_edge(a: &Room, b: &Room) -> Option<(bool, f64, f64, f64)> {
    let overlap = |lo1: f64, hi1: f64, lo2: f64, hi2: f64| (lo1.max(lo2), hi1.min(hi2));
    for (vertical, axis, other) in [(true, 0, 1), (false, 1, 0)] {
        let at = if a.max[axis] == b.min[axis] {
            a.max[axis]
        } else if b.max[axis] == a.min[axis] {
            a.min[axis]
        } else {
            continue;
        };
        let (from, to) = overlap(a.min[other], a.max[other], b.min[other], b.max[other]);
        if to > from {
            return Some((vertical, at, from, to));
        }
    }
    None
}

/// One door per room but the living room's: a tree grown from the living room, each new room
/// joined to the room already reached that is the best passage (a living room or hall, then a
/// kitchen, a bathroom, a bedroom last), over the longest shared wall among equals.
fn draw_doors(
    plan: &FloorPlan,
    settings: &DwellingSettings,
    rng: &mut ChaCha8Rng,
) -> Option<Vec<Door>> {
    let rooms = &plan.rooms;
    let margin = settings.wall_m / 2.0 + DOOR_END_MARGIN_M;
    let through = |k: RoomKind| match k {
        _ if k.is_passage() => 0,
        RoomKind::Kitchen => 1,
        RoomKind::Bathroom => 3,
        _ => 2,
    };
    let mut reached = vec![false; rooms.len()];
    reached[rooms.iter().position(|r| r.kind == RoomKind::Living)?] = true;
    let mut doors = Vec::new();
    while reached.iter().any(|r| !r) {
        let mut best: Option<(i32, f64, usize, usize, (bool, f64, f64, f64))> = None;
        for a in (0..rooms.len()).filter(|&a| reached[a]) {
            for b in (0..rooms.len()).filter(|&b| !reached[b]) {
                let Some(edge) = shared_edge(&rooms[a], &rooms[b]) else {
                    continue;
                };
                let length = edge.3 - edge.2;
                if length < settings.door_m.0 + 2.0 * margin {
                    continue;
                }
                let key = (through(rooms[a].kind), -length);
                if best.is_none_or(|(s, l, ..)| key < (s, l)) {
                    best = Some((key.0, key.1, a, b, edge));
                }
            }
        }
        let (_, _, a, b, (vertical, at, from, to)) = best?;
        reached[b] = true;
        let width = draw(rng, settings.door_m).min(to - from - 2.0 * margin);
        let start = draw(rng, (from + margin, to - margin - width));
        let wall = plan
            .walls
            .iter()
            .position(|w| w.vertical == vertical && w.at == at && w.from <= from && w.to >= to)
            .expect("every shared edge lies on a wall");
        let leaf_at_from = (uniform_open01(rng) < settings.door_leaf_share)
            .then(|| rng.next_u64().is_multiple_of(2));
        doors.push(Door {
            wall,
            from: snap(start),
            to: snap(start + width),
            rooms: [a, b],
            leaf_at_from,
        });
    }
    Some(doors)
}

/// Windows along every room's stretch of outer wall (not the hall's): one per 2.6 m of it,
/// spread with a jitter, each U(`window_m`) wide and clear of corners; a bathroom's are
/// narrow and high.
fn draw_windows(
    plan: &FloorPlan,
    settings: &DwellingSettings,
    rng: &mut ChaCha8Rng,
) -> Vec<Window> {
    let mut windows = Vec::new();
    for (k, room) in plan.rooms.iter().enumerate() {
        if room.kind == RoomKind::Hall {
            continue;
        }
        for (wall_index, wall) in plan.walls.iter().enumerate().filter(|(_, w)| w.outer) {
            let (axis, other) = if wall.vertical { (0, 1) } else { (1, 0) };
            if room.min[axis] != wall.at && room.max[axis] != wall.at {
                continue;
            }
            let (from, to) = (room.min[other], room.max[other]);
            let usable = to - from - 2.0 * WINDOW_MARGIN_M;
            let bathroom = room.kind == RoomKind::Bathroom;
            let widest = if bathroom { 0.8 } else { settings.window_m.1 };
            if usable < settings.window_m.0.min(widest) {
                continue;
            }
            let count = ((usable / 2.6).floor() as usize).max(1);
            let slot = usable / count as f64;
            for i in 0..count {
                let width = draw(rng, settings.window_m)
                    .min(widest)
                    .min(slot - WINDOW_MARGIN_M)
                    .max(0.0);
                if width < 0.5 {
                    continue;
                }
                let centre = from
                    + WINDOW_MARGIN_M
                    + slot * (i as f64 + 0.5)
                    + draw(rng, (-0.5, 0.5)) * (slot - width - WINDOW_MARGIN_M).max(0.0);
                let sill = if bathroom {
                    BATHROOM_SILL_M
                } else {
                    draw(rng, settings.window_sill_m)
                };
                windows.push(Window {
                    wall: wall_index,
                    from: snap(centre - width / 2.0),
                    to: snap(centre + width / 2.0),
                    sill_m: sill,
                    top_m: settings.window_top_m.min(plan.ceiling_m - 0.2),
                    room: k,
                });
            }
        }
    }
    windows
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;

    #[test]
    fn a_treemap_tiles_its_rectangle_with_the_areas_asked() {
        let areas = [6.0, 6.0, 4.0, 3.0, 2.0, 2.0, 1.0];
        let rects = squarify(&areas, DVec2::ZERO, DVec2::new(6.0, 4.0));
        let mut sum = 0.0;
        for (a, (lo, hi)) in areas.iter().zip(&rects) {
            let s = *hi - *lo;
            assert!((s.x * s.y - a).abs() < 1e-9, "{a} vs {s:?}");
            assert!(lo.cmpge(DVec2::ZERO).all() && hi.cmple(DVec2::new(6.0, 4.0) + 1e-9).all());
            sum += s.x * s.y;
        }
        assert!((sum - 24.0).abs() < 1e-9);
    }

    #[test]
    fn every_room_is_reached_by_one_door_and_doors_and_windows_sit_on_their_walls() {
        let settings = DwellingSettings::default();
        let mut drawn = 0;
        for seed in 0..60 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let Some(plan) = draw_plan(&settings, &mut rng) else {
                continue;
            };
            drawn += 1;
            assert_eq!(plan.doors.len(), plan.rooms.len() - 1);
            let area: f64 = plan.rooms.iter().map(Room::area_m2).sum();
            assert!((area - plan.size_m[0] * plan.size_m[1]).abs() < 1e-6);
            for d in &plan.doors {
                let w = &plan.walls[d.wall];
                assert!(!w.outer && w.from < d.from && d.to < w.to, "{d:?} {w:?}");
                assert!(d.to - d.from >= settings.door_m.0 - 0.011);
            }
            for win in &plan.windows {
                let w = &plan.walls[win.wall];
                assert!(w.outer && w.from <= win.from && win.to <= w.to);
                assert!(win.sill_m < win.top_m && win.top_m < plan.ceiling_m);
            }
        }
        assert!(drawn >= 30, "only {drawn} of 60 draws gave a plan");
    }
}
