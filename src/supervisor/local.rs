//! The local backend: a tokio pool of Blender worker processes. Each worker takes a shard (of
//! any take the feed has staged; the next take is staged in the background when fewer shards
//! than workers are queued, or by a worker that finds none left), starts
//! Blender on its spec, finishes frames as their raw files are reported, and retries a failed
//! or timed-out attempt on the frames still missing until one frame has failed more than the
//! configured count (retries count frames, not attempts: `run_shard`); each attempt's stderr
//! goes to its take's `logs/`. A take whose shards are all done goes back to the feed to be
//! finished while the workers render the next. Ctrl-C kills the workers and leaves every
//! finished frame in place, so `--resume` continues.

use std::collections::{BTreeSet, VecDeque};
use std::process::Stdio;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use indicatif::ProgressBar;
use tokio::io::{AsyncBufReadExt, BufReader};
use tokio::sync::watch;

use super::pool::{
    add_stage, frames_bar, setup_failure, shard_failure_message, worker_timing, Attempt,
    FrameTries, Outcome, PoolReport, PoolRun, PoolTake, RenderTake, ShardPool, ShardReport,
    StageSeconds, TakeFailure, TakeFeed, EXIT_SETUP_FAILED,
};
use super::staged::Shard;
use crate::render::shard::worker_command;
use crate::render::BlenderRuntime;

/// Pool settings.
#[derive(Debug, Clone, Copy)]
pub struct PoolSettings {
    pub workers: usize,
    pub shard_timeout: Duration,
    pub retries: u32,
}

/// The local backend: renders shards with a pool of local Blender workers; returns when all
/// are done, or Ctrl-C was pressed, or (when the run says so) one has failed past its retries
/// (both errors).
#[derive(Debug, Clone, Copy)]
pub struct LocalPool(pub PoolSettings);

/// A staged take in the pool: its shards not yet handed back, and whether it failed. The take
/// itself is let go once it is handed back or given up, so the pool holds only the takes in
/// flight however many a campaign has.
struct TakeInPool {
    name: String,
    take: Option<PoolTake>,
    shards_left: usize,
    failed: bool,
}

struct Shared {
    feed: Arc<Mutex<dyn TakeFeed>>,
    runtime: BlenderRuntime,
    settings: PoolSettings,
    stop_on_failure: bool,
    takes: Mutex<Vec<TakeInPool>>,
    /// (take, shard) in the order they are rendered.
    queue: Mutex<VecDeque<(usize, Shard)>>,
    /// The feed has no takes left.
    feed_done: Mutex<bool>,
    /// One take is staged at a time, ahead of need when the queue runs short (`prefetch`);
    /// the workers render meanwhile.
    staging: Arc<tokio::sync::Mutex<()>>,
    reports: Mutex<Vec<ShardReport>>,
    failed: Mutex<Option<String>>,
    failed_takes: Mutex<Vec<TakeFailure>>,
    busy_seconds: Mutex<Vec<f64>>,
    states: Mutex<Vec<String>>,
    bar: ProgressBar,
    stop: watch::Receiver<bool>,
}

impl ShardPool for LocalPool {
    fn run(
        &self,
        feed: Arc<Mutex<dyn TakeFeed>>,
        runtime: BlenderRuntime,
        run: &PoolRun,
    ) -> Result<PoolReport> {
        run_local(feed, runtime, self.0, run)
    }
}

