//! What the dwelling generator builds besides furniture (`Built`): a wall object per wall line
//! with its doorways and windows cut out, a floor, a ceiling and a lamp per room, a frame per
//! doorway and window, door leaves standing open; each a named object of boxes with its look
//! (`glb::Look`), and the pictures hung on the walls (`pictures`) with their paintings.

use glam::DVec3;

use super::glb;
use super::pictures::{self, Painting};
use super::plan::{self, FloorPlan};
use super::Placed;

/// How far short of the far face of the wall it meets a wall's end stops (m).
const WALL_END_INSET_M: f64 = 0.005;

/// A box of the generated architecture.
pub(super) type Block = (DVec3, DVec3);

/// What the generator builds besides furniture: walls, floors, ceilings, frames, leaves,
/// lamps, pictures: each a named object of boxes with its look.
pub(super) struct Built {
    pub name: String,
    pub look: glb::Look,
    pub room: Option<usize>,
    pub blocks: Vec<Block>,
    /// A picture's painting, textured onto its front; none for the rest.
    pub painting: Option<Painting>,
}

/// The architecture: a wall object per wall line (with its doorways and windows cut out), a
/// floor and a ceiling and a lamp per room, a frame per doorway and window, open leaves.
pub(super) fn build(plan: &FloorPlan) -> Vec<Built> {
    let h = plan.ceiling_m;
    let mut out = Vec::new();
    for (k, w) in plan.walls.iter().enumerate() {
        let t = plan.thickness(w);
        let mut openings: Vec<(f64, f64, f64, f64)> = plan
            .doors
            .iter()
            .filter(|d| d.wall == k)
            .map(|d| (d.from, d.to, 0.0, plan::DOOR_HEIGHT_M))
            .chain(
                plan.windows
                    .iter()
                    .filter(|win| win.wall == k)
                    .map(|win| (win.from, win.to, win.sill_m, win.top_m)),
            )
            .collect();
        openings.sort_by(|a, b| a.0.total_cmp(&b.0));
        let piece = |a: f64, b: f64, z0: f64, z1: f64| span_block(w, t, a, b, z0, z1);
        let mut blocks = Vec::new();
        // Each end runs into the wall it meets, 5 mm short of that wall's far face: an end
        // flush with it would share its face, and coplanar faces render black (each one's
        // shadow rays hit the other).
        let reach = t / 2.0 - WALL_END_INSET_M;
        let mut cursor = w.from - reach;
        for &(a, b, bottom, top) in &openings {
            blocks.push(piece(cursor, a, 0.0, h));
            if bottom > 0.0 {
                blocks.push(piece(a, b, 0.0, bottom));
            }
            blocks.push(piece(a, b, top, h));
            cursor = b;
        }
        blocks.push(piece(cursor, w.to + reach, 0.0, h));
        out.push(Built {
            name: format!("wall_{}", k + 1),
            look: glb::Look::Wall,
            room: None,
            blocks,
            painting: None,
        });
    }
    for (k, d) in plan.doors.iter().enumerate() {
        let w = &plan.walls[d.wall];
        let t = plan.thickness(w) + 0.04;
        let top = plan::DOOR_HEIGHT_M;
        out.push(Built {
            name: format!("door_frame_{}", k + 1),
            look: glb::Look::Frame,
            room: None,
            blocks: vec![
                // Jambs up to the head, the head across them: no two boxes share a face.
                span_block(w, t, d.from, d.from + 0.04, 0.0, top - 0.04),
                span_block(w, t, d.to - 0.04, d.to, 0.0, top - 0.04),
                span_block(w, t, d.from, d.to, top - 0.04, top),
            ],
            painting: None,
        });
        if let Some(at_from) = d.leaf_at_from {
            // Open at right angles into the second room, against the hinge's jamb.
            let into = plan.rooms[d.rooms[1]].min()
                + (plan.rooms[d.rooms[1]].max() - plan.rooms[d.rooms[1]].min()) / 2.0;
            let across = if w.vertical {
                into.x - w.at
            } else {
                into.y - w.at
            }
            .signum();
            // 5 mm clear of the jamb (a hinge's gap: no face shared with the frame).
            let leaf = d.to - d.from - 0.09;
            let (a, b) = if at_from {
                (d.from + 0.045, d.from + 0.085)
            } else {
                (d.to - 0.085, d.to - 0.045)
            };
            let (c0, c1) = (w.at + across * t / 2.0, w.at + across * (t / 2.0 + leaf));
            out.push(Built {
                name: format!("door_{}", k + 1),
                look: glb::Look::Leaf,
                room: Some(d.rooms[1]),
                blocks: vec![cross_block(
                    w,
                    a,
                    b,
                    c0.min(c1),
                    c0.max(c1),
                    0.01,
                    top - 0.05,
                )],
                painting: None,
            });
        }
    }
    for (k, win) in plan.windows.iter().enumerate() {
        let w = &plan.walls[win.wall];
        let t = 0.08;
        let (a, b, s, top) = (win.from, win.to, win.sill_m, win.top_m);
        out.push(Built {
            name: format!("window_{}", k + 1),
            look: glb::Look::Frame,
            room: Some(win.room),
            blocks: vec![
                // Posts and the mullion between the sill and head bars (no shared faces).
                span_block(w, t, a, a + 0.05, s + 0.05, top - 0.05),
                span_block(w, t, b - 0.05, b, s + 0.05, top - 0.05),
                span_block(w, t, a, b, s, s + 0.05),
                span_block(w, t, a, b, top - 0.05, top),
                span_block(
                    w,
                    0.05,
                    (a + b) / 2.0 - 0.02,
                    (a + b) / 2.0 + 0.02,
                    s + 0.05,
                    top - 0.05,
                ),
            ],
            painting: None,
        });
    }
    for (k, r) in plan.rooms.iter().enumerate() {
        let (lo, hi) = (r.min(), r.max());
        let c = (lo + hi) / 2.0;
        out.push(Built {
            name: format!("floor_{}", r.name),
            look: glb::Look::Floor,
            room: Some(k),
            blocks: vec![(lo.extend(-0.05), hi.extend(0.0))],
            painting: None,
        });
        out.push(Built {
            name: format!("ceiling_{}", r.name),
            look: glb::Look::Ceiling,
            room: Some(k),
            blocks: vec![(lo.extend(h), hi.extend(h + 0.05))],
            painting: None,
        });
        out.push(Built {
            name: format!("lamp_{}", r.name),
            look: glb::Look::Lamp,
            room: Some(k),
            blocks: vec![((c - 0.2).extend(h - 0.03), (c + 0.2).extend(h))],
            painting: None,
        });
    }
    out
}

