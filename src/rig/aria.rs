//! Project Aria device calibrations (projectaria-tools' JSON: `DeviceClassInfo`,
//! `OriginSpecification`, `CameraCalibrations`) read as rigs, the way projectaria-tools'
//! `device_calibration_from_json_string` reads them.
//!
//! - Cameras: `Label` picks the sensor size, valid radius and maximum angle projectaria-tools
//!   assigns (`camera-rgb`: 2880×2880, 1415 px, 1.0 rad; `camera-slam-*`: 640×480, 330 px,
//!   1.4 rad; `camera-et-*`: 640×480, no mask, 0.75 rad). `Projection.Name`
//!   `FisheyeRadTanThinPrism` (15 params) and `Fisheye62` (11 params, no thin prism) are read;
//!   other models are refused.
//! - Poses: `T_Device_Camera` (`Translation` m, `UnitQuaternion` `[w, [x, y, z]]`, Hamilton).
//!   The calibration holds no CPF; like projectaria-tools we take `T_Device_CPF` from the
//!   nominal CAD pose of the origin sensor (`OriginSpecification.ChildLabel`, normally
//!   `camera-slam-left`) for the build (`DeviceClassInfo.BuildVersion` `DVT-S` or `DVT-L`):
//!   `cpf_from_cam = (T_CPF_origin)_CAD · T_Device_Camera`. Aria's CPF axes are x left, y up,
//!   z forward — egogen's — and Aria camera frames follow the raw sensor image (x along image
//!   rows, y down the columns, z optical axis): OpenCV, in the sensor's native (rotated)
//!   orientation.
//! - Other sensors (IMU, magnetometer, …) and unknown keys are ignored, as projectaria-tools
//!   ignores them for cameras; this is a foreign format, so it is read leniently.

use std::path::Path;

use glam::{DQuat, DVec2};
use serde::Deserialize;

use super::error::RigError;
use super::pose::nearest_rotation;
use super::{ImuCalibration, Rig, RigCamera, RigImu};
use crate::camera::{Camera, Fisheye624, Resolution};
use crate::math::{mat3_from_rows, Affine3, Mat3, Real, Vec3};

/// Image size of Aria's RGB camera: full sensor (the calibration's own) or the 1408×1408
/// recording mode (crop 32 px each side, then scale 0.5, as projectaria-tools rescales it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AriaRgbResolution {
    #[default]
    Full2880,
    Rescaled1408,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaCalibration {
    device_class_info: Option<DeviceClassInfo>,
    origin_specification: Option<OriginSpecification>,
    camera_calibrations: Vec<serde_json::Value>,
    #[serde(default)]
    imu_calibrations: Vec<serde_json::Value>,
}