fn run_local(
    feed: Arc<Mutex<dyn TakeFeed>>,
    runtime: BlenderRuntime,
    settings: PoolSettings,
    run: &PoolRun,
) -> Result<PoolReport> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the worker pool")?;
    rt.block_on(async move {
        let started = Instant::now();
        let (total, done) = feed.lock().unwrap().frames();
        let bar = frames_bar(total as u64, done as u64)?;
        let (stop_tx, stop_rx) = watch::channel(false);
        let workers = settings.workers.max(1);
        let shared = Arc::new(Shared {
            feed,
            runtime,
            settings,
            stop_on_failure: run.stop_on_failure,
            takes: Mutex::new(Vec::new()),
            queue: Mutex::new(VecDeque::new()),
            feed_done: Mutex::new(false),
            staging: Arc::new(tokio::sync::Mutex::new(())),
            reports: Mutex::new(Vec::new()),
            failed: Mutex::new(None),
            failed_takes: Mutex::new(Vec::new()),
            busy_seconds: Mutex::new(vec![0.0; workers]),
            states: Mutex::new(vec!["idle".into(); workers]),
            bar: bar.clone(),
            stop: stop_rx,
        });
        let interrupt = tokio::spawn(async move {
            if tokio::signal::ctrl_c().await.is_ok() {
                let _ = stop_tx.send(true);
            }
        });
        let handles: Vec<_> = (0..workers)
            .map(|w| tokio::spawn(worker(shared.clone(), w)))
            .collect();
        for h in handles {
            h.await.context("worker task")?;
        }
        interrupt.abort();
        bar.finish_and_clear();
        let mut reports = std::mem::take(&mut *shared.reports.lock().unwrap());
        reports.sort_by(|a, b| (&a.take, a.shard).cmp(&(&b.take, b.shard)));
        let frames_finished = reports
            .iter()
            .flat_map(|r| r.attempts.iter())
            .map(|a| a.finished)
            .sum();
        let wall_seconds = started.elapsed().as_secs_f64();
        let busy_seconds = shared.busy_seconds.lock().unwrap().clone();
        let report = PoolReport {
            shards: reports,
            frames_finished,
            wall_seconds,
            workers,
            utilisation: busy_seconds.iter().sum::<f64>()
                / (workers as f64 * wall_seconds).max(1e-9),
            busy_seconds,
            failed_takes: shared.failed_takes.lock().unwrap().clone(),
        };
        // Written whatever happened: an interrupted or failed start's report is the one a
        // user reads first.
        report.write(run)?;
        if *shared.stop.borrow() {
            bail!("interrupted: finished frames are kept; rerun with --resume to continue");
        }
        if let Some(reason) = shared.failed.lock().unwrap().take() {
            bail!("{reason}");
        }
        Ok(report)
    })
}

fn set_state(shared: &Shared, w: usize, state: String) {
    let mut states = shared.states.lock().unwrap();
    states[w] = state;
    let msg = states
        .iter()
        .enumerate()
        .map(|(i, s)| format!("w{i}: {s}"))
        .collect::<Vec<_>>()
        .join(" | ");
    shared.bar.set_message(msg);
}

/// What a worker does next.
enum Next {
    Render(usize, Arc<dyn RenderTake>, Shard),
    /// Nothing queued: stage a take (or find none left).
    Stage,
    Stop,
}

fn next_work(shared: &Shared) -> Next {
    if *shared.stop.borrow() || shared.failed.lock().unwrap().is_some() {
        return Next::Stop;
    }
    loop {
        let Some((t, shard)) = shared.queue.lock().unwrap().pop_front() else {
            return if *shared.feed_done.lock().unwrap() {
                Next::Stop
            } else {
                Next::Stage
            };
        };
        let takes = shared.takes.lock().unwrap();
        if let Some(take) = takes[t].take.as_ref().filter(|_| !takes[t].failed) {
            return Next::Render(t, take.dataset.clone(), shard);
        }
    }
}

