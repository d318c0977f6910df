//! The dataset manifest (`manifest.json`): every dataset file with its size and SHA-256, and
//! `verify`, which re-checks a dataset against it (sizes, checksums, every frame file opens
//! with all channels finite).

use std::io::Read;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::inspect::ExrContents;
use crate::render::frame_file::{check_frame_channels, FrameFileError};

/// Folders of a dataset that are scratch, not data.
pub const SCRATCH_DIRS: [&str; 2] = ["work", "logs"];
pub const MANIFEST: &str = "manifest.json";

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
pub fn is_temporary(name: &str) -> bool {
    name.ends_with(".partial") || name.ends_with(".tmp")
}

/// Removes the temporaries a killed run left among the dataset files of `dir` (scratch folders
/// excluded), so that the manifest lists only data; returns what was removed.
pub fn remove_temporaries(dir: &Path) -> Result<Vec<PathBuf>> {
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
pub fn build_manifest(dir: &Path) -> Result<Manifest> {
    let files = dataset_files(dir)?
        .into_iter()
        .map(|path| {
            let p = dir.join(&path);
            Ok(ManifestEntry {
                bytes: std::fs::metadata(&p)?.len(),
                sha256: sha256_file(&p)?,
                path,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Manifest {
        egogen_manifest: 1,
        files,
    })
}

/// Writes `manifest.json` atomically.
pub fn write_manifest(dir: &Path) -> Result<Manifest> {
    let manifest = build_manifest(dir)?;
    let path = dir.join(MANIFEST);
    crate::atomic_file::write_atomically(
        &path,
        serde_json::to_string_pretty(&manifest)?.as_bytes(),
    )
    .with_context(|| format!("writing {}", path.display()))?;
    Ok(manifest)
}

/// What `verify` checked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VerifyReport {
    pub files: usize,
    pub frames: usize,
    pub bytes: u64,
}

/// Re-checks a dataset: every manifest entry exists with its size and checksum, no dataset
/// file is missing from the manifest, every frame file has every channel and only finite values.
pub fn verify(dir: &Path) -> Result<VerifyReport> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "{}: no manifest (is this an egogen dataset?)",
            path.display()
        )
    })?;
    let manifest: Manifest = serde_json::from_str(&text)
        .with_context(|| format!("{}: not an egogen manifest", path.display()))?;
    if manifest.files.is_empty() {
        bail!("{}: lists no files; not a finished dataset", path.display());
    }
    let mut problems = Vec::new();
    let mut frames = 0;
    let mut bytes = 0;
    for e in &manifest.files {
        let inside = Path::new(&e.path)
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_)));
        if !inside || e.path.is_empty() {
            problems.push(format!(
                "{}: not a path inside the dataset (the manifest lists only relative paths without `..`)",
                e.path
            ));
            continue;
        }
        let p = dir.join(&e.path);
        let Ok(meta) = std::fs::metadata(&p) else {
            problems.push(format!("{}: missing", e.path));
            continue;
        };
        if meta.len() != e.bytes {
            problems.push(format!(
                "{}: {} bytes, manifest says {}",
                e.path,
                meta.len(),
                e.bytes
            ));
            continue;
        }
        bytes += e.bytes;
        if sha256_file(&p)? != e.sha256 {
            problems.push(format!("{}: checksum differs from the manifest", e.path));
            continue;
        }
        if e.path.ends_with(".exr") && e.path.starts_with("cameras/") {
            frames += 1;
            let checked = ExrContents::read(&p)
                .map_err(FrameFileError::from)
                .and_then(|c| check_frame_channels(&c, None));
            if let Err(err) = checked {
                problems.push(format!("{}: {err}", e.path));
            }
        }
    }
    let listed = dataset_files(dir)?;
    for p in listed {
        if !manifest.files.iter().any(|e| e.path == p) {
            problems.push(format!("{p}: not in the manifest"));
        }
    }
    if !problems.is_empty() {
        bail!(
            "{}: {} problem(s):\n  {}",
            dir.display(),
            problems.len(),
            problems.join("\n  ")
        );
    }
    Ok(VerifyReport {
        files: manifest.files.len(),
        frames,
        bytes,
    })
}

/// Dataset files under `dir` (scratch folders and the manifest excluded), `/`-separated,
/// sorted.
fn dataset_files(dir: &Path) -> Result<Vec<String>> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn dataset_with(files: &[(&str, &[u8])]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for (p, bytes) in files {
            let path = dir.path().join(p);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, bytes).unwrap();
        }
        dir
    }

    #[test]
    fn verify_accepts_a_manifest_it_wrote_and_drops_temporaries_first() {
        let dir = dataset_with(&[
            ("a.json", b"{}"),
            ("sub/b.txt", b"b"),
            ("sub/c.exr.tmp", b"half"),
            ("manifest.json.partial", b"{"),
            ("work/scratch.bin", b"x"),
        ]);
        let removed = remove_temporaries(dir.path()).unwrap();
        assert_eq!(removed.len(), 2);
        let m = write_manifest(dir.path()).unwrap();
        let listed: Vec<_> = m.files.iter().map(|f| f.path.as_str()).collect();
        assert_eq!(listed, ["a.json", "sub/b.txt"]);
        assert_eq!(verify(dir.path()).unwrap().files, 2);
    }

    #[test]
    fn verify_refuses_an_empty_manifest_and_paths_outside_the_dataset() {
        let dir = dataset_with(&[("a.json", b"{}")]);
        let write = |files: Vec<ManifestEntry>| {
            let m = Manifest {
                egogen_manifest: 1,
                files,
            };
            std::fs::write(
                dir.path().join(MANIFEST),
                serde_json::to_string(&m).unwrap(),
            )
            .unwrap();
        };
        write(Vec::new());
        let err = verify(dir.path()).unwrap_err().to_string();
        assert!(err.contains("lists no files"), "{err}");
        let outside = tempfile::NamedTempFile::new().unwrap();
        let entry = |path: String| ManifestEntry {
            path,
            bytes: 0,
            sha256: sha256_file(outside.path()).unwrap(),
        };
        for path in [
            "../escape.txt".to_string(),
            outside.path().display().to_string(),
        ] {
            let good = build_manifest(dir.path()).unwrap().files;
            write([good, vec![entry(path.clone())]].concat());
            let err = format!("{:#}", verify(dir.path()).unwrap_err());
            assert!(
                err.contains("not a path inside the dataset"),
                "{path}: {err}"
            );
        }
    }
}
