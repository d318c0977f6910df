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
    check_common, check_finite, theta_of, CameraError, CameraModel, Pixel, Resolution,
    REPROJECTION_TOLERANCE_PX,
};
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
}
