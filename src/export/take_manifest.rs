//! A take's `manifest.json`: every file of the take with its size and SHA-256
//! (`crate::manifest`), written last, after every other output. Frame files and the files
//! outputs made of them are taken from the frames' records instead of hashed again.

use anyhow::Result;

use super::take::{FinishedTake, TakeExport};
use crate::manifest::write_manifest_with;

/// The take's manifest.
pub(crate) struct TakeManifest;

impl TakeExport for TakeManifest {
    fn name(&self) -> &'static str {
        "manifest"
    }

    fn finish(&self, take: &FinishedTake) -> Result<()> {
        write_manifest_with(take.folder, &take.recorded_files())?;
        Ok(())
    }
}
