//! How a Blender worker is started on a shard spec (`blender_scripts/render_shard.py`, as a
//! Python module or through a Blender executable): the one spawn path both pools use, and the
//! check of the render device before a take is staged.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::blender_runtime::{BlenderKind, BlenderRuntime};
use super::protocol::RenderDevice;

/// The worker script shipped with egogen.
pub(crate) fn render_script() -> PathBuf {
    crate::paths::crate_root().join("blender_scripts/render_shard.py")
}

/// The command that runs the worker script on a spec with this Blender.
pub(crate) fn worker_command(runtime: &BlenderRuntime, spec_path: &Path) -> Command {
    script_command(runtime, &[spec_path.as_os_str()])
}

/// A long-lived worker for the take in `take_dir` (`render_shard.py --serve TAKE_DIR`): it
/// reads `{"spec": …, "log": …}` lines on its standard input and renders each shard in the
/// scene it built for the first.
pub(crate) fn serve_command(runtime: &BlenderRuntime, take_dir: &Path) -> Command {
    script_command(runtime, &["--serve".as_ref(), take_dir.as_os_str()])
}

/// The worker script with `args` under this Blender.
pub(crate) fn script_command(runtime: &BlenderRuntime, args: &[&std::ffi::OsStr]) -> Command {
    let script = render_script();
    let mut cmd = Command::new(&runtime.path);
    match runtime.kind {
        BlenderKind::PythonModule => {
            cmd.arg(&script).args(args);
        }
        BlenderKind::Executable => {
            cmd.args([
                "--background",
                "--factory-startup",
                "--python-exit-code",
                "1",
                "--python",
            ])
            .arg(&script)
            .arg("--")
            .args(args);
        }
    }
    cmd.env("PYTHONNOUSERSITE", "1");
    cmd
}

/// Checks, before anything is staged, that this Blender can render on `device` (a GPU: one
/// that Blender finds, as the worker would look for it), saying which one; the worker's own
/// message when it cannot. Nothing to check for the CPU.
pub(crate) fn check_device(runtime: &BlenderRuntime, device: RenderDevice) -> Result<(), String> {
    if device == RenderDevice::Cpu {
        return Ok(());
    }
    let out = script_command(runtime, &["--check-device".as_ref(), "gpu".as_ref()])
        .output()
        .map_err(|e| format!("running {} to look for a GPU: {e}", runtime.path.display()))?;
    let said = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        if let Some(line) = said
            .lines()
            .find(|l| l.starts_with("egogen: Blender renders on"))
        {
            eprintln!("{line}");
        }
        return Ok(());
    }
    Err(said
        .lines()
        .find_map(|l| l.strip_prefix("EGOGEN_SETUP_FAILED "))
        .map_or_else(
            || {
                format!(
                    "looking for a GPU with {} failed: {}",
                    runtime.path.display(),
                    said.trim()
                )
            },
            str::to_string,
        ))
}
