//! Rig files: the shipped rigs load, Aria device calibrations load as rigs, and each kind of
//! broken rig gives an error naming the file, the field and what was expected.

use std::path::{Path, PathBuf};

use egogen::camera::{Camera, CameraModel};
use egogen::math::{Affine3, Mat3, Vec3};
use egogen::rig::{AriaRgbResolution, Rig, RigCamera, RigError};
use serde_json::{json, Value};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn aria_fixture() -> PathBuf {
    root().join("tests/fixtures/aria_gen1_device_calibration.json")
}

/// A valid two-camera rig to break.
fn base() -> Value {
    json!({
        "egogen_rig": 1,
        "name": "test",
        "cameras": [
            {
                "name": "front",
                "resolution_px": [64, 48],
                "model": {"type": "pinhole", "fx": 50.0, "fy": 50.0, "cx": 31.5, "cy": 23.5},
                "cpf_from_cam": {
                    "translation_m": [0.0, 0.01, 0.02],
                    "rotation": [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
                }
            },
            {
                "name": "fish",
                "resolution_px": [64, 48],
                "model": {"type": "kannala_brandt4", "fx": 30.0, "fy": 30.0, "cx": 31.5,
                          "cy": 23.5, "k1": 0.01, "k2": 0.0, "k3": 0.0, "k4": 0.0},
                "cpf_from_cam": {
                    "translation_m": [0.03, 0.0, 0.0],
                    "rotation": [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
                }
            }
        ]
    })
}

fn load_text(text: &str) -> Result<Rig, RigError> {
    Rig::from_json_str(
        Path::new("test_rig.json"),
        text,
        AriaRgbResolution::Full2880,
    )
}

fn load(v: &Value) -> Result<Rig, RigError> {
    load_text(&serde_json::to_string_pretty(v).unwrap())
}

/// The error message, asserting it names the file and each of `needles`.
fn error_of(v: &Value, needles: &[&str]) -> String {
    let msg = load(v).expect_err("rig should be refused").to_string();
    assert!(msg.contains("test_rig.json"), "file not named: {msg}");
    for n in needles {
        assert!(msg.contains(n), "`{n}` missing from: {msg}");
    }
    msg
}

#[test]
fn a_camera_far_from_the_eyes_is_refused() {
    let mut v = base();
    v["cameras"][0]["cpf_from_cam"]["translation_m"] = json!([1000.0, 0.0, 0.0]);
    error_of(&v, &["cameras[0] (front)", "translation_m", "millimetres"]);
}

#[test]
fn base_rig_loads() {
    let rig = load(&base()).unwrap();
    assert_eq!(rig.camera_names(), ["front", "fish"]);
    assert_eq!(rig.cameras[1].model.model_name(), "kannala_brandt4");
}

#[test]
fn unknown_top_level_field_is_named() {
    let mut v = base();
    v["colour"] = json!("red");
    error_of(&v, &["top level", "unknown field `colour`", "egogen_rig"]);
}

#[test]
fn unknown_camera_field_is_named() {
    let mut v = base();
    v["cameras"][1]["fov_deg"] = json!(90);
    error_of(&v, &["cameras[1] (fish)", "unknown field `fov_deg`"]);
}

#[test]
fn unknown_model_parameter_is_named() {
    let mut v = base();
    v["cameras"][0]["model"]["k1"] = json!(0.1);
    error_of(
        &v,
        &["cameras[0] (front).model", "unknown field `k1`", "fx"],
    );
}

#[test]
fn unknown_model_type_lists_the_known_ones() {
    let mut v = base();
    v["cameras"][0]["model"]["type"] = json!("orthographic");
    error_of(
        &v,
        &[
            "cameras[0] (front).model",
            "orthographic",
            "pinhole",
            "fisheye624",
            "kannala_brandt4",
        ],
    );
}

#[test]
fn missing_pinhole_parameter_is_named() {
    let mut v = base();
    v["cameras"][0]["model"]
        .as_object_mut()
        .unwrap()
        .remove("fy");
    error_of(&v, &["cameras[0] (front).model", "missing field `fy`"]);
}

#[test]
fn missing_kannala_brandt_coefficient_is_named() {
    let mut v = base();
    v["cameras"][1]["model"]
        .as_object_mut()
        .unwrap()
        .remove("k4");
    error_of(&v, &["cameras[1] (fish).model", "missing field `k4`"]);
}

#[test]
fn fisheye624_with_too_few_params_is_refused() {
    let mut v = base();
    v["cameras"][1]["model"] = json!({"type": "fisheye624", "params": [30.0, 31.5, 23.5, 0.0]});
    error_of(
        &v,
        &[
            "cameras[1] (fish).model",
            "`params`",
            "15 numbers [f, cx, cy, k0..k5, p0, p1, s0..s3]",
        ],
    );
}

#[test]
fn zero_resolution_is_refused() {
    let mut v = base();
    v["cameras"][0]["resolution_px"] = json!([0, 48]);
    error_of(
        &v,
        &[
            "cameras[0] (front).resolution_px",
            "[0, 48]",
            "[width, height]",
        ],
    );
}

#[test]
fn negative_resolution_is_refused() {
    let mut v = base();
    v["cameras"][1]["resolution_px"] = json!([64, -48]);
    error_of(&v, &["cameras[1] (fish).resolution_px", "[64, -48]"]);
}

#[test]
fn non_positive_focal_length_is_refused() {
    let mut v = base();
    v["cameras"][0]["model"]["fx"] = json!(-50.0);
    error_of(&v, &["cameras[0] (front).model", "`fx` is -50", "positive"]);
}

#[test]
fn non_orthonormal_rotation_is_refused() {
    let mut v = base();
    v["cameras"][0]["cpf_from_cam"]["rotation"] =
        json!([[-1.0, 0.1, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]);
    error_of(
        &v,
        &[
            "cameras[0] (front).cpf_from_cam",
            "not orthonormal",
            "rotation matrix",
        ],
    );
}

#[test]
fn reflection_is_refused() {
    let mut v = base();
    v["cameras"][0]["cpf_from_cam"]["rotation"] =
        json!([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]);
    error_of(
        &v,
        &[
            "cameras[0] (front).cpf_from_cam",
            "reflection",
            "determinant +1",
        ],
    );
}

#[test]
fn duplicate_camera_names_are_refused() {
    let mut v = base();
    v["cameras"][1]["name"] = json!("front");
    error_of(&v, &["`front`", "cameras[0] and cameras[1]", "unique"]);
}

#[test]
fn nan_is_refused_and_named() {
    let text = serde_json::to_string_pretty(&base())
        .unwrap()
        .replace("\"fx\": 50.0", "\"fx\": NaN");
    let err = load_text(&text).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, RigError::NonFinite { .. }), "{msg}");
    assert!(
        msg.contains("test_rig.json") && msg.contains("`fx` is NaN"),
        "{msg}"
    );
    assert!(msg.contains("line ") && msg.contains("column "), "{msg}");
}

#[test]
fn infinity_is_refused_and_named() {
    let text = serde_json::to_string_pretty(&base()).unwrap().replace(
        "\"translation_m\": [\n          0.03",
        "\"translation_m\": [\n          -Infinity",
    );
    assert!(text.contains("-Infinity"));
    let msg = load_text(&text).unwrap_err().to_string();
    assert!(msg.contains("`translation_m` is -Infinity"), "{msg}");
}

#[test]
fn wrong_format_version_is_refused() {
    let mut v = base();
    v["egogen_rig"] = json!(2);
    error_of(&v, &["egogen_rig", "version 2", "expected 1"]);
}

#[test]
fn empty_rig_is_refused() {
    let mut v = base();
    v["cameras"] = json!([]);
    error_of(&v, &["cameras", "at least one camera"]);
}

#[test]
fn max_theta_beyond_the_lens_model_is_refused() {
    let mut v = base();
    v["cameras"][1]["model"]["k1"] = json!(-0.3);
    v["cameras"][1]["model"]["max_theta_rad"] = json!(1.5);
    error_of(
        &v,
        &[
            "cameras[1] (fish).model",
            "`max_theta_rad` is 1.5",
            "stops increasing",
        ],
    );
}

#[test]
fn unreadable_file_is_named() {
    let msg = Rig::load(Path::new("/nonexistent/rig.json"))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("/nonexistent/rig.json") && msg.contains("cannot read"),
        "{msg}"
    );
}

