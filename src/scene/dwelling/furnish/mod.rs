//! Furnishing a floor plan from the catalogue, room by room, with the rules people furnish by:
//! beds, wardrobes, shelves and kitchen units with their backs to a wall; a kitchen's units in
//! one run along a wall with the fridge at an end, the cooktop on a unit and wall units above;
//! chairs pulled up to the sides of tables and to desks; a sofa against a wall and the TV
//! against the wall facing it; nothing in a doorway's swing, in front of another thing's
//! front (its use zone: where one stands to use it), or tall in front of a window; small
//! things on tables, counters, nightstands and shelves. Every piece is turned by a multiple
//! of 90°, so footprints are rectangles and no two pieces' boxes may overlap.
//!
//! Here: a placed piece, the zones kept free and the placing moves every room uses (against
//! a wall, in a corner, on the floor, on top of another piece); each room's recipe — living
//! room, kitchen and its run, bedroom, bathroom, hall, a dining table or desk with chairs —
//! is in `rooms.rs`.

mod rooms;

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;
use serde::Serialize;

use super::catalogue::{Catalogue, CatalogueModel, Role};
use super::draw;
use super::plan::{FloorPlan, RoomKind, DOOR_HEIGHT_M};

/// Places tried per piece before it is left out.
const TRIES: usize = 40;
/// Depth kept free in front of a doorway on both sides (m).
const DOOR_ZONE_M: f64 = 0.9;
/// Heights of the things [`Furnishing::drop_things`] leaves on floors (m): whose top a
/// reaching palm comes 1–8 cm over (it comes to 12–16 cm over the floor).
const DROPPED_MIN_HEIGHT_M: f64 = 0.04;
const DROPPED_MAX_HEIGHT_M: f64 = 0.15;

/// Depth kept free of tall things in front of a window (m).
const WINDOW_ZONE_M: f64 = 0.35;
/// Depth kept free behind a chair at a table or desk, to pull it out (m).
const CHAIR_PULL_M: f64 = 0.45;
/// Depth kept free in front of a kitchen's units (m).
const WORKTOP_USE_M: f64 = 0.9;
/// How far above a window's sill a piece in front of it may rise (m): a tap, a lamp's
/// shade.
const WINDOW_PASS_M: f64 = 0.3;
/// Gap left between pieces and walls (m).
const GAP_M: f64 = 0.01;
/// Height under which a use zone must be free (m): a wall unit above a worktop is no
/// obstacle to the person standing at it.
const ZONE_TOP_M: f64 = 1.3;

/// Where along a wall a piece goes.
#[derive(Debug, Clone, Copy)]
enum Along {
    Anywhere,
    /// At the wall's start (false) or end (true): in a corner.
    End(bool),
    /// Its centre this far along the wall from the room's low corner (m).
    At(f64),
}

/// The use zone `depth` deep in front of `p`; none for 0.
fn front_zone(p: &Placed, depth: f64) -> Option<Rect> {
    (depth > 0.0).then(|| p.rect().strip(p.front(), depth))
}

/// The zone `depth` deep behind `p` (a chair's: where it is pulled out to).
fn back_zone(p: &Placed, depth: f64) -> Option<Rect> {
    (depth > 0.0).then(|| p.rect().strip(-p.front(), depth))
}

/// One piece of furniture or thing placed in the dwelling.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Placed {
    pub model: String,
    #[serde(skip)]
    pub role: Role,
    pub room: usize,
    /// Centre of its footprint (m).
    pub centre: [f64; 2],
    /// Turn about the vertical in quarter turns: 0 faces −y (the model's front), 1 faces +x,
    /// 2 faces +y, 3 faces −x.
    pub quarter: u8,
    /// Height of its base over the floor (m).
    pub z_m: f64,
    /// Width, depth and height of the model (m).
    pub size_m: [f64; 3],
}

impl Placed {
    pub(crate) fn centre(&self) -> DVec2 {
        DVec2::from_array(self.centre)
    }

