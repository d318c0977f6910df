//! The ideal camera Blender renders for a rig camera. A square-pixel pinhole is rendered as
//! itself; every distorted model is rendered by a lens Cycles has and remapped to the exact
//! model in Rust (`frame_file::assemble_frame`): a Fisheye624 camera by Cycles' polynomial
//! fisheye fitted to it, scaled and padded to hold the camera's field of view at least at its
//! own resolution ([`LensPolynomial::remap_source`]: about the target's pixel count), any other
//! (Kannala-Brandt, or a Fisheye624 the polynomial cannot follow) by Cycles' equidistant fisheye
//! covering the model's widest ray at its largest angular resolution (a square around the
//! image circle: 1.5–3× the target's pixels for the Aria cameras). With
//! [`FisheyeRendering::Native`] a Fisheye624 camera is rendered by the fitted polynomial at the
//! target resolution and not remapped (off the model by the fit's error).
//!
//! Pixel convention as in [`crate::camera`]: OpenCV, centre of the top-left pixel at (0, 0).
//! Cycles' equidistant fisheye (measured with the position pass, `tests/render_passes.rs`):
//! `θ = ρ / f` with `f = size / fov` pixels per radian, `ρ` the distance from the image centre
//! `((size − 1) / 2, (size − 1) / 2)`, azimuth as in the image (x right, y down).

use crate::camera::{max_theta_in_image, Camera, CameraModel, Pixel, Resolution};
use crate::math::{Real, Vec3};
use crate::render::camera_setup::blender_lens;
use crate::render::lens_polynomial::{LensFitError, LensPolynomial, FOV_MARGIN_PX};
use crate::render::protocol::ShardLens;

/// How Fisheye624 cameras are rendered (`[render] fisheye`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FisheyeRendering {
    /// The exact model, remapped in Rust from the tightest lens Cycles can render for it: the
    /// fitted polynomial fisheye (Fisheye624), else a wider equidistant fisheye.
    #[default]
    Exact,
    /// The exact model, remapped from a wider equidistant fisheye for every distorted camera
    /// (egogen's earlier default; path-traces 1.5–3× the Aria cameras' pixels).
    Equidistant,
    /// Cycles' polynomial fisheye fitted to the model, rendered at the target resolution:
    /// faster, off the exact model by the fit's error (`docs/RENDERING.md`).
    Native,
}

/// What Blender renders for one rig camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RenderCamera {
    /// Square pixels, OpenCV intrinsics.
    Perspective {
        resolution: Resolution,
        f_px: Real,
        cx: Real,
        cy: Real,
    },
    EquidistantFisheye {
        size_px: u32,
        fov_rad: Real,
    },
    /// Cycles' polynomial fisheye, the image itself (no remap).
    PolynomialFisheye(LensPolynomial),
    /// Cycles' polynomial fisheye fitted to the camera, scaled and padded, remapped exactly.
    PolynomialSource(LensPolynomial),
}

impl RenderCamera {
    /// The render for `target`: with [`FisheyeRendering::Native`], the polynomial lens for a
    /// Fisheye624 camera; otherwise as [`Self::exact`].
    pub fn for_camera(
        target: &Camera,
        oversample: Real,
        fisheye: FisheyeRendering,
    ) -> Result<Self, LensFitError> {
        match (fisheye, target) {
            (FisheyeRendering::Native, Camera::Fisheye624(m)) => Ok(
                RenderCamera::PolynomialFisheye(LensPolynomial::for_fisheye624(m)?),
            ),
            (FisheyeRendering::Equidistant, _) => Ok(Self::equidistant(target, oversample)),
            _ => Ok(Self::exact(target, oversample)),
        }
    }

    /// The tightest render that is remapped exactly to `target`: the fitted polynomial fisheye
    /// for a Fisheye624 camera where it can follow the model, else [`Self::equidistant`];
    /// `oversample` scales the source's pixels over the target's (1 = never coarser).
    pub fn exact(target: &Camera, oversample: Real) -> Self {
        match LensPolynomial::remap_source(target, oversample, FOV_MARGIN_PX) {
            Ok(lens) => RenderCamera::PolynomialSource(lens),
            Err(_) => Self::equidistant(target, oversample),
        }
    }

    /// The wide equidistant render remapped exactly to `target` (a pinhole with square pixels
    /// renders as itself); `oversample` scales the fisheye's pixels per radian over the
    /// target's largest (1 = same angular resolution).
    pub(crate) fn equidistant(target: &Camera, oversample: Real) -> Self {
        if let Camera::Pinhole(p) = target {
            let [fx, fy, cx, cy] = p.params();
            if (fx - fy).abs() <= 1e-9 * fx {
                return RenderCamera::Perspective {
                    resolution: p.resolution(),
                    f_px: fx,
                    cx,
                    cy,
                };
            }
        }
        let theta = max_theta_in_image(target);
        let f = max_pixels_per_radian(target, theta) * oversample;
        let half = theta + FOV_MARGIN_PX / f;
        let size_px = (2.0 * half * f).ceil() as u32;
        RenderCamera::EquidistantFisheye {
            size_px,
            fov_rad: 2.0 * half,
        }
    }

    /// Whether the rendered image is the target image itself (no remap).
    pub(crate) fn is_identity(&self) -> bool {
        matches!(
            self,
            RenderCamera::Perspective { .. } | RenderCamera::PolynomialFisheye(_)
        )
    }

