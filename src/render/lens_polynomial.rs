//! Cycles' polynomial fisheye ("Fisheye Lens Polynomial" panorama) for a Fisheye624 camera: the
//! least-squares fit of its radial map, both directions of the polynomial lens, Blender's numbers
//! for it, the pixel error against the exact model when it stands in for the camera
//! (`fisheye = "native"`), and the scaled, padded source an exact remap reads
//! ([`LensPolynomial::remap_source`], the default).
//!
//! Measured with the position pass of a camera inside a sphere (bpy 4.5.15, square pixels,
//! `sensor_fit = HORIZONTAL`): Cycles images the ray at angle
//! `θ = −(k0 + k1·r + k2·r² + k3·r³ + k4·r⁴)` from the optical axis at sensor radius `r` (mm,
//! `sensor_width / width_px` mm per pixel) from the centre
//! `((w − 1)/2 − shift_x·w, (h − 1)/2 + shift_y·h)` (OpenCV pixels: the shift is in units of
//! each image side, +y up), azimuth as in the image (x right, y down). Pixels past θ = 90°,
//! or past half of the camera's `fisheye_fov`, come back with alpha 1 and a zero position (no
//! ray traced), so egogen uses the lens only up to 90° and sets `fisheye_fov` so that only the
//! valid field of view and a margin are traced ([`LensPolynomial::traced_radius_px`]), not
//! the image's corners beyond it. egogen writes `k0 = 0` and `kᵢ = −cᵢ / (mm per pixel)ⁱ` for
//! its fit `θ(ρ) = c₁ρ + c₂ρ² + c₃ρ³ + c₄ρ⁴` in pixels.
//!
//! What cannot be represented: Fisheye624's tangential and thin-prism terms (the lens is
//! radially symmetric), and a radial map that is not a quartic in ρ; [`native_error`] measures
//! what that costs.

use glam::{DMat4, DVec4};

use crate::camera::theta_poly::invert_increasing;
use crate::camera::{
    max_theta_in_image, theta_of, Camera, CameraModel, Fisheye624, Pixel, Resolution,
};
use crate::math::{Real, Vec3};

/// Rendered beyond the camera's valid field of view, in render pixels: room for the remap's
/// bilinear lookups and the denoiser's context at the rim (every lens Cycles renders for a
/// distorted camera, `render_camera`).
pub(crate) const FOV_MARGIN_PX: Real = 2.0;
/// How far inside the traced radius a pixel must lie to count as rendered: Cycles compares θ
/// in single precision (about 1e-3 px at the Aria cameras' rim).
const TRACED_RADIUS_TOLERANCE_PX: Real = 0.01;
/// Sensor width Blender is given (mm); any value works, this is Blender's default.
const SENSOR_WIDTH_MM: Real = 36.0;
/// Grid (per image side) on which egogen reports a stand-in's error ([`native_error`]).
pub(crate) const ERROR_GRID: usize = 256;
/// Azimuths × angles sampled for the fit.
const FIT_AZIMUTHS: usize = 64;
const FIT_ANGLES: usize = 256;

/// `θ(ρ) = Σᵢ cᵢ ρ^i` (i = 1..4, ρ in pixels from `centre_px`), on a square-pixel image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensPolynomial {
    pub resolution: Resolution,
    /// Where the optical axis meets the image (OpenCV pixels).
    pub centre_px: Pixel,
    /// `[c₁, c₂, c₃, c₄]`, radians per pixelⁱ.
    pub theta_coeffs: [Real; 4],
    /// Up to this radius θ(ρ) increases and stays below 90°; farther pixels are not used.
    pub max_radius_px: Real,
    /// Cycles traces pixels up to this radius (its `fisheye_fov` is twice θ here), at most
    /// `max_radius_px`: the valid field of view and its margin; farther pixels are skipped.
    pub traced_radius_px: Real,
}

/// Why a camera has no polynomial stand-in.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LensFitError {
    #[error("Cycles' polynomial fisheye stands in for Fisheye624 cameras only, not {0}")]
    Model(&'static str),
    #[error("the fitted polynomial stops increasing at {turn_px:.1} px, inside the valid field of view ({needed_px:.1} px)")]
    NotMonotonic { turn_px: Real, needed_px: Real },
}