#[test]
fn unknown_camera_lists_the_available_ones() {
    let rig = load(&base()).unwrap();
    let msg = rig.camera("back").unwrap_err().to_string();
    assert!(
        msg.contains("`back`") && msg.contains("available: front, fish"),
        "{msg}"
    );
}

/// Every number that defines a camera: intrinsics, limits, size, pose.
fn camera_numbers(cam: &RigCamera) -> Vec<f64> {
    let m = &cam.model;
    let mut v: Vec<f64> = match m {
        Camera::Pinhole(p) => p.params().to_vec(),
        Camera::Fisheye624(f) => {
            let mut v = f.params().to_vec();
            v.push(f.valid_radius_px().unwrap_or(-1.0));
            v
        }
        Camera::KannalaBrandt4(k) => {
            let (a, b) = k.params();
            a.into_iter().chain(b).collect()
        }
    };
    let r = m.resolution();
    v.extend([m.max_theta_rad(), r.width_px as f64, r.height_px as f64]);
    v.extend(cam.cpf_from_cam.matrix3.to_cols_array());
    v.extend(cam.cpf_from_cam.translation.to_array());
    v
}

/// Same cameras up to 1e-15 relative: serde_json's default float parser may round the last
/// bit differently from the shortest representation it writes.
fn assert_same_cameras(a: &Rig, b: &Rig) {
    assert_eq!(a.camera_names(), b.camera_names());
    for (ca, cb) in a.cameras.iter().zip(&b.cameras) {
        assert_eq!(ca.model.model_name(), cb.model.model_name(), "{}", ca.name);
        for (x, y) in camera_numbers(ca).into_iter().zip(camera_numbers(cb)) {
            assert!(
                (x - y).abs() <= 1e-15 * x.abs().max(1.0),
                "{}: {x} vs {y}",
                ca.name
            );
        }
    }
}

