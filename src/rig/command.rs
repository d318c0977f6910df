//! `egogen rig …`: the command-line face of rigs (check, project, convert). Parsing and
//! printing only; the rig and camera logic lives in `rig` and `camera`.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Subcommand;

use super::pose::{axis_angle, YawPitchRoll};
use super::{AriaRgbResolution, Rig, RigCamera};
use crate::camera::{theta_of, Camera, CameraModel};
use crate::math::Vec3;

/// `egogen rig` subcommands.
#[derive(Subcommand, Debug)]
pub(crate) enum RigCommand {
    /// Validate a rig and print each camera's model, resolution, field of view and pose
    /// relative to the CPF.
    Check {
        /// Rig file (`camera_rigs/*.json`) or Aria device calibration JSON.
        rig: PathBuf,
        /// Read an Aria calibration's RGB camera at 1408×1408 instead of 2880×2880.
        #[arg(long)]
        aria_rgb_1408: bool,
    },
    /// Print the pixel of a camera-frame point (metres, OpenCV: x right, y down, z forward),
    /// or say it is outside the camera's valid field of view.
    #[command(allow_negative_numbers = true)]
    Project {
        rig: PathBuf,
        /// Camera name (see `egogen rig check`).
        #[arg(long)]
        camera: String,
        /// Point x (m, camera frame).
        x: f64,
        /// Point y (m).
        y: f64,
        /// Point z (m).
        z: f64,
        #[arg(long)]
        aria_rgb_1408: bool,
    },
    /// Write a rig (or an Aria device calibration) as an egogen rig file.
    Convert {
        rig: PathBuf,
        /// Output rig file (must not exist).
        #[arg(long)]
        out: PathBuf,
        /// Rig name to record (default: the input's name).
        #[arg(long)]
        name: Option<String>,
        #[arg(long)]
        aria_rgb_1408: bool,
    },
}

fn rgb(flag: bool) -> AriaRgbResolution {
    if flag {
        AriaRgbResolution::Rescaled1408
    } else {
        AriaRgbResolution::Full2880
    }
}

/// Runs one `egogen rig` subcommand, printing to `out`.
pub(crate) fn run_command(cmd: &RigCommand, out: &mut dyn Write) -> Result<()> {
    match cmd {
        RigCommand::Check { rig, aria_rgb_1408 } => {
            let rig = Rig::load_with(rig, rgb(*aria_rgb_1408))?;
            write_check(&rig, out)?;
        }
        RigCommand::Project {
            rig,
            camera,
            x,
            y,
            z,
            aria_rgb_1408,
        } => {
            let rig = Rig::load_with(rig, rgb(*aria_rgb_1408))?;
            let cam = rig.camera(camera)?;
            let p = Vec3::new(*x, *y, *z);
            if !p.is_finite() {
                bail!("the point ({x}, {y}, {z}) must be finite");
            }
            match cam.model.project(p) {
                Some(px) => writeln!(
                    out,
                    "{}: point ({x}, {y}, {z}) m -> pixel ({:.6}, {:.6})",
                    cam.name, px.x, px.y
                )?,
                None => writeln!(
                    out,
                    "{}: point ({x}, {y}, {z}) m is outside the valid field of view \
                     ({:.2}° from the optical axis; max θ {:.2}°, image {} x {} px{})",
                    cam.name,
                    theta_of(p).to_degrees(),
                    cam.model.max_theta_rad().to_degrees(),
                    cam.model.resolution().width_px,
                    cam.model.resolution().height_px,
                    match &cam.model {
                        Camera::Fisheye624(m) => m
                            .valid_radius_px()
                            .map(|r| format!(", valid radius {r} px"))
                            .unwrap_or_default(),
                        _ => String::new(),
                    }
                )?,
            }
        }
        RigCommand::Convert {
            rig,
            out: out_path,
            name,
            aria_rgb_1408,
        } => {
            crate::atomic_file::refuse_existing(out_path)?;
            let mut rig = Rig::load_with(rig, rgb(*aria_rgb_1408))?;
            if let Some(name) = name {
                rig.name = name.clone();
            }
            std::fs::write(out_path, rig.to_json())
                .with_context(|| format!("cannot write {}", out_path.display()))?;
            writeln!(
                out,
                "wrote {} ({} cameras)",
                out_path.display(),
                rig.cameras.len()
            )?;
        }
    }
    Ok(())
}