/// Pixel error of a stand-in against the exact model over the valid field of view.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PixelError {
    pub max_px: Real,
    pub mean_px: Real,
    pub p95_px: Real,
    /// Rays measured.
    pub rays: usize,
}

impl LensPolynomial {
    /// Least-squares fit to a Fisheye624 camera's radial map over its valid field of view (up
    /// to `max_theta_rad`, the largest angle a valid pixel sees): samples `ρ(θ)` of the exact
    /// projection on 64 azimuths × 256 angles and minimises Σ (ρ′(θ)·(θ − θ_fit(ρ)))², a
    /// first-order pixel error; tangential and thin-prism terms average out over azimuth.
    pub(crate) fn fit(target: &Camera, max_theta_rad: Real) -> Result<Self, LensFitError> {
        let Camera::Fisheye624(model) = target else {
            return Err(LensFitError::Model(target.model_name()));
        };
        let centre = model.principal_point();
        let rho_at = |theta: Real, phi: Real| {
            let ray = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            (model.project_unchecked(ray) - centre).length()
        };
        let mut samples = Vec::with_capacity(FIT_AZIMUTHS * FIT_ANGLES);
        let h = 1e-6;
        for a in 0..FIT_AZIMUTHS {
            let phi = (a as Real + 0.5) / FIT_AZIMUTHS as Real * std::f64::consts::TAU;
            for t in 1..=FIT_ANGLES {
                let theta = max_theta_rad * t as Real / FIT_ANGLES as Real;
                let rho = rho_at(theta, phi);
                let slope = (rho_at(theta + h, phi) - rho_at(theta - h, phi)) / (2.0 * h);
                samples.push((rho, theta, slope));
            }
        }
        let needed_px = samples.iter().map(|s| s.0).fold(0.0, Real::max);
        // Normalised radius x = ρ / needed_px keeps the normal equations well conditioned.
        let mut ata = DMat4::ZERO;
        let mut atb = DVec4::ZERO;
        for &(rho, theta, w) in &samples {
            let x = rho / needed_px;
            let row = DVec4::new(x, x * x, x * x * x, x * x * x * x) * w;
            ata += DMat4::from_cols(row * row.x, row * row.y, row * row.z, row * row.w);
            atb += row * (theta * w);
        }
        let c = ata.inverse() * atb;
        let theta_coeffs = [
            c.x / needed_px,
            c.y / needed_px.powi(2),
            c.z / needed_px.powi(3),
            c.w / needed_px.powi(4),
        ];
        let res = model.resolution();
        let corner_px = [(-0.5, -0.5), (-0.5, 1.0), (1.0, -0.5), (1.0, 1.0)]
            .iter()
            .map(|&(x, y)| {
                let edge = |v: Real, size: u32| if v < 0.0 { -0.5 } else { size as Real - 0.5 };
                (Pixel::new(edge(x, res.width_px), edge(y, res.height_px)) - centre).length()
            })
            .fold(needed_px, Real::max);
        let mut lens = Self {
            resolution: res,
            centre_px: centre,
            theta_coeffs,
            max_radius_px: corner_px,
            traced_radius_px: corner_px,
        };
        lens.max_radius_px = lens.increasing_limit(corner_px);
        lens.traced_radius_px = lens.max_radius_px;
        if lens.max_radius_px < needed_px {
            return Err(LensFitError::NotMonotonic {
                turn_px: lens.max_radius_px,
                needed_px,
            });
        }
        Ok(lens)
    }

    /// The fit for a Fisheye624 over its valid field of view.
    /// Cycles traces the valid field of view plus `FOV_MARGIN_PX`, not the image's corners
    /// beyond it.
    pub fn for_fisheye624(model: &Fisheye624) -> Result<Self, LensFitError> {
        let cam = Camera::Fisheye624(*model);
        let mut lens = Self::fit(&cam, max_theta_in_image(&cam))?;
        let farthest = valid_boundary(&cam)
            .iter()
            .map(|(p, _)| (*p - lens.centre_px).length())
            .fold(0.0, Real::max);
        lens.traced_radius_px = lens.max_radius_px.min(farthest + FOV_MARGIN_PX);
        Ok(lens)
    }

