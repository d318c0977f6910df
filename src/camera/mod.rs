//! Camera models: the map between camera-frame points and pixels, one model per file behind
//! the [`CameraModel`] trait. Where a camera sits on the head belongs to `rig`.
//!
//! Here: `pinhole` (the ideal pinhole), `kannala_brandt` (the KB4 fisheye of OpenCV's
//! `cv::fisheye`), `fisheye624` (Aria's Fisheye624), `theta_poly` (the fisheyes' odd radial
//! polynomial and its inverse), `fov` (a model's field of view measured from its valid region).
//!
//! Conventions shared by every model:
//! - Camera frame: OpenCV (x right, y down, z forward along the optical axis), metres.
//! - Pixels: continuous coordinates with the centre of the top-left pixel at (0, 0); the image
//!   covers `[-0.5, width - 0.5] × [-0.5, height - 0.5]` (edges included), as in OpenCV and
//!   projectaria-tools.
//! - `θ` is the angle between a ray and the optical axis, `atan2(√(x² + y²), z)`.
//! - The *valid field of view* is where a model is defined and invertible: inside the image,
//!   `θ ≤ max θ`, and for fisheyes with a mask inside the valid circle around the principal
//!   point. `project` and `unproject` return `None` outside it. Both decide the boundary with
//!   their own rounding, so points within ~1e-9 px (1e-12 rad) of it may be judged differently.
//!
//! Adding a model: a file with a struct that checks its parameters in `new` (returning
//! [`CameraError`]), implements [`CameraModel`], and a variant of [`Camera`].

pub(crate) mod fisheye624;
mod fov;
pub mod kannala_brandt;
pub(crate) mod pinhole;
pub(crate) mod theta_poly;

use glam::DVec2;

use crate::math::{Real, Vec3};

pub use fisheye624::Fisheye624;
pub use kannala_brandt::KannalaBrandt4;
pub use pinhole::Pinhole;

/// A pixel position (continuous, see the module docs for the convention).
pub type Pixel = DVec2;

/// Image size in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Resolution {
    pub width_px: u32,
    pub height_px: u32,
}

impl Resolution {
    /// Whether a pixel lies on the sensor, `[-0.5, w - 0.5] × [-0.5, h - 0.5]` edges included.
    pub fn contains(&self, pixel: Pixel) -> bool {
        pixel.x >= -0.5
            && pixel.y >= -0.5
            && pixel.x <= self.width_px as Real - 0.5
            && pixel.y <= self.height_px as Real - 0.5
    }
}

/// Field of view, radians. Each is the angle between the rays of the two farthest valid
/// pixels on a line through the principal point: horizontal (along the image rows),
/// vertical (along the columns) and diagonal (parallel to the top-left → bottom-right image
/// diagonal). For a centred pinhole these are the textbook `2·atan(w / 2f)` values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fov {
    pub horizontal_rad: Real,
    pub vertical_rad: Real,
    pub diagonal_rad: Real,
}

/// A camera model's parameters that cannot work, with the parameter and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    #[error("`{field}` is {value}, expected {expected}")]
    Param {
        field: &'static str,
        value: String,
        expected: String,
    },
}

