//! What an array's tasks did once it left the queue: each task's outcome and attempt in its
//! shard's report, the frames its raw renders finished, and the pool's report.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;

use super::client::{task_ends, TaskEnd};
use super::{ShardState, Takes, Task};
use crate::supervisor::pool::{
    setup_failure, stages_from_worker_log, Attempt, Outcome, PoolReport, PoolRun, RenderTake,
    ShardReport, TakeFailure, EXIT_SETUP_FAILED,
};
use crate::supervisor::staged::Shard;

/// Adds each task's attempt of a round that has left the queue to its shard's report.
pub(super) fn record_attempts(
    takes: &Takes,
    states: &mut [ShardState],
    tasks: Vec<Task>,
    job: &str,
    run: &PoolRun,
) {
    let ends = task_ends(job);
    for (t, (i, frames, _)) in tasks.into_iter().enumerate() {
        let state = &mut states[i];
        let dataset = takes.all[state.take].dataset();
        let left = missing_frames(dataset, &state.shard);
        let still_missing = left.len();
        let end = ends.get(&(t as u32));
        let log = run.logs_dir.join(format!("slurm_{job}_{t}.log"));
        let outcome = task_outcome(end, still_missing, &log);
        if let Some(&first_left) = left.first().filter(|_| !outcome.is_ok()) {
            state.tries.charge(first_left);
        }
        state.report.attempts.push(Attempt {
            attempt: state.report.attempts.len() as u32 + 1,
            frames: frames.len(),
            finished: frames.len() - still_missing,
            outcome,
            seconds: end.map_or(0.0, |e| e.seconds),
            log: dataset.relative(&log),
            stages: std::fs::read_to_string(&log)
                .map(|t| stages_from_worker_log(&t))
                .unwrap_or_default(),
            blender: None,
        });
    }
}

pub(super) fn missing_frames(dataset: &dyn RenderTake, shard: &Shard) -> Vec<u32> {
    shard
        .frames
        .iter()
        .copied()
        .filter(|&f| !dataset.frame_done(shard.camera, f))
        .collect()
}

/// Finishes every frame of the round's shards whose raw renders are all in place (Blender
/// writes each under a temporary name and renames it). Raw renders that do not assemble are
/// removed so the frame is rendered again.
pub(super) fn finish_ready_frames(
    takes: &Takes,
    states: &[ShardState],
    todo: &[usize],
    bar: &indicatif::ProgressBar,
) -> Result<usize> {
    let mut finished = 0;
    for &i in todo {
        let shard = &states[i].shard;
        let dataset = takes.all[states[i].take].dataset();
        let name = dataset.camera_name(shard.camera);
        for f in missing_frames(dataset, shard) {
            let raw = dataset.raw_frame_files(shard.camera, f);
            if !raw.iter().all(|r| r.is_file()) {
                continue;
            }
            match dataset.finish_frame(shard.camera, f) {
                Ok(_) => {
                    finished += 1;
                    if let Some(pace) = &states[i].pace {
                        pace.frame_done();
                    }
                    bar.inc(1);
                }
                Err(e) => {
                    bar.suspend(|| {
                        eprintln!("egogen-run: {name} frame {f}: {e:#}; rendering it again")
                    });
                    for r in &raw {
                        let _ = std::fs::remove_file(r);
                    }
                }
            }
        }
    }
    Ok(finished)
}

/// The pool report of the shards so far.
pub(super) fn report_of(
    states: &[ShardState],
    frames_finished: usize,
    started: Instant,
    workers: usize,
    failed_takes: &[TakeFailure],
) -> PoolReport {
    let mut shards: Vec<ShardReport> = states.iter().map(|s| s.report.clone()).collect();
    shards.sort_by(|a, b| (&a.take, a.shard).cmp(&(&b.take, b.shard)));
    let wall_seconds = started.elapsed().as_secs_f64();
    // The tasks' run times as Slurm reports them (whole seconds), over the places they had.
    let busy: f64 = shards
        .iter()
        .flat_map(|s| &s.attempts)
        .map(|a| a.seconds)
        .sum();
    let places = workers.max(1) as f64 * wall_seconds;
    PoolReport {
        shards,
        frames_finished,
        wall_seconds,
        workers,
        busy_seconds: Vec::new(),
        utilisation: if places > 0.0 { busy / places } else { 0.0 },
        failed_takes: failed_takes.to_vec(),
    }
}

/// What one array task did, from its end state (when Slurm still knows it), the frames it
/// left missing and its log: `ok`, a setup failure (exit status 3, not retried), or why it
/// failed.
fn task_outcome(end: Option<&TaskEnd>, still_missing: usize, log: &Path) -> Outcome {
    let failed = |reason: String| Outcome::Failed { reason };
    match (end, still_missing) {
        (Some(e), 0) if e.state == "COMPLETED" => Outcome::Ok,
        (None, 0) => Outcome::Ok,
        (Some(e), 0) => failed(format!(
            "{} (exit {}) after finishing its frames",
            e.state, e.exit_code
        )),
        (Some(e), _) if e.exit_code.split(':').next() == Some(&EXIT_SETUP_FAILED.to_string()) => {
            setup_failure(log)
        }
        (Some(e), n) => failed(format!(
            "{} (exit {}), {n} frames missing",
            e.state, e.exit_code
        )),
        (None, n) => failed(format!("left the queue with {n} frames missing")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_task_that_could_not_set_up_the_scene_is_a_setup_failure() {
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("slurm_7_0.log");
        std::fs::write(
            &log,
            "Blender 4.5\nEGOGEN_SETUP_FAILED RuntimeError: Bad glTF\n",
        )
        .unwrap();
        let end = |state: &str, exit: &str| TaskEnd {
            state: state.into(),
            exit_code: exit.into(),
            seconds: 1.0,
        };
        let setup = task_outcome(Some(&end("FAILED", "3:0")), 2, &log);
        assert!(setup.repeats());
        let setup = setup.to_string();
        assert!(
            setup.starts_with(crate::supervisor::pool::SETUP_FAILED),
            "{setup}"
        );
        assert!(setup.ends_with("RuntimeError: Bad glTF"), "{setup}");
        // A killed or cancelled task is retried as before.
        let killed = task_outcome(Some(&end("CANCELLED", "0:15")), 2, &log);
        assert!(!killed.repeats());
        assert_eq!(
            killed.to_string(),
            "CANCELLED (exit 0:15), 2 frames missing"
        );
        assert_eq!(
            task_outcome(Some(&end("COMPLETED", "0:0")), 0, &log),
            Outcome::Ok
        );
        assert_eq!(
            task_outcome(Some(&end("FAILED", "13:0")), 1, &log).to_string(),
            "FAILED (exit 13:0), 1 frames missing"
        );
    }
}
