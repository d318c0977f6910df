//! Camera rigs: which cameras a head-mounted device carries and where they sit relative to
//! the eye anchor (CPF), read from rig files (`camera_rigs/*.json`) or from a Project Aria
//! device calibration; `world_from_cam = world_from_cpf · cpf_from_cam`. Projection
//! itself belongs to `camera`; the CPF of a posed body to `body::cpf`.
//!
//! Here: `file` (egogen's own rig file: parsed, validated, written back), `aria` (Project Aria
//! device calibrations read as rigs), `error` (what can go wrong reading a rig), `pose` (camera
//! poses relative to the CPF: rotation checks and the yaw/pitch/roll read-out), `wear` (each
//! wearer's small rigid offset of the headset), `command` (`egogen rig check|project|convert`).
//!
//! Frames: CPF x = wearer's left, y = up, z = forward; cameras are OpenCV (x right, y down,
//! z forward). The file schema is documented in `docs/RIGS.md`.

pub(crate) mod aria;
pub(crate) mod command;
mod error;
mod file;
pub(crate) mod pose;
pub mod wear;

use std::path::{Path, PathBuf};

use crate::camera::Camera;
use crate::math::{Affine3, Mat3, Real, Vec3};

pub(crate) use aria::aria_build_of_device;
pub use aria::AriaRgbResolution;
pub(crate) use command::{run_command, RigCommand};
pub use error::RigError;
pub(crate) use file::FORMAT_VERSION;

/// One camera of a rig.
#[derive(Debug, Clone, PartialEq)]
pub struct RigCamera {
    /// Unique within the rig (e.g. `camera-rgb`).
    pub name: String,
    pub model: Camera,
    /// Maps camera-frame (OpenCV) points into the CPF.
    pub cpf_from_cam: Affine3,
    /// A monochrome sensor (Aria SLAM, HoloLens VLC): its colour is stored as one grey channel.
    pub monochrome: bool,
}

/// A validated rig.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    pub name: String,
    /// Provenance and caveats, free text.
    pub notes: String,
    /// The file it was read from (used in messages).
    pub source: PathBuf,
    /// In file order.
    pub cameras: Vec<RigCamera>,
    /// Inertial sensors, in file order (none for most rigs).
    pub imus: Vec<RigImu>,
    /// The sensor (camera or IMU) whose frame is the device frame, the frame a device
    /// trajectory and a device calibration are expressed in (Aria: `camera-slam-left`);
    /// `None`: the first camera.
    pub device_frame: Option<String>,
}

/// An inertial measurement unit on a rig.
#[derive(Debug, Clone, PartialEq)]
pub struct RigImu {
    /// Unique among the rig's cameras and IMUs (e.g. `imu-right`).
    pub name: String,
    /// Samples per second.
    pub rate_hz: Real,
    /// Maps IMU-frame points into the CPF.
    pub cpf_from_imu: Affine3,
    /// The device's own calibration of this IMU (identity for a perfect sensor).
    pub calibration: ImuCalibration,
}

/// A device's calibration of an IMU, projectaria-tools' linear model per sensor:
/// `raw = M · rectified + bias` (so `rectified = M⁻¹ (raw − bias)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuCalibration {
    /// `M` of the accelerometer (scale and misalignment).
    pub accel_rectification: Mat3,
    /// Accelerometer bias (m/s²).
    pub accel_bias: Vec3,
    /// `M` of the gyroscope.
    pub gyro_rectification: Mat3,
    /// Gyroscope bias (rad/s).
    pub gyro_bias: Vec3,
}

impl ImuCalibration {
    /// A perfect sensor: identity, no bias.
    pub(crate) const IDEAL: ImuCalibration = ImuCalibration {
        accel_rectification: Mat3::IDENTITY,
        accel_bias: Vec3::ZERO,
        gyro_rectification: Mat3::IDENTITY,
        gyro_bias: Vec3::ZERO,
    };
}

impl Default for ImuCalibration {
    fn default() -> Self {
        Self::IDEAL
    }
}

impl Rig {
    /// Reads a rig file or an Aria device calibration (recognised by its `CameraCalibrations`
    /// key; its RGB camera keeps the full 2880×2880 sensor size).
    pub fn load(path: &Path) -> Result<Self, RigError> {
        Self::load_with(path, AriaRgbResolution::default())
    }

    /// [`Rig::load`] choosing the RGB size for Aria calibrations.
    pub fn load_with(path: &Path, aria_rgb: AriaRgbResolution) -> Result<Self, RigError> {
        let text = std::fs::read_to_string(path).map_err(|source| RigError::Read {
            path: path.into(),
            source,
        })?;
        Self::from_json_str(path, &text, aria_rgb)
    }