async fn worker(shared: Arc<Shared>, w: usize) {
    loop {
        let (t, dataset, shard) = match next_work(&shared) {
            Next::Stop => break,
            Next::Stage => {
                let _one = shared.staging.lock().await;
                if shared.queue.lock().unwrap().is_empty() && !*shared.feed_done.lock().unwrap() {
                    set_state(&shared, w, "staging a take".into());
                    stage_next(&shared).await;
                }
                continue;
            }
            Next::Render(t, dataset, shard) => (t, dataset, shard),
        };
        prefetch(&shared);
        let began = Instant::now();
        let (mut report, failure) = run_shard(&shared, &dataset, w, &shard).await;
        shared.busy_seconds.lock().unwrap()[w] += began.elapsed().as_secs_f64();
        let name = shared.takes.lock().unwrap()[t].name.clone();
        report.take = name.clone();
        if let Some(failure) = failure.filter(|_| !*shared.stop.borrow()) {
            let message = shard_failure_message(&*dataset, &report, &failure);
            if shared.stop_on_failure {
                shared.failed.lock().unwrap().get_or_insert(message);
            } else {
                fail_take(&shared, t, message).await;
            }
        } else if !*shared.stop.borrow() {
            let rendered = {
                let mut takes = shared.takes.lock().unwrap();
                takes[t].shards_left -= 1;
                takes[t].shards_left == 0 && !takes[t].failed
            };
            if rendered {
                set_state(&shared, w, format!("finishing take {name}"));
                take_rendered(&shared, t).await;
            }
        }
        shared.reports.lock().unwrap().push(report);
    }
    set_state(&shared, w, "done".into());
}

/// Stages the next take in the background when fewer shards are queued than there are
/// workers, so that no worker waits for a take's motion at another take's tail.
fn prefetch(shared: &Arc<Shared>) {
    let short = shared.queue.lock().unwrap().len() < shared.settings.workers.max(1);
    if !short || *shared.feed_done.lock().unwrap() {
        return;
    }
    let Ok(one) = shared.staging.clone().try_lock_owned() else {
        return;
    };
    let shared = shared.clone();
    tokio::spawn(async move {
        stage_next(&shared).await;
        drop(one);
    });
}

/// Stages the feed's next take and queues its shards (a take with none left is handed back
/// at once); a take that cannot be staged is recorded (or stops the run).
async fn stage_next(shared: &Arc<Shared>) {
    // While the feed pauses, the feed is free: staged takes render and finish meanwhile.
    loop {
        let feed = shared.feed.clone();
        let pause = tokio::task::spawn_blocking(move || feed.lock().unwrap().pause())
            .await
            .ok()
            .flatten();
        match pause {
            _ if *shared.stop.borrow() => return,
            Some(wait) => tokio::time::sleep(wait).await,
            None => break,
        }
    }
    let feed = shared.feed.clone();
    let next = tokio::task::spawn_blocking(move || feed.lock().unwrap().next_take())
        .await
        .unwrap_or_else(|e| {
            Some(Err(TakeFailure {
                take: "?".into(),
                reason: format!("staging panicked: {e}"),
            }))
        });
    match next {
        None => *shared.feed_done.lock().unwrap() = true,
        Some(Err(failure)) => record_failure(shared, failure),
        Some(Ok(take)) => {
            // Staging makes a take's frame count exact.
            let feed = shared.feed.clone();
            if let Ok((total, _)) =
                tokio::task::spawn_blocking(move || feed.lock().unwrap().frames()).await
            {
                shared.bar.set_length(total as u64);
            }
            let shards = take.shards.clone();
            let t = {
                let mut takes = shared.takes.lock().unwrap();
                takes.push(TakeInPool {
                    name: take.name.clone(),
                    shards_left: shards.len(),
                    take: Some(take),
                    failed: false,
                });
                takes.len() - 1
            };
            if shards.is_empty() {
                take_rendered(shared, t).await;
            }
            shared
                .queue
                .lock()
                .unwrap()
                .extend(shards.into_iter().map(|s| (t, s)));
        }
    }
}

/// Hands a rendered take back to the feed to be finished; a take that cannot be finished is
/// recorded as failed.
async fn take_rendered(shared: &Arc<Shared>, t: usize) {
    let Some(take) = shared.takes.lock().unwrap()[t].take.take() else {
        return;
    };
    let feed = shared.feed.clone();
    let name = take.name.clone();
    let finished = tokio::task::spawn_blocking(move || feed.lock().unwrap().take_rendered(&take))
        .await
        .map_err(|e| anyhow::anyhow!("finishing panicked: {e}"))
        .and_then(|r| r);
    if let Err(e) = finished {
        fail_take(shared, t, format!("finishing take {name}: {e:#}")).await;
    }
}

