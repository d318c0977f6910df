//! A wearer of a rendered take in the EuRoC MAV layout that VIO and SLAM tools read
//! (`egogen euroc export`; docs/ARIA.md "EuRoC export"):
//!
//! ```text
//! mav0/body.yaml                          the body frame B is imu0's frame S
//! mav0/cam0/{data.csv, data/<ns>.png, sensor.yaml}   the rig's first SLAM camera; cam1 the second
//! mav0/imu0/{data.csv, sensor.yaml}                  the rig's IMU (Aria: imu-right)
//! mav0/state_groundtruth_estimate0/{data.csv, sensor.yaml}   B's pose, velocity, IMU biases
//! ```
//!
//! Everything comes from the take as `egogen aria export` reads it (`take_folder`): the
//! wearer's head poses through the one headset spline (`aria::headset_spline`), the IMU
//! simulated by `imu` with the Aria gen1 error model (its noise figures go into
//! `imu0/sensor.yaml`), the cameras as the annotations record them, the images the COLMAP export
//! wrote (`images/<camera>/frame_NNNNN.png`), as 8-bit grey.
//!
//! Frames and conventions: the world R is the take's (metres, z up); B = S = the IMU's frame,
//! so imu0's `T_BS` is the identity and a camera's `T_BS` is `imu_from_cam` (OpenCV camera
//! frame), the same on every frame: the headset's offset on the head moves the IMU and the
//! cameras together. The ground truth is exactly the device's IMU pose, `world_from_cpf ·
//! cpf_from_headset · cpf_from_imu`, at every IMU sample. Time: frame `i` at `i /
//! frame_rate_hz`, in whole nanoseconds, from 0 (the Aria streams' clock). Pixels: OpenCV's
//! convention (the centre of the top-left pixel at (0, 0)) is egogen's, so intrinsics are
//! written as they are.
//!
//! The IMU's readings are the rectified ones (true specific force and rate plus white noise and
//! the bias random walk, saturated): EuRoC has no place for a device's own scale and
//! misalignment, so the rig's IMU calibration is not applied; the ground truth's biases are the
//! model's bias state at each sample (0 with ideal IMUs).
//!
//! `egogen euroc export`'s job, which says on standard error what was written, is `job`.

pub(crate) mod job;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::aria::{headset_spline, imu_seed};
use super::colmap::image_name;
use super::imu::{simulate_imu_with_biases, ImuErrors, ImuReading};
use super::take_folder::{read_rendered_cameras, read_take_heads, RenderedCamera};
use crate::atomic_file::{refuse_existing_folder, refuse_inside, StagedFolder};
use crate::camera::kannala_brandt::fit_kb4;
use crate::camera::{Camera, CameraModel, FitError};
use crate::math::{Affine3, Real};
use crate::rig::{ImuCalibration, Rig, RigImu};

/// The rig cameras EuRoC's `cam0` and `cam1` are, when a rig has them (Aria).
pub(crate) const SLAM_CAMERAS: [&str; 2] = ["camera-slam-left", "camera-slam-right"];
/// The rig IMU that is EuRoC's `imu0` when a rig has it (Aria's 1 kHz IMU).
pub(crate) const BODY_IMU: &str = "imu-right";

/// `cam0/data.csv`'s header.
pub const CAMERA_HEADER: &str = "#timestamp [ns],filename";
/// `imu0/data.csv`'s header.
pub const IMU_HEADER: &str = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],\
w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]";
/// `state_groundtruth_estimate0/data.csv`'s header.
pub const GROUND_TRUTH_HEADER: &str = "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], \
q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], \
v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], \
b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]";

/// The largest disagreement between a frame's `T_world_cam` and the IMU pose from the head
/// poses composed with the rig's extrinsics that an export accepts (m, and rad): rounding is
/// ~1e-15; more means the annotations and the head trajectory are not of one take.
const POSE_AGREEMENT: Real = 1e-6;