/// A box along wall `w`, `t` thick about its line, from `a` to `b` along it.
fn span_block(w: &plan::WallLine, t: f64, a: f64, b: f64, z0: f64, z1: f64) -> Block {
    cross_block(w, a, b, w.at - t / 2.0, w.at + t / 2.0, z0, z1)
}

/// A box from `a` to `b` along wall `w` and `c0` to `c1` across it.
fn cross_block(w: &plan::WallLine, a: f64, b: f64, c0: f64, c1: f64, z0: f64, z1: f64) -> Block {
    if w.vertical {
        (DVec3::new(c0, a, z0), DVec3::new(c1, b, z1))
    } else {
        (DVec3::new(a, c0, z0), DVec3::new(b, c1, z1))
    }
}

/// The pictures hung in a furnished plan, as built objects (`picture_N`, textured with their
/// paintings); `salt` tells draws of one seed apart.
pub(super) fn hang_pictures(
    plan: &FloorPlan,
    placed: &[Placed],
    seed: u64,
    salt: u64,
) -> Vec<Built> {
    pictures::hang(plan, placed, seed, salt)
        .into_iter()
        .enumerate()
        .map(|(k, p)| Built {
            name: format!("picture_{}", k + 1),
            look: glb::Look::Frame,
            room: Some(p.room),
            blocks: vec![p.block],
            painting: Some(p.painting),
        })
        .collect()
}
