//! A round submitted to Slurm: each pending shard's spec, the `sbatch` array script (one task
//! per shard, resources from `[supervisor.slurm]`, throttled) and its submission.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::client::slurm_tool;
use super::outcomes::missing_frames;
use super::{ShardState, SlurmSettings, Takes, Task};
use crate::atomic_file::write_atomically;
use crate::render::shard::worker_command;
use crate::render::BlenderRuntime;
use crate::supervisor::pool::PoolRun;

/// Writes one round's specs (the missing frames of the shards `todo`) and its array script
/// into `round_dir`, and submits it; returns the job id, the tasks and the script.
#[allow(clippy::too_many_arguments)]
pub(super) fn submit_round(
    takes: &Takes,
    runtime: &BlenderRuntime,
    settings: &SlurmSettings,
    states: &[ShardState],
    todo: &[usize],
    throttle: usize,
    round_dir: &Path,
    run: &PoolRun,
) -> Result<(String, Vec<Task>, PathBuf)> {
    std::fs::create_dir_all(round_dir)
        .with_context(|| format!("creating {}", round_dir.display()))?;
    let mut tasks = Vec::new();
    for (t, &i) in todo.iter().enumerate() {
        let shard = &states[i].shard;
        let dataset = takes.all[states[i].take].dataset();
        let frames = missing_frames(dataset, shard);
        let spec_path = round_dir.join(format!("task_{t:04}.json"));
        let spec = dataset.shard_spec_json(shard.camera, &frames)?;
        write_atomically(&spec_path, &spec)?;
        tasks.push((i, frames, spec_path));
    }
    let script = array_script(
        runtime,
        settings,
        &run.logs_dir,
        &tasks.iter().map(|t| t.2.clone()).collect::<Vec<_>>(),
        throttle,
    );
    let script_path = round_dir.join("array.sh");
    write_atomically(&script_path, script.as_bytes())?;
    let out = slurm_tool("sbatch", &["--parsable", &script_path.to_string_lossy()])
        .with_context(|| format!("submitting {}", script_path.display()))?;
    // `--parsable` prints `jobid` or `jobid;cluster`.
    let job = out.trim().split(';').next().unwrap_or("").to_string();
    if job.is_empty() || !job.chars().all(|c| c.is_ascii_digit()) {
        bail!("sbatch answered {out:?}; expected a job id");
    }
    Ok((job, tasks, script_path))
}

/// The array script: Slurm options, then one exact worker command per task.
pub(crate) fn array_script(
    runtime: &BlenderRuntime,
    settings: &SlurmSettings,
    logs_dir: &Path,
    specs: &[PathBuf],
    throttle: usize,
) -> String {
    let plan = &settings.plan;
    let minutes = settings.shard_timeout.as_secs().div_ceil(60).max(1);
    let mut s = String::from("#!/bin/bash\n# Written by egogen-run: one array task per shard.\n");
    let mut opt = |o: String| {
        let _ = writeln!(s, "#SBATCH {o}");
    };
    opt("--job-name=egogen".into());
    opt(format!("--array=0-{}%{}", specs.len() - 1, throttle.max(1)));
    opt(format!(
        "--output={}",
        logs_dir.join("slurm_%A_%a.log").display()
    ));
    opt(format!("--cpus-per-task={}", plan.cpus_per_task));
    opt(format!("--mem={}M", (plan.mem_gb * 1024.0).ceil() as u64));
    opt(format!("--time={minutes}"));
    opt("--requeue".into());
    if let Some(p) = &plan.partition {
        opt(format!("--partition={p}"));
    }
    for a in &plan.sbatch_args {
        opt(a.clone());
    }
    s.push_str("set -eu\n");
    s.push_str("case \"$SLURM_ARRAY_TASK_ID\" in\n");
    for (t, spec) in specs.iter().enumerate() {
        let cmd = worker_command(runtime, spec);
        let mut line = String::new();
        for (k, v) in cmd.get_envs() {
            if let Some(v) = v {
                let _ = write!(
                    line,
                    "{}={} ",
                    k.to_string_lossy(),
                    shell_quote(&v.to_string_lossy())
                );
            }
        }
        line.push_str("exec");
        for part in std::iter::once(cmd.get_program()).chain(cmd.get_args()) {
            line.push(' ');
            line.push_str(&shell_quote(&part.to_string_lossy()));
        }
        let _ = writeln!(s, "  {t}) {line} ;;");
    }
    s.push_str("  *) echo \"egogen: no task $SLURM_ARRAY_TASK_ID in this array\" >&2; exit 2 ;;\n");
    s.push_str("esac\n");
    s
}

/// `'…'` quoting for the shell: safe for every byte but NUL.
fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_quoting_survives_quotes_and_spaces() {
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
    }
}
