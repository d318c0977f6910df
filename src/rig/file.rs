//! egogen's own rig file (JSON, `camera_rigs/*.json`, schema in `docs/RIGS.md`): the raw serde
//! types, strict parsing with errors that name the camera and field, validation into a
//! [`Rig`], and writing a rig back out.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::RigError;
use super::pose::{checked_rotation, NotRotation};
use super::{ImuCalibration, Rig, RigCamera, RigImu};
use crate::camera::{Camera, Fisheye624, KannalaBrandt4, Pinhole, Resolution};
use crate::math::{mat3_from_rows, mat3_rows, Affine3, Mat3, Real, Vec3};

/// Value of the `egogen_rig` key this version reads and writes.
pub(crate) const FORMAT_VERSION: u32 = 1;

/// The top level of a rig file, as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawRig {
    /// Format version, must be [`FORMAT_VERSION`].
    egogen_rig: u32,
    /// Short rig name.
    name: String,
    /// Free text: where the numbers come from, what is estimated.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    notes: String,
    /// Cameras; parsed one by one so that errors name the camera.
    cameras: Vec<serde_json::Value>,
    /// Inertial sensors (optional); parsed one by one so that errors name the IMU.
    #[serde(default)]
    imus: Vec<serde_json::Value>,
    /// The sensor whose frame is the device frame (optional; default the first camera).
    #[serde(default)]
    device_frame: Option<String>,
}

/// One IMU, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawImu {
    name: String,
    rate_hz: Real,
    cpf_from_imu: serde_json::Value,
    /// The device's calibration (optional; default a perfect sensor).
    #[serde(default)]
    calibration: Option<RawImuCalibration>,
}

/// `raw = M · rectified + bias` per sensor (projectaria-tools' model); matrices row-major.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawImuCalibration {
    accel_rectification: [[Real; 3]; 3],
    accel_bias_m_s2: [Real; 3],
    gyro_rectification: [[Real; 3]; 3],
    gyro_bias_rad_s: [Real; 3],
}

impl RawImuCalibration {
    fn from_calibration(c: &ImuCalibration) -> Self {
        RawImuCalibration {
            accel_rectification: mat3_rows(c.accel_rectification),
            accel_bias_m_s2: c.accel_bias.to_array(),
            gyro_rectification: mat3_rows(c.gyro_rectification),
            gyro_bias_rad_s: c.gyro_bias.to_array(),
        }
    }

    fn build(&self) -> Result<ImuCalibration, String> {
        let c = ImuCalibration {
            accel_rectification: mat3_from_rows(&self.accel_rectification),
            accel_bias: Vec3::from_array(self.accel_bias_m_s2),
            gyro_rectification: mat3_from_rows(&self.gyro_rectification),
            gyro_bias: Vec3::from_array(self.gyro_bias_rad_s),
        };
        let finite = c.accel_rectification.is_finite()
            && c.accel_bias.is_finite()
            && c.gyro_rectification.is_finite()
            && c.gyro_bias.is_finite();
        if !finite {
            return Err("expected finite numbers".into());
        }
        for (key, r) in [
            ("accel_rectification", c.accel_rectification),
            ("gyro_rectification", c.gyro_rectification),
        ] {
            // A scale-and-misalignment matrix is near the identity; far from it is a mistake.
            let off = (r - Mat3::IDENTITY)
                .to_cols_array()
                .iter()
                .fold(0.0, |a: Real, v| a.max(v.abs()));
            if off > 0.5 {
                return Err(format!(
                    "{key} differs from the identity by {off:.3} in an entry; expected a scale \
                     and misalignment matrix near the identity"
                ));
            }
        }
        Ok(c)
    }
}

/// Highest IMU rate a rig may give (Hz); devices sample at 100 Hz – a few kHz.
pub(crate) const MAX_IMU_RATE_HZ: Real = 100_000.0;

/// One camera, as written (the model and pose are parsed separately so errors name them).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    name: String,
    /// `[width, height]` in pixels.
    resolution_px: [i64; 2],
    model: serde_json::Value,
    cpf_from_cam: serde_json::Value,
    /// A monochrome sensor (default false).
    #[serde(default)]
    monochrome: bool,
}

/// A camera model, as written; `type` picks the variant.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum RawModel {
    Pinhole {
        fx: Real,
        fy: Real,
        cx: Real,
        cy: Real,
    },
    Fisheye624 {
        /// `[f, cx, cy, k0..k5, p0, p1, s0..s3]` (projectaria-tools order).
        params: Vec<Real>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max_theta_rad: Option<Real>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        valid_radius_px: Option<Real>,
    },
    KannalaBrandt4 {
        fx: Real,
        fy: Real,
        cx: Real,
        cy: Real,
        k1: Real,
        k2: Real,
        k3: Real,
        k4: Real,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max_theta_rad: Option<Real>,
    },
}

