//! The `[supervisor]` section resolved: the local or Slurm backend and its settings.

use std::path::Path;

use crate::cli::config::{Backend, ConfigError, RawSlurm, RawSupervisor};
use crate::plan::{SlurmPlan, SupervisorPlan};

pub(super) fn resolve_supervisor(
    s: RawSupervisor,
    config_path: &Path,
) -> Result<SupervisorPlan, ConfigError> {
    let bad = |key: &str, message: String| ConfigError::Value {
        path: config_path.into(),
        key: key.into(),
        message,
    };
    let workers = s.workers.unwrap_or(1);
    if workers == 0 || workers > 256 {
        return Err(bad(
            "supervisor.workers",
            format!("expected 1..=256 workers, found {workers}"),
        ));
    }
    let shard_timeout_s = s.shard_timeout_s.unwrap_or(3600.0);
    if !(shard_timeout_s.is_finite() && shard_timeout_s > 0.0) {
        return Err(bad(
            "supervisor.shard_timeout_s",
            format!("expected a positive number of seconds, found {shard_timeout_s}"),
        ));
    }
    let backend = s.backend.unwrap_or(Backend::Local);
    if s.slurm.is_some() && backend != Backend::Slurm {
        return Err(bad(
            "supervisor.slurm",
            "given but `supervisor.backend` is not \"slurm\"".into(),
        ));
    }
    Ok(SupervisorPlan {
        backend,
        workers,
        shard_timeout_s,
        retries: s.retries.unwrap_or(2),
        keep_blender: s.keep_blender.unwrap_or(false),
        slurm: resolve_slurm(s.slurm.unwrap_or_default(), &bad)?,
    })
}

fn resolve_slurm(
    s: RawSlurm,
    bad: &dyn Fn(&str, String) -> ConfigError,
) -> Result<SlurmPlan, ConfigError> {
    let cpus_per_task = s.cpus_per_task.unwrap_or(2);
    if cpus_per_task == 0 {
        return Err(bad(
            "supervisor.slurm.cpus_per_task",
            "expected at least 1".into(),
        ));
    }
    let mem_gb = s.mem_gb.unwrap_or(4.0);
    if !(mem_gb.is_finite() && mem_gb > 0.0) {
        return Err(bad(
            "supervisor.slurm.mem_gb",
            format!("expected a positive number of GB, found {mem_gb}"),
        ));
    }
    let poll_interval_s = s.poll_interval_s.unwrap_or(10.0);
    if !(poll_interval_s.is_finite() && poll_interval_s > 0.0) {
        return Err(bad(
            "supervisor.slurm.poll_interval_s",
            format!("expected a positive number of seconds, found {poll_interval_s}"),
        ));
    }
    let sbatch_args = s.sbatch_args.unwrap_or_default();
    if let Some(a) = sbatch_args.iter().find(|a| !a.starts_with('-')) {
        return Err(bad(
            "supervisor.slurm.sbatch_args",
            format!("expected sbatch options starting with `-`, found {a:?}"),
        ));
    }
    if let Some(p) = &s.partition {
        if p.is_empty() || p.contains(char::is_whitespace) {
            return Err(bad(
                "supervisor.slurm.partition",
                format!("expected a partition name, found {p:?}"),
            ));
        }
    }
    Ok(SlurmPlan {
        partition: s.partition,
        cpus_per_task,
        mem_gb,
        poll_interval_s,
        sbatch_args,
    })
}
