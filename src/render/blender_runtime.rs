//! Finding, provisioning and checking the Blender that renders.
//!
//! Order: an explicit path (`--blender`), else `EGOGEN_BLENDER`, else the managed environment
//! `$EGOGEN_CACHE/bpy-4.5` (default cache `$XDG_CACHE_HOME/egogen` or `~/.cache/egogen`), which is
//! created on first use: a Python 3.11 virtual environment with PyPI `bpy==4.5.*`, built in
//! `bpy-4.5.partial/` and renamed when complete, so an interrupted install is never used.
//! A path may be a Python interpreter that imports `bpy`, or a `blender` executable.
//! Only the 4.5 series is accepted: 5.0 writes multi-part EXR files and renamed compositor APIs.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The Blender series egogen is tested with.
pub(crate) const SUPPORTED_SERIES: &str = "4.5";
/// The PyPI requirement the managed environment installs.
pub(crate) const BPY_REQUIREMENT: &str = "bpy==4.5.*";

/// How to run Blender.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BlenderKind {
    /// A Python interpreter with `bpy` importable: run scripts as `python script.py`.
    PythonModule,
    /// A Blender executable: run scripts as `blender --background --python-exit-code 1 --python script.py`.
    Executable,
}

/// A checked Blender installation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BlenderRuntime {
    pub path: PathBuf,
    pub kind: BlenderKind,
    /// As Blender reports it, e.g. `4.5.15 LTS`.
    pub version: String,
}

/// Why no usable Blender was found.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    #[error("Blender {path}: not found")]
    NotFound { path: PathBuf },
    #[error("Blender {path}: could not run it ({message}); pass a Python with bpy or a blender executable via --blender or EGOGEN_BLENDER")]
    NotBlender { path: PathBuf, message: String },
    #[error("Blender {path}: version {version} is not supported; egogen needs the {SUPPORTED_SERIES} series (PyPI bpy==4.5.*). Blender 5.x writes multi-part EXR files and renamed compositor APIs and is not tested yet")]
    UnsupportedVersion { path: PathBuf, version: String },
    #[error("provisioning Blender into {dir} failed: {message}")]
    Provision { dir: PathBuf, message: String },
}

impl BlenderRuntime {
    /// Finds (and, for the managed environment, provisions) a checked Blender.
    pub(crate) fn resolve(explicit: Option<&Path>) -> Result<Self, RuntimeError> {
        if let Some(p) = explicit {
            return Self::check(p);
        }
        if let Some(p) = std::env::var_os("EGOGEN_BLENDER").filter(|p| !p.is_empty()) {
            return Self::check(Path::new(&p));
        }
        Self::managed()
    }

    /// The managed environment, created on first use.
    pub fn managed() -> Result<Self, RuntimeError> {
        let dir = cache_dir().join(format!("bpy-{SUPPORTED_SERIES}"));
        let python = dir.join("bin/python");
        if !python.is_file() {
            // Two first runs at once: the second waits for the first's install instead of
            // removing its half-made folder.
            let lock_path = dir.with_extension("lock");
            let fail = |message: String| RuntimeError::Provision {
                dir: dir.clone(),
                message,
            };
            if let Some(parent) = dir.parent() {
                std::fs::create_dir_all(parent).map_err(|e| fail(e.to_string()))?;
            }
            let lock = std::fs::File::create(&lock_path)
                .map_err(|e| fail(format!("creating {} ({e})", lock_path.display())))?;
            lock.lock()
                .map_err(|e| fail(format!("locking {} ({e})", lock_path.display())))?;
            if !python.is_file() {
                provision(&dir)?;
            }
        }
        Self::check(&python)
    }