    pub fn resolution(&self) -> Resolution {
        match *self {
            RenderCamera::Perspective { resolution, .. } => resolution,
            RenderCamera::EquidistantFisheye { size_px, .. } => Resolution {
                width_px: size_px,
                height_px: size_px,
            },
            RenderCamera::PolynomialFisheye(lens) | RenderCamera::PolynomialSource(lens) => {
                lens.resolution
            }
        }
    }

    /// Blender's lens for this camera.
    pub(crate) fn lens(&self) -> ShardLens {
        match *self {
            RenderCamera::Perspective {
                resolution,
                f_px,
                cx,
                cy,
            } => {
                // Blender measures the principal point from the image corner.
                let (focal_mm, sensor_width_mm, shift_x, shift_y) = blender_lens(
                    resolution.width_px,
                    resolution.height_px,
                    f_px,
                    cx + 0.5,
                    cy + 0.5,
                );
                ShardLens::Perspective {
                    width_px: resolution.width_px,
                    height_px: resolution.height_px,
                    focal_mm,
                    sensor_width_mm,
                    shift_x,
                    shift_y,
                }
            }
            RenderCamera::EquidistantFisheye { size_px, fov_rad } => {
                ShardLens::EquidistantFisheye { size_px, fov_rad }
            }
            RenderCamera::PolynomialFisheye(lens) | RenderCamera::PolynomialSource(lens) => {
                let (sensor_width_mm, k, shift_x, shift_y) = lens.blender();
                ShardLens::PolynomialFisheye {
                    width_px: lens.resolution.width_px,
                    height_px: lens.resolution.height_px,
                    sensor_width_mm,
                    k,
                    shift_x,
                    shift_y,
                    fov_rad: lens.fov_rad(),
                }
            }
        }
    }

    /// Whether Blender renders this pixel meaningfully: Cycles' equidistant fisheye leaves
    /// pixels outside its image circle (`ρ > size / 2`) undefined; the polynomial lens is used
    /// where it increases.
    pub fn renders(&self, px: Pixel) -> bool {
        match *self {
            RenderCamera::Perspective { .. } => true,
            RenderCamera::EquidistantFisheye { size_px, .. } => {
                let c = 0.5 * (size_px as Real - 1.0);
                (px - Pixel::new(c, c)).length() <= 0.5 * size_px as Real
            }
            RenderCamera::PolynomialFisheye(lens) | RenderCamera::PolynomialSource(lens) => {
                lens.renders(px)
            }
        }
    }

    /// Unit ray (OpenCV camera frame) through a pixel, also beyond the rendered image (flow
    /// targets may leave it); `None` only past the fisheye's θ = π.
    pub(crate) fn pixel_to_ray(&self, px: Pixel) -> Option<Vec3> {
        match *self {
            RenderCamera::Perspective { f_px, cx, cy, .. } => {
                Some(Vec3::new((px.x - cx) / f_px, (px.y - cy) / f_px, 1.0).normalize())
            }
            RenderCamera::EquidistantFisheye { size_px, fov_rad } => {
                let c = 0.5 * (size_px as Real - 1.0);
                let f = size_px as Real / fov_rad;
                let d = px - Pixel::new(c, c);
                let rho = d.length();
                let theta = rho / f;
                if theta > std::f64::consts::PI {
                    return None;
                }
                if rho == 0.0 {
                    return Some(Vec3::Z);
                }
                let s = theta.sin() / rho;
                Some(Vec3::new(d.x * s, d.y * s, theta.cos()))
            }
            RenderCamera::PolynomialFisheye(lens) | RenderCamera::PolynomialSource(lens) => {
                lens.pixel_to_ray(px)
            }
        }
    }

    /// Pixel of a camera-frame direction (not bounded by the image).
    pub fn ray_to_pixel(&self, ray: Vec3) -> Option<Pixel> {
        match *self {
            RenderCamera::Perspective { f_px, cx, cy, .. } => (ray.z > 0.0)
                .then(|| Pixel::new(f_px * ray.x / ray.z + cx, f_px * ray.y / ray.z + cy)),
            RenderCamera::EquidistantFisheye { size_px, fov_rad } => {
                let c = 0.5 * (size_px as Real - 1.0);
                let f = size_px as Real / fov_rad;
                let r_xy = ray.x.hypot(ray.y);
                let theta = r_xy.atan2(ray.z);
                if r_xy == 0.0 {
                    return (ray.z > 0.0).then(|| Pixel::new(c, c));
                }
                let rho = f * theta;
                Some(Pixel::new(c + rho * ray.x / r_xy, c + rho * ray.y / r_xy))
            }
            RenderCamera::PolynomialFisheye(lens) | RenderCamera::PolynomialSource(lens) => {
                lens.ray_to_pixel(ray)
            }
        }
    }
}

/// Largest pixels-per-radian of a model up to `max_theta`, radially and tangentially, sampled
/// on 16 azimuths × 64 angles.
fn max_pixels_per_radian(cam: &Camera, max_theta: Real) -> Real {
    let d = 1e-4;
    let mut best: Real = 0.0;
    for a in 0..16 {
        let phi = a as Real / 16.0 * std::f64::consts::TAU;
        for t in 0..64 {
            let theta = (t as Real + 0.5) / 64.0 * (max_theta - d);
            let ray =
                |th: Real, ph: Real| Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
            let (Some(p), Some(pr), Some(pt)) = (
                cam.project_unbounded(ray(theta, phi)),
                cam.project_unbounded(ray(theta + d, phi)),
                cam.project_unbounded(ray(theta, phi + d)),
            ) else {
                continue;
            };
            best = best
                .max((pr - p).length() / d)
                .max((pt - p).length() / (d * theta.sin()));
        }
    }
    best
}
