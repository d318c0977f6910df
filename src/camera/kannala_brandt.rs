//! Kannala–Brandt fisheye with four radial coefficients (KB4), in OpenCV's `cv::fisheye`
//! convention: parameters `fx, fy, cx, cy, k1..k4` (no skew).
//!
//! ```text
//! θ = atan2(√(x² + y²), z)
//! θ_d = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)
//! (u, v) = (fx · θ_d · x / √(x² + y²) + cx,  fy · θ_d · y / √(x² + y²) + cy)
//! ```
//! OpenCV computes `θ = atan(r)` from `(x/z, y/z)`, the same angle for `z > 0`; with `atan2`
//! the map stays defined up to the maximum angle without dividing by `z`.
//!
//! Valid field of view: `θ ≤ max θ` and the pixel on the sensor. Unprojection solves
//! `θ_d(θ) = r` by bracketed Newton (steps below 1e-12 rad, at most 50 iterations) and
//! builds the ray as `(sin θ · direction, cos θ)`.

use super::fisheye624::resolve_max_theta;
use super::theta_poly::ThetaPolynomial;
use super::{
    check_common, check_finite, max_theta_in_image, theta_of, valid_pixel_rays, Camera,
    CameraError, CameraModel, FitError, Pixel, Resolution, REPROJECTION_TOLERANCE_PX,
};
use crate::math::least_squares::NormalEquations;
use crate::math::{Real, Vec3};
use glam::DVec2;

/// KB4 intrinsics plus the limit of the valid field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KannalaBrandt4 {
    fx: Real,
    fy: Real,
    cx: Real,
    cy: Real,
    radial: ThetaPolynomial<4>,
    resolution: Resolution,
    max_theta_rad: Real,
}

impl KannalaBrandt4 {
    /// Checks and builds. `max_theta_rad`: `None` takes the largest angle up to 90° where
    /// `θ_d(θ)` increases; an explicit value must lie where it increases and below 180°.
    pub fn new(
        [fx, fy, cx, cy]: [Real; 4],
        k: [Real; 4],
        resolution: Resolution,
        max_theta_rad: Option<Real>,
    ) -> Result<Self, CameraError> {
        check_common(&[("fx", fx), ("fy", fy)], cx, cy, resolution)?;
        check_finite("k1..k4", &k)?;
        let radial = ThetaPolynomial { coeffs: k };
        let max_theta_rad = resolve_max_theta(&radial, max_theta_rad)?;
        Ok(Self {
            fx,
            fy,
            cx,
            cy,
            radial,
            resolution,
            max_theta_rad,
        })
    }

    /// `([fx, fy, cx, cy], [k1, k2, k3, k4])`.
    pub fn params(&self) -> ([Real; 4], [Real; 4]) {
        ([self.fx, self.fy, self.cx, self.cy], self.radial.coeffs)
    }

    /// Pixel of a point without the field-of-view checks.
    pub(crate) fn project_unchecked(&self, p: Vec3) -> Pixel {
        let rho = p.x.hypot(p.y);
        let xd = if rho > 0.0 {
            DVec2::new(p.x, p.y) * (self.radial.eval(rho.atan2(p.z)) / rho)
        } else {
            DVec2::ZERO
        };
        Pixel::new(self.fx * xd.x + self.cx, self.fy * xd.y + self.cy)
    }
}

impl CameraModel for KannalaBrandt4 {
    fn resolution(&self) -> Resolution {
        self.resolution
    }

    fn principal_point(&self) -> Pixel {
        Pixel::new(self.cx, self.cy)
    }

    fn max_theta_rad(&self) -> Real {
        self.max_theta_rad
    }

    fn project(&self, p: Vec3) -> Option<Pixel> {
        if !p.is_finite() || p == Vec3::ZERO || !(theta_of(p) <= self.max_theta_rad) {
            return None;
        }
        let px = self.project_unchecked(p);
        self.resolution.contains(px).then_some(px)
    }

    fn unproject(&self, px: Pixel) -> Option<Vec3> {
        if !px.is_finite() || !self.resolution.contains(px) {
            return None;
        }
        let xd = DVec2::new((px.x - self.cx) / self.fx, (px.y - self.cy) / self.fy);
        let r = xd.length();
        let ray = if r == 0.0 {
            Vec3::Z
        } else {
            let theta = self.radial.invert(r, self.max_theta_rad)?;
            let (sin, cos) = theta.sin_cos();
            Vec3::new(sin * xd.x / r, sin * xd.y / r, cos)
        };
        let back = self.project_unchecked(ray);
        ((back - px).length() <= REPROJECTION_TOLERANCE_PX).then_some(ray)
    }
}

