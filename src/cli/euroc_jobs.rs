//! `egogen euroc export`: a rendered take and one of its wearers in, a EuRoC MAV folder out
//! (`export::euroc` writes it).

use std::path::PathBuf;

use anyhow::Result;

use crate::export::euroc::{export_euroc, EurocRequest};
use crate::rig::Rig;

/// What `egogen euroc export` was asked.
#[derive(Debug, Clone, clap::Args)]
pub struct EurocExportArgs {
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
pub fn euroc_export(args: &EurocExportArgs) -> Result<()> {
    let started = std::time::Instant::now();
    let rig_path = args
        .rig
        .clone()
        .unwrap_or_else(|| crate::paths::crate_root().join(super::resolve::DEFAULT_RIG));
    let rig = Rig::load(&rig_path)?;
    let written = export_euroc(&EurocRequest {
        take: &args.take,
        rig: &rig,
        wearer: args.wearer.as_deref(),
        out: &args.out,
        imu_errors: !args.ideal_imu,
        seed: args.seed,
    })?;
    for (k, cam) in written.cameras.iter().enumerate() {
        let lens = match cam.fit {
            Some(e) => format!(
                "KB4 fitted to its Fisheye624: max {:.4} px, mean {:.4} px over {} valid pixel centres",
                e.max_px, e.mean_px, e.samples
            ),
            None => "lens written exactly".into(),
        };
        eprintln!(
            "egogen euroc export: cam{k} = {} ({} images at {} Hz; {lens})",
            cam.name, cam.images, cam.rate_hz
        );
    }
    if let Some(note) = &written.note {
        eprintln!("egogen euroc export: {note}");
    }
    eprintln!(
        "egogen euroc export: imu0 = {} ({} samples at {} Hz), the body frame; ground truth at every sample",
        written.imu, written.imu_samples, written.imu_rate_hz
    );
    println!(
        "wrote {} ({} in {:.2} s)",
        args.out.display(),
        written.wearer,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
