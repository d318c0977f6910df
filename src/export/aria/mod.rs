//! A wearer's take as a Project Aria recording's machine-perception outputs, in the formats
//! projectaria-tools reads (docs/ARIA.md): the device trajectory
//! (`slam/closed_loop_trajectory.csv`, `mps.read_closed_loop_trajectory`), the calibration
//! (`slam/online_calibration.jsonl`, `mps.read_online_calibration`; `device_calibration.json`,
//! `calibration.device_calibration_from_json`, for rigs on an Aria device frame) and the IMU
//! streams (`imu/<label>.csv`), and where the wearer looks (`eye_gaze/general_eye_gaze.csv`,
//! `mps.read_eyegaze`; a model: `export::gaze`) and the wearer's hands
//! (`hand_tracking/hand_tracking_results.csv`, `mps.hand_tracking.read_hand_tracking_results`:
//! 21 landmarks per hand from the body, `body::hand_landmarks`; written by `hands`). Every
//! stream is sampled from one C² spline through the wearer's head poses (`math::pose_spline`),
//! so positions, velocities, accelerations and the IMUs agree with each other; the trajectory
//! passes through every head pose exactly.
//!
//! Time: the device clock starts at the take's frame 0 (`tracking_timestamp_us = 0`); frame
//! `i` is at `i / frame_rate_hz`. There is no wall clock (`utc_timestamp_ns = -1`, as MPS
//! writes when it has none).
//!
//! `egogen aria export`'s job, a finished take's folder in and its wearers' streams out, is
//! `job`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Context, Result};
use serde_json::json;

mod hands;
pub(crate) mod job;

use super::gaze::{eye_gaze_csv, fixations, gaze_samples, Fixation, GazeGoal, GazeWorld};
use super::imu::{sample_times_ns, simulate_imu, ImuErrors, ImuSample, GRAVITY_WORLD};
use super::take::{FinishedTake, TakeExport};
use crate::atomic_file::write_atomically;
use crate::body::hand_landmarks::HandLandmarks;
use crate::camera::Camera;
use crate::math::pose_spline::PoseSpline;
use crate::math::{mat3_rows, Affine3, Real};
use crate::rig::{aria_build_of_device, ImuCalibration, Rig};
use crate::scene::mesh_distance::SceneRays;
pub(crate) use hands::hand_tracking_csv;

/// Which streams to write; each is off unless asked.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AriaStreams {
    pub trajectory: bool,
    pub calibration: bool,
    pub imu: bool,
    pub gaze: bool,
    pub hands: bool,
}

