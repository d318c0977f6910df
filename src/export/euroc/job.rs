//! `egogen euroc export`'s job: a rendered take and one of its wearers in, a EuRoC MAV folder
//! out ([`export_euroc`]), with what was written said on standard error. `cli::euroc_jobs`
//! parses the flags and resolves the default rig.

use std::path::PathBuf;

use anyhow::Result;

use super::{export_euroc, EurocRequest};
use crate::rig::Rig;

/// What `egogen euroc export` was asked, its rig resolved.
pub(crate) struct EurocExportJob {
    /// The take: an `egogen-run` dataset rendered with the colour pass.
    pub(crate) take: PathBuf,
    /// The new folder to write, `OUT/mav0/…` (must not exist, or be empty).
    pub(crate) out: PathBuf,
    /// The wearer to export (none: the take's only one).
    pub(crate) wearer: Option<String>,
    /// The rig the take was rendered with.
    pub(crate) rig: PathBuf,
    /// Ideal IMU readings: no noise, no bias.
    pub(crate) ideal_imu: bool,
    /// Seed of the IMU's noise and bias walk.
    pub(crate) seed: u64,
}

/// Runs `egogen euroc export`.
pub(crate) fn euroc_export(args: &EurocExportJob) -> Result<()> {
    let started = std::time::Instant::now();
    let rig = Rig::load(&args.rig)?;
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
