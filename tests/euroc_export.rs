//! `egogen euroc export` of takes rendered by Blender at 1/16 of the Aria size: a take of two
//! wearers (each wearing the Aria SLAM cameras, the headset moved on each head by
//! `[render.headset_wear]`) and a one-camera take. Checked against the take itself: every
//! file and row, timestamps, the ground truth equal to the device's IMU pose composed from the
//! annotations' `T_world_cam` and the rig's extrinsics (and from the head poses), the images
//! pixel for pixel, the written KB4 against the rendered Fisheye624 over its valid field of
//! view; then read by real clients (`evo`'s EuRoC reader, PyYAML: `euroc_clients_read_the_export`,
//! which installs them from PyPI into the egogen cache on first use and says SKIPPED offline);
//! and bad requests refused, nothing written.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use egogen::camera::kannala_brandt::KannalaBrandt4;
use egogen::camera::{valid_pixel_rays, CameraModel};
use egogen::export::euroc::{CAMERA_HEADER, GROUND_TRUTH_HEADER, IMU_HEADER};
use egogen::export::imu::ImuErrors;
use egogen::math::{Affine3, Mat3, Vec3};
use egogen::rig::Rig;

/// The two rendered takes, made once for every test of this file.
struct Takes {
    _dir: tempfile::TempDir,
    /// Wearers `wearer` and `other`, cameras `<wearer>_camera-slam-{left,right}`.
    two_wearers: PathBuf,
    /// One agent, the rig `one_camera_rig` (Aria's SLAM-left camera and IMUs only).
    one_camera: PathBuf,
    one_camera_rig: PathBuf,
}

const TWO_WEARERS: &str = r#"
[body]
[motion]
source = "agents"
duration_s = 1.0
seed = 1
[[agents]]
name = "wearer"
start = [-1.0, 0.0]
goals = [[1.2, 0.0]]
[[agents]]
name = "other"
start = [1.2, 0.3]
goals = [[-1.0, 0.3]]
steering = "sampling"
k = 8
[output]
dir = "two"
mesh_every_n_frames = 0
[scene]
path = "SCENE"
[render]
cameras = ["camera-slam-left", "camera-slam-right"]
resolution_scale = 0.0625
every_n_frames = 10
samples = 2
frames_per_shard = 10
wearers = ["wearer", "other"]
[render.headset_wear]
translation_m = 0.01
rotation_deg = 3.0
seed = 5
[supervisor]
workers = 1
"#;

const ONE_CAMERA: &str = r#"
[body]
[motion]
source = "scripted_walk"
duration_s = 0.5
frame_rate_hz = 40.0
[output]
dir = "one"
mesh_every_n_frames = 0
[scene]
seed = 7
[render]
rig = "RIG"
resolution_scale = 0.0625
every_n_frames = 10
samples = 2
frames_per_shard = 10
[supervisor]
workers = 1
"#;

fn takes() -> &'static Takes {
    static TAKES: OnceLock<Takes> = OnceLock::new();
    TAKES.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let root = common::repo_root();
        let aria = Rig::load(&root.join("camera_rigs/aria_gen1.json")).unwrap();
        let one_rig = Rig {
            name: "aria_slam_left_only".into(),
            cameras: vec![aria.camera("camera-slam-left").unwrap().clone()],
            ..aria
        };
        let one_camera_rig = dir.path().join("one_camera_rig.json");
        std::fs::write(&one_camera_rig, one_rig.to_json()).unwrap();
        let configs = [
            (
                "two.toml",
                TWO_WEARERS.replace(
                    "SCENE",
                    root.join("assets/scenes/apartment.glb").to_str().unwrap(),
                ),
            ),
            (
                "one.toml",
                ONE_CAMERA.replace("RIG", one_camera_rig.to_str().unwrap()),
            ),
        ];
        for (name, text) in configs {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            common::egogen_run_ok(&path);
        }
        Takes {
            two_wearers: dir.path().join("two"),
            one_camera: dir.path().join("one"),
            one_camera_rig,
            _dir: dir,
        }
    })
}

fn euroc(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["euroc", "export"])
        .args(args)
        .output()
        .unwrap()
}

