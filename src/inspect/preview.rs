//! PNG previews of passes, chosen by pass and component names:
//! - colour (`R G B`, `Combined`, `Image`; a lone `gray.Y`): linear × exposure → sRGB,
//!   clamped; [`auto_exposure`] picks the exposure the way a camera's would;
//! - depth (`Depth`, or a lone `Z`): near → far through a perceptual colour map, background
//!   (≥ 1e9 or non-finite) black;
//! - normals (`Normal`): `0.5 + 0.5·n`;
//! - ids (`Index*`, `Segmentation`, `u32` data): a fixed palette per id, 0 black;
//! - flow (`Vector`, `Flow`): colour wheel, hue = direction, brightness = length / max length;
//! - anything else: first component, min–max grey.

use crate::exr_file::{ExrContents, ExrPass};
use crate::preview::RgbImage;

/// How a pass is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PreviewKind {
    Colour,
    /// A monochrome camera's linear grey (`gray.Y`), drawn like colour.
    Luminance,
    Depth,
    Normal,
    Ids,
    Flow,
    Grey,
}

/// Picks the drawing for a pass from its names and sample type.
pub fn preview_kind(contents: &ExrContents, pass: &ExrPass) -> PreviewKind {
    let name = pass.name.to_lowercase();
    let comps: Vec<&str> = pass.components.iter().map(|(c, _)| c.as_str()).collect();
    let first = &contents.channels[pass.components[0].1];
    if name.contains("index") || name.contains("segment") || first.sample_type == "u32" {
        PreviewKind::Ids
    } else if name.contains("vector") || name.contains("flow") {
        PreviewKind::Flow
    } else if name.contains("normal") {
        PreviewKind::Normal
    } else if name.contains("depth") || comps == ["Z"] {
        PreviewKind::Depth
    } else if ["R", "G", "B"].iter().all(|c| comps.contains(c)) {
        PreviewKind::Colour
    } else if name == "gray" && comps == ["Y"] {
        PreviewKind::Luminance
    } else {
        PreviewKind::Grey
    }
}

/// Middle grey: [`auto_exposure`] puts a frame's log-average luminance here.
pub const AUTO_EXPOSURE_KEY: f32 = 0.18;

/// The factor that brings the log-average Rec. 709 luminance of a colour pass (`R G B`, or a
/// lone grey `Y`) to [`AUTO_EXPOSURE_KEY`] (Reinhard et al. 2002's key value), over the pixels
/// of the camera's valid field of view (`valid.V` where the file has it): a frame's automatic
/// exposure. Within [2⁻¹⁶, 2¹⁶]; 1 for an image without light.
pub fn auto_exposure(contents: &ExrContents, pass: &ExrPass) -> f32 {
    let named = |n: &str| {
        pass.components
            .iter()
            .find(|(c, _)| c == n)
            .map(|(_, i)| &contents.channels[*i].values)
    };
    let valid = contents.channel("valid.V").map(|c| &c.values);
    let luminance: Box<dyn Fn(usize) -> f32> = match (named("R"), named("G"), named("B")) {
        (Some(r), Some(g), Some(b)) => {
            Box::new(move |i| 0.2126 * r[i] + 0.7152 * g[i] + 0.0722 * b[i])
        }
        _ => {
            let y = &contents.channels[pass.components[0].1].values;
            Box::new(move |i| y[i])
        }
    };
    let n = contents.channels[pass.components[0].1].values.len();
    let (mut sum, mut count) = (0.0f64, 0usize);
    for i in 0..n {
        if valid.is_some_and(|v| v[i] < 0.5) {
            continue;
        }
        let l = luminance(i);
        if l.is_finite() {
            sum += (1e-4 + l.max(0.0) as f64).ln();
            count += 1;
        }
    }
    if count == 0 {
        return 1.0;
    }
    let average = (sum / count as f64).exp() as f32;
    if average <= 2e-4 {
        return 1.0;
    }
    (AUTO_EXPOSURE_KEY / average).clamp(2f32.powi(-16), 2f32.powi(16))
}

/// Renders a pass as an 8-bit image (same size as the pass).
pub fn pass_preview(contents: &ExrContents, pass: &ExrPass) -> RgbImage {
    pass_preview_exposed(contents, pass, 1.0)
}

