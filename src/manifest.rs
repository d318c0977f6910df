//! The manifest of an output folder (`manifest.json`): every file with its size and SHA-256,
//! scratch folders and temporaries left out. Datasets and sequence folders both carry one;
//! `supervisor::verify::verify` re-checks a dataset against it.

use std::io::Read;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Folders of a dataset that are scratch, not data.
pub(crate) const SCRATCH_DIRS: [&str; 2] = ["work", "logs"];
pub(crate) const MANIFEST: &str = "manifest.json";
/// The manifest format this egogen writes and reads (`egogen_manifest`).
pub(crate) const MANIFEST_VERSION: u32 = 1;

/// One file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ManifestEntry {
    /// Relative to the dataset folder, `/`-separated.
    pub path: String,
    pub bytes: u64,
    pub sha256: String,
}

/// The manifest.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    pub egogen_manifest: u32,
    pub files: Vec<ManifestEntry>,
}

/// SHA-256 of bytes, lower-case hex.
pub(crate) fn sha256_hex(bytes: &[u8]) -> String {
    format!("{:x}", Sha256::digest(bytes))
}

/// SHA-256 of a file, lower-case hex.
pub fn sha256_file(path: &Path) -> Result<String> {
    let mut f = std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f
            .read(&mut buf)
            .with_context(|| format!("reading {}", path.display()))?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(format!("{:x}", hasher.finalize()))
}

fn collect(dir: &Path, rel: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir.join(rel))
        .with_context(|| format!("listing {}", dir.join(rel).display()))?
        .collect::<std::io::Result<_>>()?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let r = rel.join(e.file_name());
        if e.file_type()?.is_dir() {
            if rel.as_os_str().is_empty() && SCRATCH_DIRS.iter().any(|s| e.file_name() == *s) {
                continue;
            }
            collect(dir, &r, out)?;
        } else if r != Path::new(MANIFEST) {
            out.push(r);
        }
    }
    Ok(())
}

/// Whether a file name is one of egogen's temporaries (`<name>.partial` of an atomic write,
/// `<frame>.exr.tmp` of a frame being finished): never data, only ever left by a killed run.
pub(crate) fn is_temporary(name: &str) -> bool {
    name.ends_with(".partial") || name.ends_with(".tmp")
}

/// Removes the temporaries a killed run left among the dataset files of `dir` (scratch folders
/// excluded), so that the manifest lists only data; returns what was removed.
pub(crate) fn remove_temporaries(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut removed = Vec::new();
    for rel in dataset_files(dir)? {
        if is_temporary(&rel) {
            let p = dir.join(&rel);
            std::fs::remove_file(&p)
                .with_context(|| format!("removing the leftover {}", p.display()))?;
            removed.push(p);
        }
    }
    Ok(removed)
}

/// Lists and hashes every dataset file under `dir` (scratch folders excluded).
pub(crate) fn build_manifest(dir: &Path) -> Result<Manifest> {
    build_manifest_with(dir, &[])
}

/// [`build_manifest`], taking the checksum of a file from `known` (entries computed when the
/// file was written) instead of reading it, where the file has the size `known` says.
pub(crate) fn build_manifest_with(dir: &Path, known: &[ManifestEntry]) -> Result<Manifest> {
    let known: std::collections::HashMap<&str, &ManifestEntry> =
        known.iter().map(|e| (e.path.as_str(), e)).collect();
    let files = dataset_files(dir)?
        .into_iter()
        .map(|path| {
            let p = dir.join(&path);
            let bytes = std::fs::metadata(&p)
                .with_context(|| format!("reading {}", p.display()))?
                .len();
            let sha256 = match known.get(path.as_str()) {
                Some(e) if e.bytes == bytes => e.sha256.clone(),
                _ => sha256_file(&p)?,
            };
            Ok(ManifestEntry {
                bytes,
                sha256,
                path,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Manifest {
        egogen_manifest: MANIFEST_VERSION,
        files,
    })
}

/// Writes `manifest.json` atomically.
pub(crate) fn write_manifest(dir: &Path) -> Result<Manifest> {
    write_manifest_with(dir, &[])
}

/// [`write_manifest`] with checksums `known` ([`build_manifest_with`]).
pub(crate) fn write_manifest_with(dir: &Path, known: &[ManifestEntry]) -> Result<Manifest> {
    let manifest = build_manifest_with(dir, known)?;
    let path = dir.join(MANIFEST);
    crate::atomic_file::write_atomically(
        &path,
        serde_json::to_string_pretty(&manifest)?.as_bytes(),
    )
    .with_context(|| format!("writing {}", path.display()))?;
    Ok(manifest)
}

/// Dataset files under `dir` (scratch folders and the manifest excluded), `/`-separated,
/// sorted.
pub(crate) fn dataset_files(dir: &Path) -> Result<Vec<String>> {
    let mut files = Vec::new();
    collect(dir, Path::new(""), &mut files)?;
    Ok(files
        .iter()
        .map(|r| {
            r.components()
                .map(|c| c.as_os_str().to_string_lossy())
                .collect::<Vec<_>>()
                .join("/")
        })
        .collect())
}