/// Runs `egogen euroc export`, failing the test unless it succeeds; its standard error.
fn euroc_ok(take: &Path, out: &Path, more: &[&str]) -> String {
    let mut args = vec![take.as_os_str(), "--out".as_ref(), out.as_os_str()];
    args.extend(more.iter().map(|s| std::ffi::OsStr::new(*s)));
    let o = euroc(&args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "egogen euroc export failed:\n{err}");
    err
}

/// A CSV's data rows as numbers (the header checked against `header`).
fn csv_rows(path: &Path, header: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header), "{}", path.display());
    lines
        .map(|l| {
            l.split(',')
                .map(|v| {
                    v.trim()
                        .trim_end_matches(".png")
                        .parse::<f64>()
                        .unwrap_or_else(|_| panic!("{}: `{l}`", path.display()))
                })
                .collect()
        })
        .collect()
}

/// The numbers of the YAML list after `key:` (across lines, to its `]`).
fn yaml_list(text: &str, key: &str) -> Vec<f64> {
    let start = text
        .find(&format!("{key}: ["))
        .unwrap_or_else(|| panic!("no `{key}` in\n{text}"));
    let rest = &text[start + key.len() + 3..];
    let list = &rest[..rest.find(']').unwrap()];
    list.split(',').map(|v| v.trim().parse().unwrap()).collect()
}

fn yaml_number(text: &str, key: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("{key}:")))
        .unwrap_or_else(|| panic!("no `{key}` in\n{text}"));
    line[key.len() + 1..]
        .split('#')
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

fn affine_from_rows(m: &[f64]) -> Affine3 {
    Affine3 {
        matrix3: Mat3::from_cols(
            Vec3::new(m[0], m[4], m[8]),
            Vec3::new(m[1], m[5], m[9]),
            Vec3::new(m[2], m[6], m[10]),
        ),
        translation: Vec3::new(m[3], m[7], m[11]),
    }
}

fn json_affine(v: &serde_json::Value) -> Affine3 {
    let flat: Vec<f64> = v
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
        .collect();
    affine_from_rows(&flat)
}

/// The larger of the translation (m) and rotation (rad) between two poses.
fn pose_gap(a: Affine3, b: Affine3) -> f64 {
    let d = a.inverse() * b;
    egogen::math::matrix_to_axis_angle(d.matrix3)
        .length()
        .max(d.translation.length())
}

/// A ground-truth row's pose (`p`, `q` w first).
fn row_pose(r: &[f64]) -> Affine3 {
    let q = glam::DQuat::from_xyzw(r[5], r[6], r[7], r[4]);
    assert!((q.length() - 1.0).abs() < 1e-12, "{r:?}");
    Affine3 {
        matrix3: Mat3::from_quat(q),
        translation: Vec3::new(r[1], r[2], r[3]),
    }
}

/// A PNG's size, channels and pixel bytes.
fn png_pixels(path: &Path) -> (u32, u32, usize, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buf.truncate(info.buffer_size());
    (info.width, info.height, info.color_type.samples(), buf)
}

