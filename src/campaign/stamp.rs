//! What a campaign remembers of a finished take so that `--resume` need not read it again:
//! the size and modification time of every file its manifest lists, and the manifest's own
//! SHA-256, taken when the take was finished (its checksums then came from the bytes in
//! memory) or when a resume verified it in full. A later `--resume` compares only these (one
//! `stat` per file and a listing of the folder) and verifies in full — every checksum, every
//! frame file opened — a take whose files changed, or every take with `--rehash`. Kept in
//! `work/stamps/<take>.json` (scratch of the campaign).

use std::path::{Path, PathBuf};
use std::time::UNIX_EPOCH;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use crate::manifest::{dataset_files, sha256_hex, Manifest, MANIFEST};

/// A finished take's files as they were when it was stamped.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) struct TakeStamp {
    /// SHA-256 of the take's `manifest.json`.
    pub manifest_sha256: String,
    /// Every file the manifest lists, in its order: `[path, bytes, modified (ns since the
    /// epoch)]`.
    pub files: Vec<(String, u64, u128)>,
}

/// Where a take's stamp is kept.
pub(crate) fn stamp_path(campaign: &Path, take: &str) -> PathBuf {
    campaign.join("work/stamps").join(format!("{take}.json"))
}

/// The take folder `dir` as it is now, if it has a readable manifest.
fn stamp_of(dir: &Path) -> Result<TakeStamp> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
    let manifest: Manifest = serde_json::from_slice(&text)
        .with_context(|| format!("{}: not an egogen manifest", path.display()))?;
    let files = manifest
        .files
        .iter()
        .map(|e| {
            let p = dir.join(&e.path);
            let meta = std::fs::metadata(&p).with_context(|| format!("reading {}", p.display()))?;
            let modified = meta
                .modified()
                .ok()
                .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
                .map_or(0, |d| d.as_nanos());
            Ok((e.path.clone(), meta.len(), modified))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(TakeStamp {
        manifest_sha256: sha256_hex(&text),
        files,
    })
}

/// Stamps a finished, checked take: its files as they are now.
pub fn write_stamp(campaign: &Path, take: &str, dir: &Path) -> Result<()> {
    let stamp = stamp_of(dir)?;
    let path = stamp_path(campaign, take);
    let parent = path.parent().unwrap_or(campaign);
    std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    crate::atomic_file::write_atomically(&path, &serde_json::to_vec(&stamp)?)
        .with_context(|| format!("writing {}", path.display()))
}

/// Whether the take in `dir` is as it was stamped: the same manifest, every file it lists at
/// the size and modification time recorded, and no other file in the folder. `false` when
/// there is no stamp or anything differs (then the take is verified in full).
pub fn stamp_matches(campaign: &Path, take: &str, dir: &Path) -> bool {
    let Ok(text) = std::fs::read(stamp_path(campaign, take)) else {
        return false;
    };
    let Ok(kept) = serde_json::from_slice::<TakeStamp>(&text) else {
        return false;
    };
    let Ok(now) = stamp_of(dir) else {
        return false;
    };
    if now != kept {
        return false;
    }
    // A file added beside the listed ones is not in the manifest: verify says so.
    dataset_files(dir).is_ok_and(|listed| {
        listed.len() == kept.files.len()
            && listed
                .iter()
                .zip(&kept.files)
                .all(|(path, (kept_path, _, _))| path == kept_path)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stamp_matches_until_a_file_changes_or_appears() {
        let campaign = tempfile::tempdir().unwrap();
        let dir = campaign.path().join("takes/t0");
        std::fs::create_dir_all(dir.join("cameras/c")).unwrap();
        std::fs::write(dir.join("cameras/c/frame_00000.exr"), b"frame").unwrap();
        std::fs::write(dir.join("config.toml"), b"x = 1\n").unwrap();
        crate::manifest::write_manifest(&dir).unwrap();
        assert!(!stamp_matches(campaign.path(), "t0", &dir), "no stamp yet");
        write_stamp(campaign.path(), "t0", &dir).unwrap();
        assert!(stamp_matches(campaign.path(), "t0", &dir));

        // The same size, written again: its modification time differs.
        std::thread::sleep(std::time::Duration::from_millis(20));
        std::fs::write(dir.join("config.toml"), b"x = 2\n").unwrap();
        assert!(!stamp_matches(campaign.path(), "t0", &dir));
        write_stamp(campaign.path(), "t0", &dir).unwrap();
        assert!(stamp_matches(campaign.path(), "t0", &dir));

        // A file the manifest does not list.
        std::fs::write(dir.join("cameras/c/extra.txt"), b"?").unwrap();
        assert!(!stamp_matches(campaign.path(), "t0", &dir));
        std::fs::remove_file(dir.join("cameras/c/extra.txt")).unwrap();
        assert!(stamp_matches(campaign.path(), "t0", &dir));

        // A missing file, and a damaged stamp.
        std::fs::remove_file(dir.join("cameras/c/frame_00000.exr")).unwrap();
        assert!(!stamp_matches(campaign.path(), "t0", &dir));
        std::fs::write(stamp_path(campaign.path(), "t0"), b"{").unwrap();
        assert!(!stamp_matches(campaign.path(), "t0", &dir));
    }
}