impl CameraError {
    pub(crate) fn param(
        field: &'static str,
        value: impl ToString,
        expected: impl Into<String>,
    ) -> Self {
        Self::Param {
            field,
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}

/// The projection of one camera model.
pub trait CameraModel {
    /// Image size.
    fn resolution(&self) -> Resolution;

    /// Where the optical axis meets the image.
    fn principal_point(&self) -> Pixel;

    /// Largest angle θ from the optical axis that the model accepts (radians).
    fn max_theta_rad(&self) -> Real;

    /// Pixel of a camera-frame point, or `None` outside the valid field of view (behind the
    /// camera, beyond `max θ`, off the sensor or outside the valid circle).
    fn project(&self, point_in_cam: Vec3) -> Option<Pixel>;

    /// Unit ray (camera frame) through a pixel, or `None` outside the valid field of view.
    /// A returned ray reprojects to the pixel within 1e-7 px (measured: ~1e-12 px); its
    /// `project` can only be `None` within the rounding band at the boundary.
    fn unproject(&self, pixel: Pixel) -> Option<Vec3>;

    /// Horizontal, vertical and diagonal field of view (see [`Fov`]).
    fn fov(&self) -> Fov
    where
        Self: Sized,
    {
        fov::measure(self)
    }
}

/// How well a fitted lens model reproduces a camera over its valid field of view: the
/// distance between each sampled pixel centre and the fitted model's pixel of its exact ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FitError {
    pub max_px: Real,
    pub mean_px: Real,
    /// Pixel centres sampled (every one in the valid field of view).
    pub samples: usize,
}

impl FitError {
    /// The error of `fitted` (a pixel of a ray, in the same convention) over `samples`, each
    /// a pixel centre with its exact ray.
    pub(crate) fn measure(samples: &[(Pixel, Vec3)], fitted: impl Fn(Vec3) -> Pixel) -> Self {
        let mut max_px: Real = 0.0;
        let mut sum = 0.0;
        for &(px, ray) in samples {
            let e = fitted(ray).distance(px);
            max_px = max_px.max(e);
            sum += e;
        }
        FitError {
            max_px,
            mean_px: sum / samples.len().max(1) as Real,
            samples: samples.len(),
        }
    }
}

/// Every pixel centre of `camera` in its valid field of view, with its unit ray: the samples
/// lens fits solve over and are measured on.
pub fn valid_pixel_rays(camera: &Camera) -> Vec<(Pixel, Vec3)> {
    let res = CameraModel::resolution(camera);
    let mut samples = Vec::new();
    for row in 0..res.height_px {
        for col in 0..res.width_px {
            let px = Pixel::new(col as Real, row as Real);
            if let Some(ray) = CameraModel::unproject(camera, px) {
                samples.push((px, ray));
            }
        }
    }
    samples
}

/// Largest distance (px) between a pixel and the reprojection of its unprojected ray that
/// `unproject` accepts; larger means an iteration did not converge.
pub(crate) const REPROJECTION_TOLERANCE_PX: Real = 1e-7;

/// Any of the supported models, as a rig stores them.
#[derive(Debug, Clone, PartialEq)]
pub enum Camera {
    Pinhole(Pinhole),
    Fisheye624(Fisheye624),
    KannalaBrandt4(KannalaBrandt4),
}

impl Camera {
    /// Short model name as rig files spell it.
    pub fn model_name(&self) -> &'static str {
        match self {
            Camera::Pinhole(_) => "pinhole",
            Camera::Fisheye624(_) => "fisheye624",
            Camera::KannalaBrandt4(_) => "kannala_brandt4",
        }
    }

    /// The same camera on an image scaled by `scale` (as projectaria-tools rescales: focal
    /// lengths times `scale`, `c' = scale·(c + 0.5) − 0.5`). Both image sides times `scale`
    /// must be whole pixels.
    pub fn scaled(&self, scale: Real) -> Result<Camera, CameraError> {
        let res = CameraModel::resolution(self);
        let side = |px: u32| {
            let v = px as Real * scale;
            (scale > 0.0 && (v - v.round()).abs() < 1e-6 && v.round() >= 1.0)
                .then_some(v.round() as u32)
        };
        let (Some(width_px), Some(height_px)) = (side(res.width_px), side(res.height_px)) else {
            return Err(CameraError::param(
                "scale",
                scale,
                format!(
                    "a factor that turns {}x{} into whole pixels",
                    res.width_px, res.height_px
                ),
            ));
        };
        let new = Resolution {
            width_px,
            height_px,
        };
        let c = |v: Real| scale * (v + 0.5) - 0.5;
        Ok(match self {
            Camera::Pinhole(m) => {
                let [fx, fy, cx, cy] = m.params();
                Camera::Pinhole(Pinhole::new(scale * fx, scale * fy, c(cx), c(cy), new)?)
            }
            Camera::Fisheye624(m) => Camera::Fisheye624(m.rescaled(new, scale, DVec2::ZERO)?),
            Camera::KannalaBrandt4(m) => {
                let ([fx, fy, cx, cy], k) = m.params();
                Camera::KannalaBrandt4(KannalaBrandt4::new(
                    [scale * fx, scale * fy, c(cx), c(cy)],
                    k,
                    new,
                    Some(CameraModel::max_theta_rad(m)),
                )?)
            }
        })
    }

    /// Pixel of a camera-frame point ignoring the image border and mask (flow targets may
    /// leave the image); `None` only where the model itself is undefined (behind a pinhole,
    /// beyond a fisheye's `max θ`).
    pub fn project_unbounded(&self, p: Vec3) -> Option<Pixel> {
        match self {
            Camera::Pinhole(m) => {
                let [fx, fy, cx, cy] = m.params();
                (p.z > 0.0).then(|| Pixel::new(fx * p.x / p.z + cx, fy * p.y / p.z + cy))
            }
            Camera::Fisheye624(m) => {
                (theta_of(p) <= CameraModel::max_theta_rad(m)).then(|| m.project_unchecked(p))
            }
            Camera::KannalaBrandt4(m) => {
                (theta_of(p) <= CameraModel::max_theta_rad(m)).then(|| m.project_unchecked(p))
            }
        }
    }