#[test]
fn a_wearer_of_a_rendered_take_is_exported_and_equals_the_take() {
    let takes = takes();
    let take = &takes.two_wearers;
    let rig = Rig::load(&common::repo_root().join("camera_rigs/aria_gen1.json")).unwrap();
    let imu = rig.imus.iter().find(|i| i.name == "imu-right").unwrap();
    let dir = tempfile::tempdir().unwrap();
    for wearer in ["wearer", "other"] {
        // An empty folder is taken as `--out`.
        let out = dir.path().join(wearer);
        std::fs::create_dir(&out).unwrap();
        let err = euroc_ok(take, &out, &["--wearer", wearer]);
        eprintln!("{err}");
        assert!(!PathBuf::from(format!("{}.partial", out.display())).exists());
        let mav0 = out.join("mav0");
        for f in [
            "body.yaml",
            "cam0/data.csv",
            "cam0/sensor.yaml",
            "cam1/data.csv",
            "cam1/sensor.yaml",
            "imu0/data.csv",
            "imu0/sensor.yaml",
            "state_groundtruth_estimate0/data.csv",
            "state_groundtruth_estimate0/sensor.yaml",
        ] {
            assert!(mav0.join(f).is_file(), "{f} missing");
        }

        // The head poses and the headset's offset on this head.
        let heads: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(
                take.join(format!("sequence/agents/{wearer}/cpf_trajectory.json")),
            )
            .unwrap(),
        )
        .unwrap();
        let heads = heads.as_array().unwrap();
        let frame_rate_hz = 1.0 / heads[1]["time_s"].as_f64().unwrap();
        let duration_s = heads.last().unwrap()["time_s"].as_f64().unwrap();

        // imu0: every 1 ms over the take.
        let imu_rows = csv_rows(&mav0.join("imu0/data.csv"), IMU_HEADER);
        assert_eq!(
            imu_rows.len(),
            (duration_s * 1000.0 + 1e-6).floor() as usize + 1
        );
        for (k, r) in imu_rows.iter().enumerate() {
            assert_eq!(r.len(), 7);
            assert_eq!(r[0], k as f64 * 1e6, "imu0 row {k}");
        }
        // Walking heads: specific force about 1 g.
        let mut norms: Vec<f64> = imu_rows
            .iter()
            .map(|r| Vec3::new(r[4], r[5], r[6]).length())
            .collect();
        norms.sort_by(f64::total_cmp);
        assert!((9.0..11.0).contains(&norms[norms.len() / 2]), "{norms:?}");

        // The ground truth: a row per IMU sample, at the same times.
        let gt = csv_rows(
            &mav0.join("state_groundtruth_estimate0/data.csv"),
            GROUND_TRUTH_HEADER,
        );
        assert_eq!(gt.len(), imu_rows.len());
        for (g, i) in gt.iter().zip(&imu_rows) {
            assert_eq!(g.len(), 17);
            assert_eq!(g[0], i[0]);
        }

        // The ground truth is the device's IMU pose at every head pose: world_from_cpf ·
        // cpf_from_headset · cpf_from_imu.
        let cam0_annotations: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(take.join(format!(
                "cameras/{wearer}_camera-slam-left/annotations.json"
            )))
            .unwrap(),
        )
        .unwrap();
        let cpf_from_headset = json_affine(&cam0_annotations["headset_wear"]["t_cpf_headset"]);
        assert!(
            pose_gap(cpf_from_headset, Affine3::IDENTITY) > 1e-3,
            "the take moves the headset on the head"
        );
        let (mut worst_head, mut heads_checked): (f64, usize) = (0.0, 0);
        for h in heads {
            let ns = (h["time_s"].as_f64().unwrap() * 1e9).round();
            if ns % 1e6 != 0.0 {
                continue;
            }
            let device = json_affine(&h["world_from_cpf"]) * cpf_from_headset * imu.cpf_from_imu;
            worst_head = worst_head.max(pose_gap(row_pose(row_at(&gt, ns)), device));
            heads_checked += 1;
        }
        assert!(
            heads_checked == heads.len(),
            "{heads_checked} of {}",
            heads.len()
        );
        assert!(worst_head < 1e-9, "{wearer}: {worst_head}");

        // Velocities agree with the positions (central differences 1 ms apart).
        let mut v_err: Vec<f64> = (1..gt.len() - 1)
            .map(|k| {
                let d = |i: usize| Vec3::new(gt[i][1], gt[i][2], gt[i][3]);
                let v = Vec3::new(gt[k][8], gt[k][9], gt[k][10]);
                ((d(k + 1) - d(k - 1)) / 2e-3 - v).length()
            })
            .collect();
        v_err.sort_by(f64::total_cmp);
        assert!(
            v_err[v_err.len() / 2] < 1e-4,
            "{:?}",
            &v_err[v_err.len() / 2]
        );
        // Biases: the model's state, which walks away from its start of 0.
        assert_eq!(&gt[0][11..17], &[0.0; 6]);
        assert!(gt.last().unwrap()[11..17].iter().any(|b| *b != 0.0));

        // imu0's noise figures are the Aria gen1 model's of imu-right.
        let imu_yaml = std::fs::read_to_string(mav0.join("imu0/sensor.yaml")).unwrap();
        let e = ImuErrors::aria_gen1("imu-right");
        for (key, want) in [
            ("gyroscope_noise_density", e.gyroscope.noise_density),
            ("gyroscope_random_walk", e.gyroscope.bias_random_walk),
            ("accelerometer_noise_density", e.accelerometer.noise_density),
            (
                "accelerometer_random_walk",
                e.accelerometer.bias_random_walk,
            ),
            ("rate_hz", 1000.0),
        ] {
            assert_eq!(yaml_number(&imu_yaml, key), want, "{key}");
        }
        assert_eq!(
            affine_from_rows(&yaml_list(&imu_yaml, "data")),
            Affine3::IDENTITY
        );

        for (k, side) in ["left", "right"].iter().enumerate() {
            let name = format!("{wearer}_camera-slam-{side}");
            assert!(err.contains(&format!("cam{k} = {name}")), "{err}");
            let ann: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(take.join(format!("cameras/{name}/annotations.json")))
                    .unwrap(),
            )
            .unwrap();
            let frames = ann["frames"].as_array().unwrap();
            let cam_dir = mav0.join(format!("cam{k}"));
            let rows = csv_rows(&cam_dir.join("data.csv"), CAMERA_HEADER);
            assert_eq!(rows.len(), frames.len());
            let yaml = std::fs::read_to_string(cam_dir.join("sensor.yaml")).unwrap();
            let imu_from_cam = affine_from_rows(&yaml_list(&yaml, "data"));
            let rig_cam = rig.camera(&format!("camera-slam-{side}")).unwrap();
            assert!(
                pose_gap(
                    imu_from_cam,
                    imu.cpf_from_imu.inverse() * rig_cam.cpf_from_cam
                ) < 1e-12
            );
            let mut worst_frame: f64 = 0.0;
            let mut last_ns = -1.0;
            for (row, f) in rows.iter().zip(frames) {
                let frame = f["frame"].as_u64().unwrap();
                let ns = (frame as f64 * 1e9 / frame_rate_hz).round();
                assert_eq!(row, &vec![ns, ns], "cam{k} frame {frame}");
                assert!(ns > last_ns);
                last_ns = ns;
                // The ground truth at the frame is T_world_cam · cam_from_cpf · cpf_from_imu,
                // and the written T_BS takes it back to T_world_cam.
                let world_from_cam = json_affine(&f["T_world_cam"]);
                let device = world_from_cam * rig_cam.cpf_from_cam.inverse() * imu.cpf_from_imu;
                let pose = row_pose(row_at(&gt, ns));
                worst_frame = worst_frame
                    .max(pose_gap(pose, device))
                    .max(pose_gap(pose * imu_from_cam, world_from_cam));
                // The same pixels as the take's image, as one grey channel.
                let (w, h, channels, take_px) =
                    png_pixels(&take.join(format!("images/{name}/frame_{frame:05}.png")));
                let (ew, eh, ec, euroc_px) =
                    png_pixels(&cam_dir.join(format!("data/{}.png", ns as i64)));
                assert_eq!((ew, eh, ec), (w, h, 1));
                let grey: Vec<u8> = take_px
                    .chunks_exact(channels)
                    .map(|p| {
                        assert!(p.iter().all(|c| *c == p[0]), "a monochrome camera is grey");
                        p[0]
                    })
                    .collect();
                assert_eq!(euroc_px, grey, "cam{k} frame {frame}");
            }
            assert!(worst_frame < 1e-9, "cam{k}: {worst_frame}");
            assert_eq!(yaml_number(&yaml, "rate_hz"), frame_rate_hz / 10.0);

            // The written KB4 against the rendered Fisheye624, every valid pixel centre.
            let rendered = rig_cam.model.scaled(0.0625).unwrap();
            let res = CameraModel::resolution(&rendered);
            assert_eq!(
                yaml_list(&yaml, "resolution"),
                vec![res.width_px as f64, res.height_px as f64]
            );
            assert!(yaml.contains("camera_model: pinhole"));
            assert!(yaml.contains("distortion_model: equidistant"));
            let i = yaml_list(&yaml, "intrinsics");
            let d = yaml_list(&yaml, "distortion_coefficients");
            let kb4 = KannalaBrandt4::new(
                [i[0], i[1], i[2], i[3]],
                [d[0], d[1], d[2], d[3]],
                res,
                None,
            )
            .unwrap();
            let samples = valid_pixel_rays(&rendered);
            let errors: Vec<f64> = samples
                .iter()
                .map(|(px, ray)| kb4.project(*ray).unwrap().distance(*px))
                .collect();
            let max = errors.iter().copied().fold(0.0, f64::max);
            let mean = errors.iter().sum::<f64>() / errors.len() as f64;
            eprintln!(
                "{name}: KB4 off the Fisheye624 by max {max:.4} px, mean {mean:.4} px over {} pixel centres",
                samples.len()
            );
            // Measured: left max 0.096 / mean 0.033 px, right 0.048 / 0.014 px (full size:
            // 1.65 / 0.53 and 0.78 / 0.23, `camera::kannala_brandt`'s test).
            assert!(max < 0.12 && mean < 0.04, "{name}: {max} {mean}");
            assert!(
                yaml.contains(&format!("off by max {max:.4} px, mean {mean:.4} px")),
                "{yaml}"
            );
        }
    }
    // Each wearer's own device.
    let gt_of = |w: &str| {
        std::fs::read_to_string(
            dir.path()
                .join(w)
                .join("mav0/state_groundtruth_estimate0/data.csv"),
        )
        .unwrap()
    };
    assert_ne!(gt_of("wearer"), gt_of("other"));
}

