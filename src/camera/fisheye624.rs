//! Aria's Fisheye624 camera: projectaria-tools' `FisheyeRadTanThinPrism<6, true, true, true>`
//! (6 radial, 2 tangential, 4 thin-prism coefficients, one focal length).
//!
//! Parameters `[f, cx, cy, k0..k5, p0, p1, s0..s3]`. For a point `(x, y, z)` with
//! `θ = atan2(√(x² + y²), z)`:
//! ```text
//! θ_d          = θ + k0 θ³ + k1 θ⁵ + … + k5 θ¹³
//! (x_r, y_r)   = θ_d · (x, y) / √(x² + y²)              r² = x_r² + y_r²
//! u_d = x_r + (2 x_r² + r²) p0 + 2 x_r y_r p1 + s0 r² + s1 r⁴
//! v_d = y_r + (2 y_r² + r²) p1 + 2 x_r y_r p0 + s2 r² + s3 r⁴
//! (u, v)       = f · (u_d, v_d) + (cx, cy)
//! ```
//! projectaria-tools writes `θ = atan(√(a² + b²))` with `a = x/z, b = y/z`; that is the same
//! angle for `z > 0`, and `atan2` keeps the map well defined (no division by `z`) up to the
//! maximum angle.
//!
//! Valid field of view (as projectaria-tools' `CameraCalibration::project` decides it):
//! `θ ≤ max θ` (its "max solid angle", 1.0 rad for Aria RGB, 1.4 rad for SLAM), the pixel on
//! the sensor, and — when the camera has one — within `valid radius` pixels of the principal
//! point (1415 px for full-resolution RGB, 330 px for SLAM).
//!
//! Unprojection inverts the two stages like projectaria-tools does: Newton on the 2×2
//! tangential/thin-prism map (start at `(u_d, v_d)`), then Newton on `θ_d(θ)` for `θ` (bracketed,
//! see `theta_poly`). Both stop when a step is below 1e-12; more than 50 iterations, a singular
//! Jacobian, `θ > max θ` or a reprojection off by more than 1e-7 px mean the pixel is outside
//! the valid field of view. The ray is built as `(sin θ · (x_r, y_r)/r, cos θ)`, so it stays
//! accurate on the optical axis and at the edge.

use super::theta_poly::{ThetaPolynomial, MAX_NEWTON_ITERATIONS, THETA_STEP_TOLERANCE};
use super::{
    check_common, check_finite, theta_of, CameraError, CameraModel, Pixel, Resolution,
    REPROJECTION_TOLERANCE_PX,
};
use crate::math::{Real, Vec3};
use glam::{DMat2, DVec2};

/// Number of parameters: `[f, cx, cy, k0..k5, p0, p1, s0..s3]`.
pub(crate) const NUM_PARAMS: usize = 15;

/// Fisheye624 intrinsics plus the limits of the valid field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fisheye624 {
    f: Real,
    cx: Real,
    cy: Real,
    radial: ThetaPolynomial<6>,
    p: [Real; 2],
    s: [Real; 4],
    resolution: Resolution,
    max_theta_rad: Real,
    valid_radius_px: Option<Real>,
}

impl Fisheye624 {
    /// Checks and builds from projectaria-tools' parameter vector.
    ///
    /// `max_theta_rad`: the largest angle from the optical axis; `None` takes the largest
    /// angle up to 90° where `θ_d(θ)` still increases. An explicit value must lie where
    /// `θ_d` increases (otherwise the model cannot be inverted) and below 180°.
    /// `valid_radius_px`: optional circular mask around the principal point.
    pub fn new(
        params: &[Real],
        resolution: Resolution,
        max_theta_rad: Option<Real>,
        valid_radius_px: Option<Real>,
    ) -> Result<Self, CameraError> {
        if params.len() != NUM_PARAMS {
            return Err(CameraError::param(
                "params",
                format!("a list of {} numbers", params.len()),
                "15 numbers [f, cx, cy, k0..k5, p0, p1, s0..s3]",
            ));
        }
        let (f, cx, cy) = (params[0], params[1], params[2]);
        check_common(&[("f", f)], cx, cy, resolution)?;
        check_finite("params", params)?;
        let radial = ThetaPolynomial {
            coeffs: [
                params[3], params[4], params[5], params[6], params[7], params[8],
            ],
        };
        let p = [params[9], params[10]];
        let s = [params[11], params[12], params[13], params[14]];
        let max_theta_rad = resolve_max_theta(&radial, max_theta_rad)?;
        if let Some(r) = valid_radius_px {
            if !(r.is_finite() && r > 0.0) {
                return Err(CameraError::param(
                    "valid_radius_px",
                    r,
                    "a positive, finite radius in pixels",
                ));
            }
        }
        let cam = Self {
            f,
            cx,
            cy,
            radial,
            p,
            s,
            resolution,
            max_theta_rad,
            valid_radius_px,
        };
        cam.check_tangential_invertible()?;
        Ok(cam)
    }