    /// Half the footprint's extent along x and y.
    pub(crate) fn half(&self) -> DVec2 {
        let [w, d, _] = self.size_m;
        if self.quarter.is_multiple_of(2) {
            DVec2::new(w, d) / 2.0
        } else {
            DVec2::new(d, w) / 2.0
        }
    }

    /// The footprint.
    pub fn rect(&self) -> Rect {
        Rect {
            min: self.centre() - self.half(),
            max: self.centre() + self.half(),
        }
    }

    /// The way its front faces.
    pub(crate) fn front(&self) -> DVec2 {
        quarter_front(self.quarter)
    }

    /// The yaw about +z (rad).
    pub(crate) fn yaw(&self) -> f64 {
        f64::from(self.quarter) * std::f64::consts::FRAC_PI_2
    }

    pub fn top_m(&self) -> f64 {
        self.z_m + self.size_m[2]
    }

    fn overlaps(&self, other: &Placed) -> bool {
        self.rect().overlaps(&other.rect())
            && self.z_m < other.top_m() - 1e-6
            && other.z_m < self.top_m() - 1e-6
    }
}

/// The way a model turned by `quarter` quarter turns faces.
fn quarter_front(quarter: u8) -> DVec2 {
    match quarter % 4 {
        0 => DVec2::new(0.0, -1.0),
        1 => DVec2::new(1.0, 0.0),
        2 => DVec2::new(0.0, 1.0),
        _ => DVec2::new(-1.0, 0.0),
    }
}

/// An axis-aligned rectangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub min: DVec2,
    pub max: DVec2,
}

impl Rect {
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.min.x < o.max.x - 1e-6
            && o.min.x < self.max.x - 1e-6
            && self.min.y < o.max.y - 1e-6
            && o.min.y < self.max.y - 1e-6
    }
    fn inside(&self, o: &Rect) -> bool {
        self.min.cmpge(o.min - 1e-9).all() && self.max.cmple(o.max + 1e-9).all()
    }
    /// The strip `depth` deep in front of this rectangle's side facing `dir`.
    fn strip(&self, dir: DVec2, depth: f64) -> Rect {
        let (mut min, mut max) = (self.min, self.max);
        if dir.x > 0.5 {
            (min.x, max.x) = (self.max.x, self.max.x + depth);
        } else if dir.x < -0.5 {
            (min.x, max.x) = (self.min.x - depth, self.min.x);
        } else if dir.y > 0.5 {
            (min.y, max.y) = (self.max.y, self.max.y + depth);
        } else {
            (min.y, max.y) = (self.min.y - depth, self.min.y);
        }
        Rect { min, max }
    }
}

/// Space kept free: nothing lower than `top_m` may stand in it (but `owner`'s group).
#[derive(Debug, Clone, Copy)]
struct Zone {
    rect: Rect,
    top_m: f64,
    /// The piece it is the use zone of (index into the placed pieces); none for doors and
    /// windows.
    owner: Option<usize>,
    /// Only what rises above this height is kept out (windows: their sill).
    above_m: f64,
}

/// The room being furnished: its index and its floor inside the walls.
struct Room<'a> {
    catalogue: &'a Catalogue,
    room: usize,
    inside: Rect,
}

impl<'a> Room<'a> {
    /// One of the role's models, drawn.
    fn pick(&self, role: Role, rng: &mut ChaCha8Rng) -> &'a CatalogueModel {
        let models = self.catalogue.models_for(role);
        models[(rng.next_u64() % models.len() as u64) as usize]
    }

    /// The role's models in a drawn order.
    fn shuffled(&self, role: Role, rng: &mut ChaCha8Rng) -> Vec<&'a CatalogueModel> {
        let mut models = self.catalogue.models_for(role);
        for i in (1..models.len()).rev() {
            models.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        models
    }
}