impl AriaStreams {
    /// Names as configs and the command line spell them.
    pub(crate) const NAMES: [&'static str; 5] =
        ["trajectory", "calibration", "imu", "gaze", "hands"];

    /// The streams named in `names`, or an error naming the unknown one.
    pub(crate) fn parse<S: AsRef<str>>(names: &[S]) -> Result<Self, String> {
        let mut s = AriaStreams::default();
        for n in names {
            match n.as_ref() {
                "trajectory" => s.trajectory = true,
                "calibration" => s.calibration = true,
                "imu" => s.imu = true,
                "gaze" => s.gaze = true,
                "hands" => s.hands = true,
                other => {
                    return Err(format!(
                        "unknown stream `{other}`, expected any of {}",
                        Self::NAMES.join(", ")
                    ))
                }
            }
        }
        Ok(s)
    }

    pub(crate) fn any(&self) -> bool {
        self.trajectory || self.calibration || self.imu || self.gaze || self.hands
    }
}

/// How the streams are made.
#[derive(Debug, Clone, PartialEq)]
pub struct AriaSettings {
    pub streams: AriaStreams,
    /// Rows per second of the device trajectory (MPS: 1 kHz).
    pub trajectory_rate_hz: Real,
    /// The IMUs' errors (noise, bias, the device's calibration, saturation); `false`: ideal
    /// sensors, and an identity calibration written.
    pub imu_errors: bool,
    /// Errors per IMU name; IMUs not named get [`ImuErrors::aria_gen1`] of their label.
    pub imu_error_overrides: BTreeMap<String, ImuErrors>,
    /// Draws the IMU errors (with the wearer and IMU index).
    pub seed: u64,
    /// An `online_calibration.jsonl` line every this many seconds (MPS writes about 1 Hz).
    pub calibration_every_s: Real,
    /// Eye gaze samples per second (Aria's eye-tracking cameras run at 10–90 Hz).
    pub gaze_rate_hz: Real,
}

impl Default for AriaSettings {
    fn default() -> Self {
        AriaSettings {
            streams: AriaStreams::default(),
            trajectory_rate_hz: 1000.0,
            imu_errors: true,
            imu_error_overrides: BTreeMap::new(),
            seed: 0,
            calibration_every_s: 1.0,
            gaze_rate_hz: 30.0,
        }
    }
}

/// Highest trajectory rate accepted (Hz): one row per microsecond, the format's resolution.
pub(crate) const MAX_TRAJECTORY_RATE_HZ: Real = 1e6;

impl AriaSettings {
    /// Why these settings cannot be used with `rig`, naming the key, or `None`.
    pub(crate) fn problem(&self, rig: &Rig) -> Option<String> {
        let r = self.trajectory_rate_hz;
        if !(r.is_finite() && r > 0.0 && r <= MAX_TRAJECTORY_RATE_HZ) {
            return Some(format!(
                "trajectory_rate_hz = {r}: expected Hz in (0, {MAX_TRAJECTORY_RATE_HZ}]"
            ));
        }
        let g = self.gaze_rate_hz;
        if !(g.is_finite() && g > 0.0 && g <= MAX_TRAJECTORY_RATE_HZ) {
            return Some(format!(
                "gaze_rate_hz = {g}: expected Hz in (0, {MAX_TRAJECTORY_RATE_HZ}]"
            ));
        }
        let c = self.calibration_every_s;
        if !(c.is_finite() && c > 0.0) {
            return Some(format!("calibration_every_s = {c}: expected seconds > 0"));
        }
        if self.streams.imu && rig.imus.is_empty() {
            return Some(format!(
                "streams: `imu` asked, but rig {} has no IMUs (camera_rigs/aria_gen1.json has \
                 imu-left and imu-right; a rig file lists them under `imus`)",
                rig.source.display()
            ));
        }
        for (name, e) in &self.imu_error_overrides {
            if !rig.imus.iter().any(|i| &i.name == name) {
                return Some(format!(
                    "imu.{name}: rig {} has no IMU `{name}`; it has {}",
                    rig.source.display(),
                    rig.imus
                        .iter()
                        .map(|i| i.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
            if let Some(p) = e.problem() {
                return Some(format!("imu.{name}.{p}"));
            }
        }
        if self.streams.calibration {
            if let Some(cam) = rig
                .cameras
                .iter()
                .find(|c| matches!(c.model, Camera::Pinhole(_)))
            {
                return Some(format!(
                    "streams: `calibration` asked, but camera `{}` of rig {} is a pinhole, which \
                     projectaria-tools' calibration JSON cannot express (it reads \
                     FisheyeRadTanThinPrism, Fisheye62 and KannalaBrandtK3 cameras)",
                    cam.name,
                    rig.source.display()
                ));
            }
        }
        None
    }

    /// The error model of `rig`'s IMU `name` (label) in this run.
    pub(crate) fn imu_errors_of(&self, name: &str) -> ImuErrors {
        self.imu_error_overrides
            .get(name)
            .copied()
            .unwrap_or_else(|| ImuErrors::aria_gen1(name))
    }
}

/// One wearer's head through the take, and what it may look at.
#[derive(Clone)]
pub(crate) struct Wearer<'a> {
    pub name: &'a str,
    /// Its index among the take's wearers (it seeds the IMU errors).
    pub index: usize,
    pub frame_rate_hz: Real,
    /// `world_from_cpf` per frame (world z up, metres).
    pub world_from_cpf: &'a [Affine3],
    /// How the headset sits on this head (identity: as the rig says).
    pub cpf_from_headset: Affine3,
    /// The other agents' eyes (`world_from_cpf` per frame), for the gaze.
    pub others: Vec<&'a [Affine3]>,
    /// The wearer's goals in order, for the gaze.
    pub goals: Vec<GazeGoal>,
    /// What its activities act on, for the gaze.
    pub looks: Vec<crate::synth::activity::LookAt>,
    /// The scene, for gaze depths.
    pub rays: Option<&'a SceneRays>,
    /// Both hands' landmarks on every frame, in the world (when the hands are asked).
    pub hands: Option<&'a [[HandLandmarks; 2]]>,
}

/// The Aria streams as a take's output (`[render.aria]`): each wearer's streams into
/// `aria/<wearer>/` when the take is finished, from the bodies' head poses; built in
/// `aria.partial/` and renamed, and kept as they are when a resumed run finds them.
pub(crate) struct AriaExport {
    pub settings: AriaSettings,
    /// The agents wearing the rig, in order.
    pub wearers: Vec<AriaWearer>,
    /// The scene, for gaze depths (when the gaze is asked).
    pub rays: Option<SceneRays>,
}

/// An agent wearing the rig, as its streams need it beside its head poses.
#[derive(Debug, Clone)]
pub(crate) struct AriaWearer {
    /// Index into the take's agents.
    pub agent: usize,
    /// Where it walks, in order (the gaze looks ahead to it).
    pub goals: Vec<GazeGoal>,
    /// What its activities act on (the gaze looks at it while it acts).
    pub looks: Vec<crate::synth::activity::LookAt>,
    /// How the headset sits on its head.
    pub cpf_from_headset: Affine3,
    /// Both hands' landmarks on every frame, in the world (when the hands are asked).
    pub hands: Option<Vec<[HandLandmarks; 2]>>,
}

impl TakeExport for AriaExport {
    fn name(&self) -> &'static str {
        "Aria streams"
    }

    fn finish(&self, take: &FinishedTake) -> Result<()> {
        let dir = take.folder.join("aria");
        if dir.is_dir() {
            return Ok(());
        }
        let partial = take.folder.join("aria.partial");
        if partial.exists() {
            std::fs::remove_dir_all(&partial).with_context(|| {
                format!("removing {}, left by an interrupted run", partial.display())
            })?;
        }
        let eyes: Vec<Vec<Affine3>> = take
            .agents
            .iter()
            .map(|a| a.track.frames.iter().map(|f| f.world_from_cpf).collect())
            .collect();
        for (index, w) in self.wearers.iter().enumerate() {
            let agent = &take.agents[w.agent];
            let wearer = Wearer {
                name: &agent.name,
                index,
                frame_rate_hz: agent.motion.frame_rate_hz,
                world_from_cpf: &eyes[w.agent],
                cpf_from_headset: w.cpf_from_headset,
                others: (0..take.agents.len())
                    .filter(|&k| k != w.agent)
                    .map(|k| eyes[k].as_slice())
                    .collect(),
                goals: w.goals.clone(),
                looks: w.looks.clone(),
                rays: self.rays.as_ref(),
                hands: w.hands.as_deref(),
            };
            let written = write_wearer_streams(
                &partial.join(&agent.name),
                take.rig,
                &self.settings,
                &wearer,
            )?;
            eprintln!(
                "egogen-run: Aria streams of {}: {} files ({} trajectory rows, {} IMU samples)",
                agent.name,
                written.files.len(),
                written.trajectory_rows,
                written.imu_samples
            );
            if let Some(note) = written.device_calibration_note {
                eprintln!("egogen-run: {note}");
            }
        }
        std::fs::rename(&partial, &dir)
            .with_context(|| format!("renaming {} to {}", partial.display(), dir.display()))
    }
}

/// What was written for a wearer.
#[derive(Debug, Clone, Default)]
pub(crate) struct AriaWritten {
    /// Paths relative to the wearer's folder, with their sizes.
    pub files: Vec<(String, u64)>,
    pub trajectory_rows: usize,
    pub imu_samples: usize,
    /// Largest angle between a head pose and the spline's at its time (rad).
    pub spline_residual_rad: Real,
    /// Why `device_calibration.json` was not written, when `calibration` was asked.
    pub device_calibration_note: Option<String>,
    /// The gaze's fixations, when `gaze` was asked.
    pub fixations: Vec<Fixation>,
}

/// The headset's trajectory through a wearer's head poses (`world_from_cpf` at
/// `frame_rate_hz`, the headset at `cpf_from_headset` on the head): the one spline every
/// stream of a device on that head is sampled from.
pub(crate) fn headset_spline(
    name: &str,
    frame_rate_hz: Real,
    world_from_cpf: &[Affine3],
    cpf_from_headset: Affine3,
) -> Result<PoseSpline> {
    let poses: Vec<Affine3> = world_from_cpf
        .iter()
        .map(|p| *p * cpf_from_headset)
        .collect();
    PoseSpline::interpolate(frame_rate_hz, &poses)
        .with_context(|| format!("splining the head poses of {name}"))
}

/// Writes the asked streams of `wearer` into `dir` (created; each file written atomically).
pub(crate) fn write_wearer_streams(
    dir: &Path,
    rig: &Rig,
    settings: &AriaSettings,
    wearer: &Wearer,
) -> Result<AriaWritten> {
    if let Some(p) = settings.problem(rig) {
        bail!("aria streams: {p}");
    }
    let spline = headset_spline(
        wearer.name,
        wearer.frame_rate_hz,
        wearer.world_from_cpf,
        wearer.cpf_from_headset,
    )?;
    let cpf_from_device = rig.cpf_from_device();
    let mut out = AriaWritten {
        spline_residual_rad: spline.rotation_residual_rad(),
        ..Default::default()
    };
    let mut put = |rel: &str, bytes: &[u8]| -> Result<()> {
        let path = dir.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        write_atomically(&path, bytes).with_context(|| format!("writing {}", path.display()))?;
        out.files.push((rel.to_string(), bytes.len() as u64));
        Ok(())
    };
    let mut rows = 0;
    if settings.streams.trajectory {
        let (text, n) = closed_loop_trajectory_csv(
            &spline,
            cpf_from_device,
            settings.trajectory_rate_hz,
            wearer.name,
        );
        rows = n;
        put("slam/closed_loop_trajectory.csv", text.as_bytes())?;
    }
    let mut note = None;
    if settings.streams.calibration {
        let line = calibration_json(rig, settings.imu_errors);
        let mut text = String::new();
        for us in calibration_times_us(spline.duration_s(), settings.calibration_every_s) {
            let mut l = line.clone();
            l["tracking_timestamp_us"] = json!(us);
            l["utc_timestamp_ns"] = json!(-1);
            text.push_str(&serde_json::to_string(&l)?);
            text.push('\n');
        }
        put("slam/online_calibration.jsonl", text.as_bytes())?;
        match aria_build_of_device(cpf_from_device) {
            Some(build) if rig.device_frame_name() == "camera-slam-left" => {
                let mut device = line;
                device["DeviceClassInfo"] = json!({"DeviceClass": "Aria", "BuildVersion": build});
                device["OriginSpecification"] =
                    json!({"Type": "Custom", "ChildLabel": "camera-slam-left"});
                put(
                    "device_calibration.json",
                    serde_json::to_string_pretty(&device)?.as_bytes(),
                )?;
            }
            _ => {
                note = Some(format!(
                    "device_calibration.json not written: projectaria-tools places the CPF by an \
                     Aria build's CAD pose of camera-slam-left, and rig {}'s device frame `{}` \
                     is not at one",
                    rig.source.display(),
                    rig.device_frame_name()
                ));
            }
        }
    }
    let mut samples = 0;
    if settings.streams.imu {
        for (k, imu) in rig.imus.iter().enumerate() {
            let head_from_imu = imu.cpf_from_imu;
            let errors = settings.imu_errors_of(&imu.name);
            let seed = imu_seed(settings.seed, wearer.index, k);
            let stream = simulate_imu(
                &spline,
                head_from_imu,
                imu.rate_hz,
                settings
                    .imu_errors
                    .then_some((&errors, &imu.calibration, seed)),
            );
            samples += stream.len();
            put(
                &format!("imu/{}.csv", imu.name),
                imu_csv(&stream).as_bytes(),
            )?;
        }
    }
    if settings.streams.gaze {
        let world = GazeWorld {
            head: &spline,
            others: wearer.others.clone(),
            frame_rate_hz: wearer.frame_rate_hz,
            goals: &wearer.goals,
            looks: &wearer.looks,
            rays: wearer.rays,
        };
        let fixations = fixations(&world, gaze_seed(settings.seed, wearer.index));
        let samples = gaze_samples(&world, &fixations, settings.gaze_rate_hz);
        put(
            "eye_gaze/general_eye_gaze.csv",
            eye_gaze_csv(&samples, &session_uid(wearer.name)).as_bytes(),
        )?;
        out.fixations = fixations;
    }
    if settings.streams.hands {
        let Some(hands) = wearer.hands else {
            bail!(
                "aria streams: hands asked for {}, whose body is not known",
                wearer.name
            );
        };
        put(
            "hand_tracking/hand_tracking_results.csv",
            hand_tracking_csv(&spline, cpf_from_device, wearer.frame_rate_hz, hands).as_bytes(),
        )?;
    }
    out.trajectory_rows = rows;
    out.imu_samples = samples;
    out.device_calibration_note = note;
    Ok(out)
}

/// The seed of a wearer's gaze: the run's seed and the wearer (apart from the IMUs').
fn gaze_seed(seed: u64, wearer: usize) -> u64 {
    imu_seed(seed, wearer, 0xFFFF)
}

/// A name as MPS CSV text fields take it: no commas, quotes or spaces.
fn session_uid(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The seed of one IMU's errors: the run's seed, the wearer, the IMU.
pub(crate) fn imu_seed(seed: u64, wearer: usize, imu: usize) -> u64 {
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((wearer as u64) << 16)
        .wrapping_add(imu as u64)
}

/// The header of the MPS closed-loop trajectory (projectaria-tools' `TrajectoryFormat.h`).
pub(crate) const CLOSED_LOOP_HEADER: &str = "graph_uid,tracking_timestamp_us,utc_timestamp_ns,\
tx_world_device,ty_world_device,tz_world_device,qx_world_device,qy_world_device,qz_world_device,\
qw_world_device,device_linear_velocity_x_device,device_linear_velocity_y_device,\
device_linear_velocity_z_device,angular_velocity_x_device,angular_velocity_y_device,\
angular_velocity_z_device,gravity_x_world,gravity_y_world,gravity_z_world,quality_score";

/// The device trajectory as MPS writes it, one row per whole microsecond nearest to
/// `k / rate_hz`; returns the text and the number of rows.
pub fn closed_loop_trajectory_csv(
    spline: &PoseSpline,
    head_from_device: Affine3,
    rate_hz: Real,
    graph: &str,
) -> (String, usize) {
    let times_ns = sample_times_ns(rate_hz, spline.duration_s());
    let graph_uid: String = graph
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut text = String::with_capacity(times_ns.len() * 320 + 400);
    text.push_str(CLOSED_LOOP_HEADER);
    text.push('\n');
    let mut last_q: Option<glam::DQuat> = None;
    let mut last_us = i64::MIN;
    let mut rows = 0;
    for ns in times_ns {
        let us = (ns + 500) / 1000;
        if us == last_us {
            continue;
        }
        last_us = us;
        let s = spline.sample(us as Real * 1e-6).attached(head_from_device);
        let r = s.world_from_body.matrix3;
        let t = s.world_from_body.translation;
        let mut q = glam::DQuat::from_mat3(&r).normalize();
        // One hemisphere along the stream, so the quaternions read as a smooth curve.
        if last_q.is_some_and(|p| p.dot(q) < 0.0) {
            q = -q;
        }
        last_q = Some(q);
        let v = r.transpose() * s.velocity_world;
        let w = s.angular_velocity_body;
        let g = GRAVITY_WORLD;
        let _ = writeln!(
            text,
            "{graph_uid},{us},-1,{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},1",
            t.x, t.y, t.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z, g.x, g.y, g.z
        );
        rows += 1;
    }
    (text, rows)
}

/// Times of the calibration lines (µs): from 0 every `every_s`, and the take's end.
fn calibration_times_us(duration_s: Real, every_s: Real) -> Vec<i64> {
    let mut times: Vec<i64> = sample_times_ns(1.0 / every_s, duration_s)
        .into_iter()
        .map(|ns| (ns + 500) / 1000)
        .collect();
    let end = (duration_s * 1e6).round() as i64;
    if times.last() != Some(&end) {
        times.push(end);
    }
    times
}

/// `{"tracking_timestamp_us": 0, "utc_timestamp_ns": -1, "CameraCalibrations": […],
/// "ImuCalibrations": […]}` of the rig, every pose relative to the device frame. With
/// `imu_errors` off the IMUs' calibrations are the identity (the streams are ideal).
pub(crate) fn calibration_json(rig: &Rig, imu_errors: bool) -> serde_json::Value {
    let device_from_cpf = rig.cpf_from_device().inverse();
    let cameras: Vec<serde_json::Value> = rig
        .cameras
        .iter()
        .filter_map(|c| {
            use crate::camera::CameraModel;
            let (name, params): (&str, Vec<Real>) = match &c.model {
                Camera::Fisheye624(m) => ("FisheyeRadTanThinPrism", m.params().to_vec()),
                Camera::KannalaBrandt4(m) => {
                    let (f, k) = m.params();
                    ("KannalaBrandtK3", f.iter().chain(&k).copied().collect())
                }
                Camera::Pinhole(_) => return None,
            };
            let res = c.model.resolution();
            let mut config = json!({
                "ImageWidth": res.width_px,
                "ImageHeight": res.height_px,
                "MaxSolidAngle": c.model.max_theta_rad(),
            });
            if let Camera::Fisheye624(m) = &c.model {
                if let Some(r) = m.valid_radius_px() {
                    config["ValidRadius"] = json!(r);
                }
            }
            Some(json!({
                "Calibrated": true,
                "Label": c.name,
                "SerialNumber": "",
                "Projection": {"Name": name, "Params": params, "Description": ""},
                "T_Device_Camera": se3_json(device_from_cpf * c.cpf_from_cam),
                "ConfigData": config,
            }))
        })
        .collect();
    let imus: Vec<serde_json::Value> = rig
        .imus
        .iter()
        .map(|i| {
            let c = if imu_errors {
                i.calibration
            } else {
                ImuCalibration::IDEAL
            };
            json!({
                "Calibrated": true,
                "Label": i.name,
                "SerialNumber": "",
                "Accelerometer": {
                    "TimeOffsetSec_Device_Accel": 0.0,
                    "Bias": {"Name": "Constant", "Offset": c.accel_bias.to_array()},
                    "Model": {"Name": "UpperTriagonalLinear", "RectificationMatrix": mat3_rows(c.accel_rectification)},
                },
                "Gyroscope": {
                    "TimeOffsetSec_Device_Gyro": 0.0,
                    "Bias": {"Name": "Constant", "Offset": c.gyro_bias.to_array()},
                    "Model": {
                        "Name": "LinearGSensitivity",
                        "RectificationMatrix": mat3_rows(c.gyro_rectification),
                        "GSensitivityMatrix": [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
                    },
                },
                "T_Device_Imu": se3_json(device_from_cpf * i.cpf_from_imu),
            })
        })
        .collect();
    json!({
        "tracking_timestamp_us": 0,
        "utc_timestamp_ns": -1,
        "CameraCalibrations": cameras,
        "ImuCalibrations": imus,
    })
}

/// A projectaria-tools SE(3): `Translation` (m) and `UnitQuaternion` `[w, [x, y, z]]`.
fn se3_json(pose: Affine3) -> serde_json::Value {
    let q = glam::DQuat::from_mat3(&pose.matrix3).normalize();
    json!({
        "Translation": pose.translation.to_array(),
        "UnitQuaternion": [q.w, [q.x, q.y, q.z]],
    })
}

/// The IMU CSV header: device time (ns), specific force (m/s²) and angular rate (rad/s) in the
/// IMU frame, raw as the device reports them.
pub(crate) const IMU_HEADER: &str = "tracking_timestamp_ns,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2,\
gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s";

fn imu_csv(stream: &[ImuSample]) -> String {
    let mut text = String::with_capacity(stream.len() * 140 + 100);
    text.push_str(IMU_HEADER);
    text.push('\n');
    for s in stream {
        let _ = writeln!(
            text,
            "{},{},{},{},{},{},{}",
            s.timestamp_ns, s.accel.x, s.accel.y, s.accel.z, s.gyro.x, s.gyro.y, s.gyro.z
        );
    }
    text
}
