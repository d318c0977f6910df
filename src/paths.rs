//! Where egogen finds the files it ships (scenes, rigs, weights, Blender scripts, the furniture
//! catalogue): the folder named by `EGOGEN_HOME`, else the crate's own folder; and where it
//! keeps what it makes on first use (Blender, generated dwellings): its cache.

use std::path::PathBuf;

/// The folder shipped files are found under.
pub(crate) fn crate_root() -> PathBuf {
    std::env::var_os("EGOGEN_HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}

/// The cache: `$EGOGEN_CACHE`, else `$XDG_CACHE_HOME/egogen`, else `~/.cache/egogen`.
pub fn cache_dir() -> PathBuf {
    if let Some(p) = std::env::var_os("EGOGEN_CACHE").filter(|p| !p.is_empty()) {
        return PathBuf::from(p);
    }
    if let Some(p) = std::env::var_os("XDG_CACHE_HOME").filter(|p| !p.is_empty()) {
        return PathBuf::from(p).join("egogen");
    }
    let home = std::env::var_os("HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("."));
    home.join(".cache/egogen")
}
