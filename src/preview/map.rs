//! PNG of a walkable map with sensing rays drawn on it.

use glam::DVec2;

use super::RgbImage;
use crate::scene::{Obstacle2, WalkableMap};

/// Colours: walkable light, occupied dark, no floor mid grey; on stepped floors walkable cells
/// run from `WALKABLE` (the lowest floor) to `WALKABLE_HIGHEST` (the highest).
const WALKABLE: [u8; 3] = [250, 250, 245];
const WALKABLE_HIGHEST: [u8; 3] = [150, 200, 250];
const OCCUPIED: [u8; 3] = [60, 60, 70];
const NO_FLOOR: [u8; 3] = [170, 170, 175];

/// A top view of the map (x right, y up) with `px_per_cell` pixels per cell.
pub(crate) struct MapPicture<'a> {
    pub map: &'a WalkableMap,
    pub image: RgbImage,
    px_per_cell: usize,
}

impl<'a> MapPicture<'a> {
    pub(crate) fn new(map: &'a WalkableMap, max_side_px: usize) -> Self {
        let px_per_cell = (max_side_px / map.nx.max(map.ny)).max(1);
        let mut image = RgbImage::new(map.nx * px_per_cell, map.ny * px_per_cell, NO_FLOOR);
        let (lowest, highest) = map
            .floor_range(|k| map.walkable[k])
            .unwrap_or((map.floor_z_m, map.floor_z_m));
        let walkable = |k: usize| {
            let t = if highest - lowest > 1e-3 {
                (map.cell_floor_m(k) - lowest) / (highest - lowest)
            } else {
                0.0
            };
            std::array::from_fn(|c| {
                (WALKABLE[c] as f64 + t * (WALKABLE_HIGHEST[c] as f64 - WALKABLE[c] as f64)).round()
                    as u8
            })
        };
        for j in 0..map.ny {
            for i in 0..map.nx {
                let k = j * map.nx + i;
                let c = if map.walkable[k] {
                    walkable(k)
                } else if map.occupied[k] {
                    OCCUPIED
                } else {
                    NO_FLOOR
                };
                for y in 0..px_per_cell {
                    let row = (map.ny - 1 - j) * px_per_cell + y;
                    let start = row * image.width + i * px_per_cell;
                    image.pixels[start..start + px_per_cell].fill(c);
                }
            }
        }
        Self {
            map,
            image,
            px_per_cell,
        }
    }

    /// Paints the cells where `mask` holds (row-major, the map's grid) in `rgb`.
    pub(crate) fn shade_cells(&mut self, mask: &[bool], rgb: [u8; 3]) {
        let (map, px) = (self.map, self.px_per_cell);
        for j in 0..map.ny {
            for i in 0..map.nx {
                if mask.get(j * map.nx + i).copied().unwrap_or(false) {
                    for y in 0..px {
                        let row = (map.ny - 1 - j) * px + y;
                        let start = row * self.image.width + i * px;
                        self.image.pixels[start..start + px].fill(rgb);
                    }
                }
            }
        }
    }

    fn to_px(&self, p: DVec2) -> DVec2 {
        let q = (p - self.map.origin) / self.map.cell_m * self.px_per_cell as f64;
        DVec2::new(q.x, self.image.height as f64 - q.y)
    }

    /// Draws a world-space segment.
    pub(crate) fn line(&mut self, a: DVec2, b: DVec2, rgb: [u8; 3]) {
        let (pa, pb) = (self.to_px(a), self.to_px(b));
        let n = (pb - pa).abs().max_element().ceil().max(1.0) as usize;
        for s in 0..=n {
            let p = pa + (pb - pa) * (s as f64 / n as f64);
            self.dot_px(p, 0, rgb);
        }
    }

    /// Draws a filled disc of `radius_px` at a world point.
    pub(crate) fn dot(&mut self, p: DVec2, radius_px: i64, rgb: [u8; 3]) {
        let q = self.to_px(p);
        self.dot_px(q, radius_px, rgb);
    }

    fn dot_px(&mut self, p: DVec2, r: i64, rgb: [u8; 3]) {
        for dy in -r..=r {
            for dx in -r..=r {
                if dx * dx + dy * dy > r * r {
                    continue;
                }
                let (x, y) = (p.x as i64 + dx, p.y as i64 + dy);
                if x >= 0
                    && y >= 0
                    && (x as usize) < self.image.width
                    && (y as usize) < self.image.height
                {
                    self.image.pixels[y as usize * self.image.width + x as usize] = rgb;
                }
            }
        }
    }

    /// Outlines an obstacle footprint.
    pub(crate) fn obstacle(&mut self, o: &Obstacle2, rgb: [u8; 3]) {
        let pts: Vec<DVec2> = match *o {
            Obstacle2::Box {
                centre,
                half_extents,
                yaw_rad,
            } => {
                let r = DVec2::from_angle(yaw_rad);
                [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .iter()
                    .map(|&(a, b)| centre + r.rotate(half_extents * DVec2::new(a, b)))
                    .collect()
            }
            Obstacle2::Circle { centre, radius_m } => (0..32)
                .map(|k| {
                    centre + DVec2::from_angle(k as f64 / 32.0 * std::f64::consts::TAU) * radius_m
                })
                .collect(),
        };
        for k in 0..pts.len() {
            self.line(pts[k], pts[(k + 1) % pts.len()], rgb);
        }
    }
}

/// Colours of agents (their paths, starts and pictures), in turn.
pub(crate) const AGENT_COLOURS: [[u8; 3]; 8] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [148, 103, 189],
    [255, 127, 14],
    [23, 190, 207],
    [227, 119, 194],
    [140, 86, 75],
];