    /// `[f, cx, cy, k0..k5, p0, p1, s0..s3]`.
    pub fn params(&self) -> [Real; NUM_PARAMS] {
        let k = self.radial.coeffs;
        [
            self.f, self.cx, self.cy, k[0], k[1], k[2], k[3], k[4], k[5], self.p[0], self.p[1],
            self.s[0], self.s[1], self.s[2], self.s[3],
        ]
    }

    /// The circular mask radius (px), if any.
    pub fn valid_radius_px(&self) -> Option<Real> {
        self.valid_radius_px
    }

    /// The same camera on an image scaled by `scale` after cropping `offset_px` from the
    /// top-left, as projectaria-tools' `CameraCalibration::rescale` does it:
    /// `f' = s·f`, `c' = s·(c − offset + 0.5) − 0.5`, valid radius scaled, distortion unchanged.
    pub(crate) fn rescaled(
        &self,
        resolution: Resolution,
        scale: Real,
        offset_px: DVec2,
    ) -> Result<Self, CameraError> {
        // projectaria-tools requires new size = (old size − 2·offset)·scale.
        let expect = |old: u32, off: Real| (old as Real - 2.0 * off) * scale;
        let (ew, eh) = (
            expect(self.resolution.width_px, offset_px.x),
            expect(self.resolution.height_px, offset_px.y),
        );
        if (ew - resolution.width_px as Real).abs() > 1e-5
            || (eh - resolution.height_px as Real).abs() > 1e-5
        {
            return Err(CameraError::param(
                "resolution",
                format!("{}x{}", resolution.width_px, resolution.height_px),
                format!("{ew}x{eh} = (size − 2·offset)·scale"),
            ));
        }
        let mut params = self.params();
        params[0] *= scale;
        params[1] = scale * (params[1] - offset_px.x + 0.5) - 0.5;
        params[2] = scale * (params[2] - offset_px.y + 0.5) - 0.5;
        Self::new(
            &params,
            resolution,
            Some(self.max_theta_rad),
            self.valid_radius_px.map(|r| r * scale),
        )
    }

    /// Tangential + thin-prism distortion of `(x_r, y_r)`: `(u_d, v_d)` and its Jacobian.
    fn distort(&self, xr: DVec2) -> (DVec2, DMat2) {
        let [p0, p1] = self.p;
        let [s0, s1, s2, s3] = self.s;
        let r2 = xr.length_squared();
        let dot2 = 2.0 * (xr.x * p0 + xr.y * p1);
        let ud = DVec2::new(
            xr.x + dot2 * xr.x + r2 * p0 + s0 * r2 + s1 * r2 * r2,
            xr.y + dot2 * xr.y + r2 * p1 + s2 * r2 + s3 * r2 * r2,
        );
        let off = 2.0 * (xr.x * p1 + xr.y * p0);
        let t1 = 2.0 * (s0 + 2.0 * s1 * r2);
        let t2 = 2.0 * (s2 + 2.0 * s3 * r2);
        // glam matrices are column-major: from_cols(d/dx_r, d/dy_r).
        let jac = DMat2::from_cols(
            DVec2::new(
                1.0 + 6.0 * xr.x * p0 + 2.0 * xr.y * p1 + xr.x * t1,
                off + xr.x * t2,
            ),
            DVec2::new(
                off + xr.y * t1,
                1.0 + 6.0 * xr.y * p1 + 2.0 * xr.x * p0 + xr.y * t2,
            ),
        );
        (ud, jac)
    }

    /// Pixel of a point without the field-of-view checks (for `z ≤ 0` too; the angle decides).
    pub(crate) fn project_unchecked(&self, p: Vec3) -> Pixel {
        let rho = p.x.hypot(p.y);
        let xr = if rho > 0.0 {
            let theta = rho.atan2(p.z);
            DVec2::new(p.x, p.y) * (self.radial.eval(theta) / rho)
        } else {
            DVec2::ZERO
        };
        let (ud, _) = self.distort(xr);
        ud * self.f + DVec2::new(self.cx, self.cy)
    }

    /// Inverts the tangential/thin-prism stage: `(x_r, y_r)` with `distort(x_r) = ud`.
    fn undistort(&self, ud: DVec2) -> Option<DVec2> {
        let mut xr = ud;
        for _ in 0..MAX_NEWTON_ITERATIONS {
            let (est, jac) = self.distort(xr);
            let det = jac.determinant();
            if !(det.abs() > 1e-12) {
                return None;
            }
            let step = jac.inverse() * (ud - est);
            xr += step;
            if step.length() <= THETA_STEP_TOLERANCE {
                return Some(xr);
            }
        }
        None
    }

    fn in_mask(&self, px: Pixel) -> bool {
        self.resolution.contains(px)
            && self
                .valid_radius_px
                .is_none_or(|r| (px - DVec2::new(self.cx, self.cy)).length_squared() <= r * r)
    }

