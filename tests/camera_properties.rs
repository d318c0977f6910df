//! Round trips of every camera model over its whole valid field of view, on the optical axis
//! (θ → 0) and at the edge: `unproject(project(p))` and `project(unproject(px))` within 1e-6 px;
//! and the renders standing in for a fisheye trace every valid pixel up to the rim.
//! The deterministic sweeps print the measured maxima with `--nocapture`.

use std::path::PathBuf;
use std::sync::OnceLock;

use egogen::camera::{
    theta_of, Camera, CameraModel, Fisheye624, KannalaBrandt4, Pinhole, Pixel, Resolution,
};
use egogen::math::Vec3;
use egogen::render::render_camera::{FisheyeRendering, RenderCamera};
use egogen::rig::{AriaRgbResolution, Rig};
use proptest::prelude::*;

const ROUND_TRIP_TOLERANCE_PX: f64 = 1e-6;

fn res(w: u32, h: u32) -> Resolution {
    Resolution {
        width_px: w,
        height_px: h,
    }
}

/// Every model under test: a pinhole, two KB4s (equidistant and a T265-like calibration)
/// and the four Fisheye624 cameras of the Aria fixture (RGB at 2880 and 1408, SLAM left and
/// right).
fn models() -> Vec<(String, Camera)> {
    let mut out = vec![
        (
            "pinhole".to_string(),
            Camera::Pinhole(Pinhole::new(500.0, 480.0, 330.2, 235.7, res(640, 480)).unwrap()),
        ),
        (
            "kb4-equidistant".to_string(),
            Camera::KannalaBrandt4(
                KannalaBrandt4::new([380.0, 380.0, 319.5, 239.5], [0.0; 4], res(640, 480), None)
                    .unwrap(),
            ),
        ),
        (
            "kb4-t265-like".to_string(),
            Camera::KannalaBrandt4(
                KannalaBrandt4::new(
                    [285.72, 286.92, 418.38, 399.27],
                    [-0.00616, 0.04307, -0.04012, 0.00686],
                    res(848, 800),
                    None,
                )
                .unwrap(),
            ),
        ),
    ];
    let fixture = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/aria_gen1_device_calibration.json");
    for (rgb, suffix) in [
        (AriaRgbResolution::Full2880, ""),
        (AriaRgbResolution::Rescaled1408, "@1408"),
    ] {
        let rig = Rig::load_with(&fixture, rgb).unwrap();
        for cam in rig.cameras {
            if suffix.is_empty() || cam.name == "camera-rgb" {
                out.push((format!("{}{suffix}", cam.name), cam.model));
            }
        }
    }
    out
}

/// A fisheye624 with stronger tangential and thin-prism terms than Aria's, to exercise the
/// 2×2 Newton stage.
fn strong_fisheye() -> Camera {
    Camera::Fisheye624(
        Fisheye624::new(
            &[
                300.0, 322.0, 238.0, 0.02, -0.01, 0.003, 0.0, 0.0, 0.0, 0.01, -0.008, 0.012,
                -0.004, -0.009, 0.003,
            ],
            res(640, 480),
            Some(1.2),
            None,
        )
        .unwrap(),
    )
}