    fn as_model(&self) -> &dyn CameraModelDyn {
        match self {
            Camera::Pinhole(m) => m,
            Camera::Fisheye624(m) => m,
            Camera::KannalaBrandt4(m) => m,
        }
    }
}

/// Object-safe part of [`CameraModel`], for dispatch in [`Camera`].
trait CameraModelDyn {
    fn resolution(&self) -> Resolution;
    fn principal_point(&self) -> Pixel;
    fn max_theta_rad(&self) -> Real;
    fn project(&self, p: Vec3) -> Option<Pixel>;
    fn unproject(&self, px: Pixel) -> Option<Vec3>;
}

impl<T: CameraModel> CameraModelDyn for T {
    fn resolution(&self) -> Resolution {
        CameraModel::resolution(self)
    }
    fn principal_point(&self) -> Pixel {
        CameraModel::principal_point(self)
    }
    fn max_theta_rad(&self) -> Real {
        CameraModel::max_theta_rad(self)
    }
    fn project(&self, p: Vec3) -> Option<Pixel> {
        CameraModel::project(self, p)
    }
    fn unproject(&self, px: Pixel) -> Option<Vec3> {
        CameraModel::unproject(self, px)
    }
}

impl CameraModel for Camera {
    fn resolution(&self) -> Resolution {
        self.as_model().resolution()
    }
    fn principal_point(&self) -> Pixel {
        self.as_model().principal_point()
    }
    fn max_theta_rad(&self) -> Real {
        self.as_model().max_theta_rad()
    }
    fn project(&self, point_in_cam: Vec3) -> Option<Pixel> {
        self.as_model().project(point_in_cam)
    }
    fn unproject(&self, pixel: Pixel) -> Option<Vec3> {
        self.as_model().unproject(pixel)
    }
}

/// Angle between a camera-frame direction and the optical axis (radians, in [0, π]).
pub fn theta_of(point_in_cam: Vec3) -> Real {
    point_in_cam.x.hypot(point_in_cam.y).atan2(point_in_cam.z)
}

/// Largest angle from the optical axis that a valid pixel of the image sees (the image border
/// and the valid circle bound it), at most the model's `max θ`.
pub(crate) fn max_theta_in_image(cam: &Camera) -> Real {
    let res = CameraModel::resolution(cam);
    let (w, h) = (res.width_px as Real, res.height_px as Real);
    let limit = CameraModel::max_theta_rad(cam).min(3.1);
    let mut best: Real = 0.0;
    let steps = 4 * (res.width_px + res.height_px);
    for k in 0..=steps {
        let t = k as Real / steps as Real;
        for px in [
            Pixel::new(-0.5 + t * w, -0.5),
            Pixel::new(-0.5 + t * w, h - 0.5),
            Pixel::new(-0.5, -0.5 + t * h),
            Pixel::new(w - 0.5, -0.5 + t * h),
        ] {
            match CameraModel::unproject(cam, px) {
                Some(ray) => best = best.max(theta_of(ray)),
                // Border outside the valid circle: the circle bounds the view.
                None => return limit,
            }
        }
    }
    best.min(limit)
}

/// Checks shared by every model: a finite positive focal length, a finite principal point
/// on the sensor, a non-empty image.
pub(crate) fn check_common(
    focal: &[(&'static str, Real)],
    cx: Real,
    cy: Real,
    resolution: Resolution,
) -> Result<(), CameraError> {
    if resolution.width_px == 0 {
        return Err(CameraError::param("width_px", 0, "a positive image width"));
    }
    if resolution.height_px == 0 {
        return Err(CameraError::param(
            "height_px",
            0,
            "a positive image height",
        ));
    }
    for &(name, f) in focal {
        if !(f.is_finite() && f > 0.0) {
            return Err(CameraError::param(
                name,
                f,
                "a positive, finite focal length in pixels",
            ));
        }
    }
    for (name, c, size) in [
        ("cx", cx, resolution.width_px),
        ("cy", cy, resolution.height_px),
    ] {
        if !c.is_finite() || c < -0.5 || c > size as Real - 0.5 {
            return Err(CameraError::param(
                name,
                c,
                format!(
                    "a finite principal point on the sensor, in [-0.5, {}] px",
                    size as Real - 0.5
                ),
            ));
        }
    }
    Ok(())
}

/// Checks that distortion coefficients are finite numbers.
pub(crate) fn check_finite(field: &'static str, values: &[Real]) -> Result<(), CameraError> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(v) => Err(CameraError::param(field, v, "finite numbers")),
        None => Ok(()),
    }
}