/// What `egogen euroc export` was asked.
#[derive(Debug, Clone)]
pub(crate) struct EurocRequest<'a> {
    /// A dataset rendered by `egogen-run` (its `sequence/`, `cameras/`, `images/`).
    pub take: &'a Path,
    /// The rig the take was rendered with: its IMU, and its cameras to check the take's by.
    pub rig: &'a Rig,
    /// The wearer to export; `None`: the take's only one.
    pub wearer: Option<&'a str>,
    /// The new folder (absent or empty).
    pub out: &'a Path,
    /// Simulate the IMU's noise and bias walk (`false`: ideal readings, zero biases).
    pub imu_errors: bool,
    /// Draws the IMU errors.
    pub seed: u64,
}

/// What was written.
#[derive(Debug, Clone)]
pub(crate) struct EurocWritten {
    pub wearer: String,
    /// The rig's IMU that is `imu0`.
    pub imu: String,
    pub imu_rate_hz: Real,
    pub imu_samples: usize,
    /// `cam0`, `cam1`… in order.
    pub cameras: Vec<EurocCamera>,
    /// Why fewer than two cameras were written, if so.
    pub note: Option<String>,
}

/// One camera as written.
#[derive(Debug, Clone)]
pub(crate) struct EurocCamera {
    /// Its name in the take.
    pub name: String,
    pub images: usize,
    pub rate_hz: Real,
    /// The KB4 fitted to a Fisheye624 and its error; `None` where the lens is written exactly.
    pub fit: Option<FitError>,
}

/// Writes the EuRoC export of `request` into `out.partial` and renames it to `out`; nothing is
/// left under either name when it fails.
pub(crate) fn export_euroc(request: &EurocRequest) -> Result<EurocWritten> {
    let out = request.out;
    refuse_existing_folder(out, "--out")?;
    refuse_inside(out, "--out", request.take, "the take")?;
    let plan = plan_export(request)?;
    // A `.partial` left by a killed export holds only what an export writes (`mav0/`).
    let staged = StagedFolder::begin(out, "--out", "an EuRoC export", |name, is_dir| {
        is_dir && name == "mav0"
    })?;
    let written = write_export(&staged.path().join("mav0"), request, &plan)?;
    staged.finish()?;
    Ok(written)
}

/// What an export will write, every input found and checked before anything is.
struct Plan<'a> {
    wearer: String,
    imu: &'a RigImu,
    /// `cam0`, `cam1`… with their images' paths.
    cameras: Vec<(RenderedCamera, Vec<PathBuf>)>,
    note: Option<String>,
    frame_rate_hz: Real,
    world_from_cpf: Vec<Affine3>,
    cpf_from_headset: Affine3,
}

