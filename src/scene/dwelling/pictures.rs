//! Pictures hung on a dwelling's walls: where they go (on a room's own walls at eye height,
//! clear of doorways, windows and every piece standing or hanging there, apart from each
//! other) and what they show (a painting drawn per picture — shapes, a landscape or a grid of
//! coloured fields — in a frame, drawn as the picture's own PNG texture when the GLB is
//! written). They are drawn from the dwelling's seed on a stream of their own, so the plan
//! and the furniture are drawn as without them. Real rooms have pictures on their walls, and a camera close to a plain
//! wall sees nothing to track (docs/SCENES.md).

use glam::{DVec2, DVec3};
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::plan::{FloorPlan, RoomKind};
use super::{draw, Placed};
use crate::math::colour::hsv_to_rgb;

/// Pixels along a painting's longer side.
const LONG_SIDE_PX: u32 = 256;

/// How far a picture stands out from its wall's face, and how far its back is sunk into the
/// wall (no face shared with the wall: coplanar faces render black).
const DEPTH_M: f64 = 0.025;
const SUNK_M: f64 = 0.005;

/// Clearances (m): from a doorway's or window's edge, round any piece, between pictures.
const OPENING_GAP_M: f64 = 0.15;
const PIECE_GAP_M: f64 = 0.05;
const PICTURE_GAP_M: f64 = 0.25;

/// A box (its least and greatest corners, z up, m).
type Block = (DVec3, DVec3);

/// A picture hung on a wall: its box, its room and its painting.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Picture {
    pub block: Block,
    pub room: usize,
    pub painting: Painting,
}

/// A picture's painting as the GLB textures its front.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Painting {
    /// What it shows, drawn from this seed when the GLB is written ([`Painting::png`]).
    pub seed: u64,
    /// The lower left corner of its front as one faces it (z up, m).
    pub origin: DVec3,
    /// Unit vector to the right along the wall as one faces it.
    pub right: DVec2,
    /// Width and height of the front (m).
    pub size_m: [f64; 2],
}

impl Painting {
    /// The image, PNG (8-bit RGB), [`LONG_SIDE_PX`] along its longer side.
    pub(super) fn png(&self) -> Vec<u8> {
        let [width, height] = self.size_m;
        let short = |a: f64, b: f64| ((LONG_SIDE_PX as f64 * a / b).round() as u32).max(64);
        let (w, h) = if width >= height {
            (LONG_SIDE_PX, short(height, width))
        } else {
            (short(width, height), LONG_SIDE_PX)
        };
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        png_rgb(&paint(&mut rng, w, h))
    }

    /// Texture coordinates of a point of the picture's box: its front maps onto the whole
    /// image (glTF's v runs down from the image's top), the sides take the frame's edge.
    pub(super) fn uv(&self, p: DVec3) -> [f32; 2] {
        let d = p - self.origin;
        let u = (d.truncate().dot(self.right) / self.size_m[0]).clamp(0.0, 1.0);
        let v = (1.0 - d.z / self.size_m[1]).clamp(0.0, 1.0);
        [u as f32, v as f32]
    }
}

/// How many pictures a room of this kind gets (least, most).
fn pictures_in(kind: RoomKind) -> (u64, u64) {
    match kind {
        RoomKind::Living => (2, 4),
        RoomKind::Bedroom => (1, 3),
        RoomKind::Hall => (1, 2),
        RoomKind::Kitchen => (0, 2),
        RoomKind::Bathroom => (0, 1),
    }
}

/// One side of a room's interior: the wall face at `at` across, from `from` to `to` along
/// (along x for a face at constant y), facing into the room along `inward`.
struct Side {
    along_x: bool,
    at: f64,
    from: f64,
    to: f64,
    inward: f64,
}

impl Side {
    fn point(&self, along: f64, across: f64, z: f64) -> DVec3 {
        let c = self.at + self.inward * across;
        if self.along_x {
            DVec3::new(along, c, z)
        } else {
            DVec3::new(c, along, z)
        }
    }
}

