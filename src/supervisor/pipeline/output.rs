//! The output folder of a run (steps 1 and 3 of the main job): whether `<dir>` and
//! `<dir>.partial` may be written or resumed, `<dir>.partial` staged whole with the stamp
//! that says which run it holds, and the attribution a take made in a dwelling with CC-BY
//! furniture carries (`ATTRIBUTION.md`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::{RunOptions, RunState};
use crate::atomic_file::write_atomically;
use crate::manifest::MANIFEST;

fn is_non_empty_dir(p: &Path) -> bool {
    std::fs::read_dir(p)
        .map(|mut d| d.next().is_some())
        .unwrap_or(false)
}

/// What the output folder holds for a run.
pub(super) enum OutputState {
    /// Neither `<dir>` nor `<dir>.partial`: a new run.
    Fresh,
    /// `<dir>.partial` of this same run, and `--resume` asked to continue it.
    Resume,
    /// `<dir>` is this run's finished dataset, and `--resume` was asked.
    Complete,
    /// `<dir>.partial` of this same run started in another folder (moved or copied here), and
    /// `--resume` asked to continue it.
    Moved,
}

/// Checks that the run may write where it is told: `<dir>` empty or absent (or finished, under
/// `--resume`), and a `<dir>.partial` continued only by `--resume` of the same run (`state`).
/// Nothing is touched either way.
pub(super) fn check_output(
    dir: &Path,
    staging: &Path,
    state: &RunState,
    opts: &RunOptions,
) -> Result<OutputState> {
    if is_non_empty_dir(dir) {
        if opts.resume && dir.join(MANIFEST).is_file() {
            return Ok(OutputState::Complete);
        }
        bail!(
            "output folder {} already exists and is not empty; choose another `output.dir` (nothing was written)",
            dir.display()
        );
    }
    if !staging.exists() {
        return Ok(OutputState::Fresh);
    }
    if !opts.resume {
        bail!(
            "{} holds an interrupted run; rerun with --resume to continue it, or delete it (nothing was written)",
            staging.display()
        );
    }
    let state_path = staging.join("work/run.json");
    let found: RunState = std::fs::read_to_string(&state_path)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .with_context(|| {
            format!(
                "{}: missing or unreadable; cannot resume",
                state_path.display()
            )
        })?;
    let moved = found.config_sha256 != state.config_sha256
        && found.moved_sha256.is_some()
        && found.moved_sha256 == state.moved_sha256;
    if found.config_sha256 != state.config_sha256 && !moved {
        bail!(
            "{} was started from a different config than {} with these options (its values, or those the first run's command line set: --out, --seed, --scene, --up, --unit-m, --crowd-count, --duration-s, --activity-weights, --materials — give the same again); resuming would mix two runs (nothing was touched)",
            staging.display(),
            state.config
        );
    }
    if found.rig_sha256.is_some() && found.rig_sha256 != state.rig_sha256 {
        bail!(
            "{} was started with a different camera rig (a --rig override or a changed rig file); resuming would mix two runs (nothing was touched)",
            staging.display()
        );
    }
    Ok(match moved {
        true => OutputState::Moved,
        false => OutputState::Resume,
    })
}

/// A `.partial` moved here from another folder: its effective config (which names the output
/// folder) and `work/run.json` are written again for where it lies now, each atomically, and
/// it says so.
pub(super) fn restamp_moved(staging: &Path, state: &RunState, opts: &RunOptions) -> Result<()> {
    eprintln!(
        "egogen-run: {} was started in another folder (moved or copied here); its config.toml and work/run.json now name this one",
        staging.display()
    );
    write_run_stamp(staging, state, opts)
}

/// Writes what says which run a folder holds: its effective config (`config.toml`) and
/// `work/run.json`, each atomically.
fn write_run_stamp(folder: &Path, state: &RunState, opts: &RunOptions) -> Result<()> {
    write_atomically(&folder.join("config.toml"), opts.config_toml.as_bytes())
        .with_context(|| format!("writing the effective config of {}", state.config))?;
    let run_json = folder.join("work/run.json");
    write_atomically(&run_json, serde_json::to_string_pretty(state)?.as_bytes())
        .with_context(|| format!("writing {}", run_json.display()))
}

/// Creates `<dir>.partial` with the effective config and `work/run.json`, whole or not at all:
/// both are written into `<dir>.partial.new` and that folder renamed, so a run killed while
/// staging never leaves a `.partial` that no `--resume` can read. A `<dir>.partial.new` left by
/// such a run holds only those two files and is replaced.
pub(super) fn stage_run(staging: &Path, state: &RunState, opts: &RunOptions) -> Result<()> {
    let fresh = PathBuf::from(format!("{}.new", staging.display()));
    if fresh.exists() {
        std::fs::remove_dir_all(&fresh).with_context(|| {
            format!(
                "removing {}, left by a run killed while staging",
                fresh.display()
            )
        })?;
    }
    std::fs::create_dir_all(fresh.join("work"))
        .with_context(|| format!("creating {}", fresh.display()))?;
    write_run_stamp(&fresh, state, opts)?;
    std::fs::rename(&fresh, staging)
        .with_context(|| format!("renaming {} to {}", fresh.display(), staging.display()))?;
    Ok(())
}

/// Writes `ATTRIBUTION.md` into the staged take where its scene is a generated dwelling that
/// places models of an opt-in (CC-BY) library (`scene::dwelling::attribution`); nothing
/// otherwise.
pub(super) fn write_attribution(staging: &Path, scene: &Path) -> Result<()> {
    use crate::scene::dwelling::attribution::{of_scene, ATTRIBUTION_FILE};
    let path = staging.join(ATTRIBUTION_FILE);
    if let Some(text) = of_scene(scene).map_err(anyhow::Error::msg)? {
        write_atomically(&path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A start killed while staging left `<dir>.partial.new` (the config written, no
    /// `work/run.json`) and no `.partial`: the next start stages afresh, and its `.partial`
    /// is whole and resumable.
    #[test]
    fn staging_killed_half_way_leaves_nothing_a_resume_cannot_read() {
        let a = tempfile::tempdir().unwrap();
        let dir = a.path().join("take");
        let staging = a.path().join("take.partial");
        let left = a.path().join("take.partial.new");
        std::fs::create_dir_all(left.join("work")).unwrap();
        std::fs::write(left.join("config.toml"), "half").unwrap();
        let state = RunState {
            config: "run.toml".into(),
            config_sha256: "abc".into(),
            rig_sha256: None,
            moved_sha256: None,
        };
        let opts = RunOptions {
            resume: true,
            blender: None,
            config_toml: "[scene]\n".into(),
            resume_fingerprint: "abc".into(),
            moved_fingerprint: "ab".into(),
        };
        assert!(matches!(
            check_output(&dir, &staging, &state, &opts).unwrap(),
            OutputState::Fresh
        ));
        stage_run(&staging, &state, &opts).unwrap();
        assert!(!left.exists());
        assert_eq!(
            std::fs::read_to_string(staging.join("config.toml")).unwrap(),
            "[scene]\n"
        );
        assert!(matches!(
            check_output(&dir, &staging, &state, &opts).unwrap(),
            OutputState::Resume
        ));
    }
}