/// The ground-truth row at `ns` (rows every 1 ms from 0).
fn row_at(gt: &[Vec<f64>], ns: f64) -> &[f64] {
    let row = &gt[(ns / 1e6).round() as usize];
    assert_eq!(row[0], ns);
    row
}

#[test]
fn ideal_imu_has_zero_biases_and_the_seed_draws_the_noise() {
    let takes = takes();
    let dir = tempfile::tempdir().unwrap();
    let read = |name: &str, more: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["--wearer", "wearer"];
        args.extend(more);
        euroc_ok(&takes.two_wearers, &out, &args);
        (
            std::fs::read_to_string(out.join("mav0/imu0/data.csv")).unwrap(),
            csv_rows(
                &out.join("mav0/state_groundtruth_estimate0/data.csv"),
                GROUND_TRUTH_HEADER,
            ),
        )
    };
    let (ideal, ideal_gt) = read("ideal", &["--ideal-imu"]);
    assert!(ideal_gt.iter().all(|r| r[11..17] == [0.0; 6]));
    let (seed0, gt0) = read("seed0", &[]);
    let (seed0_again, _) = read("seed0_again", &["--seed", "0"]);
    let (seed1, _) = read("seed1", &["--seed", "1"]);
    assert_eq!(seed0, seed0_again);
    assert_ne!(seed0, seed1);
    assert_ne!(seed0, ideal);
    // The poses do not depend on the IMU's errors.
    for (a, b) in ideal_gt.iter().zip(&gt0) {
        assert_eq!(a[..11], b[..11]);
    }
}