fn plan_export<'a>(request: &EurocRequest<'a>) -> Result<Plan<'a>> {
    let (take, rig) = (request.take, request.rig);
    if !take.is_dir() {
        bail!("take {}: not a folder", take.display());
    }
    let rendered = read_rendered_cameras(take)?;
    if rendered.is_empty() {
        bail!(
            "take {}: no rendered cameras (cameras/<camera>/annotations.json); an EuRoC export \
             needs a dataset rendered by egogen-run with the colour pass",
            take.display()
        );
    }
    let mut wearers: Vec<&str> = Vec::new();
    for c in &rendered {
        if !wearers.contains(&c.wearer.as_str()) {
            wearers.push(&c.wearer);
        }
    }
    let wearer = match request.wearer {
        Some(w) if wearers.contains(&w) => w.to_string(),
        Some(w) => bail!(
            "--wearer {w}: no camera of take {} is worn by `{w}`; its wearers are {}",
            take.display(),
            wearers.join(", ")
        ),
        None if wearers.len() == 1 => wearers[0].to_string(),
        None => bail!(
            "take {} has {} wearers ({}); choose one with --wearer",
            take.display(),
            wearers.len(),
            wearers.join(", ")
        ),
    };
    let imu = rig
        .imus
        .iter()
        .find(|i| i.name == BODY_IMU)
        .or(rig.imus.first())
        .with_context(|| {
            format!(
                "rig {} has no IMU, and EuRoC's body frame is its IMU's; pass --rig with the rig \
                 the take was rendered with, with its IMUs (camera_rigs/aria_gen1.json has \
                 imu-left and imu-right; a rig file lists them under `imus`)",
                rig.source.display()
            )
        })?;
    // The rig's stereo pair: its SLAM cameras (Aria), else its first two cameras.
    let slam: Vec<&str> = SLAM_CAMERAS
        .iter()
        .copied()
        .filter(|n| rig.cameras.iter().any(|c| c.name == *n))
        .collect();
    let names: Vec<&str> = if slam.is_empty() {
        rig.cameras
            .iter()
            .take(2)
            .map(|c| c.name.as_str())
            .collect()
    } else {
        slam
    };
    let note = (names.len() == 1).then(|| {
        format!(
            "rig {} has one camera for EuRoC (`{}`): cam0 only, no cam1",
            rig.source.display(),
            names[0]
        )
    });
    let of_wearer: Vec<&RenderedCamera> = rendered.iter().filter(|c| c.wearer == wearer).collect();
    let mut cameras = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let prefixed = format!("{wearer}_{name}");
        let Some(cam) = of_wearer
            .iter()
            .find(|c| c.camera.name == *name || c.camera.name == prefixed)
        else {
            bail!(
                "take {} did not render camera `{name}` of rig {} on {wearer}, which is EuRoC's \
                 cam{k} (cam0, cam1: {}); it rendered {}. Render it too (`[render] cameras`), \
                 or pass --rig with the rig the take was rendered with",
                take.display(),
                rig.source.display(),
                names.join(", "),
                of_wearer
                    .iter()
                    .map(|c| format!("`{}`", c.camera.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        };
        let in_rig = rig.camera(name)?;
        let off = pose_difference(in_rig.cpf_from_cam, cam.camera.cpf_from_cam);
        if off > POSE_AGREEMENT {
            bail!(
                "camera `{}` of take {} sits {off:.2e} (m or rad) away from where rig {} places \
                 it ({}); pass --rig with the rig the take was rendered with",
                cam.camera.name,
                take.display(),
                rig.source.display(),
                cam.source.display()
            );
        }
        if cam.frames.is_empty() {
            bail!("{}: no frames", cam.source.display());
        }
        let images = camera_images(take, cam)?;
        cameras.push(((*cam).clone(), images));
    }
    let (wanted, heads) = read_take_heads(take, std::slice::from_ref(&wearer))?;
    let head = heads
        .into_iter()
        .nth(wanted[0])
        .context("the wearer's head poses")?;
    Ok(Plan {
        wearer,
        imu,
        cameras,
        note,
        frame_rate_hz: head.frame_rate_hz,
        world_from_cpf: head.world_from_cpf,
        cpf_from_headset: head.cpf_from_headset,
    })
}

/// The colour images of a rendered camera, each checked to be there at the calibrated size.
fn camera_images(take: &Path, cam: &RenderedCamera) -> Result<Vec<PathBuf>> {
    let images_dir = take.join("images").join(&cam.camera.name);
    let mut images = Vec::new();
    for &(frame, _) in &cam.frames {
        let path = images_dir.join(image_name(frame));
        if !path.is_file() {
            bail!(
                "{} is missing: an EuRoC export copies the colour images the COLMAP export \
                 writes (render with the `colour` pass and `[render] colmap`, the default \
                 with colour)",
                path.display()
            );
        }
        let size = png_size(&path)?;
        let res = CameraModel::resolution(&cam.camera.model);
        let calibrated = (res.width_px, res.height_px);
        if size != calibrated {
            bail!(
                "{} is {}×{} pixels, but camera `{}`'s calibration (and so sensor.yaml) is \
                 {}×{}: the take's images are not this camera's (nothing was written)",
                path.display(),
                size.0,
                size.1,
                cam.camera.name,
                calibrated.0,
                calibrated.1
            );
        }
        images.push(path);
    }
    Ok(images)
}

/// The larger of the translation (m) and rotation (rad) between two poses.
fn pose_difference(a: Affine3, b: Affine3) -> Real {
    let d = a.inverse() * b;
    let angle = crate::math::matrix_to_axis_angle(d.matrix3).length();
    angle.max(d.translation.length())
}

/// A frame's time on the export's clock (ns): frame `i` at `i / frame_rate_hz`.
fn frame_time_ns(frame: u32, frame_rate_hz: Real) -> i64 {
    (frame as Real * 1e9 / frame_rate_hz).round() as i64
}

fn write_export(mav0: &Path, request: &EurocRequest, plan: &Plan) -> Result<EurocWritten> {
    let rig = request.rig;
    let spline = headset_spline(
        &plan.wearer,
        plan.frame_rate_hz,
        &plan.world_from_cpf,
        plan.cpf_from_headset,
    )?;
    let imu = plan.imu;
    let errors = ImuErrors::aria_gen1(&imu.name);
    let imu_index = rig
        .imus
        .iter()
        .position(|i| i.name == imu.name)
        .unwrap_or(0);
    let readings = simulate_imu_with_biases(
        &spline,
        imu.cpf_from_imu,
        imu.rate_hz,
        request.imu_errors.then_some((
            &errors,
            &ImuCalibration::IDEAL,
            imu_seed(request.seed, 0, imu_index),
        )),
    );
    let put = |rel: &str, bytes: &[u8]| -> Result<()> {
        let path = mav0.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        std::fs::write(&path, bytes).with_context(|| format!("writing {}", path.display()))
    };
    let take = request.take.display();
    put(
        "body.yaml",
        format!(
            "# egogen: take {take}, wearer {}. The body frame B is the frame S of imu0 (rig \
             {}'s `{}`): imu0's T_BS is the identity, each camera's T_BS is imu_from_camera, \
             and state_groundtruth_estimate0 is B's pose in the world R (the take's: metres, z \
             up).\ncomment: \"body frame = imu0 ({})\"\n",
            plan.wearer,
            rig.source.display(),
            imu.name,
            imu.name
        )
        .as_bytes(),
    )?;
    put("imu0/data.csv", imu_csv(&readings).as_bytes())?;
    put(
        "imu0/sensor.yaml",
        imu_sensor_yaml(imu, &errors, request.imu_errors).as_bytes(),
    )?;
    put(
        "state_groundtruth_estimate0/data.csv",
        ground_truth_csv(&spline, imu.cpf_from_imu, &readings).as_bytes(),
    )?;
    put(
        "state_groundtruth_estimate0/sensor.yaml",
        format!(
            "# egogen: the pose of the body frame B (imu0) in the take's world R, its velocity \
             in R and imu0's biases, at every imu0 sample; exactly the device's IMU pose \
             (world_from_cpf · cpf_from_headset · cpf_from_imu), not an estimate.\n\
             sensor_type: visual-inertial\ncomment: \"egogen ground truth of {}\"\n{}",
            plan.wearer,
            t_bs_yaml(Affine3::IDENTITY)
        )
        .as_bytes(),
    )?;
    let mut cameras = Vec::new();
    for (k, (cam, images)) in plan.cameras.iter().enumerate() {
        let imu_from_cam = imu.cpf_from_imu.inverse() * cam.camera.cpf_from_cam;
        check_camera_poses(cam, &spline, imu.cpf_from_imu, imu_from_cam)?;
        let mut csv = String::from(CAMERA_HEADER);
        csv.push('\n');
        for (&(frame, _), src) in cam.frames.iter().zip(images) {
            let ns = frame_time_ns(frame, cam.frame_rate_hz);
            let bytes = std::fs::read(src).with_context(|| format!("reading {}", src.display()))?;
            let grey = grey_png(&bytes).with_context(|| format!("{}", src.display()))?;
            put(&format!("cam{k}/data/{ns}.png"), &grey)?;
            let _ = writeln!(csv, "{ns},{ns}.png");
        }
        put(&format!("cam{k}/data.csv"), csv.as_bytes())?;
        let step = match cam.frames.as_slice() {
            [a, b, ..] => b.0.saturating_sub(a.0).max(1),
            _ => 1,
        };
        let rate_hz = cam.frame_rate_hz / step as Real;
        let (yaml, fit) = camera_sensor_yaml(cam, imu, imu_from_cam, rate_hz, &plan.wearer)?;
        put(&format!("cam{k}/sensor.yaml"), yaml.as_bytes())?;
        cameras.push(EurocCamera {
            name: cam.camera.name.clone(),
            images: images.len(),
            rate_hz,
            fit,
        });
    }
    Ok(EurocWritten {
        wearer: plan.wearer.clone(),
        imu: imu.name.clone(),
        imu_rate_hz: imu.rate_hz,
        imu_samples: readings.len(),
        cameras,
        note: plan.note.clone(),
    })
}

/// Every rendered frame's `T_world_cam` must be the IMU's pose on the spline times
/// `imu_from_cam`: the annotations and the head poses are of one take.
fn check_camera_poses(
    cam: &RenderedCamera,
    spline: &crate::math::pose_spline::PoseSpline,
    headset_from_imu: Affine3,
    imu_from_cam: Affine3,
) -> Result<()> {
    for &(frame, world_from_cam) in &cam.frames {
        let t = frame as Real / cam.frame_rate_hz;
        if t > spline.duration_s() + 1e-9 {
            bail!(
                "{}: frame {frame} is at {t} s, after the wearer's head poses end ({} s)",
                cam.source.display(),
                spline.duration_s()
            );
        }
        let world_from_imu = spline.sample(t).attached(headset_from_imu).world_from_body;
        let off = pose_difference(world_from_imu * imu_from_cam, world_from_cam);
        if off > POSE_AGREEMENT {
            bail!(
                "{}: frame {frame}: T_world_cam is {off:.2e} (m or rad) off the wearer's head \
                 pose composed with the rig's extrinsics; the annotations and the head \
                 trajectory are not of one take",
                cam.source.display()
            );
        }
    }
    Ok(())
}

/// A PNG as 8-bit grey: grey as it is; colour by OpenCV's `RGB2GRAY` weights (0.299, 0.587,
/// 0.114), which leave a grey image stored as RGB (a monochrome camera's) unchanged.
/// A PNG's width and height, from its header.
fn png_size(path: &Path) -> Result<(u32, u32)> {
    let file = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .with_context(|| format!("{}: not a PNG", path.display()))?;
    let info = reader.info();
    Ok((info.width, info.height))
}

fn grey_png(bytes: &[u8]) -> Result<Vec<u8>> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().context("not a PNG")?;
    let size = reader
        .output_buffer_size()
        .context("PNG too large to decode")?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).context("decoding the PNG")?;
    if info.bit_depth != png::BitDepth::Eight {
        bail!(
            "a {:?}-bit PNG; expected 8-bit (egogen's images are)",
            info.bit_depth
        );
    }
    let data = &buf[..info.buffer_size()];
    let channels = info.color_type.samples();
    let grey: Vec<u8> = match channels {
        1 | 2 => data.chunks_exact(channels).map(|p| p[0]).collect(),
        _ => data
            .chunks_exact(channels)
            .map(|p| {
                let (r, g, b) = (p[0] as u32, p[1] as u32, p[2] as u32);
                ((299 * r + 587 * g + 114 * b + 500) / 1000) as u8
            })
            .collect(),
    };
    let mut encoded = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut encoded, info.width, info.height);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().context("encoding the grey PNG")?;
        w.write_image_data(&grey).context("encoding the grey PNG")?;
    }
    Ok(encoded)
}