/// The pictures of a dwelling, room by room. `salt` tells draws of one seed apart.
pub(super) fn hang(plan: &FloorPlan, placed: &[Placed], seed: u64, salt: u64) -> Vec<Picture> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x7069_6374_7572_6573 ^ salt.rotate_left(40));
    let mut hung: Vec<Block> = Vec::new();
    let mut out = Vec::new();
    let pieces: Vec<Block> = placed
        .iter()
        .map(|p| {
            let (c, h) = (p.centre(), p.half());
            ((c - h).extend(p.z_m), (c + h).extend(p.z_m + p.size_m[2]))
        })
        .collect();
    for (k, room) in plan.rooms.iter().enumerate() {
        let (least, most) = pictures_in(room.kind);
        let wanted = least + rng.next_u64() % (most - least + 1);
        let (lo, hi) = plan.interior(k);
        let sides = [
            Side {
                along_x: true,
                at: lo.y,
                from: lo.x,
                to: hi.x,
                inward: 1.0,
            },
            Side {
                along_x: true,
                at: hi.y,
                from: lo.x,
                to: hi.x,
                inward: -1.0,
            },
            Side {
                along_x: false,
                at: lo.x,
                from: lo.y,
                to: hi.y,
                inward: 1.0,
            },
            Side {
                along_x: false,
                at: hi.x,
                from: lo.y,
                to: hi.y,
                inward: -1.0,
            },
        ];
        let mut placed_here = 0;
        for _ in 0..12 * wanted {
            if placed_here == wanted {
                break;
            }
            let side = &sides[(rng.next_u64() % 4) as usize];
            let Some(block) = draw_spot(plan, side, &mut rng) else {
                continue;
            };
            let clear =
                |others: &[Block], gap: f64| others.iter().all(|o| !overlaps(&block, o, gap));
            if !clear(&pieces, PIECE_GAP_M)
                || !clear(&hung, PICTURE_GAP_M)
                || in_an_opening(plan, side, &block)
            {
                continue;
            }
            hung.push(block);
            placed_here += 1;
            out.push(picture(side, block, k, &mut rng));
        }
    }
    out
}

/// A picture's box on `side`, of a drawn size at eye height, where the wall is long enough.
fn draw_spot(plan: &FloorPlan, side: &Side, rng: &mut ChaCha8Rng) -> Option<Block> {
    let room_for = side.to - side.from - 2.0 * 0.2;
    let w = draw(rng, (0.35, 1.1)).min(room_for);
    let h = (w * draw(rng, (0.6, 1.3))).clamp(0.3, 0.9);
    let top = (draw(rng, (1.45, 1.65)) + h / 2.0).min(plan.ceiling_m - 0.3);
    if w < 0.3 || top - h < 1.05 {
        return None;
    }
    let s = draw(rng, (side.from + 0.2 + w / 2.0, side.to - 0.2 - w / 2.0));
    let a = side.point(s - w / 2.0, -SUNK_M, top - h);
    let b = side.point(s + w / 2.0, DEPTH_M, top);
    Some((a.min(b), a.max(b)))
}

/// Whether two boxes come within `gap` of each other.
fn overlaps(a: &Block, b: &Block, gap: f64) -> bool {
    (a.0 - gap).cmplt(b.1).all() && (b.0 - gap).cmplt(a.1).all()
}

/// Whether the box comes within [`OPENING_GAP_M`] of a doorway or window in the wall of `side`.
fn in_an_opening(plan: &FloorPlan, side: &Side, block: &Block) -> bool {
    let (a, b, z0, z1) = if side.along_x {
        (block.0.x, block.1.x, block.0.z, block.1.z)
    } else {
        (block.0.y, block.1.y, block.0.z, block.1.z)
    };
    let on_side = |wall: usize| {
        let w = &plan.walls[wall];
        w.vertical != side.along_x && (w.at - side.at).abs() <= plan.thickness(w) / 2.0 + 1e-6
    };
    let near = |from: f64, to: f64, bottom: f64, top: f64| {
        a < to + OPENING_GAP_M
            && from - OPENING_GAP_M < b
            && z0 < top + OPENING_GAP_M
            && bottom - OPENING_GAP_M < z1
    };
    plan.doors
        .iter()
        .any(|d| on_side(d.wall) && near(d.from, d.to, 0.0, super::plan::DOOR_HEIGHT_M))
        || plan
            .windows
            .iter()
            .any(|w| on_side(w.wall) && near(w.from, w.to, w.sill_m, w.top_m))
}

