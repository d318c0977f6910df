//! The ideal pinhole camera: `u = fx·x/z + cx`, `v = fy·y/z + cy`, no distortion.
//! Valid field of view: in front of the camera (`z > 0`) and on the sensor.

use super::{check_common, CameraError, CameraModel, Pixel, Resolution};
use crate::math::{Real, Vec3};

/// Pinhole intrinsics, pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pinhole {
    fx: Real,
    fy: Real,
    cx: Real,
    cy: Real,
    resolution: Resolution,
}

impl Pinhole {
    /// Checks and builds: positive finite focal lengths, principal point on the sensor.
    pub fn new(
        fx: Real,
        fy: Real,
        cx: Real,
        cy: Real,
        resolution: Resolution,
    ) -> Result<Self, CameraError> {
        check_common(&[("fx", fx), ("fy", fy)], cx, cy, resolution)?;
        Ok(Self {
            fx,
            fy,
            cx,
            cy,
            resolution,
        })
    }

    /// A centred camera with square pixels and the given horizontal field of view.
    #[cfg(test)]
    fn from_horizontal_fov(
        horizontal_fov_rad: Real,
        resolution: Resolution,
    ) -> Result<Self, CameraError> {
        if !(horizontal_fov_rad > 0.0 && horizontal_fov_rad < std::f64::consts::PI) {
            return Err(CameraError::param(
                "horizontal_fov_rad",
                horizontal_fov_rad,
                "an angle in (0, π) radians",
            ));
        }
        let f = 0.5 * resolution.width_px as Real / (0.5 * horizontal_fov_rad).tan();
        Self::new(
            f,
            f,
            0.5 * (resolution.width_px as Real - 1.0),
            0.5 * (resolution.height_px as Real - 1.0),
            resolution,
        )
    }

    /// `[fx, fy, cx, cy]`.
    pub fn params(&self) -> [Real; 4] {
        [self.fx, self.fy, self.cx, self.cy]
    }
}

impl CameraModel for Pinhole {
    fn resolution(&self) -> Resolution {
        self.resolution
    }

    fn principal_point(&self) -> Pixel {
        Pixel::new(self.cx, self.cy)
    }

    /// 90°: a pinhole sees only in front of itself (`z > 0`, so θ < 90°).
    fn max_theta_rad(&self) -> Real {
        std::f64::consts::FRAC_PI_2
    }

    fn project(&self, p: Vec3) -> Option<Pixel> {
        if !(p.z > 0.0) {
            return None;
        }
        let px = Pixel::new(self.fx * p.x / p.z + self.cx, self.fy * p.y / p.z + self.cy);
        self.resolution.contains(px).then_some(px)
    }

    fn unproject(&self, px: Pixel) -> Option<Vec3> {
        if !self.resolution.contains(px) {
            return None;
        }
        let ray = Vec3::new((px.x - self.cx) / self.fx, (px.y - self.cy) / self.fy, 1.0);
        Some(ray.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn res(w: u32, h: u32) -> Resolution {
        Resolution {
            width_px: w,
            height_px: h,
        }
    }

    #[test]
    fn fov_of_a_centred_camera_is_the_textbook_value() {
        let cam = Pinhole::from_horizontal_fov(64.69f64.to_radians(), res(1920, 1080)).unwrap();
        let fov = cam.fov();
        assert!((fov.horizontal_rad.to_degrees() - 64.69).abs() < 1e-9);
        let f = cam.params()[0];
        let v = 2.0 * (540.0 / f).atan();
        let d = 2.0 * ((960.0f64.hypot(540.0)) / f).atan();
        assert!((fov.vertical_rad - v).abs() < 1e-12);
        assert!((fov.diagonal_rad - d).abs() < 1e-12);
    }

    #[test]
    fn behind_and_off_sensor_are_outside() {
        let cam = Pinhole::new(100.0, 100.0, 31.5, 23.5, res(64, 48)).unwrap();
        assert_eq!(cam.project(Vec3::new(0.0, 0.0, -1.0)), None);
        assert_eq!(cam.project(Vec3::new(1.0, 0.0, 1.0)), None);
        assert_eq!(cam.project(Vec3::Z), Some(Pixel::new(31.5, 23.5)));
        assert_eq!(cam.unproject(Pixel::new(64.0, 0.0)), None);
    }

    #[test]
    fn bad_parameters_are_named() {
        let err = Pinhole::new(-1.0, 1.0, 0.0, 0.0, res(4, 4)).unwrap_err();
        assert!(err.to_string().contains("`fx`"), "{err}");
        let err = Pinhole::new(1.0, 1.0, 9.0, 0.0, res(4, 4)).unwrap_err();
        assert!(err.to_string().contains("`cx`"), "{err}");
    }
}
