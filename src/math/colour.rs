//! Colour conversions shared by previews and drawn materials.

/// An sRGB component in [0, 1] as linear light (IEC 61966-2-1).
pub(crate) fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// HSV to RGB in the same space (hue in degrees, any value wrapping; saturation and value
/// clamped to [0, 1]), each component in [0, 1].
pub(crate) fn hsv_to_rgb(h_deg: f64, s: f64, v: f64) -> [f64; 3] {
    let (s, v) = (s.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
    let h = h_deg.rem_euclid(360.0) / 60.0;
    let c = v * s;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m].map(|u| u.clamp(0.0, 1.0))
}

/// HSV (hue in degrees, saturation and value in [0, 1], sRGB) as linear RGB.
pub(crate) fn hsv_linear(h_deg: f64, s: f64, v: f64) -> [f64; 3] {
    hsv_to_rgb(h_deg, s, v).map(srgb_to_linear)
}

#[cfg(test)]
mod tests {
    use super::{hsv_linear, hsv_to_rgb};

    #[test]
    fn hsv_reads_back_as_linear_light() {
        assert_eq!(hsv_linear(0.0, 1.0, 1.0), [1.0, 0.0, 0.0]);
        assert_eq!(hsv_linear(360.0, 0.0, 0.0), [0.0; 3]);
    }

    #[test]
    fn primaries_greys_and_wrapped_hues() {
        assert_eq!(hsv_to_rgb(0.0, 1.0, 1.0), [1.0, 0.0, 0.0]);
        assert_eq!(hsv_to_rgb(120.0, 1.0, 1.0), [0.0, 1.0, 0.0]);
        assert_eq!(hsv_to_rgb(-120.0, 1.0, 0.5), [0.0, 0.0, 0.5]);
        assert_eq!(hsv_to_rgb(725.0, 0.0, 0.25), [0.25; 3]);
        assert_eq!(hsv_to_rgb(359.999, 2.0, 2.0)[0], 1.0);
    }
}