/// What a dwelling's rooms hold.
pub(crate) struct Furnishing<'a> {
    plan: &'a FloorPlan,
    pub placed: Vec<Placed>,
    zones: Vec<Zone>,
    /// Pieces that stand together (a table and its chairs) share a group.
    group: Vec<usize>,
    /// Largest number of small things per table, counter, nightstand or shelf.
    things: (usize, usize),
}

impl<'a> Furnishing<'a> {
    /// Furnishes every room of `plan`.
    pub(crate) fn furnish(
        plan: &'a FloorPlan,
        catalogue: &'a Catalogue,
        things: (usize, usize),
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let mut f = Furnishing {
            plan,
            placed: Vec::new(),
            zones: door_and_window_zones(plan),
            group: Vec::new(),
            things,
        };
        for room in 0..plan.rooms.len() {
            let (lo, hi) = plan.interior(room);
            let r = Room {
                catalogue,
                room,
                inside: Rect { min: lo, max: hi },
            };
            match plan.rooms[room].kind {
                RoomKind::Living => f.living(&r, rng),
                RoomKind::Kitchen => f.kitchen(&r, rng),
                RoomKind::Bedroom => f.bedroom(&r, rng),
                RoomKind::Bathroom => f.bathroom(&r, rng),
                RoomKind::Hall => f.hall(&r, rng),
            }
        }
        f
    }

    /// Whether `p` may stand where it is, with its use zone `zone` (where one stands to use
    /// it) free.
    fn fits(&self, r: &Room, p: &Placed, zone: Option<Rect>, group: Option<usize>) -> bool {
        let rect = p.rect();
        if !rect.inside(&r.inside) {
            return false;
        }
        if self.placed.iter().any(|q| q.overlaps(p)) {
            return false;
        }
        let same_group = |owner: Option<usize>| match (owner, group) {
            (Some(o), Some(g)) => self.group[o] == g,
            _ => false,
        };
        for z in &self.zones {
            if p.z_m < z.top_m
                && p.top_m() > z.above_m
                && rect.overlaps(&z.rect)
                && !same_group(z.owner)
            {
                return false;
            }
        }
        if let Some(zone) = zone {
            if !zone.inside(&r.inside) {
                return false;
            }
            for (k, q) in self.placed.iter().enumerate() {
                let ours = group.is_some_and(|g| self.group[k] == g);
                if !ours && q.z_m < ZONE_TOP_M && q.rect().overlaps(&zone) {
                    return false;
                }
            }
        }
        true
    }

    /// Places `p` with its use zone; returns its index.
    fn put(&mut self, p: Placed, zone: Option<Rect>, group: Option<usize>) -> usize {
        let k = self.placed.len();
        if let Some(rect) = zone {
            self.zones.push(Zone {
                rect,
                top_m: ZONE_TOP_M,
                owner: Some(k),
                above_m: 0.0,
            });
        }
        self.placed.push(p);
        self.group.push(group.unwrap_or(usize::MAX - k));
        k
    }

    /// A piece with its back to one of the room's walls: `side` 0–3 (the wall at −y, +x, +y,
    /// −x) or any, where `along` says, its use zone `use_m` deep in front of it.
    #[allow(clippy::too_many_arguments)]
    fn against_wall(
        &mut self,
        r: &Room,
        model: &CatalogueModel,
        role: Role,
        side: Option<u8>,
        along: Along,
        use_m: f64,
        rng: &mut ChaCha8Rng,
    ) -> Option<usize> {
        let tries = if side.is_some() && !matches!(along, Along::Anywhere) {
            1
        } else {
            TRIES
        };
        for _ in 0..tries {
            let side = side.unwrap_or((rng.next_u64() % 4) as u8);
            let p = match along {
                Along::Anywhere => at_wall(
                    r,
                    model,
                    role,
                    side,
                    draw(rng, (0.0, 1.0)),
                    model.elevation_m,
                ),
                Along::End(end) => at_wall(
                    r,
                    model,
                    role,
                    side,
                    if end { 1.0 } else { 0.0 },
                    model.elevation_m,
                ),
                Along::At(offset) => {
                    at_wall_offset(r, model, role, side, offset, model.elevation_m)
                }
            };
            let zone = front_zone(&p, use_m);
            if self.fits(r, &p, zone, None) {
                return Some(self.put(p, zone, None));
            }
        }
        None
    }

