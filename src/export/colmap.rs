//! A take's COLMAP export (`[render] colmap`): per camera a COLMAP text model of the rendered
//! frames with their ground-truth poses and intrinsics, and the colour images COLMAP can read.
//!
//! Layout (inside the dataset folder):
//! - `images/<camera>/frame_NNNNN.png` — the colour of each frame file (`rgb.R/G/B`, or
//!   `gray.Y` of a monochrome camera) times the frame's automatic exposure
//!   (`inspect::preview::auto_exposure`, `colour_exposure` in the annotations), linear →
//!   sRGB, clamped to [0, 1], 8-bit RGB (grey for
//!   a monochrome camera). COLMAP cannot read the multilayer EXR. Written only when the run
//!   asks for it (`[render] colmap`, which needs the `colour` pass), as each frame is finished
//!   ([`TakeExport::frame_file`]).
//! - `colmap/<camera>/cameras.txt` — one camera, id 1, in the COLMAP model that reproduces the
//!   rig's model exactly (see [`colmap_camera`]).
//! - `colmap/<camera>/images.txt` — one image per rendered frame, ids 1, 2, … in frame order,
//!   `NAME` = `frame_NNNNN.png` (relative to `images/<camera>/`), the world-to-camera rotation
//!   as a unit quaternion `QW QX QY QZ` (`QW ≥ 0`) and translation `TX TY TZ` in metres; the
//!   camera frame is OpenCV's, which is COLMAP's (x right, y down, z forward). The `POINTS2D`
//!   line of each image is empty: COLMAP's feature extractor supplies keypoints.
//! - `colmap/<camera>/points3D.txt` — header only, no points: `point_triangulator` builds them
//!   from matched features and these fixed poses.
//! - `colmap/<camera>/thin_prism_fisheye/` (Fisheye624 cameras only) — the same model with the
//!   camera as a fitted `THIN_PRISM_FISHEYE` (COLMAP 3.8 has no exact Fisheye624 model); its
//!   fitting error over the valid field of view is in `cameras.txt`'s comments.
//!
//! Pixel convention: COLMAP puts the centre of the top-left pixel at (0.5, 0.5), egogen at
//! (0, 0) (see [`crate::camera`]), so every principal point is written as `c + 0.5`.
//!
//! With COLMAP's feature extractor run on `images/<camera>` as a single camera into a fresh
//! database, the database's image ids and names are those of `images.txt` (the extractor
//! numbers images from 1 in sorted name order), as `point_triangulator` requires.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use glam::DQuat;

use super::annotate::colour_pass;
use super::take::{CameraWork, FinishedFrame, FinishedTake, TakeExport};
use crate::atomic_file::write_atomically;
use crate::camera::{valid_pixel_rays, Camera, CameraModel, Fisheye624, FitError, Pixel};
use crate::inspect::preview::pass_preview_exposed;
use crate::math::least_squares::NormalEquations;
use crate::math::{Affine3, Real, Vec3};

/// A camera as COLMAP's `cameras.txt` spells it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ColmapCamera {
    /// COLMAP model name (`PINHOLE`, `OPENCV_FISHEYE`, `RAD_TAN_THIN_PRISM_FISHEYE`, …).
    pub model: &'static str,
    /// Parameters in COLMAP's order, principal point in COLMAP's pixel convention.
    pub params: Vec<Real>,
    pub width_px: u32,
    pub height_px: u32,
}