#[test]
fn a_one_camera_rig_exports_cam0_only_and_says_so() {
    let takes = takes();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let err = euroc_ok(
        &takes.one_camera,
        &out,
        &["--rig", takes.one_camera_rig.to_str().unwrap()],
    );
    assert!(err.contains("cam0 only"), "{err}");
    assert!(out.join("mav0/cam0/data.csv").is_file());
    assert!(!out.join("mav0/cam1").exists());
    let rows = csv_rows(&out.join("mav0/cam0/data.csv"), CAMERA_HEADER);
    assert_eq!(rows.len(), 2); // frames 0 and 10 of a 0.5 s take
}

/// Runs a request that must fail: its standard error, checked to name each of `needles`; the
/// `--out` folder and its `.partial` are left as they were.
fn refused(take: &Path, out: &Path, more: &[&str], needles: &[&str]) {
    let before = out
        .exists()
        .then(|| std::fs::read_dir(out).unwrap().count());
    let mut args = vec![take.as_os_str(), "--out".as_ref(), out.as_os_str()];
    args.extend(more.iter().map(|s| std::ffi::OsStr::new(*s)));
    let o = euroc(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "accepted: {args:?}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
    let after = out
        .exists()
        .then(|| std::fs::read_dir(out).unwrap().count());
    assert_eq!(before, after, "{}", out.display());
    assert!(!PathBuf::from(format!("{}.partial", out.display())).exists());
}

#[test]
fn bad_requests_are_refused_and_nothing_is_written() {
    let takes = takes();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let two = &takes.two_wearers;
    refused(
        &dir.path().join("nowhere"),
        &out,
        &[],
        &["nowhere", "not a folder"],
    );
    // Not a dataset: the take's motion alone.
    refused(
        &two.join("sequence"),
        &out,
        &[],
        &["no rendered cameras", "annotations.json"],
    );
    refused(two, &out, &[], &["2 wearers", "other, wearer", "--wearer"]);
    refused(
        two,
        &out,
        &["--wearer", "nobody"],
        &["--wearer nobody", "other, wearer"],
    );
    // A take without the second SLAM camera, exported as an Aria take.
    refused(
        &takes.one_camera,
        &out,
        &[],
        &["camera-slam-right", "cam1", "[render] cameras", "--rig"],
    );
    // The right camera rendered, but its images gone.
    let partial_copy = dir.path().join("copy");
    common::copy_tree(two, &partial_copy);
    std::fs::remove_file(partial_copy.join("images/wearer_camera-slam-right/frame_00010.png"))
        .unwrap();
    refused(
        &partial_copy,
        &out,
        &["--wearer", "wearer"],
        &["frame_00010.png", "is missing", "colmap"],
    );
    // An image of another size than its camera's calibration (which sensor.yaml states).
    let resized = dir.path().join("resized");
    common::copy_tree(two, &resized);
    let image = resized.join("images/wearer_camera-slam-right/frame_00000.png");
    let mut tiny = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut tiny, 4, 4);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[128; 16]).unwrap();
    }
    std::fs::write(&image, tiny).unwrap();
    refused(
        &resized,
        &out,
        &["--wearer", "wearer"],
        &["frame_00000.png", "4×4 pixels", "calibration"],
    );
    // An export into its own take: refused, the take left as egogen-run made it.
    refused(
        two,
        &two.join("euroc"),
        &["--wearer", "wearer"],
        &["inside the take"],
    );
    // A rig without IMUs; a rig that is not the take's.
    let root = common::repo_root();
    refused(
        two,
        &out,
        &[
            "--wearer",
            "wearer",
            "--rig",
            root.join("camera_rigs/pinhole.json").to_str().unwrap(),
        ],
        &["has no IMU", "body frame"],
    );
    refused(
        &takes.one_camera,
        &out,
        &[
            "--rig",
            root.join("camera_rigs/hololens2.json").to_str().unwrap(),
        ],
        &["has no IMU"],
    );
    // An existing folder that is not empty: refused, untouched.
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "mine").unwrap();
    refused(two, &out, &["--wearer", "wearer"], &["not an empty folder"]);
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).unwrap(),
        "mine"
    );
}

/// The Python with `evo` (its EuRoC reader is the client checked), PyYAML, numpy and pytest.
fn evo_python() -> Result<PathBuf, String> {
    common::cached_python("evo-1.38.1", &["evo==1.38.1", "pyyaml", "numpy", "pytest"])
}

#[test]
fn euroc_clients_read_the_export() {
    let python = match evo_python() {
        Ok(p) => p,
        Err(e) if std::env::var_os("EGOGEN_REQUIRE_SYSTEM_TOOLS").is_none() => {
            eprintln!("SKIPPED euroc_clients_read_the_export: could not install evo: {e}");
            return;
        }
        Err(e) => panic!("could not install evo: {e}"),
    };
    let takes = takes();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    euroc_ok(&takes.two_wearers, &out, &["--wearer", "other"]);
    let root = common::repo_root();
    let o = Command::new(python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(root.join("tests/python/test_euroc_export.py"))
        .env("EGOGEN_EUROC_DIR", &out)
        .env("EGOGEN_EUROC_TAKE", &takes.two_wearers)
        .env("EGOGEN_EUROC_WEARER", "other")
        .current_dir(&root)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "pytest failed:\n{text}");
    assert!(
        text.contains(" passed") && !text.contains("skipped"),
        "{text}"
    );
}