    /// A piece of `role` against a wall: its models tried in a drawn order until one fits.
    fn any_against_wall(
        &mut self,
        r: &Room,
        role: Role,
        use_m: f64,
        rng: &mut ChaCha8Rng,
    ) -> Option<usize> {
        for m in r.shuffled(role, rng) {
            if let Some(k) = self.against_wall(r, m, role, None, Along::Anywhere, use_m, rng) {
                return Some(k);
            }
        }
        None
    }

    fn sill_below(&self, room: usize, wall: usize) -> f64 {
        self.plan
            .windows
            .iter()
            .filter(|w| w.room == room && w.wall == wall)
            .map(|w| w.sill_m)
            .fold(f64::INFINITY, f64::min)
    }

    /// A piece in a corner of the room, its back to a wall.
    fn corner(
        &mut self,
        r: &Room,
        model: &CatalogueModel,
        role: Role,
        use_m: f64,
        rng: &mut ChaCha8Rng,
    ) -> Option<usize> {
        let first = rng.next_u64() % 8;
        for c in 0..8 {
            let corner = (first + c) % 8;
            let (side, end) = ((corner / 2) as u8, corner % 2 == 1);
            if let Some(k) =
                self.against_wall(r, model, role, Some(side), Along::End(end), use_m, rng)
            {
                return Some(k);
            }
        }
        None
    }

    fn corner_piece(&mut self, r: &Room, role: Role, rng: &mut ChaCha8Rng) {
        let m = r.pick(role, rng);
        self.corner(r, m, role, 0.0, rng);
    }

    /// U(`n`) things a hand can pick up left on the floor of each living room and bedroom,
    /// anywhere free: the catalogue's small things (on tables, counters, basins and bedroom
    /// floors) that a pick-up's hand closes round — at most
    /// [`crate::scene::small_object::THING_MAX_GRIP_M`] across the narrower way and
    /// [`DROPPED_MAX_HEIGHT_M`] high. Draws nothing where `n` is `(0, 0)`.
    pub(crate) fn drop_things(
        &mut self,
        catalogue: &'a Catalogue,
        (lo, hi): (usize, usize),
        rng: &mut ChaCha8Rng,
    ) {
        if hi == 0 {
            return;
        }
        let mut models: Vec<&CatalogueModel> = Vec::new();
        for role in [
            Role::TableThing,
            Role::KitchenThing,
            Role::BathroomThing,
            Role::BedroomThing,
        ] {
            for m in catalogue.models_for(role) {
                let [x, y, z] = m.size_m;
                let fits = x.min(y) <= crate::scene::small_object::THING_MAX_GRIP_M
                    && (DROPPED_MIN_HEIGHT_M..=DROPPED_MAX_HEIGHT_M).contains(&z);
                if fits && !models.iter().any(|n| n.id == m.id) {
                    models.push(m);
                }
            }
        }
        if models.is_empty() {
            return;
        }
        for room in 0..self.plan.rooms.len() {
            if !matches!(
                self.plan.rooms[room].kind,
                RoomKind::Living | RoomKind::Bedroom
            ) {
                continue;
            }
            let (a, b) = self.plan.interior(room);
            let r = Room {
                catalogue,
                room,
                inside: Rect { min: a, max: b },
            };
            let n = lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize;
            for _ in 0..n {
                let m = models[(rng.next_u64() % models.len() as u64) as usize];
                self.on_floor(&r, m, Role::FloorThing, rng);
            }
        }
    }