/// Gives a take up: its queued shards are skipped, the feed records why.
async fn fail_take(shared: &Arc<Shared>, t: usize, reason: String) {
    let failure = {
        let mut takes = shared.takes.lock().unwrap();
        takes[t].failed = true;
        takes[t].take = None;
        TakeFailure {
            take: takes[t].name.clone(),
            reason,
        }
    };
    record_failure(shared, failure.clone());
    let feed = shared.feed.clone();
    let _ = tokio::task::spawn_blocking(move || feed.lock().unwrap().take_failed(&failure)).await;
}

/// Renders a shard's missing frames, retrying on the frames still missing. Retries are
/// counted per frame, not per attempt: a failed attempt charges one try to the frame it left
/// first unfinished (the one it was rendering when it died), so an attempt killed after
/// writing its frames costs nothing, and the shard fails only when some frame has failed
/// `retries + 1` times (or the scene could not be set up, which fails the same way every
/// time). Returns the report and, when frames are left, why.
async fn run_shard(
    shared: &Shared,
    dataset: &Arc<dyn RenderTake>,
    w: usize,
    shard: &Shard,
) -> (ShardReport, Option<String>) {
    let camera = dataset.camera_name(shard.camera).to_owned();
    let mut report = ShardReport {
        take: String::new(),
        shard: shard.id,
        camera: camera.clone(),
        frames: shard.frames.clone(),
        attempts: Vec::new(),
    };
    let missing_now = || -> Vec<u32> {
        shard
            .frames
            .iter()
            .copied()
            .filter(|&f| !dataset.frame_done(shard.camera, f))
            .collect()
    };
    let mut tries = FrameTries::default();
    let mut attempt = 0;
    loop {
        let missing = missing_now();
        if missing.is_empty() {
            return (report, None);
        }
        attempt += 1;
        set_state(
            shared,
            w,
            format!(
                "shard {} {camera} ×{} (try {attempt})",
                shard.id,
                missing.len()
            ),
        );
        let started = Instant::now();
        let log = dataset
            .logs_dir()
            .join(format!("shard_{:04}_attempt_{attempt}.log", shard.id));
        let mut stages = StageSeconds::new();
        let (finished, outcome) =
            match attempt_shard(shared, dataset, shard.camera, &missing, &log, &mut stages).await {
                Ok(n) => (n, Outcome::Ok),
                Err((n, outcome)) => (n, outcome),
            };
        let ok = outcome.is_ok();
        let setup_failed = outcome.repeats();
        report.attempts.push(Attempt {
            attempt,
            frames: missing.len(),
            finished,
            outcome,
            seconds: started.elapsed().as_secs_f64(),
            log: dataset.relative(&log),
            stages,
        });
        let left = missing_now();
        let Some(&first_left) = left.first() else {
            return (report, None);
        };
        if *shared.stop.borrow() {
            return (report, Some("interrupted".into()));
        }
        // A setup failure (the scene does not import) happens again on every try.
        if setup_failed {
            return (report, Some("the scene could not be set up".into()));
        }
        if ok {
            return (
                report,
                Some(format!(
                    "Blender exited cleanly but left {} frame(s) unfinished, first {first_left}",
                    left.len()
                )),
            );
        }
        tries.charge(first_left);
        if let Some((frame, n)) = tries.exhausted(shared.settings.retries) {
            return (report, Some(format!("frame {frame} failed {n} time(s)")));
        }
    }
}

