//! The Slurm backend: the feed's takes are staged on demand, until a few arrays' worth of
//! shards is pending (scratch only for takes in flight). Arrays overlap, at most `workers` of
//! their tasks running: each array is throttled (`%N`); places an array's tail leaves free go to
//! an array with tasks waiting (its throttle raised with `scontrol update`), else a round
//! writes one spec per pending shard of any staged take and an `sbatch` array script (one task
//! per shard, resources from `[supervisor.slurm]`) throttled to the free places and submits it
//! with `sbatch --parsable`, so no round waits for its slowest task. One `squeue` call per
//! poll follows every array in flight; frames are finished here as the tasks' raw renders
//! appear (the dataset folder is on a filesystem shared with the nodes). When an array has
//! left the queue, each task's outcome comes from `scontrol` (or `sacct` once the controller
//! has forgotten the job); shards that still miss frames — failed, timed out, cancelled,
//! killed node — go out again, up to the retry count. Ctrl-C cancels the arrays in flight
//! and leaves a resumable state; a resumed run first cancels the arrays its predecessor left
//! behind. A take whose frames are all finished goes back to the feed at the next poll.
//!
//! Here: the rounds and the polling; `client` (Slurm's client commands run and their answers
//! parsed, the arrays a run submitted recorded), `submit` (a round's shard specs, its `sbatch`
//! array script and its submission), `outcomes` (what an array's tasks did once it left the
//! queue: each task's outcome, the frames it finished, the pool's report).

mod client;
mod outcomes;
mod submit;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use indicatif::ProgressBar;

use super::pace::{FramePace, PaceAttempt};
use super::pool::{
    frames_bar, plan_pace, shard_failure_message, FrameTries, PoolReport, PoolRun, PoolTake,
    RenderTake, ShardPool, ShardReport, TakeFailure, TakeFeed,
};
use super::staged::Shard;
use crate::plan::SlurmPlan;
use crate::render::BlenderRuntime;
pub(crate) use client::check_slurm_tools;
use client::{append_job, cancel_all, cancel_previous_jobs, queued_tasks_of, raise_throttle};
use outcomes::{finish_ready_frames, missing_frames, record_attempts, report_of};
use submit::submit_round;

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
    let (slurm_dir, jobs_path) = slurm_folders(run)?;

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
        let (live, running) = follow_arrays(
            &mut in_flight,
            &takes,
            &mut states,
            &mut busy,
            &pace,
            &bar,
            run,
            &mut frames_finished,
        )?;
        close_rendered_takes(&feed, &mut takes, &states, &mut failed_takes, run)?;
        if stop.load(Ordering::SeqCst) {
            cancel_all(&in_flight);
            bar.finish_and_clear();
            report_of(&states, frames_finished, &failed_takes).write(run)?;
            bail!("interrupted: Slurm jobs cancelled; finished frames are kept; rerun with --resume to continue");
        }
        takes.release(&busy);
        let (todo, given_up) = pending_shards(&takes, &states, &busy, settings.retries);
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
        let free = raise_throttles(&mut in_flight, settings.max_running);
        if free > 0 && !todo.is_empty() {
            let shards = &todo[..];
            let throttle = free.min(shards.len());
            round += 1;
            let round_dir = slurm_dir.join(format!("round_{round:03}"));
            let array = submit_array(
                &takes, &runtime, &settings, &states, shards, throttle, &round_dir, run,
                &jobs_path, &bar, round,
            )?;
            busy.extend(shards.iter().copied());
            in_flight.push(array);
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

/// Creates the run's `slurm/` folder and the logs folder, and cancels the arrays a previous
/// run recorded in `slurm/jobs.txt`; returns both paths.
fn slurm_folders(run: &PoolRun) -> Result<(PathBuf, PathBuf)> {
    let slurm_dir = run.work_dir.join("slurm");
    std::fs::create_dir_all(&slurm_dir)
        .with_context(|| format!("creating {}", slurm_dir.display()))?;
    std::fs::create_dir_all(&run.logs_dir)
        .with_context(|| format!("creating {}", run.logs_dir.display()))?;
    let jobs_path = slurm_dir.join("jobs.txt");
    cancel_previous_jobs(&jobs_path);
    Ok((slurm_dir, jobs_path))
}

/// Follows every array in flight through the queue: each task's pace from when it is first
/// seen running until it leaves; an array that left the queue gives its frames and attempts
/// and frees its shards. Returns the tasks still in the queue and how many of them run.
#[allow(clippy::too_many_arguments)]
fn follow_arrays(
    in_flight: &mut Vec<InFlight>,
    takes: &Takes,
    states: &mut [ShardState],
    busy: &mut std::collections::BTreeSet<usize>,
    pace: &Arc<FramePace>,
    bar: &ProgressBar,
    run: &PoolRun,
    frames_finished: &mut usize,
) -> Result<(usize, usize)> {
    let queues = queued_tasks_of(in_flight)?;
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
            *frames_finished += finish_ready_frames(takes, states, &array.shards(), bar)?;
            for i in array.shards() {
                busy.remove(&i);
            }
            record_attempts(takes, states, array.tasks, &array.job, run);
        } else {
            live += queue.len();
            running += queue.values().filter(|s| s.as_str() == "RUNNING").count();
            still.push(array);
        }
    }
    *in_flight = still;
    Ok((live, running))
}

/// The open shards not in flight that still miss frames, and those of them given up: a frame
/// past its retries, or failed in a way that repeats (the scene does not load).
fn pending_shards(
    takes: &Takes,
    states: &[ShardState],
    busy: &std::collections::BTreeSet<usize>,
    retries: u32,
) -> (Vec<usize>, Vec<usize>) {
    let todo: Vec<usize> = takes
        .open_shards()
        .filter(|&i| {
            !busy.contains(&i)
                && !missing_frames(takes.all[states[i].take].dataset(), &states[i].shard).is_empty()
        })
        .collect();
    // A frame past its retries, or failed in a way that repeats (the scene does not load).
    let given_up: Vec<usize> = todo
        .iter()
        .copied()
        .filter(|&i| {
            let attempts = &states[i].report.attempts;
            states[i].tries.exhausted(retries).is_some()
                || attempts.last().is_some_and(|a| a.outcome.repeats())
        })
        .collect();
    (todo, given_up)
}

/// Gives the places an array's tail leaves free to arrays with tasks waiting (their throttle
/// raised), at most `max_running` tasks running in all; returns the places still free.
fn raise_throttles(in_flight: &mut [InFlight], max_running: usize) -> usize {
    let mut free = max_running.max(1).saturating_sub(
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
    free
}

/// Submits round `round` of the shards `shards` as one array throttled to `throttle`, records
/// its job in `jobs.txt` and says so; the array in flight.
#[allow(clippy::too_many_arguments)]
fn submit_array(
    takes: &Takes,
    runtime: &BlenderRuntime,
    settings: &SlurmSettings,
    states: &[ShardState],
    shards: &[usize],
    throttle: usize,
    round_dir: &Path,
    run: &PoolRun,
    jobs_path: &Path,
    bar: &ProgressBar,
    round: u32,
) -> Result<InFlight> {
    let (job, tasks, script_path) = submit_round(
        takes, runtime, settings, states, shards, throttle, round_dir, run,
    )?;
    append_job(jobs_path, &job)?;
    bar.suspend(|| {
        eprintln!(
            "egogen-run: round {round}: Slurm array job {job}, {} task(s) ({})",
            tasks.len(),
            script_path.display()
        )
    });
    Ok(InFlight {
        job,
        live: tasks.len(),
        tasks,
        throttle,
    })
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
