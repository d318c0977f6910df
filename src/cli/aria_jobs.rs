//! `egogen aria export`: its flags, and the default rig and body model resolved; the job (a
//! finished take in, each wearer's Aria streams out) is `export::aria::job`.

use std::path::PathBuf;

use anyhow::Result;

use crate::export::aria::job::AriaExportJob;

/// What `egogen aria export` was asked.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct AriaExportArgs {
    /// The take: a folder written by `egogen synth`, `egogen-run` without `[render]`, or an
    /// `egogen-run` dataset (its `sequence/` is read, and each camera's headset offset).
    pub take: PathBuf,
    /// The device: an egogen rig or an Aria device calibration JSON (default: the shipped
    /// Aria gen1 rig, with imu-left and imu-right).
    #[arg(long)]
    pub rig: Option<PathBuf>,
    /// The new folder to write (must not exist): `OUT/<wearer>/…` and `OUT/manifest.json`.
    #[arg(long)]
    pub out: PathBuf,
    /// Streams to write (comma-separated): trajectory, calibration, imu, gaze, hands (the
    /// hands: each wearer's 21 landmarks per hand from its body, docs/HANDS.md).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "trajectory,calibration,imu,gaze"
    )]
    pub streams: Vec<String>,
    /// Agents that wear the device (repeat or comma-separate); default: a dataset's wearers,
    /// else every agent of the take.
    #[arg(long, value_delimiter = ',')]
    pub wearer: Vec<String>,
    /// Rows per second of the device trajectory.
    #[arg(long, default_value_t = 1000.0)]
    pub trajectory_rate_hz: f64,
    /// Ideal IMUs: no noise, no bias, no saturation, an identity calibration.
    #[arg(long)]
    pub ideal_imu: bool,
    /// Seed of the IMU errors and the gaze.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Eye gaze samples per second.
    #[arg(long, default_value_t = 30.0)]
    pub gaze_rate_hz: f64,
    /// SMPL-X `.npz` model the take's bodies are posed with for the hands (default: the
    /// shipped CC0 neutral model).
    #[arg(long)]
    pub model: Option<PathBuf>,
}

impl AriaExportArgs {
    /// The job these flags ask for: the rig and the body model default to the shipped ones.
    fn job(&self) -> AriaExportJob {
        let root = crate::paths::crate_root();
        AriaExportJob {
            take: self.take.clone(),
            rig: (self.rig.clone()).unwrap_or_else(|| root.join("camera_rigs/aria_gen1.json")),
            out: self.out.clone(),
            streams: self.streams.clone(),
            wearer: self.wearer.clone(),
            trajectory_rate_hz: self.trajectory_rate_hz,
            ideal_imu: self.ideal_imu,
            seed: self.seed,
            gaze_rate_hz: self.gaze_rate_hz,
            model: (self.model.clone())
                .unwrap_or_else(|| root.join("assets/body/SMPLX_NEUTRAL.npz")),
        }
    }
}

/// Runs `egogen aria export`.
pub(crate) fn aria_export(args: &AriaExportArgs) -> Result<()> {
    crate::export::aria::job::aria_export(&args.job())
}
