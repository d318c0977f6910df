//! `egogen motion hand-stats`: how the fingers of AMASS-style SMPL-X files and of takes'
//! people move; the job is `motion::jobs::motion_hand_stats`.

use std::path::{Path, PathBuf};

use anyhow::Result;

/// Prints each motion's finger statistics as a JSON line, then a table on standard error;
/// writes them all to `json` when given.
pub fn motion_hand_stats(sources: &[PathBuf], model: &Path, json: Option<&Path>) -> Result<()> {
    crate::motion::jobs::motion_hand_stats(sources, model, json)
}