/// `cpf_from_cam`: maps camera-frame points into the CPF, `p_cpf = R · p_cam + t`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawPose {
    translation_m: [Real; 3],
    /// Row-major 3×3; its columns are the camera's x, y, z axes in CPF coordinates.
    rotation: [[Real; 3]; 3],
}

/// Parses and validates an egogen rig document.
pub(super) fn rig_from_value(path: &Path, value: serde_json::Value) -> Result<Rig, RigError> {
    let raw: RawRig = serde_json::from_value(value)
        .map_err(|e| RigError::field(path, "top level", e.to_string()))?;
    if raw.egogen_rig != FORMAT_VERSION {
        return Err(RigError::field(
            path,
            "egogen_rig",
            format!(
                "format version {} is not supported, expected {FORMAT_VERSION}",
                raw.egogen_rig
            ),
        ));
    }
    if raw.cameras.is_empty() {
        return Err(RigError::field(
            path,
            "cameras",
            "expected at least one camera",
        ));
    }
    let mut cameras: Vec<RigCamera> = Vec::with_capacity(raw.cameras.len());
    for (i, value) in raw.cameras.into_iter().enumerate() {
        let name = value
            .get("name")
            .and_then(|n| n.as_str())
            .map(|n| format!("cameras[{i}] ({n})"))
            .unwrap_or_else(|| format!("cameras[{i}]"));
        let cam = camera_from_value(path, &name, value)?;
        if let Some(first) = cameras.iter().position(|c| c.name == cam.name) {
            return Err(RigError::DuplicateCamera {
                path: path.into(),
                name: cam.name,
                first,
                second: i,
            });
        }
        cameras.push(cam);
    }
    let mut imus: Vec<RigImu> = Vec::with_capacity(raw.imus.len());
    for (i, value) in raw.imus.into_iter().enumerate() {
        let name = value
            .get("name")
            .and_then(|n| n.as_str())
            .map(|n| format!("imus[{i}] ({n})"))
            .unwrap_or_else(|| format!("imus[{i}]"));
        let imu = imu_from_value(path, &name, value)?;
        if cameras.iter().any(|c| c.name == imu.name) || imus.iter().any(|o| o.name == imu.name) {
            return Err(RigError::field(
                path,
                format!("{name}.name"),
                "is already used by another camera or IMU; sensor names must be unique",
            ));
        }
        imus.push(imu);
    }
    if let Some(device) = &raw.device_frame {
        let known =
            cameras.iter().any(|c| &c.name == device) || imus.iter().any(|i| &i.name == device);
        if !known {
            let names: Vec<&str> = cameras
                .iter()
                .map(|c| c.name.as_str())
                .chain(imus.iter().map(|i| i.name.as_str()))
                .collect();
            return Err(RigError::field(
                path,
                "device_frame",
                format!(
                    "`{device}` names no camera or IMU of the rig; expected one of {}",
                    names.join(", ")
                ),
            ));
        }
    }
    Ok(Rig {
        name: raw.name,
        notes: raw.notes,
        source: path.into(),
        cameras,
        imus,
        device_frame: raw.device_frame,
    })
}

fn imu_from_value(path: &Path, where_: &str, value: serde_json::Value) -> Result<RigImu, RigError> {
    let raw: RawImu =
        serde_json::from_value(value).map_err(|e| RigError::field(path, where_, e.to_string()))?;
    if raw.name.trim().is_empty() {
        return Err(RigError::field(
            path,
            format!("{where_}.name"),
            "expected a non-empty IMU name",
        ));
    }
    if !(raw.rate_hz.is_finite() && raw.rate_hz > 0.0 && raw.rate_hz <= MAX_IMU_RATE_HZ) {
        return Err(RigError::field(
            path,
            format!("{where_}.rate_hz"),
            format!(
                "{} is not a sample rate, expected Hz in (0, {MAX_IMU_RATE_HZ}]",
                raw.rate_hz
            ),
        ));
    }
    let pose_at = format!("{where_}.cpf_from_imu");
    let raw_pose: RawPose = serde_json::from_value(raw.cpf_from_imu)
        .map_err(|e| RigError::field(path, &pose_at, e.to_string()))?;
    let cpf_from_imu = build_pose(&raw_pose).map_err(|m| RigError::field(path, &pose_at, m))?;
    let calibration = match &raw.calibration {
        None => ImuCalibration::IDEAL,
        Some(c) => c
            .build()
            .map_err(|m| RigError::field(path, format!("{where_}.calibration"), m))?,
    };
    Ok(RigImu {
        name: raw.name,
        rate_hz: raw.rate_hz,
        cpf_from_imu,
        calibration,
    })
}