    /// The fit as the *source* of an exact remap to `target` (`[render] fisheye = "exact"`):
    /// scaled so that no target pixel is finer than a source pixel (`oversample` = 1) and put on
    /// an image just large enough to hold every valid target pixel's ray plus `margin_px` (room
    /// for bilinear lookups). The remap (`frame_file::assemble_frame`) is then exact, as from the
    /// wide equidistant render, while Cycles path-traces about the target's own pixel count.
    pub(crate) fn remap_source(
        target: &Camera,
        oversample: Real,
        margin_px: Real,
    ) -> Result<Self, LensFitError> {
        let Camera::Fisheye624(model) = target else {
            return Err(LensFitError::Model(target.model_name()));
        };
        let max_theta = max_theta_in_image(target);
        let fit = Self::fit(target, max_theta)?;
        let res = model.resolution();
        let (w, h) = (res.width_px as Real, res.height_px as Real);
        // Source pixels per target pixel: the smallest singular value of the Jacobian of
        // target pixel → fitted pixel, on a 64 × 64 grid of the valid field of view.
        let to_fit = |p: Pixel| target.unproject(p).and_then(|r| fit.ray_to_pixel(r));
        let mut coarsest: Real = Real::INFINITY;
        const GRID: usize = 64;
        for j in 0..GRID {
            for i in 0..GRID {
                let p = Pixel::new(
                    (i as Real + 0.5) / GRID as Real * w - 0.5,
                    (j as Real + 0.5) / GRID as Real * h - 0.5,
                );
                let (Some(q), Some(qx), Some(qy)) = (
                    to_fit(p),
                    to_fit(p + Pixel::new(0.25, 0.0)),
                    to_fit(p + Pixel::new(0.0, 0.25)),
                ) else {
                    continue;
                };
                let jac = glam::DMat2::from_cols((qx - q) * 4.0, (qy - q) * 4.0);
                coarsest = coarsest.min(smallest_singular_value(jac));
            }
        }
        let scale = oversample / coarsest;
        let theta_coeffs = std::array::from_fn(|i| fit.theta_coeffs[i] / scale.powi(i as i32 + 1));
        let scaled = Self {
            resolution: res,
            centre_px: Pixel::ZERO,
            theta_coeffs,
            max_radius_px: fit.max_radius_px * scale,
            traced_radius_px: fit.max_radius_px * scale,
        };
        // Where the valid target pixels land (centre at the origin): the image of the valid
        // region's boundary bounds the image of the region.
        let (mut lo, mut hi) = (Pixel::splat(Real::INFINITY), Pixel::splat(-Real::INFINITY));
        let mut needed: Real = 0.0;
        for (_, ray) in valid_boundary(target) {
            if let Some(q) = scaled.ray_to_pixel(ray) {
                lo = lo.min(q);
                hi = hi.max(q);
                needed = needed.max(q.length());
            }
        }
        let centre = Pixel::splat(margin_px) - lo;
        let size = (hi - lo + Pixel::splat(2.0 * margin_px + 1.0)).ceil();
        let mut source = Self {
            resolution: Resolution {
                width_px: size.x as u32,
                height_px: size.y as u32,
            },
            centre_px: centre,
            ..scaled
        };
        let corner = [
            Pixel::ZERO,
            Pixel::new(size.x, 0.0),
            Pixel::new(0.0, size.y),
            size,
        ]
        .iter()
        .map(|&c| (c - Pixel::splat(0.5) - centre).length())
        .fold(0.0, Real::max);
        source.max_radius_px = source.increasing_limit(corner);
        let needed_px = needed + margin_px * std::f64::consts::SQRT_2;
        if source.max_radius_px < needed_px.min(corner) {
            return Err(LensFitError::NotMonotonic {
                turn_px: source.max_radius_px,
                needed_px,
            });
        }
        // The corners beyond the valid field of view (a fifth of an Aria RGB image) are not
        // traced.
        source.traced_radius_px = source.max_radius_px.min(needed_px);
        Ok(source)
    }

