//! Every output of a take beside its frame files, in one place. Two kinds:
//! - made from a finished take through one seam, [`take::TakeExport`] (`take`: what a take is
//!   to its outputs; [`take_exports`] lists them): the per-camera annotations (`annotate`
//!   writes them, `annotations` is the file's types), the COLMAP export (`colmap`), the
//!   Project Aria streams (`aria`) and, last, the manifest (`take_manifest`);
//! - the models the Aria streams are made with: what a device on a wearer's head would have
//!   recorded (`aria`: device trajectory, calibration, IMU and eye gaze in the formats
//!   projectaria-tools reads), built on the IMU measurement and error model (`imu`) and the
//!   gaze model (`gaze`); each a function of the wearer's head poses and the rig, none reading
//!   images (`egogen aria` makes them of a finished dataset too; `aria_tests`, tests only:
//!   the IMU, spline and gaze models against the motion they come from);
//! - exports of a finished take's folder, read back by `take_folder`: the Aria streams
//!   (`egogen aria export`) and a wearer in the EuRoC MAV layout for VIO/SLAM tools (`euroc`:
//!   SLAM camera images, the IMU, the device's ground truth).
//!
//! Also `egogen motion head-stats`' job (`head_stats`): how a head moves in takes, clips and
//! MPS trajectories, with the IMU computed as the exports compute theirs.

pub(crate) mod annotate;
pub mod annotations;
pub mod aria;
#[cfg(test)]
mod aria_tests;
pub mod colmap;
pub mod euroc;
pub(crate) mod gaze;
pub(crate) mod head_stats;
pub mod imu;
pub(crate) mod take;
pub(crate) mod take_folder;
pub(crate) mod take_manifest;

pub(crate) use take::{FinishedTake, TakeExport, TakeExports};

/// A take's outputs in the order they are written: its annotations, its COLMAP export when
/// `colmap` (`[render] colmap`), the Aria streams when asked (`[render.aria]`), and last its
/// manifest (which lists what the others wrote).
pub(crate) fn take_exports(colmap: bool, aria: Option<aria::AriaExport>) -> TakeExports {
    let mut list: Vec<Box<dyn TakeExport>> = vec![Box::new(annotate::Annotations)];
    if colmap {
        list.push(Box::new(colmap::Colmap));
    }
    if let Some(aria) = aria {
        list.push(Box::new(aria));
    }
    list.push(Box::new(take_manifest::TakeManifest));
    TakeExports::new(list)
}