/// The COLMAP model that is exactly egogen's camera:
/// - pinhole → `PINHOLE fx fy cx cy`;
/// - Kannala–Brandt (KB4) → `OPENCV_FISHEYE fx fy cx cy k1 k2 k3 k4` (same `θ_d` polynomial);
/// - Fisheye624 → `RAD_TAN_THIN_PRISM_FISHEYE fx fy cx cy k0..k5 p0 p1 s0..s3` with `fx = fy = f`
///   (COLMAP ≥ 3.10; the same equations as projectaria-tools, see `src/colmap/sensor/models.h`).
///
/// Principal points move by +0.5 px into COLMAP's convention.
pub(crate) fn colmap_camera(camera: &Camera) -> ColmapCamera {
    let res = camera.resolution();
    let (model, params) = match camera {
        Camera::Pinhole(m) => {
            let [fx, fy, cx, cy] = m.params();
            ("PINHOLE", vec![fx, fy, cx + 0.5, cy + 0.5])
        }
        Camera::KannalaBrandt4(m) => {
            let ([fx, fy, cx, cy], k) = m.params();
            let mut p = vec![fx, fy, cx + 0.5, cy + 0.5];
            p.extend(k);
            ("OPENCV_FISHEYE", p)
        }
        Camera::Fisheye624(m) => {
            let q = m.params();
            let mut p = vec![q[0], q[0], q[1] + 0.5, q[2] + 0.5];
            p.extend(&q[3..]);
            ("RAD_TAN_THIN_PRISM_FISHEYE", p)
        }
    };
    ColmapCamera {
        model,
        params,
        width_px: res.width_px,
        height_px: res.height_px,
    }
}

/// COLMAP's `THIN_PRISM_FISHEYE` projection of a camera-frame point (COLMAP pixels): the
/// equidistant point `(u, v) = θ·(x, y)/ρ`, then radial `k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸`,
/// tangential `p1 p2` and thin prism `sx1 sy1` on `(u, v)` itself.
pub(crate) fn thin_prism_fisheye_project(params: &[Real; 12], p: Vec3) -> Pixel {
    let [fx, fy, cx, cy, ..] = *params;
    let (u, v) = equidistant(p);
    let [du, dv] = thin_prism_terms(u, v);
    let d =
        |terms: &[Real; 8]| -> Real { terms.iter().zip(&params[4..]).map(|(t, k)| t * k).sum() };
    Pixel::new(fx * (u + d(&du)) + cx, fy * (v + d(&dv)) + cy)
}

fn equidistant(p: Vec3) -> (Real, Real) {
    let rho = p.x.hypot(p.y);
    if rho == 0.0 {
        return (0.0, 0.0);
    }
    let theta = rho.atan2(p.z);
    (theta * p.x / rho, theta * p.y / rho)
}

/// The distortion of `THIN_PRISM_FISHEYE` is linear in its eight coefficients
/// `[k1, k2, p1, p2, k3, k4, sx1, sy1]`: the factors of each in `du` and in `dv`.
fn thin_prism_terms(u: Real, v: Real) -> [[Real; 8]; 2] {
    let r2 = u * u + v * v;
    let (r4, r6, r8) = (r2 * r2, r2 * r2 * r2, r2 * r2 * r2 * r2);
    [
        [
            u * r2,
            u * r4,
            2.0 * u * v,
            r2 + 2.0 * u * u,
            u * r6,
            u * r8,
            r2,
            0.0,
        ],
        [
            v * r2,
            v * r4,
            r2 + 2.0 * v * v,
            2.0 * u * v,
            v * r6,
            v * r8,
            0.0,
            r2,
        ],
    ]
}

/// Fits COLMAP 3.8's `THIN_PRISM_FISHEYE` to a Fisheye624 camera: focal length and principal
/// point are kept (`fx = fy = f`, `c + 0.5`), the eight distortion coefficients solve a linear
/// least-squares problem over every pixel centre in the valid field of view (each pixel's
/// exact ray must land on that pixel). Returns the parameters and the pixel error over the
/// same pixels.
pub(crate) fn fit_thin_prism_fisheye(camera: &Fisheye624) -> ([Real; 12], FitError) {
    let q = camera.params();
    let (f, cx, cy) = (q[0], q[1] + 0.5, q[2] + 0.5);
    let samples: Vec<(Pixel, Vec3)> = valid_pixel_rays(&Camera::Fisheye624(*camera))
        .into_iter()
        .map(|(px, ray)| (px + Pixel::splat(0.5), ray))
        .collect();
    // The 2·n residuals (u + d·k) − (pixel − c)/f.
    let mut eq = NormalEquations::<8>::default();
    for (px, ray) in &samples {
        let (u, v) = equidistant(*ray);
        let terms = thin_prism_terms(u, v);
        let targets = [(px.x - cx) / f - u, (px.y - cy) / f - v];
        for (row, b) in terms.iter().zip(targets) {
            eq.add(row, b);
        }
    }
    let k = eq.solve();
    let mut params = [0.0; 12];
    params[..4].copy_from_slice(&[f, f, cx, cy]);
    params[4..].copy_from_slice(&k);
    let error = FitError::measure(&samples, |ray| thin_prism_fisheye_project(&params, ray));
    (params, error)
}

