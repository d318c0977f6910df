//! The Slurm backend: the feed's takes are staged on demand, until a few arrays' worth of
//! shards is pending (scratch only for takes in flight). Arrays overlap, at most `workers` of
//! their tasks running: each array is throttled (`%N`); places an array's tail leaves free go to
//! an array with tasks waiting (its throttle raised with `scontrol update`), else a round
//! writes one spec per pending shard of any staged take and an `sbatch` array script (one task
//! per shard, resources from `[supervisor.slurm]`) throttled to the free places and submits it
//! with `sbatch --parsable`, so no round waits for its slowest task. One `squeue` call per poll follows every array in flight; frames are finished
//! here as the tasks' raw renders appear (the dataset folder is on a filesystem shared with the
//! nodes). When an array has left the queue, each task's outcome comes from `scontrol` (or
//! `sacct` once the controller has forgotten the job); shards that still miss frames — failed,
//! timed out, cancelled, killed node — go out again, up to the retry count. Ctrl-C cancels the
//! arrays in flight and leaves a resumable state; a resumed run first cancels the arrays its
//! predecessor left behind. A take whose frames are all finished goes back to the feed at the
//! next poll.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

use super::pace::{FramePace, PaceAttempt};
use super::pool::{
    frames_bar, plan_pace, setup_failure, shard_failure_message, stages_from_worker_log, Attempt,
    FrameTries, Outcome, PoolReport, PoolRun, PoolTake, RenderTake, ShardPool, ShardReport,
    TakeFailure, TakeFeed, EXIT_SETUP_FAILED,
};
use super::staged::Shard;
use crate::atomic_file::write_atomically;
use crate::plan::SlurmPlan;
use crate::render::shard::worker_command;
use crate::render::BlenderRuntime;

/// Slurm backend settings.
#[derive(Debug, Clone)]
pub struct SlurmSettings {
    pub plan: SlurmPlan,
    /// Array tasks running at once (`--array=…%N`).
    pub max_running: usize,
    /// Becomes each task's `--time` (whole minutes, rounded up).
    pub shard_timeout: Duration,
    pub retries: u32,
}

/// How a finished array task ended, as Slurm reports it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TaskEnd {
    pub state: String,
    pub exit_code: String,
    pub seconds: f64,
}

struct ShardState {
    /// Index of the shard's take in the run's takes.
    take: usize,
    shard: Shard,
    report: ShardReport,
    /// Failed tries charged to each frame (retries count frames, not attempts).
    tries: FrameTries,
    /// Its task's pace while Slurm runs it (for the ETA).
    pace: Option<PaceAttempt>,
}

/// A staged take in the run, and whether it is done with (finished or given up). The take
/// itself is let go once it is closed and none of its shards is in flight, so the run holds
/// only the takes in flight however many a campaign has.
struct TakeInRun {
    name: String,
    take: Option<PoolTake>,
    closed: bool,
    /// Its shards' indices in the run's shard states.
    shards: Vec<usize>,
}

impl TakeInRun {
    /// The take's work: held while it is open or any of its shards is in flight.
    fn dataset(&self) -> &dyn RenderTake {
        &*self
            .take
            .as_ref()
            .expect("a take is held while open or in flight")
            .dataset
    }
}

/// The takes of a run, and which of them are open (in staging order).
#[derive(Default)]
struct Takes {
    all: Vec<TakeInRun>,
    open: Vec<usize>,
    /// Closed takes still held (some of their shards were in flight when they closed).
    held: Vec<usize>,
}

impl Takes {
    /// Closes take `t`.
    fn close(&mut self, t: usize) {
        self.all[t].closed = true;
        self.open.retain(|&o| o != t);
        self.held.push(t);
    }