fn angle(a: Vec3, b: Vec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// `project(p)` → `unproject` → `project` again; returns (pixel error, ray angle error), or
/// None when `p` is outside the valid field of view.
fn point_round_trip(cam: &Camera, p: Vec3) -> Option<(f64, f64)> {
    let px = cam.project(p)?;
    let ray = cam
        .unproject(px)
        .unwrap_or_else(|| panic!("{p:?} projects to {px:?} but that pixel does not unproject"));
    let back = cam
        .project(ray)
        .unwrap_or_else(|| panic!("ray {ray:?} of {px:?} does not project"));
    Some(((back - px).length(), angle(ray, p)))
}

/// `unproject(px)` → `project`; returns the pixel error, or None outside the valid FOV.
fn pixel_round_trip(cam: &Camera, px: Pixel) -> Option<f64> {
    let ray = cam.unproject(px)?;
    assert!((ray.length() - 1.0).abs() < 1e-14, "ray {ray:?} not unit");
    let back = cam
        .project(ray)
        .unwrap_or_else(|| panic!("{px:?} unprojects to {ray:?}, which does not project"));
    Some((back - px).length())
}

fn direction(theta: f64, phi: f64) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// θ in [0, max]: uniform, tiny (down to 1e-15 rad), or just inside the maximum.
fn theta_strategy() -> impl Strategy<Value = (u8, f64)> {
    (0u8..3, 0.0f64..1.0)
}

fn pick_theta(kind: u8, u: f64, max: f64) -> f64 {
    match kind {
        0 => u * max,
        1 => 10f64.powf(-3.0 - 12.0 * u),
        _ => max * (1.0 - 10f64.powf(-3.0 - 6.0 * u)),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    #[test]
    fn unproject_of_project_is_exact(
        (kind, u) in theta_strategy(),
        phi in 0.0f64..std::f64::consts::TAU,
        depth in 0.01f64..100.0,
    ) {
        for (name, cam) in models().into_iter().chain([("strong".to_string(), strong_fisheye())]) {
            let max = cam.max_theta_rad().min(std::f64::consts::FRAC_PI_2 - 1e-9);
            let theta = pick_theta(kind, u, max);
            let p = direction(theta, phi) * depth;
            if let Some((px_err, ray_err)) = point_round_trip(&cam, p) {
                prop_assert!(px_err <= ROUND_TRIP_TOLERANCE_PX, "{name}: θ {theta}: {px_err} px");
                prop_assert!(ray_err <= 1e-9, "{name}: θ {theta}: ray off by {ray_err} rad");
            }
        }
    }

    #[test]
    fn project_of_unproject_is_exact(
        fx in 0.0f64..1.0,
        fy in 0.0f64..1.0,
        near_axis in prop::option::of(0.0f64..1.0),
    ) {
        for (name, cam) in models().into_iter().chain([("strong".to_string(), strong_fisheye())]) {
            let r = cam.resolution();
            let px = match near_axis {
                // Within 1e-3 .. 1e-12 px of the principal point.
                Some(s) => {
                    let d = 10f64.powf(-3.0 - 9.0 * s);
                    cam.principal_point() + Pixel::new(d * (fx - 0.5), d * (fy - 0.5))
                }
                None => Pixel::new(
                    -0.5 + fx * r.width_px as f64,
                    -0.5 + fy * r.height_px as f64,
                ),
            };
            if let Some(err) = pixel_round_trip(&cam, px) {
                prop_assert!(err <= ROUND_TRIP_TOLERANCE_PX, "{name}: {px:?}: {err} px");
            }
        }
    }
}

/// Dense deterministic sweeps: every model, a 201×201 pixel grid over the sensor and a 400 × 72 polar grid of
/// directions up to the maximum angle; prints and checks the largest errors.
#[test]
fn sweeps_over_the_whole_valid_fov() {
    let mut worst_px = 0.0f64;
    let mut worst_ray = 0.0f64;
    for (name, cam) in models()
        .into_iter()
        .chain([("strong".to_string(), strong_fisheye())])
    {
        let r = cam.resolution();
        let (mut max_pix, mut n_pix) = (0.0f64, 0);
        for i in 0..=200 {
            for j in 0..=200 {
                // The grid spans the sensor inset by 1e-6 px: exactly on the edge, rounding
                // may put the reprojection a hair outside (see `camera` module docs).
                let px = Pixel::new(
                    -0.5 + 1e-6 + (r.width_px as f64 - 2e-6) * i as f64 / 200.0,
                    -0.5 + 1e-6 + (r.height_px as f64 - 2e-6) * j as f64 / 200.0,
                );
                if let Some(e) = pixel_round_trip(&cam, px) {
                    max_pix = max_pix.max(e);
                    n_pix += 1;
                }
            }
        }
        let max_theta = cam.max_theta_rad().min(std::f64::consts::FRAC_PI_2 - 1e-9);
        let (mut max_pt, mut max_ray, mut n_pt) = (0.0f64, 0.0f64, 0);
        for i in 0..400 {
            // 20 angles from 1e-15 to 1e-3.6 rad, then uniform up to 1e-9 short of the maximum.
            let theta = if i < 20 {
                10f64.powf(-15.0 + i as f64 * 0.6)
            } else {
                max_theta * (1.0 - 1e-9) * (i - 19) as f64 / 380.0
            };
            for k in 0..72 {
                let p = direction(theta, k as f64 * 5f64.to_radians()) * 3.0;
                if let Some((e, a)) = point_round_trip(&cam, p) {
                    max_pt = max_pt.max(e);
                    max_ray = max_ray.max(a);
                    n_pt += 1;
                }
            }
        }
        let fov = cam.fov();
        println!(
            "{name:18} pixels {n_pix:6} valid, max |Δ| {max_pix:.2e} px | points {n_pt:6} valid, \
             max |Δ| {max_pt:.2e} px, ray {max_ray:.2e} rad | fov h {:.2}° v {:.2}° d {:.2}°",
            fov.horizontal_rad.to_degrees(),
            fov.vertical_rad.to_degrees(),
            fov.diagonal_rad.to_degrees()
        );
        assert!(n_pix > 0 && n_pt > 0, "{name}: empty valid FOV");
        assert!(max_pix <= ROUND_TRIP_TOLERANCE_PX, "{name}: {max_pix} px");
        assert!(max_pt <= ROUND_TRIP_TOLERANCE_PX, "{name}: {max_pt} px");
        worst_px = worst_px.max(max_pix).max(max_pt);
        worst_ray = worst_ray.max(max_ray);
    }
    println!("worst round trip: {worst_px:.2e} px, {worst_ray:.2e} rad");
}

/// Inside the image and the valid circle, Aria's cameras see less than their maximum angle,
/// so every such pixel must unproject (no Newton failure anywhere in the mask).
#[test]
fn every_aria_pixel_in_the_mask_unprojects() {
    for (name, cam) in models() {
        let Camera::Fisheye624(f) = &cam else {
            continue;
        };
        let radius = f.valid_radius_px().unwrap();
        let (r, pp) = (cam.resolution(), cam.principal_point());
        for i in 0..=300 {
            for j in 0..=300 {
                let px = Pixel::new(
                    -0.5 + r.width_px as f64 * i as f64 / 300.0,
                    -0.5 + r.height_px as f64 * j as f64 / 300.0,
                );
                let inside = (px - pp).length() <= radius;
                assert_eq!(cam.unproject(px).is_some(), inside, "{name}: {px:?}");
            }
        }
    }
}

/// Points on the optical axis land on the principal point and come back as +z exactly.
#[test]
fn optical_axis_is_exact() {
    for (name, cam) in models()
        .into_iter()
        .chain([("strong".to_string(), strong_fisheye())])
    {
        for z in [1e-6, 1.0, 1e6] {
            let px = cam.project(Vec3::new(0.0, 0.0, z)).unwrap();
            assert!((px - cam.principal_point()).length() < 1e-12, "{name}");
        }
        assert_eq!(
            cam.unproject(cam.principal_point()),
            Some(Vec3::Z),
            "{name}"
        );
    }
}

/// Just inside the boundary of the valid field of view (found along the FOV lines), pixels
/// round-trip; just outside they are refused; points beyond the maximum angle are refused.
#[test]
fn edges_of_the_valid_fov() {
    for (name, cam) in models()
        .into_iter()
        .chain([("strong".to_string(), strong_fisheye())])
    {
        let pp = cam.principal_point();
        let r = cam.resolution();
        for k in 0..16 {
            let dir = Pixel::from_angle(k as f64 * std::f64::consts::TAU / 16.0);
            // Bisect the valid boundary along dir.
            let (mut lo, mut hi) = (0.0, (r.width_px + r.height_px) as f64);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if cam.unproject(pp + dir * mid).is_some() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let inside = pp + dir * (lo - 1e-6);
            let err = pixel_round_trip(&cam, inside)
                .unwrap_or_else(|| panic!("{name}: edge pixel {inside:?} refused"));
            assert!(
                err <= ROUND_TRIP_TOLERANCE_PX,
                "{name}: edge {inside:?}: {err} px"
            );
            assert!(cam.unproject(pp + dir * (hi + 1e-6)).is_none(), "{name}");
        }
        let beyond = cam.max_theta_rad() + 1e-6;
        if beyond < std::f64::consts::PI {
            assert!(cam.project(direction(beyond, 0.7)).is_none(), "{name}");
        }
        assert!(cam.project(Vec3::new(0.0, 0.0, -1.0)).is_none(), "{name}");
        assert!(theta_of(Vec3::new(0.0, 0.0, -1.0)) > std::f64::consts::PI - 2e-3);
    }
}

/// The last valid pixel from the principal point in direction `phi` (image axes): on the
/// image's border where that is valid, else on the valid circle (bisected to 1e-9 px).
fn valid_boundary_pixel(cam: &Camera, phi: f64) -> Pixel {
    let r = cam.resolution();
    let c = cam.principal_point();
    let d = Pixel::new(phi.cos(), phi.sin());
    let reach = |from: f64, dir: f64, size: u32| match dir {
        x if x > 0.0 => (size as f64 - 1.0 - from) / x,
        x if x < 0.0 => -from / x,
        _ => f64::INFINITY,
    };
    let far = reach(c.x, d.x, r.width_px).min(reach(c.y, d.y, r.height_px));
    if cam.unproject(c + d * far).is_some() {
        return c + d * far;
    }
    let (mut lo, mut hi) = (0.0, far);
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        match cam.unproject(c + d * mid) {
            Some(_) => lo = mid,
            None => hi = mid,
        }
    }
    c + d * lo
}

/// Each Fisheye624 camera of [`models`] at ⅛, ¼ and full size, with the two renders that stand
/// in for it: the exact mode's source (remapped) and the native polynomial lens (built once).
fn fisheye_renders() -> &'static [(String, Camera, RenderCamera, RenderCamera)] {
    static RENDERS: OnceLock<Vec<(String, Camera, RenderCamera, RenderCamera)>> = OnceLock::new();
    RENDERS.get_or_init(|| {
        let mut out = Vec::new();
        for (name, cam) in models() {
            if !matches!(cam, Camera::Fisheye624(_)) {
                continue;
            }
            for scale in [0.125, 0.25, 1.0] {
                let cam = cam.scaled(scale).unwrap();
                let exact = RenderCamera::for_camera(&cam, 1.0, FisheyeRendering::Exact).unwrap();
                let native = RenderCamera::for_camera(&cam, 1.0, FisheyeRendering::Native).unwrap();
                out.push((format!("{name} × {scale}"), cam, exact, native));
            }
        }
        out
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// What Blender traces holds every valid pixel up to the rim of the field of view: the
    /// exact mode reads the four source pixels around the pixel's ray (bilinear colour, nearest
    /// ground truth), all traced; a native lens's valid pixels are traced themselves. Pixels
    /// are drawn anywhere in the image or on the boundary of its valid region (the image's
    /// border or the valid circle), in any direction from the principal point.
    #[test]
    fn the_renders_trace_every_valid_pixel_to_the_rim(
        phi in 0.0f64..std::f64::consts::TAU,
        fx in 0.0f64..1.0,
        fy in 0.0f64..1.0,
        on_rim in any::<bool>(),
    ) {
        for (name, cam, exact, native) in fisheye_renders() {
            let r = cam.resolution();
            let (w, h) = (r.width_px as f64, r.height_px as f64);
            let px = if on_rim {
                valid_boundary_pixel(cam, phi)
            } else {
                Pixel::new(fx * (w - 1.0), fy * (h - 1.0))
            };
            let Some(ray) = cam.unproject(px) else { continue };
            let q = exact.ray_to_pixel(ray);
            prop_assert!(q.is_some(), "{name}: {px:?} has no source pixel");
            let q = q.unwrap();
            let src = exact.resolution();
            let (x0, y0) = (q.x.floor(), q.y.floor());
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let corner = Pixel::new(x0 + dx, y0 + dy);
                prop_assert!(
                    corner.x >= 0.0 && corner.y >= 0.0
                        && corner.x <= src.width_px as f64 - 1.0
                        && corner.y <= src.height_px as f64 - 1.0,
                    "{name}: {px:?} reads {corner:?}, outside the source"
                );
                prop_assert!(exact.renders(corner), "{name}: {px:?} reads untraced {corner:?}");
            }
            // The native image is the frame: its valid (whole) pixels are traced.
            let whole = Pixel::new(px.x.round(), px.y.round());
            if cam.unproject(whole).is_some() {
                prop_assert!(native.renders(whole), "{name}: native {whole:?} untraced");
            }
        }
    }
}
