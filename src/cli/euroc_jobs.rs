//! `egogen euroc export`: its flags, and the default rig resolved; the job (a rendered take and
//! one of its wearers in, a EuRoC MAV folder out) is `export::euroc::job`.

use std::path::PathBuf;

use anyhow::Result;

use crate::export::euroc::job::EurocExportJob;

/// What `egogen euroc export` was asked.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct EurocExportArgs {
    /// The take: an `egogen-run` dataset rendered with the colour pass (its `sequence/`,
    /// `cameras/<camera>/annotations.json` and `images/<camera>/`).
    pub take: PathBuf,
    /// The new folder to write, `OUT/mav0/…` (must not exist, or be empty).
    #[arg(long)]
    pub out: PathBuf,
    /// The wearer to export (default: the take's only one).
    #[arg(long)]
    pub wearer: Option<String>,
    /// The rig the take was rendered with (default: the shipped Aria gen1 rig); its IMU is the
    /// body frame (imu-right, else its first), its SLAM cameras cam0 and cam1.
    #[arg(long)]
    pub rig: Option<PathBuf>,
    /// Ideal IMU readings: no noise, no bias.
    #[arg(long)]
    pub ideal_imu: bool,
    /// Seed of the IMU's noise and bias walk.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Runs `egogen euroc export`.
pub(crate) fn euroc_export(args: &EurocExportArgs) -> Result<()> {
    let rig = (args.rig.clone())
        .unwrap_or_else(|| crate::paths::crate_root().join(super::resolve::DEFAULT_RIG));
    crate::export::euroc::job::euroc_export(&EurocExportJob {
        take: args.take.clone(),
        out: args.out.clone(),
        wearer: args.wearer.clone(),
        rig,
        ideal_imu: args.ideal_imu,
        seed: args.seed,
    })
}
