//! egogen's Fisheye624 and Aria calibration reading against projectaria-tools (PyPI), whose
//! outputs `tools/make_camera_golden.py` stored in `tests/fixtures/fisheye624_golden.json`.
//! Run with `--nocapture` to see the measured errors.

use std::path::PathBuf;

use egogen::camera::{Camera, CameraModel, Pixel};
use egogen::math::{Mat3, Vec3};
use egogen::rig::{AriaRgbResolution, Rig};
use serde_json::Value;

/// Largest pixel difference accepted against projectaria-tools.
const PIXEL_TOLERANCE_PX: f64 = 1e-6;
/// Largest angle between unprojected rays accepted.
const RAY_TOLERANCE_RAD: f64 = 1e-9;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn golden() -> Value {
    let text = std::fs::read_to_string(fixture("fisheye624_golden.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn vec3(v: &Value) -> Vec3 {
    Vec3::new(
        v[0].as_f64().unwrap(),
        v[1].as_f64().unwrap(),
        v[2].as_f64().unwrap(),
    )
}

fn pixel(v: &Value) -> Option<Pixel> {
    (!v.is_null()).then(|| Pixel::new(v[0].as_f64().unwrap(), v[1].as_f64().unwrap()))
}

fn rig(rgb_1408: bool) -> Rig {
    let rgb = if rgb_1408 {
        AriaRgbResolution::Rescaled1408
    } else {
        AriaRgbResolution::Full2880
    };
    Rig::load_with(&fixture("aria_gen1_device_calibration.json"), rgb).unwrap()
}

fn cameras() -> Vec<(String, Value, Camera, egogen::math::Affine3)> {
    let g = golden();
    let (full, small) = (rig(false), rig(true));
    g["cameras"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let label = c["label"].as_str().unwrap();
            let r = if c["rgb_1408"].as_bool().unwrap() {
                &small
            } else {
                &full
            };
            let cam = r.camera(label).unwrap();
            let tag = format!(
                "{label}{}",
                if c["rgb_1408"].as_bool().unwrap() {
                    "@1408"
                } else {
                    ""
                }
            );
            (tag, c.clone(), cam.model.clone(), cam.cpf_from_cam)
        })
        .collect()
}

#[test]
fn calibration_matches_projectaria_tools() {
    for (tag, g, cam, cpf_from_cam) in cameras() {
        let Camera::Fisheye624(f) = &cam else {
            panic!("{tag}: expected fisheye624")
        };
        let ours = f.params();
        for (k, theirs) in g["params"].as_array().unwrap().iter().enumerate() {
            let theirs = theirs.as_f64().unwrap();
            assert!(
                (ours[k] - theirs).abs() <= 1e-12 * theirs.abs().max(1.0),
                "{tag}: param {k}: ours {} vs {theirs}",
                ours[k]
            );
        }
        let res = cam.resolution();
        assert_eq!(
            [res.width_px as u64, res.height_px as u64],
            [
                g["image_size"][0].as_u64().unwrap(),
                g["image_size"][1].as_u64().unwrap()
            ],
            "{tag}"
        );
        assert_eq!(f.valid_radius_px(), g["valid_radius"].as_f64(), "{tag}");
        assert_eq!(
            cam.max_theta_rad(),
            g["max_solid_angle"].as_f64().unwrap(),
            "{tag}"
        );
        let rows = &g["cpf_from_cam_rows"];
        let r_theirs = Mat3::from_cols_array_2d(&[
            [
                rows[0][0].as_f64().unwrap(),
                rows[1][0].as_f64().unwrap(),
                rows[2][0].as_f64().unwrap(),
            ],
            [
                rows[0][1].as_f64().unwrap(),
                rows[1][1].as_f64().unwrap(),
                rows[2][1].as_f64().unwrap(),
            ],
            [
                rows[0][2].as_f64().unwrap(),
                rows[1][2].as_f64().unwrap(),
                rows[2][2].as_f64().unwrap(),
            ],
        ]);
        let t_theirs = Vec3::new(
            rows[0][3].as_f64().unwrap(),
            rows[1][3].as_f64().unwrap(),
            rows[2][3].as_f64().unwrap(),
        );
        let dr = (cpf_from_cam.matrix3 - r_theirs)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        let dt = (cpf_from_cam.translation - t_theirs).abs().max_element();
        println!("{tag}: cpf_from_cam max |ΔR| = {dr:.2e}, max |Δt| = {dt:.2e} m");
        assert!(
            dr < 1e-9 && dt < 1e-9,
            "{tag}: cpf_from_cam differs: {dr:e} {dt:e}"
        );
    }
}

#[test]
fn projection_matches_projectaria_tools() {
    let mut worst = 0.0f64;
    for (tag, g, cam, _) in cameras() {
        let near: Vec<u64> = g["near_boundary"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        let points = g["points"].as_array().unwrap();
        let pixels = g["pixels"].as_array().unwrap();
        let mut max_err = 0.0f64;
        let mut valid = 0;
        for (i, (p, px)) in points.iter().zip(pixels).enumerate() {
            let p = vec3(p);
            let theirs = pixel(px);
            let ours = cam.project(p);
            match (ours, theirs) {
                (Some(a), Some(b)) => {
                    valid += 1;
                    max_err = max_err.max((a - b).length());
                }
                (None, None) => {}
                _ if near.contains(&(i as u64)) => {}
                _ => panic!("{tag}: point {i} {p:?}: ours {ours:?}, projectaria-tools {theirs:?}"),
            }
        }
        println!(
            "{tag}: {} points, {valid} inside the valid FOV, max |Δpixel| = {max_err:.3e} px",
            points.len()
        );
        assert!(max_err <= PIXEL_TOLERANCE_PX, "{tag}: {max_err:e} px");
        worst = worst.max(max_err);
    }
    println!("projection: worst |Δpixel| over all cameras = {worst:.3e} px");
}

#[test]
fn unprojection_matches_projectaria_tools() {
    let mut worst = 0.0f64;
    for (tag, g, cam, _) in cameras() {
        let query = g["query_pixels"].as_array().unwrap();
        let rays = g["rays"].as_array().unwrap();
        let mut max_angle = 0.0f64;
        let mut valid = 0;
        for (i, (q, r)) in query.iter().zip(rays).enumerate() {
            let q = pixel(q).unwrap();
            let ours = cam.unproject(q);
            let theirs = (!r.is_null()).then(|| vec3(r));
            match (ours, theirs) {
                (Some(a), Some(b)) => {
                    valid += 1;
                    max_angle = max_angle.max(a.cross(b).length().atan2(a.dot(b)));
                }
                (None, None) => {}
                _ => panic!("{tag}: pixel {i} {q:?}: ours {ours:?}, projectaria-tools {theirs:?}"),
            }
        }
        println!(
            "{tag}: {} pixels, {valid} inside the valid FOV, max ray angle Δ = {max_angle:.3e} rad",
            query.len()
        );
        assert!(max_angle <= RAY_TOLERANCE_RAD, "{tag}: {max_angle:e} rad");
        worst = worst.max(max_angle);
    }
    println!("unprojection: worst ray angle Δ over all cameras = {worst:.3e} rad");
}

#[test]
fn shipped_aria_rig_is_the_converted_fixture() {
    let converted = rig(true);
    let mut converted = converted;
    converted.name = "aria_gen1".into();
    let shipped_path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("camera_rigs/aria_gen1.json");
    let shipped = std::fs::read_to_string(&shipped_path).unwrap();
    assert!(
        shipped == converted.to_json(),
        "camera_rigs/aria_gen1.json is not the conversion of the fixture; regenerate it with \
         `egogen rig convert tests/fixtures/aria_gen1_device_calibration.json --aria-rgb-1408 \
         --name aria_gen1 --out camera_rigs/aria_gen1.json` (after removing the old file)"
    );
}

/// KB4 against OpenCV's `cv::fisheye` (`tools/make_kb4_golden.py`,
/// `tests/fixtures/kb4_golden.json`).
#[test]
fn kannala_brandt_matches_opencv_fisheye() {
    use egogen::camera::{KannalaBrandt4, Resolution};
    let text = std::fs::read_to_string(fixture("kb4_golden.json")).unwrap();
    let g: Value = serde_json::from_str(&text).unwrap();
    for c in g["cameras"].as_array().unwrap() {
        let name = c["name"].as_str().unwrap();
        let f = |k: &str| c[k].as_f64().unwrap();
        let k: Vec<f64> = c["k"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let cam = KannalaBrandt4::new(
            [f("fx"), f("fy"), f("cx"), f("cy")],
            [k[0], k[1], k[2], k[3]],
            Resolution {
                width_px: c["size"][0].as_u64().unwrap() as u32,
                height_px: c["size"][1].as_u64().unwrap() as u32,
            },
            None,
        )
        .unwrap();
        let (mut max_px, mut n_px) = (0.0f64, 0);
        for (p, px) in c["points"]
            .as_array()
            .unwrap()
            .iter()
            .zip(c["pixels"].as_array().unwrap())
        {
            let p = vec3(p);
            let theirs = pixel(px).unwrap();
            match cam.project(p) {
                Some(ours) => {
                    max_px = max_px.max((ours - theirs).length());
                    n_px += 1;
                }
                None => assert!(
                    !cam.resolution().contains(theirs)
                        || egogen::camera::theta_of(p) > cam.max_theta_rad(),
                    "{name}: {p:?} refused but OpenCV puts it at {theirs:?}, on the sensor"
                ),
            }
        }
        let (mut max_ray, mut n_ray) = (0.0f64, 0);
        for (q, r) in c["query_pixels"]
            .as_array()
            .unwrap()
            .iter()
            .zip(c["rays"].as_array().unwrap())
        {
            let q = pixel(q).unwrap();
            let ours = cam
                .unproject(q)
                .unwrap_or_else(|| panic!("{name}: {q:?} refused"));
            let theirs = vec3(r);
            max_ray = max_ray.max(ours.cross(theirs).length().atan2(ours.dot(theirs)));
            n_ray += 1;
        }
        println!(
            "kb4 {name}: {n_px} points, max |Δpixel| = {max_px:.3e} px; {n_ray} pixels, max ray \
             angle Δ = {max_ray:.3e} rad"
        );
        assert!(max_px <= PIXEL_TOLERANCE_PX, "{name}: {max_px:e} px");
        assert!(max_ray <= RAY_TOLERANCE_RAD, "{name}: {max_ray:e} rad");
    }
}
