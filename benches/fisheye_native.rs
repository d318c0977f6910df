//! The native polynomial fisheye against the exact remap, in one run, for the Aria cameras:
//! 1. the fit's pixel error against the exact Fisheye624 over the valid field of view
//!    (analytic: 1024 × 1024 rays), at full resolution and at the rendered resolutions, with
//!    the part left when the camera's tangential/thin-prism terms are zeroed (radial fit only);
//! 2. time per frame of both modes, rendered alternately by `egogen-run` (16 samples, shutter
//!    ½ frame): Blender attempt seconds for 1 and for 6 frames, and the marginal frame
//!    `(t₆ − t₁) / 5` (start-up, scene import and Rust's frame assembly are in the attempt);
//! 3. the error confirmed on the native render: every surface pixel's position-pass point
//!    projected with the exact model, against the pixel itself and against the analytic offset.
//!
//! `cargo bench --bench fisheye_native`

use egogen::camera::{Camera, CameraModel, Fisheye624, Pixel};
use egogen::inspect::ExrContents;
use egogen::math::{Affine3, Real, Vec3};
use egogen::render::lens_polynomial::{native_error, pixel_error_stats, LensPolynomial};
use egogen::rig::Rig;

mod common;
use common::{egogen_run, walk_config};

/// Cameras and the resolution scale they are rendered at.
const RENDERED: [(&str, Real); 2] = [("camera-rgb", 0.25), ("camera-slam-left", 0.5)];
const FRAMES: usize = 6;
const REPEATS: usize = 2;
const GRID: usize = 1024;

fn config(camera: &str, scale: Real, frames: usize, fisheye: &str) -> String {
    walk_config(
        frames,
        &format!(
            r#"cameras = ["{camera}"]
resolution_scale = {scale}
samples = 16
fisheye = "{fisheye}""#
        ),
    )
}

fn aria(name: &str, scale: Real) -> Fisheye624 {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let rig = Rig::load(&root.join("camera_rigs/aria_gen1.json")).unwrap();
    match rig.camera(name).unwrap().model.scaled(scale).unwrap() {
        Camera::Fisheye624(m) => m,
        _ => panic!("{name} is Fisheye624"),
    }
}

fn analytic_table() {
    println!(
        "| camera | image | max px | mean px | 95% px | radial fit only: max / mean px | rays |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (name, scale) in [
        ("camera-rgb", 1.0),
        ("camera-slam-left", 1.0),
        ("camera-slam-right", 1.0),
        (RENDERED[0].0, RENDERED[0].1),
        (RENDERED[1].0, RENDERED[1].1),
    ] {
        let m = aria(name, scale);
        let e = native_error(
            &Camera::Fisheye624(m),
            &LensPolynomial::for_fisheye624(&m).unwrap(),
            GRID,
        );
        let mut p = m.params();
        p[9..].iter_mut().for_each(|v| *v = 0.0);
        let radial = Fisheye624::new(
            &p,
            m.resolution(),
            Some(m.max_theta_rad()),
            m.valid_radius_px(),
        )
        .unwrap();
        let r = native_error(
            &Camera::Fisheye624(radial),
            &LensPolynomial::for_fisheye624(&radial).unwrap(),
            GRID,
        );
        let res = m.resolution();
        println!(
            "| {name} | {}×{} | {:.3} | {:.3} | {:.3} | {:.3} / {:.3} | {} |",
            res.width_px, res.height_px, e.max_px, e.mean_px, e.p95_px, r.max_px, r.mean_px, e.rays
        );
    }
}

