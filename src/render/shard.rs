//! How a Blender worker is started on a shard spec (`blender_scripts/render_shard.py`, as a
//! Python module or through a Blender executable): the one spawn path both pools use.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::blender_runtime::{BlenderKind, BlenderRuntime};

/// The worker script shipped with egogen.
pub(crate) fn render_script() -> PathBuf {
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