    /// Shards of open takes, in staging order.
    fn open_shards(&self) -> impl Iterator<Item = usize> + '_ {
        self.open
            .iter()
            .flat_map(move |&t| self.all[t].shards.iter().copied())
    }

    /// Lets go of closed takes none of whose shards is in flight.
    fn release(&mut self, busy: &std::collections::BTreeSet<usize>) {
        let all = &mut self.all;
        self.held.retain(|&t| {
            if all[t].shards.iter().any(|i| busy.contains(i)) {
                return true;
            }
            all[t].take = None;
            false
        });
    }
}

/// The Slurm backend: renders shards as Slurm array tasks; returns when every frame is
/// finished, or fails when Ctrl-C was pressed or (when the run says so) a shard has failed
/// past its retries.
#[derive(Debug, Clone)]
pub struct SlurmPool(pub SlurmSettings);

impl ShardPool for SlurmPool {
    fn run(
        &self,
        feed: Arc<Mutex<dyn TakeFeed>>,
        runtime: BlenderRuntime,
        run: &PoolRun,
    ) -> Result<PoolReport> {
        run_slurm(feed, runtime, self.0.clone(), run)
    }
}

/// Shards pending per task Slurm may run at once before staging stops: takes are staged on
/// demand, enough to fill a few arrays, so scratch is held for the takes in flight only.
const STAGED_SHARDS_PER_TASK: usize = 4;

/// Stages takes until `want` shards of open takes are pending or the feed is out (then it
/// says so); takes that cannot be staged are recorded.
fn stage_more(
    feed: &Mutex<dyn TakeFeed>,
    takes: &mut Takes,
    states: &mut Vec<ShardState>,
    failed: &mut Vec<TakeFailure>,
    want: usize,
    pace: &FramePace,
) -> bool {
    // Counted once from disk; a newly staged take adds its shards (all pending).
    let mut pending = takes
        .open_shards()
        .filter(|&i| {
            let s = &states[i];
            !missing_frames(takes.all[s.take].dataset(), &s.shard).is_empty()
        })
        .count();
    loop {
        if pending >= want {
            return false;
        }
        // Paused: asked again at the next poll, the jobs in flight going on meanwhile.
        if feed.lock().unwrap().pause().is_some() {
            return false;
        }
        let next = feed.lock().unwrap().next_take();
        match next {
            None => return true,
            Some(Err(f)) => failed.push(f),
            Some(Ok(take)) => {
                plan_pace(pace, take.dataset.as_ref(), &take.shards);
                pending += take.shards.len();
                let t = takes.all.len();
                let first = states.len();
                states.extend(take.shards.iter().map(|shard| ShardState {
                    take: t,
                    report: ShardReport {
                        take: take.name.clone(),
                        shard: shard.id,
                        camera: take.dataset.camera_name(shard.camera).to_owned(),
                        frames: shard.frames.clone(),
                        attempts: Vec::new(),
                    },
                    shard: shard.clone(),
                    tries: FrameTries::default(),
                    pace: None,
                }));
                takes.all.push(TakeInRun {
                    name: take.name.clone(),
                    shards: (first..states.len()).collect(),
                    take: Some(take),
                    closed: false,
                });
                takes.open.push(t);
            }
        }
    }
}