    /// A thing on the floor, anywhere free.
    fn on_floor(&mut self, r: &Room, model: &CatalogueModel, role: Role, rng: &mut ChaCha8Rng) {
        for _ in 0..TRIES {
            let quarter = (rng.next_u64() % 4) as u8;
            let mut p = placed(model, role, r.room, DVec2::ZERO, quarter, 0.0);
            let (lo, hi) = (r.inside.min + p.half(), r.inside.max - p.half());
            if lo.x > hi.x || lo.y > hi.y {
                return;
            }
            p.centre = DVec2::new(draw(rng, (lo.x, hi.x)), draw(rng, (lo.y, hi.y))).to_array();
            if self.fits(r, &p, None, None) {
                self.put(p, None, None);
                return;
            }
        }
    }

    /// U(`things`) small things on top of piece `k`, inside its footprint.
    fn things_on(&mut self, r: &Room, k: usize, role: Role, rng: &mut ChaCha8Rng) {
        let (lo, hi) = self.things;
        let n = lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize;
        let support = self.placed[k].clone();
        let surface = support.z_m
            + r.catalogue
                .models
                .get(&support.model)
                .map_or(support.size_m[2], CatalogueModel::surface_m);
        for _ in 0..n {
            let m = r.pick(role, rng);
            for _ in 0..8 {
                let quarter = (rng.next_u64() % 4) as u8;
                let mut p = placed(m, role, r.room, DVec2::ZERO, quarter, surface);
                let inset = p.half() + 0.03;
                let (a, b) = (support.rect().min + inset, support.rect().max - inset);
                if a.x > b.x || a.y > b.y {
                    break;
                }
                p.centre = DVec2::new(draw(rng, (a.x, b.x)), draw(rng, (a.y, b.y))).to_array();
                if p.top_m() < self.plan.ceiling_m - 0.1
                    && !self
                        .placed
                        .iter()
                        .enumerate()
                        .any(|(j, q)| j != k && q.overlaps(&p))
                {
                    self.put(p, None, None);
                    break;
                }
            }
        }
    }
}

fn placed(
    model: &CatalogueModel,
    role: Role,
    room: usize,
    centre: DVec2,
    quarter: u8,
    z_m: f64,
) -> Placed {
    Placed {
        model: model.id.clone(),
        role,
        room,
        centre: centre.to_array(),
        quarter,
        z_m,
        size_m: model.size_m,
    }
}

/// The quarter turn of a piece with its back to wall `side` (0: the wall at −y, so it faces
/// +y; 1: +x; 2: +y; 3: −x).
fn quarter_for_side(side: u8) -> u8 {
    match side % 4 {
        0 => 2,
        1 => 3,
        2 => 0,
        _ => 1,
    }
}

/// The wall side a piece turned by `quarter` has at its back.
fn wall_side_of(quarter: u8) -> u8 {
    (0..4)
        .find(|&s| quarter_for_side(s) == quarter % 4)
        .unwrap_or(0)
}

fn wall_length(r: &Room, side: u8) -> f64 {
    let size = r.inside.max - r.inside.min;
    if side.is_multiple_of(2) {
        size.x
    } else {
        size.y
    }
}

/// Distance along wall `side` from its start (the room's low corner) of the coordinate `c`.
fn offset_along(r: &Room, side: u8, c: f64) -> f64 {
    if side.is_multiple_of(2) {
        c - r.inside.min.x
    } else {
        c - r.inside.min.y
    }
}

/// The wall side of the room a wall line is.
fn side_of_wall(r: &Room, line: &super::plan::WallLine) -> u8 {
    let c = (r.inside.min + r.inside.max) / 2.0;
    match (
        line.vertical,
        if line.vertical {
            line.at > c.x
        } else {
            line.at > c.y
        },
    ) {
        (false, false) => 0,
        (true, true) => 1,
        (false, true) => 2,
        (true, false) => 3,
    }
}

