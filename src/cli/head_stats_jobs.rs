//! `egogen motion head-stats`: how a head moves for take folders, AMASS-style clips and MPS
//! trajectories; the job is `export::head_stats`.

use std::path::{Path, PathBuf};

use anyhow::Result;

/// `egogen motion head-stats`: the head-motion statistics ([`crate::motion::head_motion`]) of
/// every source (take folders, clips or folders of clips, MPS trajectories), one JSON line
/// each, then a table; every record in `json` when given.
pub fn motion_head_stats(
    sources: &[PathBuf],
    model: &Path,
    rig: &Path,
    imu_rate_hz: f64,
    json: Option<&Path>,
) -> Result<()> {
    crate::export::head_stats::motion_head_stats(sources, model, rig, imu_rate_hz, json)
}
