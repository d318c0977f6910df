//! egogen's one rule for what it writes (docs/ARCHITECTURE.md, "Outputs"): nothing is
//! replaced unasked and nothing is left half-written. An output that exists is refused (a
//! folder output may be an empty folder), so is one inside the input it is made from; a file
//! is written to `<path>.partial`, flushed to disk and renamed into place; a folder is built in
//! `<dir>.partial` and renamed whole ([`StagedFolder`]), and a `.partial` left by a killed run
//! is started again only when it holds nothing but what that output writes. `tools/outputs.py`
//! is the same rule for the Python tools.

use std::io::Write;
use std::path::{Path, PathBuf};

/// An output refused by the rule.
#[derive(Debug, thiserror::Error)]
pub(crate) enum OutputError {
    #[error("{} already exists; not overwriting it (choose a new path; nothing was written)", .path.display())]
    Exists { path: PathBuf },
    #[error("{flag} {} already exists and is not an empty folder; choose a new folder (nothing was written)", .path.display())]
    FolderNotEmpty { flag: String, path: PathBuf },
    #[error("{flag} {} is inside {what} {}: write it beside its input, not in it, which keeps the input as it was (nothing was written)", .path.display(), .input.display())]
    Inside {
        flag: String,
        path: PathBuf,
        what: String,
        input: PathBuf,
    },
    #[error("{} exists and holds files {what} does not write; move it away first (nothing was written)", .path.display())]
    NotOurs { path: PathBuf, what: String },
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Writes `bytes` to `<path>.partial` and renames it into place.
pub(crate) fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = partial_of(path);
    let result = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    match result {
        Ok(()) => std::fs::rename(&tmp, path),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// `<path>.partial`: where `path` is made before it is renamed into place.
pub(crate) fn partial_of(path: &Path) -> PathBuf {
    PathBuf::from(format!("{}.partial", path.display()))
}

/// Refuses to write over an existing file or folder.
pub(crate) fn refuse_existing(path: &Path) -> Result<(), OutputError> {
    match path.exists() || path.is_symlink() {
        true => Err(OutputError::Exists { path: path.into() }),
        false => Ok(()),
    }
}

/// Refuses a folder output (`flag`, e.g. `--out`) that exists and is not an empty folder.
pub(crate) fn refuse_existing_folder(path: &Path, flag: &str) -> Result<(), OutputError> {
    if !(path.exists() || path.is_symlink()) {
        return Ok(());
    }
    let empty = std::fs::read_dir(path).is_ok_and(|mut d| d.next().is_none());
    match empty {
        true => Ok(()),
        false => Err(OutputError::FolderNotEmpty {
            flag: flag.into(),
            path: path.into(),
        }),
    }
}

/// Refuses an output `path` (given as `flag`) inside the input folder `input` (`what`, e.g.
/// "the take"), or the input itself; links are followed, a path not made yet is taken where
/// it would be.
pub(crate) fn refuse_inside(
    path: &Path,
    flag: &str,
    input: &Path,
    what: &str,
) -> Result<(), OutputError> {
    if let (Ok(input_abs), Some(out_abs)) = (input.canonicalize(), absolute_of(path)) {
        if out_abs.starts_with(&input_abs) {
            return Err(OutputError::Inside {
                flag: flag.into(),
                path: path.into(),
                what: what.into(),
                input: input.into(),
            });
        }
    }
    Ok(())
}

/// `path` made absolute with its existing part's links resolved (the rest as written).
fn absolute_of(path: &Path) -> Option<PathBuf> {
    let path = std::path::absolute(path).ok()?;
    let mut rest = Vec::new();
    let mut base = path.as_path();
    loop {
        if let Ok(real) = base.canonicalize() {
            return Some(rest.iter().rev().fold(real, |p, c| p.join(c)));
        }
        rest.push(base.file_name()?.to_owned());
        base = base.parent()?;
    }
}

/// A folder output built in `<out>.partial` and renamed to `out` when it is whole; dropped
/// unfinished, the `.partial` is removed (it is this run's own).
#[derive(Debug)]
pub(crate) struct StagedFolder {
    out: PathBuf,
    staging: PathBuf,
    finished: bool,
}

impl StagedFolder {
    /// Starts `out` (given as `flag`): refused where it exists and is not an empty folder; a
    /// `.partial` left by a killed run is removed when every entry in it is one `ours` accepts
    /// (name, is a folder), else refused naming `what` (e.g. "an EuRoC export").
    pub(crate) fn begin(
        out: &Path,
        flag: &str,
        what: &str,
        ours: impl Fn(&str, bool) -> bool,
    ) -> Result<Self, OutputError> {
        refuse_existing_folder(out, flag)?;
        let staging = partial_of(out);
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| OutputError::Io { path, source }
        };
        if staging.exists() || staging.is_symlink() {
            let left_by_us = staging.is_dir()
                && !staging.is_symlink()
                && std::fs::read_dir(&staging).is_ok_and(|d| {
                    d.flatten().all(|e| {
                        let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
                        ours(&e.file_name().to_string_lossy(), is_dir)
                    })
                });
            if !left_by_us {
                return Err(OutputError::NotOurs {
                    path: staging,
                    what: what.into(),
                });
            }
            eprintln!(
                "egogen: {} is left by an interrupted run; starting it again",
                staging.display()
            );
            std::fs::remove_dir_all(&staging).map_err(io(&staging))?;
        }
        std::fs::create_dir_all(&staging).map_err(io(&staging))?;
        Ok(Self {
            out: out.into(),
            staging,
            finished: false,
        })
    }

    /// The folder being built.
    pub(crate) fn path(&self) -> &Path {
        &self.staging
    }

    /// Renames the built folder to its output (replacing the empty folder there, if any).
    pub(crate) fn finish(mut self) -> Result<PathBuf, OutputError> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| OutputError::Io { path, source }
        };
        if self.out.exists() {
            std::fs::remove_dir(&self.out).map_err(io(&self.out))?;
        }
        std::fs::rename(&self.staging, &self.out).map_err(io(&self.out))?;
        self.finished = true;
        Ok(self.out.clone())
    }
}