    /// `(θ, dθ/dρ)` at radius `rho_px`.
    pub(crate) fn theta_with_slope(&self, rho_px: Real) -> (Real, Real) {
        let [c1, c2, c3, c4] = self.theta_coeffs;
        let r = rho_px;
        (
            r * (c1 + r * (c2 + r * (c3 + r * c4))),
            c1 + r * (2.0 * c2 + r * (3.0 * c3 + r * 4.0 * c4)),
        )
    }

    /// The first radius in `(0, upper]` where θ stops increasing or reaches 90°, else `upper`.
    fn increasing_limit(&self, upper: Real) -> Real {
        const STEPS: usize = 4096;
        for i in 1..=STEPS {
            let r = upper * i as Real / STEPS as Real;
            let (theta, slope) = self.theta_with_slope(r);
            if slope <= 0.0 || theta >= std::f64::consts::FRAC_PI_2 {
                return upper * (i - 1) as Real / STEPS as Real;
            }
        }
        upper
    }

    /// Whether Cycles renders this pixel: within the traced radius (0.01 px inside it, for
    /// Cycles' single-precision θ), on the fitted, increasing part of the lens.
    pub(crate) fn renders(&self, px: Pixel) -> bool {
        (px - self.centre_px).length() <= self.traced_radius_px - TRACED_RADIUS_TOLERANCE_PX
    }

    /// Cycles' `fisheye_fov`: twice θ at the traced radius (pixels beyond it are skipped).
    pub(crate) fn fov_rad(&self) -> Real {
        2.0 * self.theta_with_slope(self.traced_radius_px).0
    }

    /// Unit ray (OpenCV camera frame) of a pixel, as Cycles traces it; `None` past the radius
    /// where θ stops increasing.
    pub fn pixel_to_ray(&self, px: Pixel) -> Option<Vec3> {
        let d = px - self.centre_px;
        let rho = d.length();
        if rho > self.max_radius_px {
            return None;
        }
        if rho == 0.0 {
            return Some(Vec3::Z);
        }
        let (sin, cos) = self.theta_with_slope(rho).0.sin_cos();
        Some(Vec3::new(d.x / rho * sin, d.y / rho * sin, cos))
    }

    /// Pixel of a camera-frame direction (not bounded by the image), inverting θ(ρ) by
    /// bracketed Newton to 1e-10 px; `None` beyond the increasing part.
    pub(crate) fn ray_to_pixel(&self, ray: Vec3) -> Option<Pixel> {
        let theta = theta_of(ray);
        let r_xy = ray.x.hypot(ray.y);
        if r_xy == 0.0 {
            return (ray.z > 0.0).then_some(self.centre_px);
        }
        let (top, _) = self.theta_with_slope(self.max_radius_px);
        if theta > top {
            return None;
        }
        let rho = invert_increasing(
            |r| self.theta_with_slope(r),
            theta,
            self.max_radius_px,
            theta / self.theta_coeffs[0].max(1e-12),
            1e-10,
        )?;
        Some(self.centre_px + Pixel::new(ray.x, ray.y) * (rho / r_xy))
    }

    /// Blender's camera numbers: `(sensor_width_mm, [k0..k4], shift_x, shift_y)` for
    /// `sensor_fit = HORIZONTAL` (see the module docs for the measured convention).
    pub(crate) fn blender(&self) -> (Real, [Real; 5], Real, Real) {
        let (w, h) = (
            self.resolution.width_px as Real,
            self.resolution.height_px as Real,
        );
        let mm_per_px = SENSOR_WIDTH_MM / w;
        let mut k = [0.0; 5];
        for (i, c) in self.theta_coeffs.iter().enumerate() {
            k[i + 1] = -c / mm_per_px.powi(i as i32 + 1);
        }
        let shift_x = (0.5 * (w - 1.0) - self.centre_px.x) / w;
        let shift_y = (self.centre_px.y - 0.5 * (h - 1.0)) / h;
        (SENSOR_WIDTH_MM, k, shift_x, shift_y)
    }
}

