//! `verify`: re-checks a finished dataset against its manifest (sizes, checksums, every frame
//! file opens with all channels finite). The manifest itself is `crate::manifest`.

use std::path::Path;

use anyhow::{bail, Context, Result};

use crate::exr_file::ExrContents;
use std::collections::HashSet;

use crate::manifest::{dataset_files, sha256_file, Manifest, MANIFEST, MANIFEST_VERSION};
use crate::render::frame_file::{check_frame_channels, FrameFileError};

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
    let text = match std::fs::read(&path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if dir.join("campaign.json").is_file() {
                bail!(
                    "{}: a campaign's folder, not one dataset: each take is one, verify them one \
                     by one (egogen-run verify {})",
                    dir.display(),
                    dir.join("takes/<take>").display()
                );
            }
            bail!(
                "{}: no manifest (is this an egogen dataset?)",
                path.display()
            );
        }
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
        Ok(bytes) => String::from_utf8(bytes).map_err(|_| {
            anyhow::anyhow!(
                "{}: not text (expected the JSON manifest egogen-run writes; a damaged or \
                 foreign file)",
                path.display()
            )
        })?,
    };
    let manifest: Manifest = serde_json::from_str(&text)
        .with_context(|| format!("{}: not an egogen manifest", path.display()))?;
    if manifest.egogen_manifest != MANIFEST_VERSION {
        bail!(
            "{}: key egogen_manifest: format version {}, expected {MANIFEST_VERSION} (written by another egogen version?)",
            path.display(),
            manifest.egogen_manifest
        );
    }
    if manifest.files.is_empty() {
        bail!("{}: lists no files; not a finished dataset", path.display());
    }
    let mut problems = Vec::new();
    let mut frames = 0;
    let mut bytes = 0;
    let mut seen = HashSet::new();
    for e in &manifest.files {
        if !seen.insert(e.path.as_str()) {
            problems.push(format!(
                "{}: listed more than once in {MANIFEST} (each file once)",
                e.path
            ));
            continue;
        }
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
                .and_then(|c| check_frame_channels(&c));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manifest::{build_manifest, remove_temporaries, write_manifest, ManifestEntry};

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
                egogen_manifest: MANIFEST_VERSION,
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

    #[test]
    fn verify_refuses_a_file_listed_twice_and_another_format_version() {
        let dir = dataset_with(&[("a.json", b"{}"), ("b.txt", b"b")]);
        let good = build_manifest(dir.path()).unwrap();
        let write = |m: &Manifest| {
            std::fs::write(dir.path().join(MANIFEST), serde_json::to_string(m).unwrap()).unwrap()
        };
        write(&good);
        assert_eq!(verify(dir.path()).unwrap().files, 2);
        let mut twice = good.clone();
        twice.files.push(good.files[1].clone());
        write(&twice);
        let err = format!("{:#}", verify(dir.path()).unwrap_err());
        assert!(
            err.contains("b.txt: listed more than once in manifest.json"),
            "{err}"
        );
        let other = Manifest {
            egogen_manifest: 2,
            ..good
        };
        write(&other);
        let err = format!("{:#}", verify(dir.path()).unwrap_err());
        assert!(
            err.contains("manifest.json: key egogen_manifest: format version 2, expected 1"),
            "{err}"
        );
    }
}
