//! Each room's recipe: what a living room, kitchen, bedroom, bathroom and hall hold and where
//! (the rules in `furnish`'s docs), built from the placing moves of `furnish`.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;

use super::*;

impl Furnishing<'_> {
    pub(super) fn living(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        if let Some(k) = self.any_against_wall(r, Role::Sofa, 0.7, rng) {
            // The TV on the wall the sofa faces, across from it.
            let opposite = (self.placed[k].quarter + 2) % 4;
            let side = wall_side_of(opposite);
            let c = self.placed[k].centre();
            let s = offset_along(r, side, if side.is_multiple_of(2) { c.x } else { c.y });
            let tv = r.pick(Role::TvCabinet, rng);
            self.against_wall(r, tv, Role::TvCabinet, Some(side), Along::At(s), 0.0, rng)
                .or_else(|| {
                    self.against_wall(
                        r,
                        tv,
                        Role::TvCabinet,
                        Some(side),
                        Along::Anywhere,
                        0.0,
                        rng,
                    )
                });
        }
        for _ in 0..(rng.next_u64() % 3) {
            let m = r.pick(Role::Armchair, rng);
            self.against_wall(r, m, Role::Armchair, None, Along::Anywhere, 0.5, rng);
        }
        self.dining(r, rng);
        let shelf = r.pick(Role::Bookcase, rng);
        self.against_wall(r, shelf, Role::Bookcase, None, Along::Anywhere, 0.6, rng);
        self.radiators(r, rng);
        for _ in 0..(1 + rng.next_u64() % 2) {
            self.corner_piece(r, Role::Plant, rng);
        }
        if rng.next_u64().is_multiple_of(2) {
            self.corner_piece(r, Role::FloorThing, rng);
        }
    }

    pub(super) fn kitchen(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        self.kitchen_run(r, rng);
        if rng.next_u64().is_multiple_of(2) {
            self.dining(r, rng);
        } else {
            self.stools(r, rng);
        }
        self.radiators(r, rng);
    }

    pub(super) fn bedroom(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        if let Some(k) = self.any_against_wall(r, Role::Bed, 0.6, rng) {
            let b = self.placed[k].clone();
            // Nightstands beside the head, against the same wall.
            let stand = r.pick(Role::Nightstand, rng);
            let back = -b.front();
            let across = DVec2::new(back.y, -back.x);
            for sign in [-1.0, 1.0] {
                let half_bed = b.half().dot(across.abs());
                let mut p = b.clone();
                p.model = stand.id.clone();
                p.role = Role::Nightstand;
                p.size_m = stand.size_m;
                p.z_m = 0.0;
                let depth_back = b.half().dot(back.abs());
                let half_stand = p.half();
                let c = b.centre()
                    + back * (depth_back - half_stand.dot(back.abs()))
                    + across * sign * (half_bed + half_stand.dot(across.abs()) + 0.05);
                p.centre = c.to_array();
                if self.fits(r, &p, None, None) {
                    let s = self.put(p, None, None);
                    self.things_on(r, s, Role::TableThing, rng);
                }
            }
        }
        self.any_against_wall(r, Role::Wardrobe, 0.7, rng);
        if rng.next_u64().is_multiple_of(2) {
            self.desk(r, rng);
        }
        self.radiators(r, rng);
        for _ in 0..(rng.next_u64() % 3) {
            let m = r.pick(Role::BedroomThing, rng);
            self.on_floor(r, m, Role::BedroomThing, rng);
        }
    }

    pub(super) fn bathroom(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        let shower = r.pick(Role::Shower, rng);
        self.corner(r, shower, Role::Shower, 0.6, rng);
        self.any_against_wall(r, Role::Toilet, 0.6, rng);
        if let Some(k) = self.any_against_wall(r, Role::Washbasin, 0.6, rng) {
            self.things_on(r, k, Role::BathroomThing, rng);
        }
        let rack = r.pick(Role::TowelRack, rng);
        self.against_wall(r, rack, Role::TowelRack, None, Along::Anywhere, 0.0, rng);
    }

    pub(super) fn hall(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        self.any_against_wall(r, Role::Wardrobe, 0.6, rng);
        self.corner_piece(r, Role::Plant, rng);
        if rng.next_u64().is_multiple_of(2) {
            self.corner_piece(r, Role::FloorThing, rng);
        }
    }

    /// A table with chairs pulled up to its sides (two at least), in the middle of the room or
    /// against a wall.
    fn dining(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        let chair = r.pick(Role::DiningChair, rng);
        let reach = chair.size_m[1] + 0.45;
        let tables = r.shuffled(Role::DiningTable, rng);
        for table in tables.iter().cycle().take(TRIES) {
            let quarter = (rng.next_u64() % 2) as u8;
            let mut t = placed(table, Role::DiningTable, r.room, DVec2::ZERO, quarter, 0.0);
            let margin = t.half() + reach;
            let (lo, hi) = (r.inside.min + margin, r.inside.max - margin);
            if lo.x > hi.x || lo.y > hi.y {
                continue;
            }
            t.centre = DVec2::new(draw(rng, (lo.x, hi.x)), draw(rng, (lo.y, hi.y))).to_array();
            if !self.fits(r, &t, None, None) {
                continue;
            }
            let group = self.placed.len();
            let chairs = chairs_round(&t, chair, r.room);
            let fitting: Vec<Placed> = chairs
                .into_iter()
                .filter(|c| self.fits(r, c, back_zone(c, CHAIR_PULL_M), Some(group)))
                .collect();
            if fitting.len() < 2 {
                continue;
            }
            let tk = self.put(t, None, Some(group));
            for c in fitting {
                // Chairs placed one by one: two may not take the same place.
                let zone = back_zone(&c, CHAIR_PULL_M);
                if self.fits(r, &c, zone, Some(group)) {
                    self.put(c, zone, Some(group));
                }
            }
            self.things_on(r, tk, Role::TableThing, rng);
            return;
        }
    }

    /// A desk against a wall with its chair pulled up to it.
    fn desk(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        let desk = r.pick(Role::Desk, rng);
        let chair = r.pick(Role::DeskChair, rng);
        for _ in 0..TRIES {
            let side = (rng.next_u64() % 4) as u8;
            let d = at_wall(r, desk, Role::Desk, side, draw(rng, (0.0, 1.0)), 0.0);
            if !self.fits(r, &d, None, None) {
                continue;
            }
            let group = self.placed.len();
            let front = d.front();
            let mut c = placed(
                chair,
                Role::DeskChair,
                r.room,
                DVec2::ZERO,
                (d.quarter + 2) % 4,
                0.0,
            );
            let gap = draw(rng, (0.0, 0.08));
            c.centre = (d.centre()
                + front * (d.half().dot(front.abs()) + c.half().dot(front.abs()) + gap))
                .to_array();
            let zone = back_zone(&c, CHAIR_PULL_M);
            if !self.fits(r, &c, zone, Some(group)) {
                continue;
            }
            let dk = self.put(d, None, Some(group));
            self.put(c, zone, Some(group));
            self.things_on(r, dk, Role::TableThing, rng);
            return;
        }
    }

    /// Two or three stools in a row against a free wall.
    fn stools(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        let stool = r.pick(Role::Stool, rng);
        for _ in 0..(2 + rng.next_u64() % 2) {
            self.against_wall(r, stool, Role::Stool, None, Along::Anywhere, 0.4, rng);
        }
    }

    /// The kitchen's units in one run along a wall: the fridge at one end, then worktop units
    /// (one the sink, one under the cooktop), a tall unit at the other end when there is room;
    /// wall units above the worktop.
    fn kitchen_run(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        let mut sides: Vec<u8> = (0..4).collect();
        let start = (rng.next_u64() % 4) as usize;
        sides.rotate_left(start);
        let fridge = r.pick(Role::Fridge, rng);
        let unit = r.pick(Role::KitchenUnit, rng);
        let sink = r.pick(Role::SinkUnit, rng);
        let tall = r.pick(Role::TallUnit, rng);
        let cooktop = r.pick(Role::Cooktop, rng);
        let wall_unit = r.pick(Role::WallUnit, rng);
        // With the fridge at an end of the run first; else the run alone and the fridge
        // against another wall.
        let attempts: Vec<(bool, u8, bool)> = [true, false]
            .into_iter()
            .flat_map(|with_fridge| {
                sides
                    .iter()
                    .flat_map(move |&side| [(with_fridge, side, false), (with_fridge, side, true)])
            })
            .collect();
        for (with_fridge, side, reverse) in attempts {
            let length = wall_length(r, side) - 2.0 * GAP_M;
            let fridge_m = if with_fridge { fridge.size_m[0] } else { 0.0 };
            let most = ((length - fridge_m) / unit.size_m[0]).floor() as i64;
            let Some(run) = (2..=most.min(9)).rev().find_map(|worktop| {
                let with_tall = worktop >= 6;
                let units = (worktop - i64::from(with_tall)) as usize;
                let sink_at = 1 + (rng.next_u64() % (units as u64 - 1).max(1)) as usize;
                let mut sequence: Vec<(&CatalogueModel, Role)> = Vec::new();
                if with_fridge {
                    sequence.push((fridge, Role::Fridge));
                }
                for i in 0..units {
                    sequence.push(if i == sink_at.min(units - 1) {
                        (sink, Role::SinkUnit)
                    } else {
                        (unit, Role::KitchenUnit)
                    });
                }
                if with_tall {
                    sequence.push((tall, Role::TallUnit));
                }
                if reverse {
                    sequence.reverse();
                }
                let total: f64 = sequence.iter().map(|(m, _)| m.size_m[0]).sum();
                let slack = (length - total).max(0.0);
                (0..4).find_map(|_| {
                    let mut s = GAP_M + draw(rng, (0.0, slack));
                    let run: Vec<Placed> = sequence
                        .iter()
                        .map(|(m, role)| {
                            let p = at_wall_offset(r, m, *role, side, s + m.size_m[0] / 2.0, 0.0);
                            s += m.size_m[0];
                            p
                        })
                        .collect();
                    let group = self.placed.len();
                    run.iter()
                        .all(|p| self.fits(r, p, front_zone(p, WORKTOP_USE_M), Some(group)))
                        .then_some(run)
                })
            }) else {
                continue;
            };
            let group = self.placed.len();
            let mut units_placed = Vec::new();
            for p in run {
                let role = p.role;
                let zone = front_zone(&p, WORKTOP_USE_M);
                let k = self.put(p, zone, Some(group));
                if role == Role::KitchenUnit {
                    units_placed.push(k);
                }
            }
            let cook_unit = units_placed
                .get((rng.next_u64() % units_placed.len().max(1) as u64) as usize)
                .copied();
            let mut counters = Vec::new();
            for &k in &units_placed {
                let u = self.placed[k].clone();
                if Some(k) == cook_unit {
                    let mut c = u.clone();
                    c.model = cooktop.id.clone();
                    c.role = Role::Cooktop;
                    c.size_m = cooktop.size_m;
                    c.z_m = u.z_m + unit.surface_m();
                    if c.rect().inside(&u.rect()) && self.fits(r, &c, None, None) {
                        self.put(c, None, None);
                    }
                    continue;
                }
                counters.push(k);
                let mut w = u.clone();
                w.model = wall_unit.id.clone();
                w.role = Role::WallUnit;
                w.size_m = wall_unit.size_m;
                w.z_m = wall_unit.elevation_m.max(u.top_m() + 0.5);
                let back = -u.front();
                w.centre = (u.centre()
                    + back * (u.half().dot(back.abs()) - w.half().dot(back.abs())))
                .to_array();
                if w.top_m() < self.plan.ceiling_m - 0.05 && self.fits(r, &w, None, None) {
                    self.put(w, None, None);
                }
            }
            for k in counters {
                if rng.next_u64().is_multiple_of(2) {
                    self.things_on(r, k, Role::KitchenThing, rng);
                }
            }
            if !with_fridge {
                self.any_against_wall(r, Role::Fridge, WORKTOP_USE_M, rng);
            }
            return;
        }
    }

    /// A radiator under each window of the room, where there is room.
    fn radiators(&mut self, r: &Room, rng: &mut ChaCha8Rng) {
        let windows: Vec<(usize, f64)> = self
            .plan
            .windows
            .iter()
            .filter(|w| w.room == r.room)
            .map(|w| (w.wall, (w.from + w.to) / 2.0))
            .collect();
        for (wall, centre) in windows {
            if rng.next_u64().is_multiple_of(3) {
                continue;
            }
            let m = r.pick(Role::Radiator, rng);
            let line = self.plan.walls[wall];
            let side = side_of_wall(r, &line);
            let p = at_wall_offset(
                r,
                m,
                Role::Radiator,
                side,
                offset_along(r, side, centre),
                0.0,
            );
            if p.top_m() < self.sill_below(r.room, wall) && self.fits(r, &p, None, None) {
                self.put(p, None, None);
            }
        }
    }
}