#[test]
fn written_rig_reads_back_identically() {
    for name in ["aria_gen1", "hololens2", "pinhole"] {
        let path = root().join("camera_rigs").join(format!("{name}.json"));
        let rig = Rig::load(&path).unwrap();
        let again = Rig::from_json_str(&path, &rig.to_json(), AriaRgbResolution::Full2880).unwrap();
        assert_eq!((&rig.name, &rig.notes), (&again.name, &again.notes));
        assert_same_cameras(&rig, &again);
    }
}

#[test]
fn shipped_rigs_load() {
    let aria = Rig::load(&root().join("camera_rigs/aria_gen1.json")).unwrap();
    assert_eq!(
        aria.camera_names(),
        ["camera-slam-left", "camera-slam-right", "camera-rgb"]
    );
    let rgb = aria.camera("camera-rgb").unwrap();
    assert_eq!(rgb.model.resolution().width_px, 1408);
    assert!(matches!(rgb.model, Camera::Fisheye624(_)));

    let hl = Rig::load(&root().join("camera_rigs/hololens2.json")).unwrap();
    assert_eq!(
        hl.camera_names(),
        [
            "pv",
            "vlc-lf",
            "vlc-rf",
            "vlc-ll",
            "vlc-rr",
            "depth-long-throw"
        ]
    );
    let pv = hl.camera("pv").unwrap();
    assert!((pv.model.fov().horizontal_rad.to_degrees() - 64.69).abs() < 1e-9);
    let lt = hl.camera("depth-long-throw").unwrap().model.resolution();
    assert_eq!((lt.width_px, lt.height_px), (320, 288));

    let pin = Rig::load(&root().join("camera_rigs/pinhole.json")).unwrap();
    assert_eq!(pin.cameras.len(), 1);
    assert_eq!(pin.cameras[0].cpf_from_cam.translation, Vec3::ZERO);
    // Looks along the CPF's forward axis.
    assert_eq!(pin.cameras[0].cpf_from_cam.matrix3.z_axis, Vec3::Z);
}

#[test]
fn aria_calibration_loads_as_a_rig() {
    let rig = Rig::load(&aria_fixture()).unwrap();
    assert_eq!(
        rig.camera_names(),
        ["camera-slam-left", "camera-slam-right", "camera-rgb"]
    );
    let rgb = rig.camera("camera-rgb").unwrap();
    assert_eq!(rgb.model.resolution().width_px, 2880);
    assert_eq!(rgb.model.max_theta_rad(), 1.0);
    let slam = rig.camera("camera-slam-left").unwrap();
    let Camera::Fisheye624(f) = &slam.model else {
        panic!()
    };
    assert_eq!(f.valid_radius_px(), Some(330.0));
    assert_eq!(slam.model.max_theta_rad(), 1.4);
    // The origin camera's pose is exactly its CAD pose relative to the CPF: on the wearer's
    // left (+x), looking forward-left and slightly down.
    assert!(
        (slam.cpf_from_cam.translation - Vec3::new(0.069051, 0.002372, 0.009254)).length() < 1e-9
    );
    let axis = slam.cpf_from_cam.matrix3.z_axis;
    assert!(axis.x > 0.5 && axis.y < 0.0 && axis.z > 0.5, "{axis:?}");
    // The RGB camera looks forward and about 7.5° down.
    let axis = rgb.cpf_from_cam.matrix3.z_axis;
    assert!(axis.z > 0.98 && (axis.y + 0.13).abs() < 0.01, "{axis:?}");
    assert!(rig.notes.contains("CAD"));
}

