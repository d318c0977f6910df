//! The COLMAP export against the real COLMAP (Debian's `colmap` 3.8, CPU SIFT): a short walk
//! through the apartment rendered by `egogen-run` with a forward pinhole camera, exported, then
//! COLMAP extracts and matches SIFT features in the exported PNGs and triangulates them with
//! the exported (fixed) poses and intrinsics (`point_triangulator`).
//!
//! Checked: COLMAP's mean reprojection error and the number of triangulated points; the poses
//! COLMAP writes back equal ours; and, against Blender's position pass (independent ground
//! truth), where each triangulated point lies relative to the surface point seen at each of its
//! keypoints, in pixels. That last figure is what catches a principal point off by half a pixel
//! (the pixel-centre convention): the same run with `c − 0.5` written instead of `c + 0.5`
//! must be measurably worse — a constant pixel offset barely changes the reprojection error
//! when the images' orientations are alike, so the reprojection error alone could not tell.
//!
//! Needs `colmap` and `sqlite3` on PATH (Debian packages `colmap`, `sqlite3`); without them the
//! test says so on stderr and passes. Run: `cargo test --test colmap_export -- --nocapture`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use egogen::inspect::ExrContents;
use egogen::math::{Affine3, Vec3};
use egogen::rig::{AriaRgbResolution, Rig, RigCamera};

/// Seed 7 starts the walk facing the living room (sofas, table, shelves, plant): the
/// apartment's materials are plain colours, so SIFT needs furniture edges and corners in view.
const CONFIG: &str = r#"
[body]
betas = []
[motion]
source = "scripted_walk"
duration_s = 1.0
frame_rate_hz = 40.0
[output]
dir = "out"
mesh_every_n_frames = 0
[scene]
seed = 7
[render]
rig = "RIG"
resolution_scale = 0.5
every_n_frames = 8
samples = 16
denoise = true
denoise_prefilter = "fast"
shutter_frames = 0.0
frames_per_shard = 10
[supervisor]
workers = 1
"#;

