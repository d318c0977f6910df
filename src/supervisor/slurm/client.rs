//! Slurm's client commands: whether they are here, `sbatch`, `squeue`, `scontrol`,
//! `sacct` and `scancel` run and their answers parsed, and the arrays a run submitted
//! recorded (so a resumed run cancels those its predecessor left behind).

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use anyhow::{bail, Context, Result};

use super::InFlight;
use crate::atomic_file::write_atomically;

/// Whether Slurm's client commands are here (checked before a run stages anything).
pub(crate) fn check_slurm_tools() -> Result<()> {
    slurm_tool("sbatch", &["--version"]).context(
        "the Slurm backend needs Slurm's client commands (sbatch, squeue, scancel) on PATH; \
         install them or use `supervisor.backend = \"local\"`",
    )?;
    Ok(())
}

/// Runs a Slurm client command; its stdout, or an error with its stderr.
pub(super) fn slurm_tool(program: &str, args: &[&str]) -> Result<String> {
    let out = Command::new(program)
        .args(args)
        .output()
        .with_context(|| format!("running `{program}`"))?;
    if !out.status.success() {
        bail!(
            "`{program} {}` failed ({}): {}",
            args.join(" "),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Lets Slurm run up to `throttle` tasks of an array at once; false when it refused (the
/// places then stay free until the next poll tries again).
pub(super) fn raise_throttle(job: &str, throttle: usize) -> bool {
    slurm_tool(
        "scontrol",
        &[
            "update",
            &format!("JobId={job}"),
            &format!("ArrayTaskThrottle={throttle}"),
        ],
    )
    .is_ok()
}

/// Cancels every array in flight (Ctrl-C, or a run stopped by a failure).
pub(super) fn cancel_all(in_flight: &[InFlight]) {
    for a in in_flight {
        let _ = slurm_tool("scancel", &[&a.job]);
    }
}

/// Each array's tasks still in the queue, in the order of `in_flight`: one `squeue` call for
/// all of them (one per array only when the controller has purged one of them).
pub(super) fn queued_tasks_of(in_flight: &[InFlight]) -> Result<Vec<BTreeMap<u32, String>>> {
    if in_flight.is_empty() {
        return Ok(Vec::new());
    }
    let jobs: Vec<&str> = in_flight.iter().map(|a| a.job.as_str()).collect();
    let list = jobs.join(",");
    let out = Command::new("squeue")
        .args([
            "--noheader",
            "--array",
            "--jobs",
            &list,
            "--format=%F %K %T",
        ])
        .output()
        .context("running `squeue`")?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        if err.contains("Invalid job id") {
            return jobs.iter().map(|j| queued_tasks(j)).collect();
        }
        bail!("`squeue --jobs {list}` failed: {}", err.trim());
    }
    let by_job = parse_squeue_jobs(&String::from_utf8_lossy(&out.stdout));
    Ok(jobs
        .iter()
        .map(|j| by_job.get(*j).cloned().unwrap_or_default())
        .collect())
}

/// Parses `squeue --array --format="%F %K %T"` lines: array job, task, state.
pub(crate) fn parse_squeue_jobs(text: &str) -> BTreeMap<String, BTreeMap<u32, String>> {
    let mut out: BTreeMap<String, BTreeMap<u32, String>> = BTreeMap::new();
    for l in text.lines() {
        let mut it = l.split_whitespace();
        let (Some(job), Some(task), Some(state)) = (it.next(), it.next(), it.next()) else {
            continue;
        };
        let Ok(task) = task.parse() else {
            continue;
        };
        out.entry(job.to_string())
            .or_default()
            .insert(task, state.to_string());
    }
    out
}

/// The array's tasks still in the queue (pending, running, completing), by task id.
fn queued_tasks(job: &str) -> Result<BTreeMap<u32, String>> {
    let out = Command::new("squeue")
        .args(["--noheader", "--array", "--jobs", job, "--format=%K %T"])
        .output()
        .context("running `squeue`")?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        // A job the controller has already purged is no longer queued.
        if err.contains("Invalid job id") {
            return Ok(BTreeMap::new());
        }
        bail!("`squeue --jobs {job}` failed: {}", err.trim());
    }
    Ok(parse_squeue(&String::from_utf8_lossy(&out.stdout)))
}

/// Parses `squeue --array --format="%K %T"` lines.
pub(crate) fn parse_squeue(text: &str) -> BTreeMap<u32, String> {
    text.lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            let task = it.next()?.parse().ok()?;
            Some((task, it.next()?.to_string()))
        })
        .collect()
}

/// How each task of a finished array ended: from `scontrol show job` while the controller
/// remembers the job (`MinJobAge`), else from `sacct` where accounting is enabled; empty when
/// neither knows (outcomes then come from the frames on disk alone).
pub(super) fn task_ends(job: &str) -> BTreeMap<u32, TaskEnd> {
    if let Ok(text) = slurm_tool("scontrol", &["--oneliner", "show", "job", job]) {
        let ends = parse_scontrol(&text);
        if !ends.is_empty() {
            return ends;
        }
    }
    slurm_tool(
        "sacct",
        &[
            "--jobs",
            job,
            "--noheader",
            "--parsable2",
            "--allocations",
            "--format=JobID,State,ExitCode,ElapsedRaw",
        ],
    )
    .map(|t| parse_sacct(&t))
    .unwrap_or_default()
}