/// The picture in `block` on `side`, its painting drawn.
fn picture(side: &Side, block: Block, room: usize, rng: &mut ChaCha8Rng) -> Picture {
    let (lo, hi) = block;
    // Facing the wall (looking along −inward), right is (−inward) × z.
    let right = if side.along_x {
        DVec2::new(side.inward, 0.0)
    } else {
        DVec2::new(0.0, -side.inward)
    };
    let (from, to) = if side.along_x {
        (lo.x, hi.x)
    } else {
        (lo.y, hi.y)
    };
    let (width, height) = (to - from, hi.z - lo.z);
    let left_along = if right.x + right.y > 0.0 { from } else { to };
    let origin = side.point(left_along, DEPTH_M, lo.z);
    Picture {
        block,
        room,
        painting: Painting {
            seed: rng.next_u64(),
            origin,
            right,
            size_m: [width, height],
        },
    }
}

/// An RGB image, row by row from the top.
struct Canvas {
    w: u32,
    h: u32,
    px: Vec<[u8; 3]>,
}

impl Canvas {
    fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < self.w && (y as u32) < self.h {
            self.px[(y as u32 * self.w + x as u32) as usize] = c;
        }
    }

    /// Fills the pixels whose centres `inside` says are in, over the box `lo`..`hi` (pixels).
    fn fill(&mut self, lo: DVec2, hi: DVec2, c: [u8; 3], inside: impl Fn(DVec2) -> bool) {
        for y in lo.y.floor().max(0.0) as i64..hi.y.ceil().min(self.h as f64) as i64 {
            for x in lo.x.floor().max(0.0) as i64..hi.x.ceil().min(self.w as f64) as i64 {
                if inside(DVec2::new(x as f64 + 0.5, y as f64 + 0.5)) {
                    self.set(x, y, c);
                }
            }
        }
    }
}

fn colour(rng: &mut ChaCha8Rng, s: (f64, f64), v: (f64, f64)) -> [u8; 3] {
    let rgb = hsv_to_rgb(draw(rng, (0.0, 360.0)), draw(rng, s), draw(rng, v));
    rgb.map(|c| (c * 255.0).round() as u8)
}

/// A frame's colour: black, white, a wood or gilt.
fn frame_colour(rng: &mut ChaCha8Rng) -> [u8; 3] {
    let (hue, s, v) = match rng.next_u64() % 4 {
        0 => ((0.0, 360.0), (0.0, 0.1), (0.05, 0.15)),
        1 => ((0.0, 360.0), (0.0, 0.08), (0.85, 0.95)),
        2 => ((20.0, 40.0), (0.4, 0.7), (0.25, 0.6)),
        _ => ((40.0, 50.0), (0.5, 0.7), (0.6, 0.8)),
    };
    let rgb = hsv_to_rgb(draw(rng, hue), draw(rng, s), draw(rng, v));
    rgb.map(|c| (c * 255.0).round() as u8)
}