/// COLMAP's pose of an image: `cam_from_world` as `(QW, QX, QY, QZ)` with `QW ≥ 0` and the
/// translation.
pub fn colmap_pose(world_from_cam: Affine3) -> ([Real; 4], Vec3) {
    let cam_from_world = world_from_cam.inverse();
    let q = DQuat::from_mat3(&cam_from_world.matrix3).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    ([q.w, q.x, q.y, q.z], cam_from_world.translation)
}

/// The image name of a frame in `images.txt` (and its file in `images/<camera>/`).
pub(crate) fn image_name(frame: u32) -> String {
    format!("frame_{frame:05}.png")
}

fn join(values: &[Real]) -> String {
    values
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

fn cameras_txt(camera: &ColmapCamera, comment: &str) -> String {
    format!(
        "# Camera list with one line of data per camera:\n\
         #   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n\
         # Number of cameras: 1\n{comment}\
         1 {} {} {} {}\n",
        camera.model,
        camera.width_px,
        camera.height_px,
        join(&camera.params)
    )
}

fn images_txt(work: &CameraWork) -> String {
    let mut out = format!(
        "# Image list with two lines of data per image:\n\
         #   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n\
         #   POINTS2D[] as (X, Y, POINT3D_ID)\n\
         # Number of images: {}, mean observations per image: 0\n",
        work.frames.len()
    );
    for (i, &f) in work.frames.iter().enumerate() {
        let (q, t) = colmap_pose(work.world_from_cam[f as usize]);
        let _ = writeln!(
            out,
            "{} {} {} 1 {}\n",
            i + 1,
            join(&q),
            join(&t.to_array()),
            image_name(f)
        );
    }
    out
}

const POINTS3D_TXT: &str = "# 3D point list with one line of data per point:\n\
    #   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n\
    # Number of points: 0, mean track length: 0\n";

fn write_model(dir: &Path, cameras: &str, images: &str) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (name, text) in [
        ("cameras.txt", cameras),
        ("images.txt", images),
        ("points3D.txt", POINTS3D_TXT),
    ] {
        let path = dir.join(name);
        write_atomically(&path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The COLMAP export: each frame's image as the frame is finished, the models when the take is.
pub(crate) struct Colmap;

impl TakeExport for Colmap {
    fn name(&self) -> &'static str {
        "colmap"
    }

    fn frame_file_path(&self, camera: &CameraWork, frame: u32) -> Option<PathBuf> {
        Some(
            Path::new("images")
                .join(&camera.camera.name)
                .join(image_name(frame)),
        )
    }

    /// The frame's colour times its exposure as an 8-bit PNG.
    fn frame_file(&self, frame: &FinishedFrame) -> Result<Vec<u8>> {
        let contents = frame.contents;
        match (colour_pass(contents), frame.annotation.colour_exposure) {
            (Some(colour), Some(exposure)) => {
                Ok(pass_preview_exposed(contents, colour, exposure).encode_png()?)
            }
            _ => anyhow::bail!(
                "{}: no colour (`rgb` or `gray`) for the COLMAP image",
                contents.path.display()
            ),
        }
    }

    fn finish(&self, take: &FinishedTake) -> Result<()> {
        write_colmap(take.folder, take.cameras)
    }
}

/// Writes `colmap/<camera>/` for every camera of a take in `folder` whose frames are finished
/// (their images, `images/<camera>/*.png`, were written with the frames).
fn write_colmap(folder: &Path, cameras: &[CameraWork]) -> Result<()> {
    for work in cameras {
        let name = &work.camera.name;
        let model_dir = folder.join("colmap").join(name);
        let images = images_txt(work);
        let exact = colmap_camera(&work.camera.model);
        write_model(&model_dir, &cameras_txt(&exact, ""), &images)?;
        if let Camera::Fisheye624(m) = &work.camera.model {
            let (params, err) = fit_thin_prism_fisheye(m);
            let fitted = ColmapCamera {
                model: "THIN_PRISM_FISHEYE",
                params: params.to_vec(),
                ..exact
            };
            let comment = format!(
                "# Fitted to the camera's Fisheye624 model: max {:.4} px, mean {:.4} px over {} valid pixel centres\n",
                err.max_px, err.mean_px, err.samples
            );
            write_model(
                &model_dir.join("thin_prism_fisheye"),
                &cameras_txt(&fitted, &comment),
                &images,
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{KannalaBrandt4, Pinhole, Resolution};

    const RES: Resolution = Resolution {
        width_px: 64,
        height_px: 48,
    };

    #[test]
    fn pinhole_principal_point_moves_half_a_pixel() {
        let cam = Camera::Pinhole(Pinhole::new(50.0, 51.0, 31.5, 23.5, RES).unwrap());
        let c = colmap_camera(&cam);
        assert_eq!(c.model, "PINHOLE");
        assert_eq!(c.params, vec![50.0, 51.0, 32.0, 24.0]);
    }

    #[test]
    fn kannala_brandt_is_opencv_fisheye() {
        let k = [0.1, -0.02, 0.003, -0.0004];
        let cam = Camera::KannalaBrandt4(
            KannalaBrandt4::new([40.0, 41.0, 30.0, 22.0], k, RES, None).unwrap(),
        );
        let c = colmap_camera(&cam);
        assert_eq!(c.model, "OPENCV_FISHEYE");
        assert_eq!(
            c.params,
            vec![40.0, 41.0, 30.5, 22.5, k[0], k[1], k[2], k[3]]
        );
    }

    #[test]
    fn pose_is_world_to_camera() {
        let world_from_cam = Affine3::from_mat3_translation(
            glam::DMat3::from_rotation_z(0.3) * glam::DMat3::from_rotation_x(-1.2),
            Vec3::new(1.0, -2.0, 1.5),
        );
        let (q, t) = colmap_pose(world_from_cam);
        assert!(q[0] >= 0.0);
        let r = glam::DMat3::from_quat(DQuat::from_xyzw(q[1], q[2], q[3], q[0]));
        let p_world = Vec3::new(0.4, 0.7, -0.2);
        let p_cam = r * p_world + t;
        let back = world_from_cam.transform_point3(p_cam);
        assert!((back - p_world).length() < 1e-12);
    }

    #[test]
    fn thin_prism_fit_recovers_its_own_model() {
        // A Fisheye624 with only k0, k1 and p0, p1 set differs from THIN_PRISM_FISHEYE only
        // through the tangential terms acting after the radial scaling; with p = 0 the two
        // models coincide and the fit must be exact.
        let mut params = [0.0; 15];
        params[..3].copy_from_slice(&[30.0, 31.5, 23.5]);
        params[3] = 0.02;
        params[4] = -0.005;
        let cam = Fisheye624::new(&params, RES, Some(1.2), None).unwrap();
        let (fit, err) = fit_thin_prism_fisheye(&cam);
        assert!(err.samples > 1000, "{err:?}");
        assert!(err.max_px < 1e-6, "{err:?}");
        assert!(
            (fit[4] - 0.02).abs() < 1e-9 && (fit[5] + 0.005).abs() < 1e-9,
            "{fit:?}"
        );
    }

    /// The fitted model's error on the shipped Aria rig at full size (measured: SLAM left
    /// max 0.149 / mean 0.026 px, SLAM right 0.062 / 0.008 px, RGB 0.754 / 0.108 px).
    #[test]
    fn aria_cameras_fit_thin_prism_fisheye_closely() {
        let rig = crate::rig::Rig::load(Path::new("camera_rigs/aria_gen1.json")).unwrap();
        for cam in &rig.cameras {
            let Camera::Fisheye624(m) = &cam.model else {
                panic!("{} is not Fisheye624", cam.name);
            };
            let (_, err) = fit_thin_prism_fisheye(m);
            let (max, mean) = if cam.name == "camera-rgb" {
                (0.8, 0.12)
            } else {
                (0.16, 0.03)
            };
            assert!(
                err.max_px < max && err.mean_px < mean,
                "{}: {err:?}",
                cam.name
            );
        }
    }
}