fn run_slurm(
    feed: Arc<Mutex<dyn TakeFeed>>,
    runtime: BlenderRuntime,
    settings: SlurmSettings,
    run: &PoolRun,
) -> Result<PoolReport> {
    let started = Instant::now();
    check_slurm_tools()?;
    let slurm_dir = run.work_dir.join("slurm");
    std::fs::create_dir_all(&slurm_dir)
        .with_context(|| format!("creating {}", slurm_dir.display()))?;
    std::fs::create_dir_all(&run.logs_dir)
        .with_context(|| format!("creating {}", run.logs_dir.display()))?;
    let jobs_path = slurm_dir.join("jobs.txt");
    cancel_previous_jobs(&jobs_path);

    let stop = ctrl_c_flag();

    let (total, done) = feed.lock().unwrap().frames();
    let pace = Arc::new(FramePace::default());
    let bar = frames_bar(total as u64, done as u64, pace.clone());
    let mut failed_takes = Vec::new();
    let mut takes = Takes::default();
    let mut states: Vec<ShardState> = Vec::new();
    let window = settings.max_running.max(1) * STAGED_SHARDS_PER_TASK;
    let mut feed_done = false;
    let mut round = 0u32;
    let mut frames_finished = 0usize;
    let report_of = |states: &[ShardState], frames_finished, failed: &[TakeFailure]| {
        report_of(
            states,
            frames_finished,
            started,
            settings.max_running,
            failed,
        )
    };
    // Arrays in the queue, and the shards they render.
    let mut in_flight: Vec<InFlight> = Vec::new();
    let mut busy: std::collections::BTreeSet<usize> = std::collections::BTreeSet::new();
    let poll = Duration::from_secs_f64(settings.plan.poll_interval_s);
    loop {
        if !feed_done {
            feed_done = stage_more(
                &feed,
                &mut takes,
                &mut states,
                &mut failed_takes,
                window,
                &pace,
            );
            if run.stop_on_failure {
                if let Some(f) = failed_takes.first() {
                    cancel_all(&in_flight);
                    bar.finish_and_clear();
                    bail!("{}", f.reason);
                }
            }
            bar.set_length(feed.lock().unwrap().frames().0 as u64);
        }
        // Frames of every array in flight; arrays that left the queue give their attempts.
        let flying: Vec<usize> = busy.iter().copied().collect();
        frames_finished += finish_ready_frames(&takes, &states, &flying, &bar)?;
        let queues = queued_tasks_of(&in_flight)?;
        let (mut live, mut running) = (0, 0);
        let mut still = Vec::new();
        for (mut array, queue) in in_flight.drain(..).zip(queues) {
            array.live = queue.len();
            // The pace of each task from when it is first seen running until it leaves.
            for (t, (i, _, _)) in array.tasks.iter().enumerate() {
                let state = &mut states[*i];
                match queue.get(&(t as u32)).map(String::as_str) {
                    Some("RUNNING") if state.pace.is_none() => {
                        let dataset = takes.all[state.take].dataset();
                        let frames = missing_frames(dataset, &state.shard).len() as u64;
                        let camera = dataset.camera_name(state.shard.camera);
                        state.pace = Some(pace.attempt(camera, frames));
                    }
                    None => state.pace = None,
                    _ => {}
                }
            }
            if queue.is_empty() {
                frames_finished += finish_ready_frames(&takes, &states, &array.shards(), &bar)?;
                for i in array.shards() {
                    busy.remove(&i);
                }
                record_attempts(&takes, &mut states, array.tasks, &array.job, run);
            } else {
                live += queue.len();
                running += queue.values().filter(|s| s.as_str() == "RUNNING").count();
                still.push(array);
            }
        }
        in_flight = still;
        close_rendered_takes(&feed, &mut takes, &states, &mut failed_takes, run)?;
        if stop.load(Ordering::SeqCst) {
            cancel_all(&in_flight);
            bar.finish_and_clear();
            report_of(&states, frames_finished, &failed_takes).write(run)?;
            bail!("interrupted: Slurm jobs cancelled; finished frames are kept; rerun with --resume to continue");
        }
        takes.release(&busy);
        let todo: Vec<usize> = takes
            .open_shards()
            .filter(|&i| {
                !busy.contains(&i)
                    && !missing_frames(takes.all[states[i].take].dataset(), &states[i].shard)
                        .is_empty()
            })
            .collect();
        // A frame past its retries, or failed in a way that repeats (the scene does not load).
        let given_up: Vec<usize> = todo
            .iter()
            .copied()
            .filter(|&i| {
                let attempts = &states[i].report.attempts;
                states[i].tries.exhausted(settings.retries).is_some()
                    || attempts.last().is_some_and(|a| a.outcome.repeats())
            })
            .collect();
        if !given_up.is_empty() {
            for &i in &given_up {
                let t = states[i].take;
                if takes.all[t].closed {
                    continue;
                }
                let worst = states[i].tries.exhausted(settings.retries);
                let why = worst.map_or_else(
                    || "the scene could not be set up".into(),
                    |(f, n)| format!("frame {f} failed {n} time(s)"),
                );
                let message =
                    shard_failure_message(takes.all[t].dataset(), &states[i].report, &why);
                if run.stop_on_failure {
                    cancel_all(&in_flight);
                    bar.finish_and_clear();
                    report_of(&states, frames_finished, &failed_takes).write(run)?;
                    bail!("{message}");
                }
                let failure = TakeFailure {
                    take: takes.all[t].name.clone(),
                    reason: message,
                };
                feed.lock().unwrap().take_failed(&failure);
                failed_takes.push(failure);
                takes.close(t);
            }
            continue;
        }
        if todo.is_empty() && in_flight.is_empty() {
            if feed_done {
                break;
            }
            continue;
        }
        // Arrays overlap, at most `workers` tasks of them running: a place an array's tail
        // leaves free goes to an array with tasks waiting (its throttle raised), else to a new
        // array of the pending shards, so no round waits for its slowest task.
        let mut free = settings.max_running.max(1).saturating_sub(
            in_flight
                .iter()
                .map(|a| a.live.min(a.throttle))
                .sum::<usize>(),
        );
        for array in in_flight.iter_mut() {
            let more = free.min(array.live.saturating_sub(array.throttle));
            if more > 0 && raise_throttle(&array.job, array.throttle + more) {
                array.throttle += more;
                free -= more;
            }
        }
        if free > 0 && !todo.is_empty() {
            let shards = &todo[..];
            let throttle = free.min(shards.len());
            round += 1;
            let round_dir = slurm_dir.join(format!("round_{round:03}"));
            let (job, tasks, script_path) = submit_round(
                &takes, &runtime, &settings, &states, shards, throttle, &round_dir, run,
            )?;
            append_job(&jobs_path, &job)?;
            bar.suspend(|| {
                eprintln!(
                    "egogen-run: round {round}: Slurm array job {job}, {} task(s) ({})",
                    tasks.len(),
                    script_path.display()
                )
            });
            busy.extend(shards.iter().copied());
            in_flight.push(InFlight {
                job,
                live: tasks.len(),
                tasks,
                throttle,
            });
            continue;
        }
        bar.set_message(format!(
            "{} array(s): {running} task(s) running, {} queued",
            in_flight.len(),
            live - running
        ));
        if sleep_unless_stopped(poll, &stop) {
            cancel_all(&in_flight);
            bar.finish_and_clear();
            report_of(&states, frames_finished, &failed_takes).write(run)?;
            bail!(
                "interrupted: Slurm jobs cancelled; finished frames are kept; rerun with --resume to continue"
            );
        }
    }
    bar.finish_and_clear();
    let report = report_of(&states, frames_finished, &failed_takes);
    report.write(run)?;
    Ok(report)
}