/// A painting of `w` by `h` pixels in its frame: shapes, a landscape or coloured fields.
fn paint(rng: &mut ChaCha8Rng, w: u32, h: u32) -> Canvas {
    let mut c = Canvas {
        w,
        h,
        px: vec![[0; 3]; (w * h) as usize],
    };
    let (wf, hf) = (w as f64, h as f64);
    let all = (DVec2::ZERO, DVec2::new(wf, hf));
    match rng.next_u64() % 3 {
        0 => {
            c.fill(all.0, all.1, colour(rng, (0.1, 0.5), (0.6, 0.95)), |_| true);
            for _ in 0..10 + rng.next_u64() % 20 {
                let centre = DVec2::new(draw(rng, (0.0, wf)), draw(rng, (0.0, hf)));
                let r = draw(rng, (0.04, 0.25)) * wf.min(hf);
                let ink = colour(rng, (0.3, 0.95), (0.2, 0.95));
                match rng.next_u64() % 3 {
                    0 => c.fill(centre - r, centre + r, ink, |p| p.distance(centre) <= r),
                    1 => {
                        let half = DVec2::new(r, r * draw(rng, (0.3, 1.5)));
                        c.fill(centre - half, centre + half, ink, |_| true)
                    }
                    _ => {
                        let t = [0, 1, 2].map(|_| {
                            centre + DVec2::new(draw(rng, (-r, r)), draw(rng, (-r, r))) * 1.5
                        });
                        let side = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
                        let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                        c.fill(lo, hi, ink, |p| {
                            let s = [
                                side(t[0], t[1], p),
                                side(t[1], t[2], p),
                                side(t[2], t[0], p),
                            ];
                            s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
                        })
                    }
                }
            }
        }
        1 => {
            // Sky fading to the horizon, a sun, ridges nearer and darker down the picture.
            let (top, low) = (
                colour(rng, (0.2, 0.7), (0.6, 1.0)),
                colour(rng, (0.1, 0.5), (0.7, 1.0)),
            );
            for y in 0..h {
                let t = y as f64 / hf;
                let mix = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * t).round() as u8;
                let row = [
                    mix(top[0], low[0]),
                    mix(top[1], low[1]),
                    mix(top[2], low[2]),
                ];
                c.fill(
                    DVec2::new(0.0, y as f64),
                    DVec2::new(wf, y as f64 + 1.0),
                    row,
                    |_| true,
                );
            }
            let sun = DVec2::new(draw(rng, (0.1, 0.9)) * wf, draw(rng, (0.1, 0.4)) * hf);
            let r = draw(rng, (0.04, 0.1)) * wf.min(hf);
            c.fill(sun - r, sun + r, colour(rng, (0.2, 0.8), (0.9, 1.0)), |p| {
                p.distance(sun) <= r
            });
            let ridges = 2 + rng.next_u64() % 3;
            for k in 0..ridges {
                let base = hf * (0.35 + 0.5 * (k + 1) as f64 / (ridges + 1) as f64);
                let waves: Vec<(f64, f64, f64)> = (0..4)
                    .map(|_| {
                        (
                            draw(rng, (0.5, 3.5)) / wf,
                            draw(rng, (0.0, 6.3)),
                            draw(rng, (0.015, 0.06)) * hf,
                        )
                    })
                    .collect();
                let ink = colour(rng, (0.2, 0.8), (0.15, 0.7 - 0.12 * k as f64));
                c.fill(DVec2::ZERO, DVec2::new(wf, hf), ink, |p| {
                    let ridge: f64 = waves
                        .iter()
                        .map(|(f, ph, a)| a * (std::f64::consts::TAU * f * p.x + ph).sin())
                        .sum();
                    p.y >= base + ridge
                });
            }
        }
        _ => {
            // Fields split again and again, lines between them.
            let mut fields = vec![all];
            for _ in 0..6 + rng.next_u64() % 8 {
                let k = (rng.next_u64() % fields.len() as u64) as usize;
                let (lo, hi) = fields.swap_remove(k);
                let size = hi - lo;
                if size.min_element() < 24.0 {
                    fields.push((lo, hi));
                    continue;
                }
                let t = draw(rng, (0.3, 0.7));
                if size.x > size.y {
                    let x = lo.x + t * size.x;
                    fields.push((lo, DVec2::new(x, hi.y)));
                    fields.push((DVec2::new(x, lo.y), hi));
                } else {
                    let y = lo.y + t * size.y;
                    fields.push((lo, DVec2::new(hi.x, y)));
                    fields.push((DVec2::new(lo.x, y), hi));
                }
            }
            let line = colour(rng, (0.0, 0.3), (0.05, 0.2));
            c.fill(all.0, all.1, line, |_| true);
            for (lo, hi) in fields {
                let ink = if rng.next_u64().is_multiple_of(3) {
                    colour(rng, (0.6, 1.0), (0.5, 0.95))
                } else {
                    colour(rng, (0.0, 0.15), (0.8, 0.97))
                };
                c.fill(lo + 2.0, hi - 2.0, ink, |_| true);
            }
        }
    }
    // The frame: a band round the edge, with a dark line inside it.
    let band = (0.07 * wf.min(hf)).round().max(3.0);
    let frame = frame_colour(rng);
    let (inner_lo, inner_hi) = (DVec2::splat(band), DVec2::new(wf - band, hf - band));
    let edge = DVec2::splat(1.5);
    c.fill(all.0, all.1, [30, 26, 22], |p| {
        !(p.cmpgt(inner_lo + edge).all() && p.cmplt(inner_hi - edge).all())
    });
    c.fill(all.0, all.1, frame, |p| {
        !(p.cmpgt(inner_lo).all() && p.cmplt(inner_hi).all())
    });
    c
}

