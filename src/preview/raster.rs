//! A z-buffered, flat-shaded triangle rasteriser with an orthographic camera, enough to show
//! that a mesh is a body. Not a renderer of record: datasets come from Blender Cycles.

use std::path::Path;

use crate::math::{Mat3, Vec3};

/// An 8-bit RGB image.
#[derive(Debug, Clone)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[u8; 3]>,
}

impl RgbImage {
    /// A blank image of one colour.
    pub fn new(width: usize, height: usize, fill: [u8; 3]) -> Self {
        Self {
            width,
            height,
            pixels: vec![fill; width * height],
        }
    }

    /// Places `other` side by side to the right of `self` (tops aligned).
    pub(crate) fn hconcat(&self, other: &RgbImage, fill: [u8; 3]) -> RgbImage {
        let height = self.height.max(other.height);
        let mut out = RgbImage::new(self.width + other.width, height, fill);
        for (img, x0) in [(self, 0), (other, self.width)] {
            for y in 0..img.height {
                let src = &img.pixels[y * img.width..(y + 1) * img.width];
                out.pixels[y * out.width + x0..y * out.width + x0 + img.width].copy_from_slice(src);
            }
        }
        out
    }

    /// The image shrunk by a whole factor (box-averaged) so that its longer side fits
    /// `max_px`; the image itself when it fits already.
    pub(crate) fn downscaled_to(&self, max_px: usize) -> RgbImage {
        let factor = self.width.max(self.height).div_ceil(max_px.max(1)).max(1);
        if factor == 1 {
            return self.clone();
        }
        let (w, h) = (self.width / factor, self.height / factor);
        let mut out = RgbImage::new(w.max(1), h.max(1), [0, 0, 0]);
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0u32; 3];
                for dy in 0..factor {
                    for dx in 0..factor {
                        let p = self.pixels[(y * factor + dy) * self.width + x * factor + dx];
                        for c in 0..3 {
                            sum[c] += p[c] as u32;
                        }
                    }
                }
                let n = (factor * factor) as u32;
                out.pixels[y * out.width + x] = sum.map(|s| ((s + n / 2) / n) as u8);
            }
        }
        out
    }

    /// `images` centred in square cells of `cell_px` (a larger one cropped to its cell),
    /// `per_row` (≥ 1) to a row, on `fill`; one blank cell when there are none.
    pub(crate) fn contact_sheet(
        images: &[RgbImage],
        cell_px: usize,
        per_row: usize,
        fill: [u8; 3],
    ) -> RgbImage {
        let cols = images.len().clamp(1, per_row);
        let rows = images.len().div_ceil(per_row).max(1);
        let mut out = RgbImage::new(cols * cell_px, rows * cell_px, fill);
        for (k, img) in images.iter().enumerate() {
            let (w, h) = (img.width.min(cell_px), img.height.min(cell_px));
            let x0 = (k % per_row) * cell_px + (cell_px - w) / 2;
            let y0 = (k / per_row) * cell_px + (cell_px - h) / 2;
            for y in 0..h {
                let row = (y0 + y) * out.width + x0;
                out.pixels[row..row + w]
                    .copy_from_slice(&img.pixels[y * img.width..y * img.width + w]);
            }
        }
        out
    }

    /// Writes a PNG, atomically (see [`crate::atomic_file`]).
    pub fn write_png(&self, path: &Path) -> std::io::Result<()> {
        crate::atomic_file::write_atomically(path, &self.encode_png()?)
    }

    /// The image as PNG bytes (8-bit RGB).
    pub(crate) fn encode_png(&self) -> std::io::Result<Vec<u8>> {
        let mut encoded = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut encoded, self.width as u32, self.height as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(std::io::Error::other)?;
            let bytes: Vec<u8> = self.pixels.iter().flatten().copied().collect();
            w.write_image_data(&bytes).map_err(std::io::Error::other)?;
        }
        Ok(encoded)
    }
}

/// An orthographic view: a rotation from world to view (x right, y up, z towards the viewer).
#[derive(Debug, Clone, Copy)]
pub struct MeshView {
    pub view_from_world: Mat3,
}

impl MeshView {
    /// Looking along `-forward`… i.e. the camera sits at `+back` and looks towards the origin,
    /// with `up` pointing up in the image.
    pub(crate) fn looking_from(back: Vec3, up: Vec3) -> Self {
        let z = back.normalize();
        let x = up.cross(z).normalize();
        let y = z.cross(x);
        Self {
            view_from_world: Mat3::from_cols(x, y, z).transpose(),
        }
    }

    /// Rasterises `meshes` (vertices, triangles, base colour) into a `width`×`height` image,
    /// framing them all with a margin. Triangles are shaded by their normal (two-sided).
    pub(crate) fn render(
        &self,
        meshes: &[(&[Vec3], &[[u32; 3]], [f64; 3])],
        width: usize,
        height: usize,
    ) -> RgbImage {
        let mut img = RgbImage::new(width, height, [245, 245, 240]);
        let mut depth = vec![f64::NEG_INFINITY; width * height];
        let projected: Vec<Vec<Vec3>> = meshes
            .iter()
            .map(|(v, _, _)| v.iter().map(|&p| self.view_from_world * p).collect())
            .collect();
        let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
        for p in projected.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if !lo.is_finite() {
            return img;
        }
        let extent = (hi - lo).max(Vec3::splat(1e-9));
        let scale = 0.9 * (width as f64 / extent.x).min(height as f64 / extent.y);
        let centre = (lo + hi) * 0.5;
        let to_px = |p: Vec3| {
            Vec3::new(
                width as f64 * 0.5 + (p.x - centre.x) * scale,
                height as f64 * 0.5 - (p.y - centre.y) * scale,
                p.z,
            )
        };
        let light = Vec3::new(0.4, 0.6, 1.0).normalize();
        for ((_, faces, colour), pts) in meshes.iter().zip(&projected) {
            for f in faces.iter() {
                let [a, b, c] = f.map(|i| pts[i as usize]);
                let n = (b - a).cross(c - a);
                let Some(n) = n.try_normalize() else { continue };
                let shade = 0.25 + 0.75 * n.dot(light).abs();
                let rgb = colour.map(|ch| (ch * shade * 255.0).clamp(0.0, 255.0) as u8);
                fill_triangle(&mut img, &mut depth, [to_px(a), to_px(b), to_px(c)], rgb);
            }
        }
        img
    }
}

fn fill_triangle(img: &mut RgbImage, depth: &mut [f64], t: [Vec3; 3], rgb: [u8; 3]) {
    let (w, h) = (img.width as f64, img.height as f64);
    let min_x = t
        .iter()
        .map(|p| p.x)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let max_x = t
        .iter()
        .map(|p| p.x)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(w - 1.0);
    let min_y = t
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let max_y = t
        .iter()
        .map(|p| p.y)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(h - 1.0);
    if max_x < 0.0 || max_y < 0.0 {
        return;
    }
    let area = edge(t[0], t[1], t[2].x, t[2].y);
    if area.abs() < 1e-12 {
        return;
    }
    for y in min_y..=max_y as usize {
        for x in min_x..=max_x as usize {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let w0 = edge(t[1], t[2], px, py) / area;
            let w1 = edge(t[2], t[0], px, py) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * t[0].z + w1 * t[1].z + w2 * t[2].z;
            let i = y * img.width + x;
            if z > depth[i] {
                depth[i] = z;
                img.pixels[i] = rgb;
            }
        }
    }
}

fn edge(a: Vec3, b: Vec3, px: f64, py: f64) -> f64 {
    (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)
}