/// Hands every take whose frames are all finished back to the feed; one that cannot be
/// finished is given up (or fails the run).
fn close_rendered_takes(
    feed: &Mutex<dyn TakeFeed>,
    takes: &mut Takes,
    states: &[ShardState],
    failed: &mut Vec<TakeFailure>,
    run: &PoolRun,
) -> Result<()> {
    let rendered: Vec<usize> = takes
        .open
        .iter()
        .copied()
        .filter(|&t| {
            let take = &takes.all[t];
            take.shards
                .iter()
                .all(|&i| missing_frames(take.dataset(), &states[i].shard).is_empty())
        })
        .collect();
    for t in rendered {
        takes.close(t);
        let take = &takes.all[t];
        let Some(pool_take) = take.take.as_ref() else {
            continue;
        };
        if let Err(e) = feed.lock().unwrap().take_rendered(pool_take) {
            let failure = TakeFailure {
                take: take.name.clone(),
                reason: format!("finishing take {}: {e:#}", take.name),
            };
            if run.stop_on_failure {
                bail!("{}", failure.reason);
            }
            feed.lock().unwrap().take_failed(&failure);
            failed.push(failure);
        }
    }
    Ok(())
}

/// A flag raised by Ctrl-C (a thread waits for the signal).
fn ctrl_c_flag() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    std::thread::spawn(move || {
        let Ok(rt) = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
        else {
            return;
        };
        rt.block_on(async {
            if tokio::signal::ctrl_c().await.is_ok() {
                flag.store(true, Ordering::SeqCst);
            }
        })
    });
    stop
}