fn on_path(tool: &str, arg: &str) -> bool {
    Command::new(tool)
        .arg(arg)
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Runs a command; panics with its stderr on failure; returns stdout.
fn run(cmd: &mut Command) -> String {
    let out = cmd
        .env("QT_QPA_PLATFORM", "offscreen")
        .output()
        .unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{cmd:?} failed: {}",
        &stderr[stderr.len().saturating_sub(3000)..]
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn colmap(args: &[&str]) -> String {
    run(Command::new("colmap").args(args))
}

/// The one data line of a `cameras.txt`: model name and parameters.
fn camera_line(cameras_txt: &Path) -> (String, Vec<f64>) {
    let text = std::fs::read_to_string(cameras_txt).unwrap();
    let line = text.lines().find(|l| !l.starts_with('#')).unwrap();
    let fields: Vec<&str> = line.split_whitespace().collect();
    let params = fields[4..].iter().map(|v| v.parse().unwrap()).collect();
    (fields[1].to_string(), params)
}

/// A COLMAP text model as read back after triangulation.
struct Model {
    /// Image id → (name, qvec, tvec, keypoints with their point ids).
    images: HashMap<u32, (String, [f64; 4], [f64; 3], Vec<(f64, f64, i64)>)>,
    /// Point id → (xyz, error, track as (image id, keypoint index)).
    points: HashMap<i64, (Vec3, f64, Vec<(u32, usize)>)>,
}

fn read_model(dir: &Path) -> Model {
    let text = std::fs::read_to_string(dir.join("images.txt")).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let mut images = HashMap::new();
    while let Some(head) = lines.next() {
        let f: Vec<&str> = head.split_whitespace().collect();
        if f.is_empty() {
            continue;
        }
        let n = |i: usize| f[i].parse::<f64>().unwrap();
        let pts: Vec<&str> = lines.next().unwrap_or("").split_whitespace().collect();
        let keypoints = pts
            .chunks(3)
            .map(|c| {
                (
                    c[0].parse().unwrap(),
                    c[1].parse().unwrap(),
                    c[2].parse().unwrap(),
                )
            })
            .collect();
        images.insert(
            f[0].parse().unwrap(),
            (
                f[9].to_string(),
                [n(1), n(2), n(3), n(4)],
                [n(5), n(6), n(7)],
                keypoints,
            ),
        );
    }
    let text = std::fs::read_to_string(dir.join("points3D.txt")).unwrap();
    let mut points = HashMap::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let f: Vec<&str> = line.split_whitespace().collect();
        let n = |i: usize| f[i].parse::<f64>().unwrap();
        let track = f[8..]
            .chunks(2)
            .map(|c| (c[0].parse().unwrap(), c[1].parse().unwrap()))
            .collect();
        points.insert(
            f[0].parse().unwrap(),
            (Vec3::new(n(1), n(2), n(3)), n(7), track),
        );
    }
    Model { images, points }
}

/// One rendered frame's ground truth: the camera pose and the position pass.
struct Frame {
    world_from_cam: Affine3,
    exr: ExrContents,
}

impl Frame {
    /// World point of the surface at a COLMAP pixel (centre of the top-left pixel at
    /// (0.5, 0.5)), bilinear between the four nearest pixel centres; `None` where any of them
    /// shows nothing or they lie on different surfaces (more than 2 cm apart in depth).
    fn surface_at(&self, x: f64, y: f64) -> Option<Vec3> {
        let (u, v) = (x - 0.5, y - 0.5);
        let ch = |n: &str| self.exr.channel(n).unwrap();
        let w = ch("depth.Z").width;
        let h = ch("depth.Z").height;
        let (u0, v0) = (u.floor(), v.floor());
        if u0 < 0.0 || v0 < 0.0 || u0 + 1.0 >= w as f64 || v0 + 1.0 >= h as f64 {
            return None;
        }
        let (fu, fv) = (u - u0, v - v0);
        let mut p = Vec3::ZERO;
        let (mut zmin, mut zmax) = (f64::INFINITY, 0.0f64);
        for (du, dv, wt) in [
            (0, 0, (1.0 - fu) * (1.0 - fv)),
            (1, 0, fu * (1.0 - fv)),
            (0, 1, (1.0 - fu) * fv),
            (1, 1, fu * fv),
        ] {
            let i = (v0 as usize + dv) * w + u0 as usize + du;
            let z = ch("depth.Z").values[i] as f64;
            zmin = zmin.min(z);
            zmax = zmax.max(z);
            let q = Vec3::new(
                ch("position.X").values[i] as f64,
                ch("position.Y").values[i] as f64,
                ch("position.Z").values[i] as f64,
            );
            p += wt * q;
        }
        (zmin > 0.0 && zmax - zmin < 0.02).then_some(p)
    }
}

fn affine_of(rows: &serde_json::Value) -> Affine3 {
    let m = |r: usize, c: usize| rows[r][c].as_f64().unwrap();
    Affine3::from_cols_array(&[
        m(0, 0),
        m(1, 0),
        m(2, 0),
        m(0, 1),
        m(1, 1),
        m(2, 1),
        m(0, 2),
        m(1, 2),
        m(2, 2),
        m(0, 3),
        m(1, 3),
        m(2, 3),
    ])
}

/// The camera and frames of a rendered camera, from its annotations and frame files.
fn ground_truth(dataset: &Path, camera: &str) -> (RigCamera, HashMap<String, Frame>) {
    let dir = dataset.join("cameras").join(camera);
    let ann: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("annotations.json")).unwrap())
            .unwrap();
    let rig_text =
        serde_json::json!({"egogen_rig": 1, "name": "annotations", "cameras": [ann["camera"]]});
    let rig = Rig::from_json_str(
        &dir.join("annotations.json"),
        &rig_text.to_string(),
        AriaRgbResolution::default(),
    )
    .unwrap();
    let mut frames = HashMap::new();
    for f in ann["frames"].as_array().unwrap() {
        let file = f["file"].as_str().unwrap();
        frames.insert(
            file.replace(".exr", ".png"),
            Frame {
                world_from_cam: affine_of(&f["T_world_cam"]),
                exr: ExrContents::read(&dir.join(file)).unwrap(),
            },
        );
    }
    (rig.cameras[0].clone(), frames)
}

/// What one triangulation measured.
#[derive(Debug)]
struct Figures {
    points: usize,
    observations: usize,
    /// COLMAP's own mean reprojection error (its per-point errors weighted by track length).
    mean_reprojection_px: f64,
    /// Per observation: image distance between the triangulated point and the rendered
    /// surface point at the keypoint (both projected with egogen's camera), median and mean.
    gt_offset_median_px: f64,
    gt_offset_mean_px: f64,
    /// Mean of the signed offsets (x, y): a bias the pixel-centre convention would cause.
    gt_offset_bias_px: [f64; 2],
    gt_offset_samples: usize,
}