fn camera_from_value(
    path: &Path,
    where_: &str,
    value: serde_json::Value,
) -> Result<RigCamera, RigError> {
    let raw: RawCamera =
        serde_json::from_value(value).map_err(|e| RigError::field(path, where_, e.to_string()))?;
    if raw.name.trim().is_empty() {
        return Err(RigError::field(
            path,
            format!("{where_}.name"),
            "expected a non-empty camera name",
        ));
    }
    let [w, h] = raw.resolution_px;
    let valid = |v: i64| (1..=65_536).contains(&v);
    if !(valid(w) && valid(h)) {
        return Err(RigError::field(
            path,
            format!("{where_}.resolution_px"),
            format!("[{w}, {h}] is not a valid size, expected [width, height] in pixels, each in 1..=65536"),
        ));
    }
    let resolution = Resolution {
        width_px: w as u32,
        height_px: h as u32,
    };
    let model_at = format!("{where_}.model");
    let raw_model: RawModel = serde_json::from_value(raw.model)
        .map_err(|e| RigError::field(path, &model_at, e.to_string()))?;
    let model = build_model(raw_model, resolution)
        .map_err(|e| RigError::field(path, &model_at, e.to_string()))?;
    let pose_at = format!("{where_}.cpf_from_cam");
    let raw_pose: RawPose = serde_json::from_value(raw.cpf_from_cam)
        .map_err(|e| RigError::field(path, &pose_at, e.to_string()))?;
    let cpf_from_cam = build_pose(&raw_pose).map_err(|m| RigError::field(path, &pose_at, m))?;
    Ok(RigCamera {
        name: raw.name,
        model,
        cpf_from_cam,
        monochrome: raw.monochrome,
    })
}

fn build_model(
    raw: RawModel,
    resolution: Resolution,
) -> Result<Camera, crate::camera::CameraError> {
    Ok(match raw {
        RawModel::Pinhole { fx, fy, cx, cy } => {
            Camera::Pinhole(Pinhole::new(fx, fy, cx, cy, resolution)?)
        }
        RawModel::Fisheye624 {
            params,
            max_theta_rad,
            valid_radius_px,
        } => Camera::Fisheye624(Fisheye624::new(
            &params,
            resolution,
            max_theta_rad,
            valid_radius_px,
        )?),
        RawModel::KannalaBrandt4 {
            fx,
            fy,
            cx,
            cy,
            k1,
            k2,
            k3,
            k4,
            max_theta_rad,
        } => Camera::KannalaBrandt4(KannalaBrandt4::new(
            [fx, fy, cx, cy],
            [k1, k2, k3, k4],
            resolution,
            max_theta_rad,
        )?),
    })
}

/// Farthest a rig's camera may sit from the eyes (CPF) it is mounted on (m): head-mounted
/// devices keep their cameras within centimetres; one a metre away is a unit mistake (mm).
pub(crate) const MAX_CAMERA_OFFSET_M: Real = 1.0;

fn build_pose(raw: &RawPose) -> Result<Affine3, String> {
    let t = Vec3::from_array(raw.translation_m);
    if !t.is_finite() {
        return Err(format!(
            "translation_m {:?} must be three finite numbers (metres)",
            raw.translation_m
        ));
    }
    if t.length() > MAX_CAMERA_OFFSET_M {
        return Err(format!(
            "translation_m {:?} puts the sensor {:.3} m from the eyes (CPF); a head-mounted \
             sensor sits within {MAX_CAMERA_OFFSET_M} m of them: is it in millimetres? \
             (expected metres)",
            raw.translation_m,
            t.length()
        ));
    }
    let r = raw.rotation;
    let m = mat3_from_rows(&r);
    if !m.is_finite() {
        return Err(format!("rotation {r:?} must hold finite numbers"));
    }
    let rotation = checked_rotation(m).map_err(|e| match e {
        NotRotation::NotOrthonormal(dev) => format!(
            "rotation {r:?} is not orthonormal (max |RᵀR − I| = {dev:.3e}, expected ≤ {:.0e}); \
             expected a rotation matrix, row-major, whose columns are the camera axes in CPF \
             coordinates",
            super::pose::ORTHONORMAL_TOLERANCE
        ),
        NotRotation::Reflection => format!(
            "rotation {r:?} is a reflection (determinant −1), expected a proper rotation \
             (determinant +1)"
        ),
    })?;
    Ok(Affine3 {
        matrix3: rotation,
        translation: t,
    })
}

