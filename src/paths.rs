//! Where egogen finds the files it ships (scenes, rigs, weights, Blender scripts): the folder
//! named by `EGOGEN_HOME`, else the crate's own folder.

use std::path::PathBuf;

/// The folder shipped files are found under.
pub fn crate_root() -> PathBuf {
    std::env::var_os("EGOGEN_HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}