/// Smallest singular value of a 2 × 2 matrix.
fn smallest_singular_value(m: glam::DMat2) -> Real {
    // Eigenvalues of mᵀm: (t ± √(t² − 4d)) / 2 with t its trace, d its determinant.
    let mtm = m.transpose() * m;
    let (t, d) = (mtm.x_axis.x + mtm.y_axis.y, mtm.determinant());
    (0.5 * (t - (t * t - 4.0 * d).max(0.0).sqrt()))
        .max(0.0)
        .sqrt()
}

/// Pixel error of the polynomial lens against the exact model: for the rays of a grid of
/// `grid × grid` points spread evenly over the image (cell centres) that lie in the valid field
/// of view, `|project_exact(ray) − project_polynomial(ray)|`.
pub fn native_error(target: &Camera, lens: &LensPolynomial, grid: usize) -> PixelError {
    let res = target.resolution();
    let mut errors = Vec::with_capacity(grid * grid);
    for j in 0..grid {
        for i in 0..grid {
            let px = Pixel::new(
                -0.5 + (i as Real + 0.5) / grid as Real * res.width_px as Real,
                -0.5 + (j as Real + 0.5) / grid as Real * res.height_px as Real,
            );
            let Some(ray) = target.unproject(px) else {
                continue;
            };
            // The exact projection of `ray` is `px` itself (within 1e-7 px).
            let err = lens
                .ray_to_pixel(ray)
                .map_or(Real::INFINITY, |q| (q - px).length());
            errors.push(err);
        }
    }
    pixel_error_stats(errors)
}

/// Max, mean and 95th percentile (nearest rank) of pixel errors.
pub fn pixel_error_stats(mut errors: Vec<Real>) -> PixelError {
    if errors.is_empty() {
        return PixelError {
            max_px: 0.0,
            mean_px: 0.0,
            p95_px: 0.0,
            rays: 0,
        };
    }
    errors.sort_by(Real::total_cmp);
    let n = errors.len();
    PixelError {
        max_px: errors[n - 1],
        mean_px: errors.iter().sum::<Real>() / n as Real,
        p95_px: errors[((0.95 * n as Real).ceil() as usize).clamp(1, n) - 1],
        rays: n,
    }
}