    /// Parses rig JSON; `path` is only used in messages.
    pub fn from_json_str(
        path: &Path,
        text: &str,
        aria_rgb: AriaRgbResolution,
    ) -> Result<Self, RigError> {
        let value = parse_json(path, text)?;
        if !value.is_object() {
            return Err(RigError::field(
                path,
                "top level",
                "expected a JSON object: an egogen rig (key `egogen_rig`) or a Project Aria \
                 device calibration (key `CameraCalibrations`)",
            ));
        }
        if aria::is_aria_calibration(&value) {
            aria::rig_from_aria_value(path, value, aria_rgb)
        } else {
            file::rig_from_value(path, value)
        }
    }

    /// The camera called `name`, or an error listing the names there are.
    pub fn camera(&self, name: &str) -> Result<&RigCamera, RigError> {
        self.cameras
            .iter()
            .find(|c| c.name == name)
            .ok_or_else(|| RigError::UnknownCamera {
                path: self.source.clone(),
                name: name.into(),
                available: self.camera_names().join(", "),
            })
    }

    /// Maps device-frame points into the CPF: the pose of [`Rig::device_frame`]'s sensor.
    pub fn cpf_from_device(&self) -> Affine3 {
        let name = self.device_frame_name();
        self.cameras
            .iter()
            .find(|c| c.name == name)
            .map(|c| c.cpf_from_cam)
            .or_else(|| {
                self.imus
                    .iter()
                    .find(|i| i.name == name)
                    .map(|i| i.cpf_from_imu)
            })
            .unwrap_or(Affine3::IDENTITY)
    }

    /// The name of the sensor whose frame is the device frame.
    pub fn device_frame_name(&self) -> &str {
        self.device_frame
            .as_deref()
            .unwrap_or(self.cameras[0].name.as_str())
    }

    /// Camera names in file order.
    pub fn camera_names(&self) -> Vec<&str> {
        self.cameras.iter().map(|c| c.name.as_str()).collect()
    }

    /// This rig as an egogen rig file (pretty JSON); loading it gives the same rig back.
    pub fn to_json(&self) -> String {
        file::rig_to_json(self)
    }
}

impl RigCamera {
    /// Pose of this camera in the world for a head whose CPF is at `world_from_cpf`.
    pub fn world_from_cam(&self, world_from_cpf: Affine3) -> Affine3 {
        world_from_cpf * self.cpf_from_cam
    }
}

/// Parses JSON text, turning the NaN / Infinity tokens that some writers emit into an error
/// that names the field.
fn parse_json(path: &Path, text: &str) -> Result<serde_json::Value, RigError> {
    serde_json::from_str(text).map_err(|e| {
        if let Some((token, field)) = non_finite_token(text, e.line(), e.column()) {
            RigError::NonFinite {
                path: path.into(),
                line: e.line(),
                column: e.column(),
                field,
                token,
            }
        } else {
            RigError::Syntax {
                path: path.into(),
                message: e.to_string(),
            }
        }
    })
}

/// If the syntax error at (line, column), both 1-based, sits on a `NaN` / `Infinity` / `inf`
/// token, that token and the last key before it.
fn non_finite_token(text: &str, line: usize, column: usize) -> Option<(String, String)> {
    let line_start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    let line_text = text[line_start..].lines().next().unwrap_or("");
    let chars: Vec<char> = line_text.chars().collect();
    let at = column.saturating_sub(1).min(chars.len().saturating_sub(1));
    let is_tok = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '+' || c == '.';
    let mut start = at;
    while start > 0 && is_tok(chars[start - 1]) {
        start -= 1;
    }
    let mut end = at;
    while end < chars.len() && is_tok(chars[end]) {
        end += 1;
    }
    let token: String = chars.get(start..end)?.iter().collect();
    let bare = token.trim_start_matches(['-', '+']).to_ascii_lowercase();
    if !matches!(bare.as_str(), "nan" | "infinity" | "inf") {
        return None;
    }
    // The key: the last `"…"` followed by `:` before the token.
    let byte_offset = line_start + chars[..start].iter().map(|c| c.len_utf8()).sum::<usize>();
    let before = &text[..byte_offset];
    let colon = before.rfind(':')?;
    let key_end = before[..colon].rfind('"')?;
    let key_start = before[..key_end].rfind('"')? + 1;
    Some((token, before[key_start..key_end].to_string()))
}