/// One Blender run over `frames`; returns frames finished, or (finished, reason). Adds where
/// its time went to `stages`.
async fn attempt_shard(
    shared: &Shared,
    dataset: &Arc<dyn RenderTake>,
    camera: usize,
    frames: &[u32],
    log: &std::path::Path,
    stages: &mut StageSeconds,
) -> std::result::Result<usize, (usize, Outcome)> {
    let spawned = Instant::now();
    let fail = |n: usize, reason: String| (n, Outcome::Failed { reason });
    let spec = dataset
        .shard_spec_json(camera, frames)
        .map_err(|e| fail(0, format!("preparing the shard: {e:#}")))?;
    let spec_path = log.with_extension("json");
    let io = |e: std::io::Error| fail(0, format!("preparing the shard: {e}"));
    std::fs::create_dir_all(dataset.logs_dir()).map_err(io)?;
    std::fs::write(&spec_path, spec).map_err(io)?;
    let stderr = std::fs::File::create(log).map_err(io)?;
    let mut cmd = tokio::process::Command::from(worker_command(&shared.runtime, &spec_path));
    cmd.stdout(Stdio::piped())
        .stderr(Stdio::from(stderr))
        .stdin(Stdio::null())
        .kill_on_drop(true);
    let mut child = cmd.spawn().map_err(|e| {
        fail(
            0,
            format!("starting {}: {e}", shared.runtime.path.display()),
        )
    })?;
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let mut reported: BTreeSet<std::path::PathBuf> = BTreeSet::new();
    let mut finished = 0usize;
    let mut stop = shared.stop.clone();
    let deadline = tokio::time::sleep(shared.settings.shard_timeout);
    tokio::pin!(deadline);
    loop {
        tokio::select! {
            line = lines.next_line() => {
                match line {
                    Ok(Some(line)) => {
                        if let Some((stage, s)) = worker_timing(&line) {
                            match stage {
                                "ready" => add_stage(stages, "blender_start_up", spawned.elapsed().as_secs_f64()),
                                _ => add_stage(stages, stage, s),
                            }
                            continue;
                        }
                        let Some(path) = line.strip_prefix("EGOGEN_DONE ") else { continue };
                        reported.insert(path.into());
                        for &f in frames {
                            let raw = dataset.raw_frame_files(camera, f);
                            if raw.iter().all(|r| reported.contains(r))
                                && !dataset.frame_done(camera, f)
                            {
                                let ds = dataset.clone();
                                let result = tokio::task::spawn_blocking(move || ds.finish_frame(camera, f))
                                    .await
                                    .map_err(|e| fail(finished, format!("finishing frame {f}: {e}")))?;
                                let done = result.map_err(|e| fail(finished, format!("frame {f}: {e:#}")))?;
                                for (stage, s) in done.seconds {
                                    add_stage(stages, stage, s);
                                }
                                finished += 1;
                                shared.bar.inc(1);
                            }
                        }
                    }
                    Ok(None) => break,
                    Err(e) => return Err(fail(finished, format!("reading worker output: {e}"))),
                }
            }
            _ = &mut deadline => {
                let _ = child.kill().await;
                return Err(fail(finished, format!("timed out after {:?}", shared.settings.shard_timeout)));
            }
            _ = stop.changed() => {
                let _ = child.kill().await;
                return Err(fail(finished, "interrupted".into()));
            }
        }
    }
    let status = child
        .wait()
        .await
        .map_err(|e| fail(finished, format!("waiting for Blender: {e}")))?;
    if status.code() == Some(EXIT_SETUP_FAILED) {
        return Err((finished, setup_failure(log)));
    }
    if !status.success() {
        // The last thing the worker said is usually why.
        let said = std::fs::read_to_string(log).ok().and_then(|t| {
            t.lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .map(str::to_owned)
        });
        return Err(fail(
            finished,
            match said {
                Some(line) => format!("Blender exited with {status}; its last words: {line}"),
                None => format!("Blender exited with {status}"),
            },
        ));
    }
    let missing = frames
        .iter()
        .filter(|&&f| !dataset.frame_done(camera, f))
        .count();
    if missing > 0 {
        return Err(fail(
            finished,
            format!("Blender exited cleanly but {missing} frames are missing"),
        ));
    }
    Ok(finished)
}

/// Lists a failed take in the report; it stops the run when the run says so.
fn record_failure(shared: &Shared, failure: TakeFailure) {
    if shared.stop_on_failure {
        shared
            .failed
            .lock()
            .unwrap()
            .get_or_insert(failure.reason.clone());
    }
    shared.failed_takes.lock().unwrap().push(failure);
}