    /// Runs `path` to learn what it is and which version it has.
    pub(crate) fn check(path: &Path) -> Result<Self, RuntimeError> {
        if !path.exists() {
            return Err(RuntimeError::NotFound {
                path: path.to_owned(),
            });
        }
        let is_executable = path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("blender"));
        let (kind, output) = if is_executable {
            (
                BlenderKind::Executable,
                Command::new(path).arg("--version").output(),
            )
        } else {
            let probe = "import bpy; print('BLENDER_VERSION', bpy.app.version_string)";
            (
                BlenderKind::PythonModule,
                Command::new(path).arg("-c").arg(probe).output(),
            )
        };
        let output = output.map_err(|e| RuntimeError::NotBlender {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        let stdout = String::from_utf8_lossy(&output.stdout);
        let version = match kind {
            BlenderKind::PythonModule => stdout
                .lines()
                .find_map(|l| l.strip_prefix("BLENDER_VERSION "))
                .map(str::to_owned),
            BlenderKind::Executable => stdout
                .lines()
                .find_map(|l| l.strip_prefix("Blender "))
                .map(|v| v.trim().to_owned()),
        };
        let Some(version) = version.filter(|_| output.status.success()) else {
            let stderr = String::from_utf8_lossy(&output.stderr);
            let tail: String = stderr
                .lines()
                .rev()
                .take(3)
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect::<Vec<_>>()
                .join(" | ");
            return Err(RuntimeError::NotBlender {
                path: path.to_owned(),
                message: format!(
                    "it did not report a Blender version ({}; {tail})",
                    output.status
                ),
            });
        };
        if !version.starts_with(&format!("{SUPPORTED_SERIES}.")) {
            return Err(RuntimeError::UnsupportedVersion {
                path: path.to_owned(),
                version,
            });
        }
        Ok(Self {
            path: path.to_owned(),
            kind,
            version,
        })
    }
}

pub use crate::paths::cache_dir;

/// Creates the managed environment: venv in `<dir>.partial`, install, rename. The caller holds
/// `<dir>.lock`, so a `<dir>.partial` found here is a killed install's, not a running one's.
fn provision(dir: &Path) -> Result<(), RuntimeError> {
    let fail = |message: String| RuntimeError::Provision {
        dir: dir.to_owned(),
        message,
    };
    let partial = dir.with_extension("partial");
    if partial.exists() {
        std::fs::remove_dir_all(&partial)
            .map_err(|e| fail(format!("removing a stale {} ({e})", partial.display())))?;
    }
    if let Some(parent) = dir.parent() {
        std::fs::create_dir_all(parent).map_err(|e| fail(e.to_string()))?;
    }
    eprintln!(
        "egogen: first use of Blender: installing PyPI {BPY_REQUIREMENT} (Blender {SUPPORTED_SERIES} LTS as a Python module, ~400 MB download) into {}",
        dir.display()
    );
    let python = ["python3.11", "python3"]
        .into_iter()
        .find(|p| {
            Command::new(p)
                .arg("-c")
                .arg("import sys; assert sys.version_info[:2] == (3, 11)")
                .status()
                .is_ok_and(|s| s.success())
        })
        .ok_or_else(|| {
            fail("bpy 4.5 needs Python 3.11; none found as python3.11 or python3".into())
        })?;
    let run = |cmd: &mut Command, what: &str| -> Result<(), RuntimeError> {
        // Progress goes to stderr; stdout stays for the command's own answer.
        let status = cmd
            .stdout(std::process::Stdio::from(std::io::stderr()))
            .status()
            .map_err(|e| fail(format!("{what}: {e}")))?;
        if status.success() {
            Ok(())
        } else {
            Err(fail(format!("{what} exited with {status}")))
        }
    };
    run(
        Command::new(python).arg("-m").arg("venv").arg(&partial),
        "creating the virtual environment",
    )?;
    // pip's own progress bars go to the terminal (stderr is inherited).
    run(
        Command::new(partial.join("bin/python")).args([
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            BPY_REQUIREMENT,
        ]),
        "pip install",
    )?;
    std::fs::rename(&partial, dir)
        .map_err(|e| fail(format!("moving {} into place ({e})", partial.display())))?;
    eprintln!("egogen: Blender ready in {}", dir.display());
    Ok(())
}