fn imu_csv(readings: &[ImuReading]) -> String {
    let mut text = String::with_capacity(readings.len() * 140 + 200);
    text.push_str(IMU_HEADER);
    text.push('\n');
    for r in readings {
        let (w, a) = (r.sample.gyro, r.sample.accel);
        let _ = writeln!(
            text,
            "{},{},{},{},{},{},{}",
            r.sample.timestamp_ns, w.x, w.y, w.z, a.x, a.y, a.z
        );
    }
    text
}

/// The IMU's pose, velocity and biases at each of its samples.
fn ground_truth_csv(
    spline: &crate::math::pose_spline::PoseSpline,
    headset_from_imu: Affine3,
    readings: &[ImuReading],
) -> String {
    let mut text = String::with_capacity(readings.len() * 340 + 400);
    text.push_str(GROUND_TRUTH_HEADER);
    text.push('\n');
    let mut last_q: Option<glam::DQuat> = None;
    for r in readings {
        let ns = r.sample.timestamp_ns;
        let s = spline.sample(ns as Real * 1e-9).attached(headset_from_imu);
        let p = s.world_from_body.translation;
        let mut q = glam::DQuat::from_mat3(&s.world_from_body.matrix3).normalize();
        // One hemisphere along the stream, so the quaternions read as a smooth curve.
        if last_q.is_some_and(|l| l.dot(q) < 0.0) {
            q = -q;
        }
        last_q = Some(q);
        let v = s.velocity_world;
        // `+ 0.0` writes a bias that is −0 (a zero draw times −1) as 0.
        let (bw, ba) = (r.gyro_bias + 0.0, r.accel_bias + 0.0);
        let _ = writeln!(
            text,
            "{ns},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            p.x, p.y, p.z, q.w, q.x, q.y, q.z, v.x, v.y, v.z, bw.x, bw.y, bw.z, ba.x, ba.y, ba.z
        );
    }
    text
}