#[test]
fn aria_calibration_at_1408_matches_the_shipped_rig() {
    let rig = Rig::load_with(&aria_fixture(), AriaRgbResolution::Rescaled1408).unwrap();
    let shipped = Rig::load(&root().join("camera_rigs/aria_gen1.json")).unwrap();
    assert_same_cameras(&rig, &shipped);
}

fn aria_value() -> Value {
    serde_json::from_str(&std::fs::read_to_string(aria_fixture()).unwrap()).unwrap()
}

fn aria_error(v: &Value, needles: &[&str]) {
    let msg = load(v).expect_err("should be refused").to_string();
    for n in needles {
        assert!(msg.contains(n), "`{n}` missing from: {msg}");
    }
}

#[test]
fn aria_unknown_build_is_refused() {
    let mut v = aria_value();
    v["DeviceClassInfo"]["BuildVersion"] = json!("EVT");
    aria_error(
        &v,
        &["DeviceClassInfo.BuildVersion", "`EVT`", "DVT-S or DVT-L"],
    );
}

#[test]
fn aria_missing_origin_is_refused() {
    let mut v = aria_value();
    v.as_object_mut().unwrap().remove("OriginSpecification");
    aria_error(&v, &["OriginSpecification", "missing"]);
}

#[test]
fn aria_unknown_label_is_refused() {
    let mut v = aria_value();
    v["CameraCalibrations"][0]["Label"] = json!("camera-thermal");
    aria_error(
        &v,
        &["CameraCalibrations[0] (camera-thermal).Label", "camera-rgb"],
    );
}

#[test]
fn aria_unsupported_projection_is_refused() {
    let mut v = aria_value();
    v["CameraCalibrations"][2]["Projection"]["Name"] = json!("KannalaBrandtK3");
    aria_error(
        &v,
        &[
            "CameraCalibrations[2] (camera-rgb).Projection.Name",
            "KannalaBrandtK3",
        ],
    );
}

#[test]
fn aria_non_unit_quaternion_is_refused() {
    let mut v = aria_value();
    v["CameraCalibrations"][1]["T_Device_Camera"]["UnitQuaternion"][0] = json!(0.5);
    aria_error(
        &v,
        &["camera-slam-right).T_Device_Camera", "unit quaternion"],
    );
}

#[test]
fn aria_missing_params_are_named() {
    let mut v = aria_value();
    v["CameraCalibrations"][0]["Projection"]
        .as_object_mut()
        .unwrap()
        .remove("Params");
    aria_error(
        &v,
        &[
            "CameraCalibrations[0] (camera-slam-left)",
            "missing field `Params`",
        ],
    );
}

#[test]
fn world_from_cam_chains_the_cpf_pose() {
    let rig = load(&base()).unwrap();
    let cam = &rig.cameras[1];
    let world_from_cpf = Affine3 {
        matrix3: Mat3::from_rotation_z(0.3),
        translation: Vec3::new(1.0, 2.0, 1.6),
    };
    let world_from_cam = cam.world_from_cam(world_from_cpf);
    // The camera centre sits 3 cm to the wearer's left of the CPF.
    let centre = world_from_cam.transform_point3(Vec3::ZERO);
    let expected = world_from_cpf.transform_point3(Vec3::new(0.03, 0.0, 0.0));
    assert!((centre - expected).length() < 1e-15);
}