/// The `rig check` report.
pub(crate) fn write_check(rig: &Rig, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        out,
        "rig `{}` ({}): {} camera(s)",
        rig.name,
        rig.source.display(),
        rig.cameras.len()
    )?;
    writeln!(
        out,
        "frames: CPF x left, y up, z forward; cameras OpenCV x right, y down, z forward"
    )?;
    if !rig.notes.is_empty() {
        writeln!(out, "notes: {}", rig.notes)?;
    }
    for cam in &rig.cameras {
        writeln!(out)?;
        write_camera(cam, out)?;
    }
    Ok(())
}

fn write_camera(cam: &RigCamera, out: &mut dyn Write) -> std::io::Result<()> {
    let m = &cam.model;
    let res = m.resolution();
    let pp = m.principal_point();
    writeln!(out, "{}", cam.name)?;
    let intrinsics = match m {
        Camera::Pinhole(p) => {
            let [fx, fy, _, _] = p.params();
            format!("fx {fx:.4} px, fy {fy:.4} px")
        }
        Camera::Fisheye624(f) => {
            let p = f.params();
            let mut s = format!(
                "f {:.4} px, k0..k5 {:?}, p0 p1 {:?}, s0..s3 {:?}, max θ {:.2}°",
                p[0],
                &p[3..9],
                &p[9..11],
                &p[11..15],
                f.max_theta_rad().to_degrees()
            );
            if let Some(r) = f.valid_radius_px() {
                s += &format!(", valid radius {r} px");
            }
            s
        }
        Camera::KannalaBrandt4(k) => {
            let ([fx, fy, _, _], ks) = k.params();
            format!(
                "fx {fx:.4} px, fy {fy:.4} px, k1..k4 {ks:?}, max θ {:.2}°",
                k.max_theta_rad().to_degrees()
            )
        }
    };
    writeln!(out, "  model        {}", m.model_name())?;
    writeln!(
        out,
        "  intrinsics   {intrinsics}, principal point ({:.4}, {:.4}) px",
        pp.x, pp.y
    )?;
    writeln!(
        out,
        "  resolution   {} x {} px",
        res.width_px, res.height_px
    )?;
    let fov = m.fov();
    writeln!(
        out,
        "  fov          horizontal {:.2}°, vertical {:.2}°, diagonal {:.2}°",
        fov.horizontal_rad.to_degrees(),
        fov.vertical_rad.to_degrees(),
        fov.diagonal_rad.to_degrees()
    )?;
    let t = cam.cpf_from_cam.translation * 1000.0;
    writeln!(
        out,
        "  position     ({:.2}, {:.2}, {:.2}) mm in the CPF",
        t.x, t.y, t.z
    )?;
    let r = cam.cpf_from_cam.matrix3;
    let ypr = YawPitchRoll::of(r);
    let aa = axis_angle(r);
    writeln!(
        out,
        "  rotation     yaw {:.2}°, pitch {:.2}°, roll {:.2}° (from an upright camera looking \
         forward; + = left, up, clockwise); axis-angle ({:.6}, {:.6}, {:.6}) rad, {:.2}°",
        ypr.yaw_rad.to_degrees(),
        ypr.pitch_rad.to_degrees(),
        ypr.roll_rad.to_degrees(),
        aa.x,
        aa.y,
        aa.z,
        aa.length().to_degrees()
    )?;
    let z = r.z_axis;
    writeln!(
        out,
        "  optical axis ({:.4}, {:.4}, {:.4}) in the CPF",
        z.x, z.y, z.z
    )?;
    Ok(())
}