/// Parses `scontrol --oneliner show job` (one line per array task).
pub(crate) fn parse_scontrol(text: &str) -> BTreeMap<u32, TaskEnd> {
    text.lines()
        .filter_map(|line| {
            let field = |key: &str| {
                line.split_whitespace()
                    .find_map(|kv| kv.strip_prefix(key)?.strip_prefix('='))
            };
            let task = field("ArrayTaskId")?.parse().ok()?;
            Some((
                task,
                TaskEnd {
                    state: field("JobState")?.to_string(),
                    exit_code: field("ExitCode").unwrap_or("?").to_string(),
                    seconds: field("RunTime").map_or(0.0, parse_slurm_duration),
                },
            ))
        })
        .collect()
}

/// Parses `sacct --parsable2 --format=JobID,State,ExitCode,ElapsedRaw` (`JOB_TASK|…`).
pub(crate) fn parse_sacct(text: &str) -> BTreeMap<u32, TaskEnd> {
    text.lines()
        .filter_map(|line| {
            let f: Vec<&str> = line.split('|').collect();
            let task = f.first()?.split_once('_')?.1.parse().ok()?;
            Some((
                task,
                TaskEnd {
                    // `CANCELLED by 0` → `CANCELLED`.
                    state: f.get(1)?.split_whitespace().next()?.to_string(),
                    exit_code: f.get(2).unwrap_or(&"?").to_string(),
                    seconds: f.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.0),
                },
            ))
        })
        .collect()
}

/// `[D-]HH:MM:SS` (or `MM:SS`) in seconds.
fn parse_slurm_duration(s: &str) -> f64 {
    let (days, hms) = match s.split_once('-') {
        Some((d, rest)) => (d.parse::<f64>().unwrap_or(0.0), rest),
        None => (0.0, s),
    };
    let secs = hms
        .split(':')
        .fold(0.0, |acc, p| acc * 60.0 + p.parse::<f64>().unwrap_or(0.0));
    days * 86400.0 + secs
}

pub(super) fn append_job(jobs_path: &Path, job: &str) -> Result<()> {
    let mut text = std::fs::read_to_string(jobs_path).unwrap_or_default();
    text.push_str(job);
    text.push('\n');
    Ok(write_atomically(jobs_path, text.as_bytes())?)
}

/// A resumed run cancels the arrays of the run it continues (they may still be queued if that
/// supervisor was killed); finished frames are on disk either way.
pub(super) fn cancel_previous_jobs(jobs_path: &Path) {
    let Ok(text) = std::fs::read_to_string(jobs_path) else {
        return;
    };
    for job in text.lines().filter(|l| !l.is_empty()) {
        if queued_tasks(job).is_ok_and(|q| !q.is_empty()) {
            eprintln!("egogen-run: cancelling Slurm job {job} left by the interrupted run");
            let _ = slurm_tool("scancel", &[job]);
        }
    }
}

/// How a finished array task ended, as Slurm reports it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TaskEnd {
    pub state: String,
    pub exit_code: String,
    pub seconds: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_queue_and_task_ends() {
        let q = parse_squeue("3 RUNNING\n1 PENDING\n\nbogus\n");
        assert_eq!(q.len(), 2);
        assert_eq!(q[&1], "PENDING");
        let j =
            parse_squeue_jobs("12 3 RUNNING\n12 1 PENDING\n15 0 RUNNING\n\nbogus\n12 x PENDING\n");
        assert_eq!(j.len(), 2);
        assert_eq!(j["12"].len(), 2);
        assert_eq!(j["12"][&1], "PENDING");
        assert_eq!(j["15"][&0], "RUNNING");
        let s = parse_scontrol(
            "JobId=6 ArrayJobId=3 ArrayTaskId=2 JobState=COMPLETED Reason=None ExitCode=0:0 RunTime=00:00:09\n\
             JobId=3 ArrayJobId=3 ArrayTaskId=3 JobState=FAILED Reason=NonZeroExitCode ExitCode=3:0 RunTime=1-00:01:11\n\
             JobId=1 ArrayJobId=1 ArrayTaskId=2-3 JobState=PENDING\n",
        );
        assert_eq!(s.len(), 2);
        assert_eq!(s[&3].state, "FAILED");
        assert_eq!(s[&3].exit_code, "3:0");
        assert_eq!(s[&3].seconds, 86400.0 + 71.0);
        assert_eq!(s[&2].seconds, 9.0);
        let a = parse_sacct("7_0|COMPLETED|0:0|12\n7_1|CANCELLED by 0|0:15|3\n7|FAILED|1:0|4\n");
        assert_eq!(a.len(), 2);
        assert_eq!(a[&1].state, "CANCELLED");
        assert_eq!(a[&0].seconds, 12.0);
    }
}