    /// The Jacobian of the tangential/thin-prism map must stay invertible (positive
    /// determinant) over the disc the valid field of view covers, or unprojection can fail.
    fn check_tangential_invertible(&self) -> Result<(), CameraError> {
        let r_max = self.radial.eval(self.max_theta_rad);
        for i in 1..=32 {
            let r = r_max * i as Real / 32.0;
            for j in 0..64 {
                let phi = std::f64::consts::TAU * j as Real / 64.0;
                let (_, jac) = self.distort(DVec2::new(r * phi.cos(), r * phi.sin()));
                if !(jac.determinant() > 0.05) {
                    return Err(CameraError::param(
                        "params",
                        "a tangential/thin-prism distortion that folds over",
                        format!(
                            "p0, p1, s0..s3 small enough to be invertible up to θ = {:.3} rad",
                            self.max_theta_rad
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The largest angle of the valid field of view: explicit, or where `θ_d` increases up to 90°.
pub(crate) fn resolve_max_theta<const N: usize>(
    radial: &ThetaPolynomial<N>,
    max_theta_rad: Option<Real>,
) -> Result<Real, CameraError> {
    use std::f64::consts::{FRAC_PI_2, PI};
    match max_theta_rad {
        None => {
            let limit = radial.increasing_limit(FRAC_PI_2);
            if limit < FRAC_PI_2 {
                // Stop a little short of the turning point, where θ_d is flat.
                Ok(0.99 * limit)
            } else {
                Ok(limit)
            }
        }
        Some(m) => {
            if !(m.is_finite() && m > 0.0 && m < PI) {
                return Err(CameraError::param(
                    "max_theta_rad",
                    m,
                    "an angle from the optical axis in (0, π) radians",
                ));
            }
            let limit = radial.increasing_limit(m);
            if limit < m {
                return Err(CameraError::param(
                    "max_theta_rad",
                    m,
                    format!(
                        "at most {limit:.6} rad, where the radial polynomial θ_d(θ) stops increasing"
                    ),
                ));
            }
            Ok(m)
        }
    }
}

impl CameraModel for Fisheye624 {
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
        self.in_mask(px).then_some(px)
    }

    fn unproject(&self, px: Pixel) -> Option<Vec3> {
        if !px.is_finite() || !self.in_mask(px) {
            return None;
        }
        let ud = (px - DVec2::new(self.cx, self.cy)) / self.f;
        let xr = self.undistort(ud)?;
        let r = xr.length();
        let ray = if r == 0.0 {
            Vec3::Z
        } else {
            let theta = self.radial.invert(r, self.max_theta_rad)?;
            let (sin, cos) = theta.sin_cos();
            let dir = xr / r;
            Vec3::new(sin * dir.x, sin * dir.y, cos)
        };
        let back = self.project_unchecked(ray);
        ((back - px).length() <= REPROJECTION_TOLERANCE_PX).then_some(ray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slam_like() -> Fisheye624 {
        // camera-slam-left of the shared fixture.
        Fisheye624::new(
            &[
                241.74642944335938,
                320.6287536621094,
                242.64068603515625,
                -0.02694184333086,
                0.103186674416065,
                -0.072545729577541,
                0.01231786981225,
                0.001513113966211,
                -0.000479895825264,
                0.001933769090101,
                0.001900697243399,
                -0.003100696252658,
                -0.000324406602885,
                -0.002613446209579,
                1.6337084161e-05,
            ],
            Resolution {
                width_px: 640,
                height_px: 480,
            },
            Some(1.4),
            Some(330.0),
        )
        .unwrap()
    }

    #[test]
    fn optical_axis_lands_on_the_principal_point() {
        let cam = slam_like();
        let px = cam.project(Vec3::new(0.0, 0.0, 2.0)).unwrap();
        assert_eq!(px, cam.principal_point());
        assert_eq!(cam.unproject(px), Some(Vec3::Z));
        // Tiny angles: pixel offset is f·θ to first order.
        let px = cam.project(Vec3::new(1e-12, 0.0, 1.0)).unwrap();
        // cx ≈ 320 has an ulp of 6e-14 px.
        assert!((px.x - cam.principal_point().x - 2.417_464_294_433_594e-10).abs() < 1e-13);
    }

    #[test]
    fn beyond_max_theta_is_outside() {
        let cam = slam_like();
        let t: Real = 1.41;
        assert_eq!(cam.project(Vec3::new(t.sin(), 0.0, t.cos())), None);
        assert_eq!(cam.project(Vec3::new(0.0, 0.0, -1.0)), None);
    }

    #[test]
    fn jacobian_matches_finite_difference() {
        let cam = slam_like();
        let x = DVec2::new(0.4, -0.7);
        let (_, jac) = cam.distort(x);
        let h = 1e-7;
        for (k, e) in [DVec2::X, DVec2::Y].into_iter().enumerate() {
            let fd = (cam.distort(x + e * h).0 - cam.distort(x - e * h).0) / (2.0 * h);
            assert!((fd - jac.col(k)).length() < 1e-8);
        }
    }

    #[test]
    fn wrong_param_count_is_reported() {
        let err = Fisheye624::new(
            &[1.0; 11],
            Resolution {
                width_px: 4,
                height_px: 4,
            },
            None,
            None,
        )
        .unwrap_err();
        assert!(err.to_string().contains("15 numbers"), "{err}");
    }
}