/// [`pass_preview`] with colour multiplied by `exposure` before it is encoded.
pub fn pass_preview_exposed(contents: &ExrContents, pass: &ExrPass, exposure: f32) -> RgbImage {
    let ch = |k: usize| &contents.channels[pass.components[k.min(pass.components.len() - 1)].1];
    // EXR stores channels sorted by name (B, G, R): look colour components up by name.
    let named = |n: &str| {
        pass.components
            .iter()
            .find(|(c, _)| c == n)
            .map(|(_, i)| &contents.channels[*i])
    };
    let (w, h) = (ch(0).width, ch(0).height);
    let mut img = RgbImage::new(w, h, [0, 0, 0]);
    let n = w * h;
    match preview_kind(contents, pass) {
        PreviewKind::Colour => {
            let get = |n: &str| &named(n).expect("colour passes have R, G and B").values;
            let (r, g, b) = (get("R"), get("G"), get("B"));
            let e = |v: f32| srgb(exposure * v);
            for i in 0..n {
                img.pixels[i] = [e(r[i]), e(g[i]), e(b[i])];
            }
        }
        PreviewKind::Luminance => {
            let y = &ch(0).values;
            for i in 0..n {
                let g = srgb(exposure * y[i]);
                img.pixels[i] = [g, g, g];
            }
        }
        PreviewKind::Depth => {
            let z = &ch(0).values;
            let valid = |v: f32| v.is_finite() && v < 1e9;
            let (lo, hi) = z
                .iter()
                .copied()
                .filter(|v| valid(*v))
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            for i in 0..n {
                if valid(z[i]) {
                    let t = if hi > lo {
                        (z[i] - lo) / (hi - lo)
                    } else {
                        0.0
                    };
                    img.pixels[i] = colormap(t);
                }
            }
        }
        PreviewKind::Normal => {
            let (x, y, z) = (&ch(0).values, &ch(1).values, &ch(2).values);
            let u = |v: f32| ((0.5 + 0.5 * v).clamp(0.0, 1.0) * 255.0).round() as u8;
            for i in 0..n {
                img.pixels[i] = [u(x[i]), u(y[i]), u(z[i])];
            }
        }
        PreviewKind::Ids => {
            let ids = &ch(0).values;
            for i in 0..n {
                img.pixels[i] = palette(ids[i]);
            }
        }
        PreviewKind::Flow => {
            let (fx, fy) = (&ch(0).values, &ch(1).values);
            let max = (0..n)
                .map(|i| fx[i].hypot(fy[i]))
                .filter(|m| m.is_finite())
                .fold(0.0f32, f32::max);
            for i in 0..n {
                let m = fx[i].hypot(fy[i]);
                if m.is_finite() && max > 0.0 {
                    let hue = fy[i].atan2(fx[i]).to_degrees().rem_euclid(360.0);
                    img.pixels[i] = hsv(hue, 1.0, m / max);
                }
            }
        }
        PreviewKind::Grey => {
            let v = &ch(0).values;
            let (lo, hi) = v
                .iter()
                .copied()
                .filter(|x| x.is_finite())
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), x| {
                    (a.min(x), b.max(x))
                });
            for i in 0..n {
                if v[i].is_finite() {
                    let t = if hi > lo {
                        (v[i] - lo) / (hi - lo)
                    } else {
                        0.5
                    };
                    let g = (t * 255.0).round() as u8;
                    img.pixels[i] = [g, g, g];
                }
            }
        }
    }
    img
}

fn srgb(linear: f32) -> u8 {
    let c = if linear.is_finite() {
        linear.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// A perceptual map from dark blue (near) through green to yellow (far), piecewise linear
/// through viridis' anchor colours.
pub fn colormap(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } * 4.0;
    let k = (t.floor() as usize).min(3);
    let f = t - k as f32;
    std::array::from_fn(|c| (STOPS[k][c] + (STOPS[k + 1][c] - STOPS[k][c]) * f).round() as u8)
}

/// A fixed colour per id (0 and non-finite black).
pub fn palette(id: f32) -> [u8; 3] {
    if !id.is_finite() || id.round() == 0.0 {
        return [0, 0, 0];
    }
    let mut x = (id.round() as i64 as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    [
        (x >> 8) as u8 | 0x30,
        (x >> 24) as u8 | 0x30,
        (x >> 40) as u8 | 0x30,
    ]
}

fn hsv(h_deg: f32, s: f32, v: f32) -> [u8; 3] {
    crate::math::colour::hsv_to_rgb(h_deg as f64, s as f64, v as f64)
        .map(|c| (c * 255.0).round() as u8)
}
