//! Running one shard through Blender: write the spec, start the worker script, collect the
//! frames it reports, and turn failures into errors that say what to look at.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::blender_runtime::{BlenderKind, BlenderRuntime};
use super::protocol::ShardSpec;

/// A shard that did not render.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    #[error("writing the shard spec {path}: {message}")]
    Spec { path: PathBuf, message: String },
    #[error("Blender worker ({blender}) failed with {status} after {done} of {total} frames; stderr tail:\n{stderr_tail}")]
    Worker {
        blender: PathBuf,
        status: String,
        done: usize,
        total: usize,
        stderr_tail: String,
    },
}

/// The worker script shipped with egogen.
pub fn render_script() -> PathBuf {
    crate::paths::crate_root().join("blender_scripts/render_shard.py")
}

/// The command that runs the worker script on a spec with this Blender.
pub fn worker_command(runtime: &BlenderRuntime, spec_path: &Path) -> Command {
    let script = render_script();
    let mut cmd = match runtime.kind {
        BlenderKind::PythonModule => {
            let mut c = Command::new(&runtime.path);
            c.arg(&script).arg(spec_path);
            c
        }
        BlenderKind::Executable => {
            let mut c = Command::new(&runtime.path);
            c.args([
                "--background",
                "--factory-startup",
                "--python-exit-code",
                "1",
                "--python",
            ])
            .arg(&script)
            .arg("--")
            .arg(spec_path);
            c
        }
    };
    cmd.env("PYTHONNOUSERSITE", "1");
    cmd
}

/// Renders a shard; returns the EXR files Blender reported done, in order.
pub fn render_shard(
    runtime: &BlenderRuntime,
    spec: &ShardSpec,
    spec_path: &Path,
) -> Result<Vec<PathBuf>, ShardError> {
    let json = serde_json::to_vec_pretty(spec).map_err(|e| ShardError::Spec {
        path: spec_path.into(),
        message: e.to_string(),
    })?;
    std::fs::write(spec_path, json).map_err(|e| ShardError::Spec {
        path: spec_path.into(),
        message: e.to_string(),
    })?;
    let mut cmd = worker_command(runtime, spec_path);
    let output = cmd.output().map_err(|e| ShardError::Worker {
        blender: runtime.path.clone(),
        status: e.to_string(),
        done: 0,
        total: spec.num_outputs(),
        stderr_tail: String::new(),
    })?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    let done: Vec<PathBuf> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("EGOGEN_DONE "))
        .map(PathBuf::from)
        .collect();
    let total = spec.num_outputs();
    if !output.status.success() || done.len() != total {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let lines: Vec<&str> = stderr.lines().collect();
        let stderr_tail = lines[lines.len().saturating_sub(20)..].join("\n");
        return Err(ShardError::Worker {
            blender: runtime.path.clone(),
            status: output.status.to_string(),
            done: done.len(),
            total,
            stderr_tail,
        });
    }
    Ok(done)
}