/// The top level as `rig_to_json` writes it (same keys as [`RawRig`], typed cameras so the
/// key order stays readable).
#[derive(Serialize)]
struct WrittenRig<'a> {
    egogen_rig: u32,
    name: &'a str,
    #[serde(skip_serializing_if = "str::is_empty")]
    notes: &'a str,
    cameras: Vec<WrittenCamera<'a>>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    imus: Vec<WrittenImu<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    device_frame: Option<&'a str>,
}

#[derive(Serialize)]
struct WrittenImu<'a> {
    name: &'a str,
    rate_hz: Real,
    cpf_from_imu: RawPose,
    #[serde(skip_serializing_if = "Option::is_none")]
    calibration: Option<RawImuCalibration>,
}

#[derive(Serialize)]
struct WrittenCamera<'a> {
    name: &'a str,
    resolution_px: [i64; 2],
    model: RawModel,
    cpf_from_cam: RawPose,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    monochrome: bool,
}

/// The rig as an egogen rig document, pretty-printed (what `egogen rig convert` writes).
pub(super) fn rig_to_json(rig: &Rig) -> String {
    use crate::camera::CameraModel;
    let cameras = rig
        .cameras
        .iter()
        .map(|c| {
            let res = c.model.resolution();
            let model = match &c.model {
                Camera::Pinhole(m) => {
                    let [fx, fy, cx, cy] = m.params();
                    RawModel::Pinhole { fx, fy, cx, cy }
                }
                Camera::Fisheye624(m) => RawModel::Fisheye624 {
                    params: m.params().to_vec(),
                    max_theta_rad: Some(m.max_theta_rad()),
                    valid_radius_px: m.valid_radius_px(),
                },
                Camera::KannalaBrandt4(m) => {
                    let ([fx, fy, cx, cy], [k1, k2, k3, k4]) = m.params();
                    RawModel::KannalaBrandt4 {
                        fx,
                        fy,
                        cx,
                        cy,
                        k1,
                        k2,
                        k3,
                        k4,
                        max_theta_rad: Some(m.max_theta_rad()),
                    }
                }
            };
            WrittenCamera {
                name: &c.name,
                resolution_px: [res.width_px as i64, res.height_px as i64],
                model,
                cpf_from_cam: raw_pose(&c.cpf_from_cam),
                monochrome: c.monochrome,
            }
        })
        .collect();
    let mut text = serde_json::to_string_pretty(&WrittenRig {
        egogen_rig: FORMAT_VERSION,
        name: &rig.name,
        notes: &rig.notes,
        cameras,
        imus: rig
            .imus
            .iter()
            .map(|i| WrittenImu {
                name: &i.name,
                rate_hz: i.rate_hz,
                cpf_from_imu: raw_pose(&i.cpf_from_imu),
                calibration: (i.calibration != ImuCalibration::IDEAL)
                    .then(|| RawImuCalibration::from_calibration(&i.calibration)),
            })
            .collect(),
        device_frame: rig.device_frame.as_deref(),
    })
    .expect("a rig serialises");
    text = compact_number_arrays(&text);
    text.push('\n');
    text
}

fn raw_pose(pose: &Affine3) -> RawPose {
    RawPose {
        translation_m: pose.translation.to_array(),
        rotation: mat3_rows(pose.matrix3),
    }
}

/// Puts every array that holds only numbers on one line (`[1.0, 2.0, 3.0]`), so that
/// parameter lists and rotation rows read as rows. Skips string contents.
fn compact_number_arrays(pretty: &str) -> String {
    let bytes = pretty.as_bytes();
    let mut out: Vec<u8> = Vec::with_capacity(pretty.len());
    let mut i = 0;
    let mut in_string = false;
    while i < bytes.len() {
        let c = bytes[i];
        if in_string {
            if c == b'\\' {
                out.extend_from_slice(&bytes[i..i + 2]);
                i += 2;
                continue;
            }
            in_string = c != b'"';
        } else if c == b'"' {
            in_string = true;
        } else if c == b'[' {
            if let Some(len) = pretty[i + 1..].find(']') {
                let inner = &pretty[i + 1..i + 1 + len];
                let numeric = !inner.trim().is_empty()
                    && inner
                        .bytes()
                        .all(|b| b.is_ascii_digit() || b".-+eE, \n".contains(&b));
                if numeric {
                    let items: Vec<&str> = inner.split(',').map(str::trim).collect();
                    out.push(b'[');
                    out.extend_from_slice(items.join(", ").as_bytes());
                    out.push(b']');
                    i += len + 2;
                    continue;
                }
            }
        }
        out.push(c);
        i += 1;
    }
    // Only ASCII runs were rewritten, so the bytes are still UTF-8.
    String::from_utf8(out).expect("UTF-8 preserved")
}