/// A shard's task in a round: its index in the states, the frames it renders, its spec.
type Task = (usize, Vec<u32>, PathBuf);

/// Writes one round's specs (the missing frames of the shards `todo`) and its array script
/// into `round_dir`, and submits it; returns the job id, the tasks and the script.
#[allow(clippy::too_many_arguments)]
fn submit_round(
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

/// Adds each task's attempt of a round that has left the queue to its shard's report.
fn record_attempts(
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

fn missing_frames(dataset: &dyn RenderTake, shard: &Shard) -> Vec<u32> {
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
fn finish_ready_frames(
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
fn report_of(
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

/// Runs a Slurm client command; its stdout, or an error with its stderr.
/// Whether Slurm's client commands are here (checked before a run stages anything).
pub(crate) fn check_slurm_tools() -> Result<()> {
    slurm_tool("sbatch", &["--version"]).context(
        "the Slurm backend needs Slurm's client commands (sbatch, squeue, scancel) on PATH; \
         install them or use `supervisor.backend = \"local\"`",
    )?;
    Ok(())
}

fn slurm_tool(program: &str, args: &[&str]) -> Result<String> {
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

/// An array job in the queue and its tasks.
struct InFlight {
    job: String,
    tasks: Vec<Task>,
    /// How many of its tasks Slurm may run at once (`%N`, raised as places free up).
    throttle: usize,
    /// Its tasks in the queue at the last poll (pending or running).
    live: usize,
}

impl InFlight {
    /// The shards its tasks render.
    fn shards(&self) -> Vec<usize> {
        self.tasks.iter().map(|t| t.0).collect()
    }
}

/// Lets Slurm run up to `throttle` tasks of an array at once; false when it refused (the
/// places then stay free until the next poll tries again).
fn raise_throttle(job: &str, throttle: usize) -> bool {
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
fn cancel_all(in_flight: &[InFlight]) {
    for a in in_flight {
        let _ = slurm_tool("scancel", &[&a.job]);
    }
}

/// Each array's tasks still in the queue, in the order of `in_flight`: one `squeue` call for
/// all of them (one per array only when the controller has purged one of them).
fn queued_tasks_of(in_flight: &[InFlight]) -> Result<Vec<BTreeMap<u32, String>>> {
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
fn task_ends(job: &str) -> BTreeMap<u32, TaskEnd> {
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

fn append_job(jobs_path: &Path, job: &str) -> Result<()> {
    let mut text = std::fs::read_to_string(jobs_path).unwrap_or_default();
    text.push_str(job);
    text.push('\n');
    Ok(write_atomically(jobs_path, text.as_bytes())?)
}

/// A resumed run cancels the arrays of the run it continues (they may still be queued if that
/// supervisor was killed); finished frames are on disk either way.
fn cancel_previous_jobs(jobs_path: &Path) {
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

/// Sleeps `d` in short steps; true as soon as `stop` is set.
fn sleep_unless_stopped(d: Duration, stop: &AtomicBool) -> bool {
    let until = Instant::now() + d;
    while Instant::now() < until {
        if stop.load(Ordering::SeqCst) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(100).min(until - Instant::now()));
    }
    stop.load(Ordering::SeqCst)
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

    #[test]
    fn shell_quoting_survives_quotes_and_spaces() {
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
    }
}