#[test]
fn headset_wear_offsets_are_seeded_bounded_and_exact() {
    use egogen::rig::wear::{HeadsetWear, WearOffset};
    let wear = HeadsetWear {
        translation_m: 0.01,
        rotation_rad: 3f64.to_radians(),
        seed: 7,
    };
    let offsets: Vec<WearOffset> = (0..64).map(|i| wear.draw(i)).collect();
    // The same seed and wearer: the same offset; another wearer: another.
    assert_eq!(wear.draw(3), offsets[3]);
    assert_ne!(offsets[0], offsets[1]);
    for o in &offsets {
        assert!(o.translation_m.iter().all(|t| t.abs() <= 0.01));
        assert!(o
            .rotation_xyz_rad
            .iter()
            .all(|r| r.abs() <= 3f64.to_radians()));
        // The recorded matrix is the transform used.
        let m = o.cpf_from_headset();
        let p = glam::DVec3::new(0.3, -0.2, 0.5);
        let q = m.transform_point3(p);
        let t = &o.t_cpf_headset;
        for (row, want) in t.iter().take(3).zip(q.to_array()) {
            let got = row[0] * p.x + row[1] * p.y + row[2] * p.z + row[3];
            assert!((got - want).abs() < 1e-12);
        }
        assert_eq!(t[3], [0.0, 0.0, 0.0, 1.0]);
    }
    // The ranges are used, not a corner of them: some offsets reach past half of each.
    assert!(offsets.iter().any(|o| o.translation_m[0].abs() > 0.005));
    assert!(offsets
        .iter()
        .any(|o| o.rotation_xyz_rad[2].abs() > 1.5f64.to_radians()));
    // Zero ranges: no offset at all.
    let none = HeadsetWear {
        translation_m: 0.0,
        rotation_rad: 0.0,
        seed: 7,
    };
    assert_eq!(none.draw(0), WearOffset::none());
    assert_eq!(
        none.draw(0).cpf_from_headset(),
        egogen::math::Affine3::IDENTITY
    );
}

fn with_imu() -> Value {
    let mut v = base();
    v["imus"] = json!([{
        "name": "imu-a",
        "rate_hz": 1000.0,
        "cpf_from_imu": {
            "translation_m": [0.05, 0.0, 0.0],
            "rotation": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        }
    }]);
    v["device_frame"] = json!("imu-a");
    v
}

#[test]
fn imus_and_the_device_frame_load_and_write_back() {
    let rig = load(&with_imu()).unwrap();
    assert_eq!(rig.imus.len(), 1);
    assert_eq!(rig.device_frame_name(), "imu-a");
    assert_eq!(rig.cpf_from_device().translation.x, 0.05);
    assert_eq!(load_text(&rig.to_json()).unwrap().imus, rig.imus);
    // Without `device_frame`, the first camera's frame is the device frame.
    let plain = load(&base()).unwrap();
    assert_eq!(plain.device_frame_name(), "front");
}

#[test]
fn bad_imus_are_named() {
    let mut v = with_imu();
    v["imus"][0]["rate_hz"] = json!(0.0);
    error_of(&v, &["imus[0] (imu-a).rate_hz", "sample rate"]);
    let mut v = with_imu();
    v["imus"][0]["name"] = json!("front");
    error_of(&v, &["imus[0] (front).name", "unique"]);
    let mut v = with_imu();
    v["imus"][0]["cpf_from_imu"]["translation_m"] = json!([2.0, 0.0, 0.0]);
    error_of(&v, &["imus[0] (imu-a).cpf_from_imu", "millimetres"]);
    let mut v = with_imu();
    v["device_frame"] = json!("imu-z");
    error_of(&v, &["device_frame", "`imu-z`", "front, fish, imu-a"]);
    let mut v = with_imu();
    v["imus"][0]["calibration"] = json!({
        "accel_rectification": [[3.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        "accel_bias_m_s2": [0.0, 0.0, 0.0],
        "gyro_rectification": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        "gyro_bias_rad_s": [0.0, 0.0, 0.0]
    });
    error_of(&v, &["imus[0] (imu-a).calibration", "accel_rectification"]);
}

#[test]
fn an_aria_calibration_keeps_its_imus() {
    let rig = Rig::load(&aria_fixture()).unwrap();
    let names: Vec<&str> = rig.imus.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(names, ["imu-left", "imu-right"]);
    assert_eq!(rig.imus[0].rate_hz, 800.0);
    assert_eq!(rig.imus[1].rate_hz, 1000.0);
    assert_eq!(rig.device_frame_name(), "camera-slam-left");
    // The calibration's accelerometer bias of imu-left, as written in the fixture.
    assert_eq!(rig.imus[0].calibration.accel_bias.x, 0.221434286143159);
}