/// The KB4 closest to `camera` over its valid field of view, and its pixel error there
/// (pixels in the convention of this module, which is OpenCV's and egogen's: the centre of the
/// top-left pixel at (0, 0)).
///
/// A KB4 is returned as it is (error 0). Otherwise `fx = fy = f`, the principal point and
/// `k1..k4` solve one linear least-squares problem over every pixel centre in the valid field
/// of view (each centre's exact ray must land on it): with `a₀ = f` and `aᵢ = f·kᵢ`, a pixel
/// is `Σ aᵢ θ^(2i+1) · (x, y)/ρ + (cx, cy)`, linear in `a₀..a₄, cx, cy`. A Fisheye624 (Aria)
/// has tangential and thin-prism terms no KB4 holds, so the fit is close, not exact; letting
/// `f` and the principal point move absorbs part of them (on the shipped Aria cameras the
/// largest error is 12–28 % below that of keeping the Fisheye624's; `fx ≠ fy` gains nothing
/// more). `max θ` is the widest ray of the image.
pub(crate) fn fit_kb4(camera: &Camera) -> Result<(KannalaBrandt4, FitError), CameraError> {
    let samples = valid_pixel_rays(camera);
    if let Camera::KannalaBrandt4(m) = camera {
        return Ok((*m, FitError::measure(&samples, |r| m.project_unchecked(r))));
    }
    let mut eq = NormalEquations::<7>::default();
    for &(px, ray) in &samples {
        let rho = ray.x.hypot(ray.y);
        if rho == 0.0 {
            eq.add(&[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], px.x);
            eq.add(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0], px.y);
            continue;
        }
        let theta = rho.atan2(ray.z);
        let t2 = theta * theta;
        let powers = [
            theta,
            theta * t2,
            theta * t2 * t2,
            theta * t2.powi(3),
            theta * t2.powi(4),
        ];
        for (axis, (direction, pixel)) in [(ray.x / rho, px.x), (ray.y / rho, px.y)]
            .into_iter()
            .enumerate()
        {
            let mut row = [0.0; 7];
            for (r, p) in row.iter_mut().zip(powers) {
                *r = p * direction;
            }
            row[5 + axis] = 1.0;
            eq.add(&row, pixel);
        }
    }
    let a = eq.solve();
    let f = a[0];
    let k = [a[1] / f, a[2] / f, a[3] / f, a[4] / f];
    let fitted = KannalaBrandt4::new(
        [f, f, a[5], a[6]],
        k,
        CameraModel::resolution(camera),
        Some(max_theta_in_image(camera)),
    )?;
    Ok((
        fitted,
        FitError::measure(&samples, |r| fitted.project_unchecked(r)),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_distortion_is_equidistant() {
        let cam = KannalaBrandt4::new(
            [200.0, 200.0, 319.5, 239.5],
            [0.0; 4],
            Resolution {
                width_px: 640,
                height_px: 480,
            },
            None,
        )
        .unwrap();
        let t: Real = 0.6;
        let px = cam.project(Vec3::new(t.sin(), 0.0, t.cos())).unwrap();
        assert!((px.x - (319.5 + 200.0 * t)).abs() < 1e-12);
        assert_eq!(cam.max_theta_rad(), std::f64::consts::FRAC_PI_2);
    }

    #[test]
    fn max_theta_beyond_the_turning_point_is_refused() {
        let err = KannalaBrandt4::new(
            [200.0, 200.0, 319.5, 239.5],
            [-0.3, 0.0, 0.0, 0.0],
            Resolution {
                width_px: 640,
                height_px: 480,
            },
            Some(1.5),
        )
        .unwrap_err();
        assert!(err.to_string().contains("max_theta_rad"), "{err}");
    }

    #[test]
    fn a_fisheye624_without_its_extra_terms_is_fitted_exactly() {
        // Fisheye624 with k4 = k5 = 0 and no tangential or thin-prism terms is a KB4.
        let mut params = [0.0; 15];
        params[..7].copy_from_slice(&[30.0, 31.5, 23.5, 0.02, -0.005, 0.001, -0.0002]);
        let cam = Camera::Fisheye624(
            super::super::Fisheye624::new(
                &params,
                Resolution {
                    width_px: 64,
                    height_px: 48,
                },
                Some(1.2),
                None,
            )
            .unwrap(),
        );
        let (fit, err) = fit_kb4(&cam).unwrap();
        assert!(err.samples > 1000, "{err:?}");
        assert!(err.max_px < 1e-6, "{err:?}");
        let ([fx, fy, cx, cy], k) = fit.params();
        assert!(
            (fx - 30.0).abs() < 1e-6 && (fy - 30.0).abs() < 1e-6,
            "{fx} {fy}"
        );
        assert!(
            (cx - 31.5).abs() < 1e-6 && (cy - 23.5).abs() < 1e-6,
            "{cx} {cy}"
        );
        for (got, want) in k.iter().zip([0.02, -0.005, 0.001, -0.0002]) {
            assert!((got - want).abs() < 1e-6, "{k:?}");
        }
    }
}