/// A number as YAML reads a float (PyYAML wants a dot: `1` is an integer, `1e-5` a string).
fn yaml_float(v: Real) -> String {
    let s = format!("{v}");
    if s.contains('.') || !v.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

fn yaml_list(values: &[Real]) -> String {
    let items: Vec<String> = values.iter().map(|v| yaml_float(*v)).collect();
    format!("[{}]", items.join(", "))
}

/// `T_BS` as EuRoC writes it: a 4×4 row-major matrix.
fn t_bs_yaml(body_from_sensor: Affine3) -> String {
    let m = crate::math::row_major(body_from_sensor);
    let rows: Vec<String> = m
        .iter()
        .map(|r| {
            r.iter()
                .map(|v| yaml_float(*v))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect();
    format!(
        "T_BS:\n  cols: 4\n  rows: 4\n  data: [{},\n         {},\n         {},\n         {}]\n",
        rows[0], rows[1], rows[2], rows[3]
    )
}

fn imu_sensor_yaml(imu: &RigImu, errors: &ImuErrors, imu_errors: bool) -> String {
    let readings = if imu_errors {
        "the rectified readings of this model: true specific force and rate, white noise, the \
         bias random walk, saturation (the device's own scale and misalignment are not applied)"
    } else {
        "ideal readings (--ideal-imu: no noise, no bias); the figures are the model's, for \
         estimators that need them"
    };
    let (g, a) = (&errors.gyroscope, &errors.accelerometer);
    format!(
        "# egogen: the rig's `{name}` as imu0, the body frame (T_BS = identity). Noise figures: \
         egogen's Aria gen1 error model of {name} (export::imu, docs/ARIA.md); data.csv holds \
         {readings}.\nsensor_type: imu\ncomment: \"egogen {name}\"\n\n\
         # Sensor extrinsics wrt. the body-frame.\n{t_bs}rate_hz: {rate}\n\n\
         # inertial sensor noise model parameters (static)\n\
         gyroscope_noise_density: {gn}     # [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )\n\
         gyroscope_random_walk: {gw}       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )\n\
         accelerometer_noise_density: {an} # [ m / s^2 / sqrt(Hz) ]  ( accel \"white noise\" )\n\
         accelerometer_random_walk: {aw}   # [ m / s^3 / sqrt(Hz) ]  ( accel bias diffusion )\n",
        name = imu.name,
        t_bs = t_bs_yaml(Affine3::IDENTITY),
        rate = yaml_float(imu.rate_hz),
        gn = yaml_float(g.noise_density),
        gw = yaml_float(g.bias_random_walk),
        an = yaml_float(a.noise_density),
        aw = yaml_float(a.bias_random_walk),
    )
}

/// A camera's `sensor.yaml` and, for a Fisheye624, its KB4 fit's error.
fn camera_sensor_yaml(
    cam: &RenderedCamera,
    imu: &RigImu,
    imu_from_cam: Affine3,
    rate_hz: Real,
    wearer: &str,
) -> Result<(String, Option<FitError>)> {
    let model = &cam.camera.model;
    let res = CameraModel::resolution(model);
    let (intrinsics, distortion, coefficients, lens, fit) = match model {
        Camera::Pinhole(m) => {
            let p = m.params();
            (
                p,
                "radial-tangential",
                [0.0; 4],
                "a pinhole, written exactly (no distortion)".to_string(),
                None,
            )
        }
        Camera::KannalaBrandt4(m) => {
            let (p, k) = m.params();
            (
                p,
                "equidistant",
                k,
                "Kannala–Brandt (KB4), written exactly".to_string(),
                None,
            )
        }
        Camera::Fisheye624(_) => {
            let (kb4, err) = fit_kb4(model)
                .with_context(|| format!("fitting a KB4 to camera `{}`", cam.camera.name))?;
            let (p, k) = kb4.params();
            (
                p,
                "equidistant",
                k,
                format!(
                    "Fisheye624 (Project Aria), which KB4 cannot hold exactly: the KB4 below is \
                     fitted to it over its valid field of view (θ ≤ {:.4} rad), off by max \
                     {:.4} px, mean {:.4} px over its {} valid pixel centres",
                    kb4.max_theta_rad(),
                    err.max_px,
                    err.mean_px,
                    err.samples
                ),
                Some(err),
            )
        }
    };
    let yaml = format!(
        "# egogen: camera `{name}` worn by {wearer}. Lens: {lens}.\n\
         # Pixels: OpenCV's convention (centre of the top-left pixel at (0, 0)), which is egogen's.\n\
         # T_BS: imu_from_camera (body = imu0 = the rig's `{imu}`; camera frame x right, y down, z forward).\n\
         sensor_type: camera\ncomment: \"egogen {name}\"\n\n\
         # Sensor extrinsics wrt. the body-frame.\n{t_bs}\n\
         # Camera specific definitions.\nrate_hz: {rate}\nresolution: [{w}, {h}]\n\
         camera_model: pinhole\nintrinsics: {intr} # fu, fv, cu, cv\n\
         distortion_model: {distortion}\ndistortion_coefficients: {coef}\n",
        name = cam.camera.name,
        imu = imu.name,
        t_bs = t_bs_yaml(imu_from_cam),
        rate = yaml_float(rate_hz),
        w = res.width_px,
        h = res.height_px,
        intr = yaml_list(&intrinsics),
        coef = yaml_list(&coefficients),
    );
    Ok((yaml, fit))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The KB4 written for the shipped Aria cameras at full size (measured: SLAM left max
    /// 1.647 / mean 0.529 px, SLAM right 0.784 / 0.229 px, RGB 0.982 / 0.213 px; at
    /// `resolution_scale = 1/16` a sixteenth of that). Their tangential and thin-prism terms
    /// are what KB4 lacks: without them the radial part fits to 0.04 px (SLAM) and 0.55 px
    /// (RGB).
    #[test]
    fn aria_cameras_fit_kb4_to_about_a_pixel() {
        let rig = Rig::load(Path::new("camera_rigs/aria_gen1.json")).unwrap();
        for cam in &rig.cameras {
            let (_, err) = fit_kb4(&cam.model).unwrap();
            let (max, mean) = match cam.name.as_str() {
                "camera-slam-left" => (1.7, 0.55),
                "camera-slam-right" => (0.8, 0.24),
                _ => (1.0, 0.22),
            };
            assert!(
                err.max_px < max && err.mean_px < mean,
                "{}: {err:?}",
                cam.name
            );
        }
    }

    #[test]
    fn yaml_numbers_read_as_floats() {
        assert_eq!(yaml_float(1.0), "1.0");
        assert_eq!(yaml_float(-2.0), "-2.0");
        assert_eq!(yaml_float(2.5e-6), "0.0000025");
        assert_eq!(yaml_list(&[1.0, 0.5]), "[1.0, 0.5]");
    }

    #[test]
    fn a_colour_png_turns_grey_by_opencv_weights_and_a_grey_one_stays() {
        let encode = |color: png::ColorType, data: &[u8]| {
            let mut out = Vec::new();
            let mut enc = png::Encoder::new(&mut out, 2, 1);
            enc.set_color(color);
            enc.set_depth(png::BitDepth::Eight);
            enc.write_header().unwrap().write_image_data(data).unwrap();
            out
        };
        let decode = |bytes: &[u8]| {
            let mut r = png::Decoder::new(std::io::Cursor::new(bytes))
                .read_info()
                .unwrap();
            let mut buf = vec![0; r.output_buffer_size().unwrap()];
            let info = r.next_frame(&mut buf).unwrap();
            assert_eq!(info.color_type, png::ColorType::Grayscale);
            buf[..info.buffer_size()].to_vec()
        };
        let rgb = encode(png::ColorType::Rgb, &[7, 7, 7, 255, 0, 0]);
        assert_eq!(decode(&grey_png(&rgb).unwrap()), vec![7, 76]);
        let grey = encode(png::ColorType::Grayscale, &[3, 250]);
        assert_eq!(decode(&grey_png(&grey).unwrap()), vec![3, 250]);
        assert!(grey_png(b"not a png").is_err());
    }
}