impl Drop for StagedFolder {
    fn drop(&mut self) {
        if !self.finished {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_existing_output_is_refused_and_nothing_half_written_is_left() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.json");
        write_atomically(&file, b"one").unwrap();
        assert!(refuse_existing(&file)
            .unwrap_err()
            .to_string()
            .contains("already exists"));
        assert!(!partial_of(&file).exists());
        // A folder output: an empty folder is taken, a full one refused.
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        refuse_existing_folder(&out, "--out").unwrap();
        std::fs::write(out.join("x"), b"").unwrap();
        let e = refuse_existing_folder(&out, "--out")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--out") && e.contains("not an empty folder"),
            "{e}"
        );
    }

    #[test]
    fn an_output_inside_its_input_is_refused_through_links_too() {
        let dir = tempfile::tempdir().unwrap();
        let take = dir.path().join("take");
        std::fs::create_dir(&take).unwrap();
        let e = refuse_inside(&take.join("export"), "--out", &take, "the take").unwrap_err();
        assert!(e.to_string().contains("is inside the take"), "{e}");
        assert!(refuse_inside(&take, "--out", &take, "the take").is_err());
        #[cfg(unix)]
        {
            let link = dir.path().join("link");
            std::os::unix::fs::symlink(&take, &link).unwrap();
            assert!(refuse_inside(&link.join("x/y"), "--out", &take, "the take").is_err());
        }
        refuse_inside(&dir.path().join("beside"), "--out", &take, "the take").unwrap();
    }

    #[test]
    fn a_staged_folder_appears_whole_or_not_at_all_and_a_foreign_partial_is_kept() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("export");
        let ours = |name: &str, is_dir: bool| is_dir && name == "mav0";
        // Dropped unfinished: nothing under either name.
        let staged = StagedFolder::begin(&out, "--out", "an export", ours).unwrap();
        std::fs::create_dir(staged.path().join("mav0")).unwrap();
        drop(staged);
        assert!(!out.exists() && !partial_of(&out).exists());
        // A leftover of ours is started again; finished, it is renamed whole.
        std::fs::create_dir_all(partial_of(&out).join("mav0")).unwrap();
        let staged = StagedFolder::begin(&out, "--out", "an export", ours).unwrap();
        assert!(!staged.path().join("mav0").exists());
        std::fs::write(staged.path().join("f"), b"1").unwrap();
        staged.finish().unwrap();
        assert_eq!(std::fs::read(out.join("f")).unwrap(), b"1");
        // A leftover holding anything else is refused and kept as it is.
        let other = dir.path().join("other");
        std::fs::create_dir_all(partial_of(&other)).unwrap();
        std::fs::write(partial_of(&other).join("notes.txt"), b"mine").unwrap();
        let e = StagedFolder::begin(&other, "--out", "an export", ours).unwrap_err();
        assert!(
            e.to_string()
                .contains("holds files an export does not write"),
            "{e}"
        );
        assert_eq!(
            std::fs::read(partial_of(&other).join("notes.txt")).unwrap(),
            b"mine"
        );
    }
}