/// The canvas as PNG bytes (the same canvas, the same bytes).
fn png_rgb(c: &Canvas) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, c.w, c.h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("PNG header into memory");
    let flat: Vec<u8> = c.px.iter().flatten().copied().collect();
    writer
        .write_image_data(&flat)
        .expect("PNG data into memory");
    writer.finish().expect("PNG into memory");
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::dwelling::{generate, shipped_catalogue_dir, Catalogue, DwellingSettings};

    #[test]
    fn pictures_hang_on_walls_clear_of_openings_and_pieces_and_show_a_framed_painting() {
        let catalogue = Catalogue::load(&shipped_catalogue_dir()).unwrap();
        let mut total = 0;
        for seed in 300..306 {
            let d = generate(&DwellingSettings::default(), &catalogue, seed).unwrap();
            // The dwelling's own pictures: those of its last draw.
            let pictures = hang(&d.plan, &d.placed, seed, d.tries as u64);
            let in_mesh = d
                .mesh
                .objects
                .iter()
                .filter(|o| o.name.starts_with("picture_"));
            assert_eq!(in_mesh.count(), pictures.len(), "seed {seed}");
            total += pictures.len();
            for p in &pictures {
                let (lo, hi) = d.plan.interior(p.room);
                // On a wall of its own room: its back sunk into the wall, the rest inside.
                let flat = p.block.1 - p.block.0;
                assert!(flat.min_element() <= DEPTH_M + SUNK_M + 1e-9);
                assert!(p.block.0.truncate().cmpge(lo - SUNK_M - 1e-9).all());
                assert!(p.block.1.truncate().cmple(hi + SUNK_M + 1e-9).all());
                assert!(p.block.0.z >= 1.05 - 1e-9 && p.block.1.z <= d.plan.ceiling_m - 0.3 + 1e-9);
                for piece in &d.placed {
                    let (c, h) = (piece.centre(), piece.half());
                    let bounds = (
                        (c - h).extend(piece.z_m),
                        (c + h).extend(piece.z_m + piece.size_m[2]),
                    );
                    assert!(
                        !overlaps(&p.block, &bounds, 0.0),
                        "seed {seed}: {}",
                        piece.model
                    );
                }
                let png = p.painting.png();
                let decoder = png::Decoder::new(std::io::Cursor::new(png.as_slice()));
                let info = decoder.read_info().unwrap().info().clone();
                assert_eq!(info.width.max(info.height), LONG_SIDE_PX);
                let [w, h] = p.painting.size_m;
                let aspect = info.width as f64 / info.height as f64;
                assert!((w / h - aspect).abs() < 0.05 + 64.0 / LONG_SIDE_PX as f64);
                // Its front's lower left and upper right corners map to the image's corners.
                let o = p.painting.origin;
                let corner = o + p.painting.right.extend(0.0) * w + DVec3::Z * h;
                assert_eq!(p.painting.uv(o), [0.0, 1.0]);
                assert_eq!(p.painting.uv(corner), [1.0, 0.0]);
                assert!(!in_an_opening(&d.plan, &side_of(&d.plan, p), &p.block));
            }
            for (i, a) in pictures.iter().enumerate() {
                for b in &pictures[i + 1..] {
                    assert!(!overlaps(&a.block, &b.block, 0.2), "seed {seed}");
                }
            }
            let rooms_with: std::collections::BTreeSet<usize> =
                pictures.iter().map(|p| p.room).collect();
            assert!(
                rooms_with.len() >= 2,
                "seed {seed}: pictures in {rooms_with:?}"
            );
        }
        assert!(total >= 6 * 4, "{total} pictures in 6 dwellings");
    }

    /// The side of its room a picture hangs on: the one its thin box's back is sunk into.
    fn side_of(plan: &FloorPlan, p: &Picture) -> Side {
        let (lo, hi) = plan.interior(p.room);
        let (a, c) = p.block;
        let at_lo = |x: f64, face: f64| (x - (face - SUNK_M)).abs() < 1e-9;
        if c.y - a.y < 0.1 {
            let (at, inward) = if at_lo(a.y, lo.y) {
                (lo.y, 1.0)
            } else {
                (hi.y, -1.0)
            };
            Side {
                along_x: true,
                at,
                from: lo.x,
                to: hi.x,
                inward,
            }
        } else {
            let (at, inward) = if at_lo(a.x, lo.x) {
                (lo.x, 1.0)
            } else {
                (hi.x, -1.0)
            };
            Side {
                along_x: false,
                at,
                from: lo.y,
                to: hi.y,
                inward,
            }
        }
    }

    #[test]
    fn a_painting_is_drawn_again_the_same() {
        let draw_one = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let c = paint(&mut rng, 200, 120);
            png_rgb(&c)
        };
        assert_eq!(draw_one(3), draw_one(3));
        assert_ne!(draw_one(3), draw_one(4));
    }
}