/// Error of the native frames of a run: exact projection of each surface point vs its pixel,
/// and vs the analytic offset at that pixel.
fn confirm(run: &common::Run, name: &str, model: &Fisheye624) {
    let cam = Camera::Fisheye624(*model);
    let lens = LensPolynomial::for_fisheye624(model).unwrap();
    let dir = run.out().join("cameras").join(name);
    let ann: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("annotations.json")).unwrap())
            .unwrap();
    let res = model.resolution();
    let (mut errors, mut vs_analytic) = (Vec::new(), 0.0f64);
    for frame in ann["frames"].as_array().unwrap() {
        let m: Vec<Vec<f64>> = serde_json::from_value(frame["T_world_cam"].clone()).unwrap();
        let world_from_cam = Affine3::from_mat4(
            glam::DMat4::from_cols_array_2d(&[
                [m[0][0], m[0][1], m[0][2], m[0][3]],
                [m[1][0], m[1][1], m[1][2], m[1][3]],
                [m[2][0], m[2][1], m[2][2], m[2][3]],
                [m[3][0], m[3][1], m[3][2], m[3][3]],
            ])
            .transpose(),
        );
        let cam_from_world = world_from_cam.inverse();
        let exr = ExrContents::read(&dir.join(frame["file"].as_str().unwrap())).unwrap();
        let ch = |n: &str| exr.channel(n).unwrap().values.clone();
        let (depth, px_, py_, pz_) = (
            ch("depth.Z"),
            ch("position.X"),
            ch("position.Y"),
            ch("position.Z"),
        );
        for y in 0..res.height_px as usize {
            for x in 0..res.width_px as usize {
                let i = y * res.width_px as usize + x;
                if depth[i] <= 0.0 {
                    continue;
                }
                let px = Pixel::new(x as Real, y as Real);
                let p = Vec3::new(px_[i] as Real, py_[i] as Real, pz_[i] as Real);
                let off = cam
                    .project_unbounded(cam_from_world.transform_point3(p))
                    .unwrap()
                    - px;
                let predicted = cam
                    .project_unbounded(lens.pixel_to_ray(px).unwrap())
                    .unwrap()
                    - px;
                vs_analytic = vs_analytic.max((off - predicted).length());
                errors.push(off.length());
            }
        }
    }
    let e = pixel_error_stats(errors);
    println!(
        "| {name} | {}×{} | {} | {:.3} | {:.3} | {:.3} | {vs_analytic:.4} |",
        res.width_px, res.height_px, e.rays, e.max_px, e.mean_px, e.p95_px
    );
}

fn main() {
    println!("## Fit error against the exact model (analytic, {GRID}×{GRID} rays)\n");
    analytic_table();
    println!("\n## Time per frame ({FRAMES} frames vs 1, Blender attempt seconds)\n");
    println!(
        "| camera | image | mode | rendered image | 1 frame s | {FRAMES} frames s | per frame s |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut native_runs = Vec::new();
    for (name, scale) in RENDERED {
        let model = aria(name, scale);
        let res = model.resolution();
        let exact_render =
            egogen::render::render_camera::RenderCamera::exact(&Camera::Fisheye624(model), 1.0)
                .resolution();
        let mut per_frame = [Vec::new(), Vec::new()];
        for repeat in 0..REPEATS {
            for (k, mode) in ["exact", "native"].into_iter().enumerate() {
                let one = egogen_run(&config(name, scale, 1, mode)).attempt_seconds[0];
                let run = egogen_run(&config(name, scale, FRAMES, mode));
                let many = run.attempt_seconds[0];
                let marginal = (many - one) / (FRAMES - 1) as Real;
                per_frame[k].push(marginal);
                let rendered = if k == 0 { exact_render } else { res };
                println!(
                    "| {name} | {}×{} | {mode} | {}×{} | {one:.2} | {many:.2} | {marginal:.2} |",
                    res.width_px, res.height_px, rendered.width_px, rendered.height_px
                );
                if k == 1 && repeat + 1 == REPEATS {
                    native_runs.push((run, name, model));
                }
            }
        }
        let mean = |v: &[Real]| v.iter().sum::<Real>() / v.len() as Real;
        println!(
            "| {name} | | exact / native per frame | | | | {:.2}× |",
            mean(&per_frame[0]) / mean(&per_frame[1])
        );
    }
    println!("\n## Error on the native renders ({FRAMES} frames each, every surface pixel)\n");
    println!(
        "| camera | image | pixels | max px | mean px | 95% px | max |measured − analytic| px |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (run, name, model) in &native_runs {
        confirm(run, name, model);
    }
}