/// One entry of `ImuCalibrations` (the keys projectaria-tools reads).
#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaImu {
    label: String,
    accelerometer: AriaImuSensor,
    gyroscope: AriaImuSensor,
    #[serde(rename = "T_Device_Imu")]
    t_device_imu: AriaSe3,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaImuSensor {
    bias: AriaImuBias,
    model: AriaImuModel,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaImuBias {
    offset: [Real; 3],
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaImuModel {
    /// Row-major.
    rectification_matrix: [[Real; 3]; 3],
}

/// Sample rates of the Aria gen1 IMUs (projectaria-tools: imu-right stream 1202-1 at 1 kHz,
/// imu-left 1202-2 at 800 Hz).
fn imu_rate_hz(label: &str) -> Real {
    if label == "imu-left" {
        800.0
    } else {
        1000.0
    }
}

/// The Aria build whose nominal CAD pose of `camera-slam-left` (the device frame) is
/// `cpf_from_device` to 1e-9, if any: the rigs read from an Aria calibration, and the shipped
/// `aria_gen1` rig, have one.
pub(crate) fn aria_build_of_device(cpf_from_device: Affine3) -> Option<&'static str> {
    [("DVT-S", &CAD_DVT_S), ("DVT-L", &CAD_DVT_L)]
        .into_iter()
        .find(|(_, table)| {
            let cad = table[0].cpf_from_sensor();
            (cad.translation - cpf_from_device.translation).length() < 1e-9
                && (cad.matrix3 - cpf_from_device.matrix3)
                    .to_cols_array()
                    .iter()
                    .all(|d| d.abs() < 1e-9)
        })
        .map(|(build, _)| build)
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct DeviceClassInfo {
    build_version: String,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct OriginSpecification {
    #[serde(rename = "Type")]
    kind: String,
    child_label: String,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaCamera {
    label: String,
    projection: AriaProjection,
    #[serde(rename = "T_Device_Camera")]
    t_device_camera: AriaSe3,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaProjection {
    name: String,
    params: Vec<Real>,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "PascalCase")]
struct AriaSe3 {
    translation: [Real; 3],
    /// `[w, [x, y, z]]`.
    unit_quaternion: (Real, [Real; 3]),
}

/// One row of projectaria-tools' `DeviceCadExtrinsics`: `T_CPF_sensor` as translation (m)
/// and the sensor's y and z axes in the CPF.
struct CadRow {
    label: &'static str,
    translation_m: [Real; 3],
    y_axis: [Real; 3],
    z_axis: [Real; 3],
}

/// The camera rows of projectaria-tools' CAD tables (`core/calibration/DeviceCadExtrinsics.cpp`,
/// Apache-2.0, Meta Platforms; see `assets/NOTICE`).
const CAD_DVT_S: [CadRow; 3] = [
    CadRow {
        label: "camera-slam-left",
        translation_m: [0.069051, 0.002372, 0.009254],
        y_axis: [0.793353, 0.000000, -0.608761],
        z_axis: [0.607927, -0.052336, 0.792266],
    },
    CadRow {
        label: "camera-slam-right",
        translation_m: [-0.069051, 0.002372, 0.009254],
        y_axis: [0.793353, 0.000000, 0.608761],
        z_axis: [-0.607927, -0.052336, 0.792266],
    },
    CadRow {
        label: "camera-rgb",
        translation_m: [0.056000, 0.007121, 0.012883],
        y_axis: [1.000000, 0.000000, 0.000000],
        z_axis: [0.000000, -0.130526, 0.991445],
    },
];

const CAD_DVT_L: [CadRow; 3] = [
    CadRow {
        label: "camera-slam-left",
        translation_m: [0.071351, 0.002372, 0.008454],
        y_axis: [0.793353, 0.000000, -0.608761],
        z_axis: [0.607927, -0.052336, 0.792266],
    },
    CadRow {
        label: "camera-slam-right",
        translation_m: [-0.071351, 0.002372, 0.008454],
        y_axis: [0.793353, 0.000000, 0.608761],
        z_axis: [-0.607927, -0.052336, 0.792266],
    },
    CadRow {
        label: "camera-rgb",
        translation_m: [0.058250, 0.007186, 0.012096],
        y_axis: [1.000000, 0.000000, 0.000000],
        z_axis: [0.000000, -0.130526, 0.991445],
    },
];

impl CadRow {
    /// `T_CPF_sensor`, built as projectaria-tools does: normalised y and z, x = y × z, then the
    /// nearest rotation (Sophus `makeRotationMatrix`).
    fn cpf_from_sensor(&self) -> Affine3 {
        let y = Vec3::from_array(self.y_axis).normalize();
        let z = Vec3::from_array(self.z_axis).normalize();
        Affine3 {
            matrix3: nearest_rotation(Mat3::from_cols(y.cross(z), y, z)),
            translation: Vec3::from_array(self.translation_m),
        }
    }
}

/// Whether a JSON document looks like an Aria device calibration.
pub(super) fn is_aria_calibration(value: &serde_json::Value) -> bool {
    value.get("CameraCalibrations").is_some()
}

/// Sensor size, valid radius and maximum angle projectaria-tools gives each label.
fn label_limits(label: &str) -> Option<(Resolution, Option<Real>, Real)> {
    let res = |w, h| Resolution {
        width_px: w,
        height_px: h,
    };
    match label {
        "camera-rgb" => Some((res(2880, 2880), Some(1415.0), 1.0)),
        "camera-slam-left" | "camera-slam-right" => Some((res(640, 480), Some(330.0), 1.4)),
        "camera-et-left" | "camera-et-right" => Some((res(640, 480), None, 0.75)),
        _ => None,
    }
}

/// Reads an Aria device calibration document as a rig.
pub(super) fn rig_from_aria_value(
    path: &Path,
    value: serde_json::Value,
    rgb: AriaRgbResolution,
) -> Result<Rig, RigError> {
    let cal: AriaCalibration = serde_json::from_value(value)
        .map_err(|e| RigError::field(path, "Aria calibration (top level)", e.to_string()))?;
    let build = cal
        .device_class_info
        .map(|d| d.build_version)
        .ok_or_else(|| {
            RigError::field(
                path,
                "DeviceClassInfo.BuildVersion",
                "missing; expected DVT-S or DVT-L (it picks the CAD pose of the CPF)",
            )
        })?;
    let table: &[CadRow] = match build.as_str() {
        "DVT-S" => &CAD_DVT_S,
        "DVT-L" => &CAD_DVT_L,
        other => {
            return Err(RigError::field(
                path,
                "DeviceClassInfo.BuildVersion",
                format!("`{other}` has no known CAD pose of the CPF; expected DVT-S or DVT-L"),
            ))
        }
    };
    let origin = cal.origin_specification.ok_or_else(|| {
        RigError::field(
            path,
            "OriginSpecification",
            "missing; expected {\"Type\": \"Custom\", \"ChildLabel\": \"camera-slam-left\"}",
        )
    })?;
    if origin.kind != "Custom" {
        return Err(RigError::field(
            path,
            "OriginSpecification.Type",
            format!("`{}`, expected `Custom`", origin.kind),
        ));
    }
    let cad = table
        .iter()
        .find(|r| r.label == origin.child_label)
        .ok_or_else(|| {
            RigError::field(
                path,
                "OriginSpecification.ChildLabel",
                format!(
                    "`{}`, expected one of camera-slam-left, camera-slam-right, camera-rgb",
                    origin.child_label
                ),
            )
        })?;
    let cpf_from_device = cad.cpf_from_sensor();

    let mut cameras: Vec<RigCamera> = Vec::new();
    for (i, value) in cal.camera_calibrations.into_iter().enumerate() {
        let label_hint = value
            .get("Label")
            .and_then(|l| l.as_str())
            .map(|l| format!("CameraCalibrations[{i}] ({l})"))
            .unwrap_or_else(|| format!("CameraCalibrations[{i}]"));
        let cam: AriaCamera = serde_json::from_value(value)
            .map_err(|e| RigError::field(path, &label_hint, e.to_string()))?;
        let model = camera_model(path, &cam, &label_hint, rgb)?;
        let device_from_cam = se3(&cam.t_device_camera)
            .map_err(|m| RigError::field(path, format!("{label_hint}.T_Device_Camera"), m))?;
        if cameras.iter().any(|c| c.name == cam.label) {
            let first = cameras
                .iter()
                .position(|c| c.name == cam.label)
                .unwrap_or(0);
            return Err(RigError::DuplicateCamera {
                path: path.into(),
                name: cam.label,
                first,
                second: i,
            });
        }
        let monochrome = cam.label != "camera-rgb";
        cameras.push(RigCamera {
            name: cam.label,
            model: Camera::Fisheye624(model),
            cpf_from_cam: cpf_from_device * device_from_cam,
            // Only the RGB camera sees colour; SLAM and eye-tracking cameras are monochrome.
            monochrome,
        });
    }
    if cameras.is_empty() {
        return Err(RigError::field(
            path,
            "CameraCalibrations",
            "expected at least one camera",
        ));
    }
    let imus = aria_imus(path, cal.imu_calibrations, &cameras, cpf_from_device)?;
    let notes = rig_notes(path, &build, &origin.child_label, rgb);
    Ok(Rig {
        name: path
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "aria".into()),
        notes,
        source: path.into(),
        cameras,
        imus,
        device_frame: Some(origin.child_label.clone()),
    })
}

/// A camera's projection: the calibration's Fisheye624 parameters (a Fisheye62's padded) with
/// its label's sensor size, valid radius and maximum angle; camera-rgb rescaled as `rgb` asks.
fn camera_model(
    path: &Path,
    cam: &AriaCamera,
    label_hint: &str,
    rgb: AriaRgbResolution,
) -> Result<Fisheye624, RigError> {
    let (resolution, radius, max_theta) = label_limits(&cam.label).ok_or_else(|| {
        RigError::field(
            path,
            format!("{label_hint}.Label"),
            "unknown Aria camera label, expected camera-rgb, camera-slam-left, \
                 camera-slam-right, camera-et-left or camera-et-right",
        )
    })?;
    let mut params = cam.projection.params.clone();
    let proj_at = format!("{label_hint}.Projection");
    match (cam.projection.name.as_str(), params.len()) {
        ("FisheyeRadTanThinPrism", 15) => {}
        ("Fisheye62", 11) => params.extend([0.0; 4]),
        ("FisheyeRadTanThinPrism" | "Fisheye62", n) => {
            return Err(RigError::field(
                path,
                format!("{proj_at}.Params"),
                format!(
                    "{n} numbers for {}, expected {}",
                    cam.projection.name,
                    if cam.projection.name == "Fisheye62" {
                        11
                    } else {
                        15
                    }
                ),
            ))
        }
        (other, _) => {
            return Err(RigError::field(
                path,
                format!("{proj_at}.Name"),
                format!("`{other}` is not supported, expected FisheyeRadTanThinPrism or Fisheye62"),
            ))
        }
    }
    let mut model = Fisheye624::new(&params, resolution, Some(max_theta), radius)
        .map_err(|e| RigError::field(path, &proj_at, e.to_string()))?;
    if cam.label == "camera-rgb" && rgb == AriaRgbResolution::Rescaled1408 {
        let binned = Resolution {
            width_px: 1408,
            height_px: 1408,
        };
        model = model
            .rescaled(binned, 0.5, DVec2::splat(32.0))
            .map_err(|e| RigError::field(path, &proj_at, e.to_string()))?;
    }
    Ok(model)
}

/// The rig's IMUs, from the calibration's `ImuCalibrations`; labels unique among all sensors.
fn aria_imus(
    path: &Path,
    imu_calibrations: Vec<serde_json::Value>,
    cameras: &[RigCamera],
    cpf_from_device: Affine3,
) -> Result<Vec<RigImu>, RigError> {
    let mut imus: Vec<RigImu> = Vec::new();
    for (i, value) in imu_calibrations.into_iter().enumerate() {
        let hint = value
            .get("Label")
            .and_then(|l| l.as_str())
            .map(|l| format!("ImuCalibrations[{i}] ({l})"))
            .unwrap_or_else(|| format!("ImuCalibrations[{i}]"));
        let imu: AriaImu = serde_json::from_value(value)
            .map_err(|e| RigError::field(path, &hint, e.to_string()))?;
        let device_from_imu = se3(&imu.t_device_imu)
            .map_err(|m| RigError::field(path, format!("{hint}.T_Device_Imu"), m))?;
        let calibration = ImuCalibration {
            accel_rectification: mat3_from_rows(&imu.accelerometer.model.rectification_matrix),
            accel_bias: Vec3::from_array(imu.accelerometer.bias.offset),
            gyro_rectification: mat3_from_rows(&imu.gyroscope.model.rectification_matrix),
            gyro_bias: Vec3::from_array(imu.gyroscope.bias.offset),
        };
        if cameras.iter().any(|c| c.name == imu.label) || imus.iter().any(|o| o.name == imu.label) {
            return Err(RigError::field(
                path,
                format!("{hint}.Label"),
                "is already used by another sensor; labels must be unique",
            ));
        }
        imus.push(RigImu {
            rate_hz: imu_rate_hz(&imu.label),
            name: imu.label,
            cpf_from_imu: cpf_from_device * device_from_imu,
            calibration,
        });
    }
    Ok(imus)
}

/// The rig's notes: where its intrinsics and poses come from.
fn rig_notes(path: &Path, build: &str, origin_label: &str, rgb: AriaRgbResolution) -> String {
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    format!(
        "From the Project Aria device calibration {file_name} (BuildVersion {build}, device \
         frame = {origin}). Intrinsics: the calibration's FisheyeRadTanThinPrism (Fisheye624) \
         parameters; sensor sizes, valid radii and maximum angles as projectaria-tools assigns \
         them per label{rgb_note}. Poses: cpf_from_cam = T_CPF_{origin} (projectaria-tools' \
         {build} CAD extrinsics, nominal, not calibrated) * T_Device_Camera (calibrated). Camera \
         frames are the sensors' native OpenCV frames (Aria images are stored rotated; rotate \
         90 degrees clockwise to view upright).",
        origin = origin_label,
        rgb_note = match rgb {
            AriaRgbResolution::Full2880 => "",
            AriaRgbResolution::Rescaled1408 =>
                "; camera-rgb rescaled to 1408x1408 (crop 32 px per side, scale 0.5) as \
                 projectaria-tools does for 1408x1408 recordings",
        },
    )
}

/// A projectaria-tools SE(3): the quaternion is normalised (as Sophus does) after checking
/// it is unit length to 1e-6.
fn se3(raw: &AriaSe3) -> Result<Affine3, String> {
    let t = Vec3::from_array(raw.translation);
    let (w, [x, y, z]) = raw.unit_quaternion;
    let q = DQuat::from_xyzw(x, y, z, w);
    if !t.is_finite() || !q.is_finite() {
        return Err("expected finite Translation and UnitQuaternion values".into());
    }
    if (q.length() - 1.0).abs() > 1e-6 {
        return Err(format!(
            "UnitQuaternion [{w}, [{x}, {y}, {z}]] has norm {}, expected a unit quaternion \
             [w, [x, y, z]]",
            q.length()
        ));
    }
    Ok(Affine3 {
        matrix3: Mat3::from_quat(q.normalize()),
        translation: t,
    })
}
