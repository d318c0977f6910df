//! `egogen inspect`: EXR files' channels and statistics printed, and a PNG contact sheet of
//! their passes; the job is `inspect::report`.

use std::path::{Path, PathBuf};

use anyhow::Result;

/// Prints every file's parts, passes and channel statistics (only the pass `only`, when
/// given) and, with `preview`, writes one sheet of their tiles; `exposure` is `none`, `auto`
/// or stops.
pub fn inspect_exr(
    files: &[PathBuf],
    preview: Option<&Path>,
    only: Option<&str>,
    exposure: &str,
) -> Result<()> {
    crate::inspect::report::inspect_exr(files, preview, only, exposure)
}