/// A piece with its back to wall `side`, at `s` (0–1) of the length its footprint can slide.
fn at_wall(r: &Room, model: &CatalogueModel, role: Role, side: u8, s: f64, z_m: f64) -> Placed {
    let q = quarter_for_side(side);
    let p = placed(model, role, r.room, DVec2::ZERO, q, z_m);
    let half_along = if side.is_multiple_of(2) {
        p.half().x
    } else {
        p.half().y
    };
    let free = (wall_length(r, side) - 2.0 * (half_along + GAP_M)).max(0.0);
    at_wall_offset(r, model, role, side, GAP_M + half_along + s * free, z_m)
}

/// A piece with its back to wall `side`, its centre `offset` along the wall from the room's
/// low corner.
fn at_wall_offset(
    r: &Room,
    model: &CatalogueModel,
    role: Role,
    side: u8,
    offset: f64,
    z_m: f64,
) -> Placed {
    let q = quarter_for_side(side);
    let mut p = placed(model, role, r.room, DVec2::ZERO, q, z_m);
    let h = p.half();
    let (lo, hi) = (r.inside.min, r.inside.max);
    let c = match side % 4 {
        0 => DVec2::new(lo.x + offset, lo.y + GAP_M + h.y),
        1 => DVec2::new(hi.x - GAP_M - h.x, lo.y + offset),
        2 => DVec2::new(lo.x + offset, hi.y - GAP_M - h.y),
        _ => DVec2::new(lo.x + GAP_M + h.x, lo.y + offset),
    };
    p.centre = c.to_array();
    p
}

/// Chairs pulled up to a table's sides, facing it, as many as each side seats (three at most).
fn chairs_round(t: &Placed, chair: &CatalogueModel, room: usize) -> Vec<Placed> {
    let mut out = Vec::new();
    let rect = t.rect();
    for side in 0..4u8 {
        // The side of the table the chairs stand at, and the chairs' turn: facing back at it.
        let out_dir = quarter_front(side);
        let proto = placed(
            chair,
            Role::DiningChair,
            room,
            DVec2::ZERO,
            (side + 2) % 4,
            0.0,
        );
        let across = DVec2::new(out_dir.y, -out_dir.x).abs();
        let length = (rect.max - rect.min).dot(across);
        let width = proto.half().dot(across) * 2.0;
        let n = ((length + 0.1) / (width + 0.15)).floor().min(3.0) as usize;
        let depth = proto.half().dot(out_dir.abs());
        let edge = t.centre() + out_dir * t.half().dot(out_dir.abs());
        for i in 0..n {
            let s = (i as f64 + 0.5) / n as f64 - 0.5;
            let mut c = proto.clone();
            c.centre = (edge + out_dir * (depth + 0.02) + across * s * length).to_array();
            out.push(c);
        }
    }
    out
}

/// Zones kept free: in front of each doorway on both sides, and in front of each window (of
/// whatever rises above its sill).
fn door_and_window_zones(plan: &FloorPlan) -> Vec<Zone> {
    // The strip `depth` deep on both sides of wall `wall` from `from` to `to` along it.
    let across = |wall: usize, from: f64, to: f64, depth: f64| {
        let w = &plan.walls[wall];
        let (a, b) = (w.point(from), w.point(to));
        let depth = depth + plan.thickness(w) / 2.0;
        let normal = if w.vertical { DVec2::X } else { DVec2::Y };
        Rect {
            min: a.min(b) - normal * depth,
            max: a.max(b) + normal * depth,
        }
    };
    let doors = plan.doors.iter().map(|d| Zone {
        rect: across(d.wall, d.from - 0.1, d.to + 0.1, DOOR_ZONE_M),
        top_m: DOOR_HEIGHT_M,
        owner: None,
        above_m: 0.0,
    });
    let windows = plan.windows.iter().map(|w| Zone {
        rect: across(w.wall, w.from, w.to, WINDOW_ZONE_M),
        top_m: w.top_m,
        owner: None,
        above_m: w.sill_m + WINDOW_PASS_M,
    });
    doors.chain(windows).collect()
}