/// Triangulates the exported model of `camera` (in `model_dir`, relative to the dataset)
/// against a database of the exported images, with the principal point moved by
/// `principal_shift_px` (0 = as exported), and measures it.
fn triangulate(
    dataset: &Path,
    camera: &str,
    model_dir: &str,
    work: &Path,
    principal_shift_px: f64,
) -> Figures {
    let export = dataset.join(model_dir);
    let image_path = dataset.join("images").join(camera);
    let (model, params) = camera_line(&export.join("cameras.txt"));
    let db = work.join("database.db");
    if !db.exists() {
        std::fs::create_dir_all(work).unwrap();
        let db_s = db.to_str().unwrap();
        colmap(&["database_creator", "--database_path", db_s]);
        let params_csv: Vec<String> = params.iter().map(|p| p.to_string()).collect();
        colmap(&[
            "feature_extractor",
            "--database_path",
            db_s,
            "--image_path",
            image_path.to_str().unwrap(),
            "--ImageReader.single_camera",
            "1",
            "--ImageReader.camera_model",
            &model,
            "--ImageReader.camera_params",
            &params_csv.join(","),
            "--SiftExtraction.use_gpu",
            "0",
            "--SiftExtraction.num_threads",
            "2",
        ]);
        colmap(&[
            "exhaustive_matcher",
            "--database_path",
            db_s,
            "--SiftMatching.use_gpu",
            "0",
            "--SiftMatching.num_threads",
            "2",
        ]);
    }
    // The feature extractor numbers images as its threads finish them, so the model takes the
    // database's ids (matched by name); there is one camera, id 1.
    let listed = run(Command::new("sqlite3")
        .args(["-separator", " "])
        .arg(&db)
        .arg("SELECT name, image_id, camera_id FROM images"));
    let mut ids = HashMap::new();
    for line in listed.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(f[2], "1", "database camera id of {}", f[0]);
        ids.insert(f[0].to_string(), f[1].to_string());
    }
    let input = work.join(format!("input_shift_{principal_shift_px}"));
    let output = work.join(format!("triangulated_shift_{principal_shift_px}"));
    let text = work.join(format!("text_shift_{principal_shift_px}"));
    for d in [&input, &output, &text] {
        std::fs::create_dir_all(d).unwrap();
    }
    let images_txt = std::fs::read_to_string(export.join("images.txt")).unwrap();
    let mut renumbered = String::new();
    let mut lines = images_txt.lines();
    while let Some(line) = lines.next() {
        if line.starts_with('#') {
            renumbered += &format!("{line}\n");
            continue;
        }
        let mut f: Vec<&str> = line.split_whitespace().collect();
        let id = ids
            .get(f[9])
            .unwrap_or_else(|| panic!("{} not in the database", f[9]));
        f[0] = id;
        renumbered += &format!("{}\n{}\n", f.join(" "), lines.next().unwrap());
    }
    std::fs::write(input.join("images.txt"), renumbered).unwrap();
    std::fs::copy(export.join("points3D.txt"), input.join("points3D.txt")).unwrap();
    // Every model egogen writes is `fx fy cx cy …`.
    let mut shifted = params.clone();
    shifted[2] += principal_shift_px;
    shifted[3] += principal_shift_px;
    let cams = std::fs::read_to_string(export.join("cameras.txt")).unwrap();
    let line = cams.lines().find(|l| !l.starts_with('#')).unwrap();
    let fields: Vec<&str> = line.split_whitespace().collect();
    let new_line = format!(
        "{} {} {} {} {}",
        fields[0],
        fields[1],
        fields[2],
        fields[3],
        shifted
            .iter()
            .map(|p| p.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    std::fs::write(input.join("cameras.txt"), cams.replace(line, &new_line)).unwrap();
    colmap(&[
        "point_triangulator",
        "--database_path",
        db.to_str().unwrap(),
        "--image_path",
        image_path.to_str().unwrap(),
        "--input_path",
        input.to_str().unwrap(),
        "--output_path",
        output.to_str().unwrap(),
    ]);
    colmap(&[
        "model_converter",
        "--input_path",
        output.to_str().unwrap(),
        "--output_path",
        text.to_str().unwrap(),
        "--output_type",
        "TXT",
    ]);
    let result = read_model(&text);

    // Poses were fixed: COLMAP must hand back ours.
    let (rig_camera, frames) = ground_truth(dataset, camera);
    for (name, q, t, _) in result.images.values() {
        let frame = &frames[name];
        let (q0, t0) = egogen::export::colmap::colmap_pose(frame.world_from_cam);
        for k in 0..4 {
            assert!((q[k] - q0[k]).abs() < 1e-9, "{name}: qvec {q:?} vs {q0:?}");
        }
        assert!(
            (Vec3::from_array(*t) - t0).length() < 1e-9,
            "{name}: tvec {t:?} vs {t0}"
        );
    }

    let mut observations = 0;
    let mut weighted = 0.0;
    let mut offsets = Vec::new();
    let mut bias = glam::DVec2::ZERO;
    for (x, error, track) in result.points.values() {
        observations += track.len();
        weighted += error * track.len() as f64;
        for &(image_id, idx) in track {
            let (name, _, _, keypoints) = &result.images[&image_id];
            let (kx, ky, _) = keypoints[idx];
            let frame = &frames[name];
            let Some(surface) = frame.surface_at(kx, ky) else {
                continue;
            };
            let cam_from_world = frame.world_from_cam.inverse();
            let project = |p: Vec3| {
                rig_camera
                    .model
                    .project_unbounded(cam_from_world.transform_point3(p))
            };
            if let (Some(a), Some(b)) = (project(*x), project(surface)) {
                offsets.push(a.distance(b));
                bias += a - b;
            }
        }
    }
    offsets.sort_by(f64::total_cmp);
    Figures {
        points: result.points.len(),
        observations,
        mean_reprojection_px: weighted / observations.max(1) as f64,
        gt_offset_median_px: offsets.get(offsets.len() / 2).copied().unwrap_or(f64::NAN),
        gt_offset_mean_px: offsets.iter().sum::<f64>() / offsets.len().max(1) as f64,
        gt_offset_bias_px: (bias / offsets.len().max(1) as f64).to_array(),
        gt_offset_samples: offsets.len(),
    }
}

fn render(dir: &Path, rig: &Path) -> PathBuf {
    let config = dir.join("run.toml");
    std::fs::write(&config, CONFIG.replace("RIG", rig.to_str().unwrap())).unwrap();
    run(Command::new(env!("CARGO_BIN_EXE_egogen-run")).arg(&config));
    dir.join("out")
}

fn tools_missing() -> bool {
    let missing: Vec<&str> = [("colmap", "help"), ("sqlite3", "-version")]
        .into_iter()
        .filter(|(t, a)| !on_path(t, a))
        .map(|(t, _)| t)
        .collect();
    if !missing.is_empty() {
        assert!(
            std::env::var("EGOGEN_REQUIRE_SYSTEM_TOOLS").as_deref() != Ok("1"),
            "EGOGEN_REQUIRE_SYSTEM_TOOLS=1 but {} not on PATH (apt-get install colmap sqlite3)",
            missing.join(" and ")
        );
        eprintln!(
            "SKIPPED colmap_export: {} not on PATH (Debian: apt-get install colmap sqlite3)",
            missing.join(" and ")
        );
    }
    !missing.is_empty()
}

#[test]
fn pinhole_export_triangulates_in_colmap() {
    if tools_missing() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dataset = render(dir.path(), &root.join("camera_rigs/pinhole.json"));
    let manifest = std::fs::read_to_string(dataset.join("manifest.json")).unwrap();
    for f in [
        "colmap/forward/cameras.txt",
        "colmap/forward/images.txt",
        "colmap/forward/points3D.txt",
        "images/forward/frame_00000.png",
        "images/forward/frame_00032.png",
    ] {
        assert!(manifest.contains(f), "{f} not in the manifest");
    }
    let work = dir.path().join("colmap_work");
    let exported = triangulate(&dataset, "forward", "colmap/forward", &work, 0.0);
    let half_pixel_bug = triangulate(&dataset, "forward", "colmap/forward", &work, -0.5);
    eprintln!("pinhole 320x240, 5 frames, as exported: {exported:?}");
    eprintln!("pinhole, principal point written in egogen's convention (c, not c + 0.5): {half_pixel_bug:?}");
    assert!(
        exported.points >= 40 && exported.observations >= 150,
        "{exported:?}"
    );
    assert!(exported.mean_reprojection_px <= 1.0, "{exported:?}");
    assert!(exported.gt_offset_samples >= 50, "{exported:?}");
    assert!(
        exported.gt_offset_median_px <= 0.5 && exported.gt_offset_mean_px <= 0.6,
        "{exported:?}"
    );
    for axis in 0..2 {
        assert!(
            exported.gt_offset_bias_px[axis].abs() <= 0.1,
            "{exported:?}"
        );
        assert!(
            half_pixel_bug.gt_offset_bias_px[axis].abs() >= 0.4,
            "a half-pixel principal point error must show: {half_pixel_bug:?}"
        );
    }
}