/// Points on the boundary of a camera's valid region, each target pixel with its ray: pixel
/// centres along the image border where valid, and the valid circle (the model's `max θ`)
/// where it cuts the image. The region's image under any lens that keeps it connected is
/// bounded by these points' images.
fn valid_boundary(target: &Camera) -> Vec<(Pixel, Vec3)> {
    let res = target.resolution();
    let (w, h) = (res.width_px as Real, res.height_px as Real);
    let mut points = Vec::new();
    let steps = 4 * (res.width_px + res.height_px) as usize;
    for k in 0..=steps {
        let t = k as Real / steps as Real;
        for p in [
            Pixel::new(t * (w - 1.0), 0.0),
            Pixel::new(t * (w - 1.0), h - 1.0),
            Pixel::new(0.0, t * (h - 1.0)),
            Pixel::new(w - 1.0, t * (h - 1.0)),
        ] {
            if let Some(ray) = target.unproject(p) {
                points.push((p, ray));
            }
        }
    }
    let rim = target.max_theta_rad();
    if rim <= max_theta_in_image(target) + 1e-9 {
        for k in 0..4 * steps {
            let phi = k as Real / (4 * steps) as Real * std::f64::consts::TAU;
            let ray = Vec3::new(rim.sin() * phi.cos(), rim.sin() * phi.sin(), rim.cos());
            if let Some(p) = target.project_unbounded(ray) {
                if (0.0..=w - 1.0).contains(&p.x) && (0.0..=h - 1.0).contains(&p.y) {
                    points.push((p, ray));
                }
            }
        }
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::Rig;

    fn aria(name: &str) -> Fisheye624 {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let rig = Rig::load(&root.join("camera_rigs/aria_gen1.json")).unwrap();
        match &rig.camera(name).unwrap().model {
            Camera::Fisheye624(m) => *m,
            _ => panic!("{name} is Fisheye624"),
        }
    }

    #[test]
    fn pixel_and_ray_round_trip() {
        let lens = LensPolynomial::for_fisheye624(&aria("camera-slam-left")).unwrap();
        for (x, y) in [
            (320.0, 240.0),
            (10.0, 200.0),
            (600.0, 470.0),
            (321.7, 242.1),
        ] {
            let px = Pixel::new(x, y);
            let ray = lens.pixel_to_ray(px).unwrap();
            assert!((ray.length() - 1.0).abs() < 1e-12);
            let back = lens.ray_to_pixel(ray).unwrap();
            assert!((back - px).length() < 1e-8, "{px:?} → {back:?}");
        }
    }

    #[test]
    fn aria_cameras_fit_within_a_few_pixels() {
        for name in ["camera-slam-left", "camera-slam-right", "camera-rgb"] {
            let m = aria(name);
            let lens = LensPolynomial::for_fisheye624(&m).unwrap();
            let err = native_error(&Camera::Fisheye624(m), &lens, 128);
            eprintln!("{name}: {err:?} {:?}", lens.theta_coeffs);
            assert!(err.rays > 8000 && err.max_px.is_finite());
            assert!(err.mean_px <= err.p95_px && err.p95_px <= err.max_px);
        }
    }

    #[test]
    fn blender_numbers_reproduce_the_lens() {
        let lens = LensPolynomial::for_fisheye624(&aria("camera-slam-left")).unwrap();
        let (sensor_mm, k, sx, sy) = lens.blender();
        let (w, h) = (640.0, 480.0);
        let mm = sensor_mm / w;
        let centre = Pixel::new(0.5 * (w - 1.0) - sx * w, 0.5 * (h - 1.0) + sy * h);
        assert!((centre - lens.centre_px).length() < 1e-12);
        let px = Pixel::new(100.0, 400.0);
        let r = (px - centre).length() * mm;
        let theta = -(k[0] + k[1] * r + k[2] * r * r + k[3] * r.powi(3) + k[4] * r.powi(4));
        assert!((theta - theta_of(lens.pixel_to_ray(px).unwrap())).abs() < 1e-12);
    }

    /// Every valid pixel of the Aria cameras (full size and the default run's quarter/half
    /// size) finds its ray inside the remap source with room for a bilinear lookup, no finer
    /// than a source pixel, and the source path-traces little more than the target's pixels.
    #[test]
    fn the_remap_source_holds_every_valid_pixel_at_the_target_resolution() {
        for (name, scale) in [
            ("camera-rgb", 1.0),
            ("camera-slam-left", 1.0),
            ("camera-slam-right", 1.0),
            ("camera-rgb", 0.25),
            ("camera-slam-left", 0.25),
        ] {
            let target = Camera::Fisheye624(aria(name)).scaled(scale).unwrap();
            let source = LensPolynomial::remap_source(&target, 1.0, 2.0).unwrap();
            let (res, src) = (target.resolution(), source.resolution);
            let step = if scale < 1.0 { 1 } else { 3 };
            let (mut least_room, mut coarsest, mut valid) = (Real::INFINITY, Real::INFINITY, 0);
            for y in (0..res.height_px).step_by(step) {
                for x in (0..res.width_px).step_by(step) {
                    let p = Pixel::new(x as Real, y as Real);
                    let Some(ray) = target.unproject(p) else {
                        continue;
                    };
                    valid += 1;
                    let q = source.ray_to_pixel(ray).unwrap();
                    assert!(source.renders(q), "{name} ({x}, {y}) → {q:?}");
                    let room =
                        q.x.min(q.y)
                            .min(src.width_px as Real - 1.0 - q.x)
                            .min(src.height_px as Real - 1.0 - q.y);
                    least_room = least_room.min(room);
                    let (Some(rx), Some(ry)) = (
                        target.unproject(p + Pixel::new(0.25, 0.0)),
                        target.unproject(p + Pixel::new(0.0, 0.25)),
                    ) else {
                        continue;
                    };
                    let jac = glam::DMat2::from_cols(
                        (source.ray_to_pixel(rx).unwrap() - q) * 4.0,
                        (source.ray_to_pixel(ry).unwrap() - q) * 4.0,
                    );
                    coarsest = coarsest.min(smallest_singular_value(jac));
                }
            }
            let ratio =
                (src.width_px * src.height_px) as Real / (res.width_px * res.height_px) as Real;
            // What Cycles traces: the source's pixels within the traced radius, against the
            // target's valid pixels.
            let count = |w: u32, h: u32, keep: &dyn Fn(Pixel) -> bool| {
                (0..h)
                    .flat_map(|y| (0..w).map(move |x| Pixel::new(x as Real, y as Real)))
                    .filter(|&p| keep(p))
                    .count() as Real
            };
            let traced = count(src.width_px, src.height_px, &|p| source.renders(p));
            let target_valid = count(res.width_px, res.height_px, &|p| {
                target.unproject(p).is_some()
            });
            let traced_ratio = traced / target_valid;
            eprintln!(
                "{name} × {scale}: {}×{} from {}×{} ({ratio:.3}× the pixels; traced {traced_ratio:.3}× the valid pixels, {:.3}× all); {valid} px, least room {least_room:.2} px, source px per target px ≥ {coarsest:.4}",
                res.width_px, res.height_px, src.width_px, src.height_px,
                traced / (res.width_px * res.height_px) as Real
            );
            assert!(valid > 10_000);
            assert!(least_room >= 1.99, "{name}: {least_room}");
            assert!(coarsest >= 0.995, "{name}: {coarsest}");
            assert!(ratio < 1.2, "{name}: {ratio}");
            assert!(traced_ratio < 1.15, "{name}: {traced_ratio}");
            assert!(source.fov_rad() < std::f64::consts::PI);
        }
    }

    /// A native lens traces every valid pixel of the image and not the corners beyond the
    /// valid field of view.
    #[test]
    fn a_native_lens_traces_the_valid_field_of_view() {
        for (name, scale) in [
            ("camera-rgb", 1.0),
            ("camera-slam-left", 1.0),
            ("camera-rgb", 0.25),
        ] {
            let target = Camera::Fisheye624(aria(name)).scaled(scale).unwrap();
            let Camera::Fisheye624(model) = target else {
                unreachable!()
            };
            let lens = LensPolynomial::for_fisheye624(&model).unwrap();
            let res = target.resolution();
            let (mut valid, mut traced) = (0, 0);
            for y in 0..res.height_px {
                for x in 0..res.width_px {
                    let p = Pixel::new(x as Real, y as Real);
                    let is_valid = target.unproject(p).is_some();
                    valid += usize::from(is_valid);
                    traced += usize::from(lens.renders(p));
                    assert!(!is_valid || lens.renders(p), "{name} ({x}, {y})");
                }
            }
            let ratio = traced as Real / valid as Real;
            eprintln!("{name} × {scale}: traces {ratio:.3}× its valid pixels");
            assert!(ratio < 1.05, "{name}: {ratio}");
            assert!(lens.traced_radius_px <= lens.max_radius_px);
        }
    }

    #[test]
    fn smallest_singular_values() {
        let m = glam::DMat2::from_cols(glam::DVec2::new(3.0, 0.0), glam::DVec2::new(0.0, 0.5));
        assert!((smallest_singular_value(m) - 0.5).abs() < 1e-12);
        let r = glam::DMat2::from_angle(0.7) * m;
        assert!((smallest_singular_value(r) - 0.5).abs() < 1e-12);
        assert_eq!(smallest_singular_value(glam::DMat2::ZERO), 0.0);
    }

    #[test]
    fn only_fisheye624_is_fitted() {
        let cam = Camera::Pinhole(
            crate::camera::Pinhole::new(
                10.0,
                10.0,
                4.5,
                4.5,
                Resolution {
                    width_px: 10,
                    height_px: 10,
                },
            )
            .unwrap(),
        );
        assert_eq!(
            LensPolynomial::fit(&cam, 0.5),
            Err(LensFitError::Model("pinhole"))
        );
    }
}
