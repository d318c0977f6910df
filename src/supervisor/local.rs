//! The local backend: a tokio pool of Blender worker processes. Each worker takes a shard (of
//! any take the feed has staged; the next take is staged in the background when fewer shards
//! than workers are queued, or by a worker that finds none left), starts Blender on its spec —
//! or, with `keep_blender`, hands the spec to the Blender it keeps for that take
//! (`LiveBlender`: started on the take's first shard, the scene built once, replaced for
//! another take, after `SHARDS_PER_BLENDER` shards, when its memory grows, or when it fails)
//! — finishes frames as their raw files are reported, and retries a
//! failed or timed-out attempt on the frames still missing until one frame has failed more than
//! the configured count (retries count frames, not attempts: `run_shard`); each attempt's
//! stderr goes to its take's `logs/`. A take whose shards are all done goes back to the feed to be
//! finished while the workers render the next. Ctrl-C kills the workers and leaves every
//! finished frame in place, so `--resume` continues.

use std::collections::{BTreeSet, VecDeque};
use std::process::Stdio;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use indicatif::ProgressBar;
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader};
use tokio::sync::watch;

use super::pace::FramePace;
use super::pool::{
    add_stage, frames_bar, plan_pace, setup_failure, shard_failure_message, worker_timing, Attempt,
    BlenderUse, FrameTries, Outcome, PoolReport, PoolRun, PoolTake, RenderTake, ShardPool,
    ShardReport, StageSeconds, TakeFailure, TakeFeed, EXIT_SETUP_FAILED,
};
use super::staged::Shard;
use crate::render::shard::{serve_command, worker_command};
use crate::render::BlenderRuntime;

/// Pool settings.
#[derive(Debug, Clone, Copy)]
pub struct PoolSettings {
    pub workers: usize,
    pub shard_timeout: Duration,
    pub retries: u32,
    /// Each worker keeps its Blender across a take's shards (`LiveBlender`); else one
    /// Blender per attempt.
    pub keep_blender: bool,
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
    /// Each camera's pace, for the bar's ETA.
    pace: Arc<FramePace>,
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
        let pace = Arc::new(FramePace::default());
        let bar = frames_bar(total as u64, done as u64, pace.clone());
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
            pace,
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
    // The Blender this worker keeps across a take's shards.
    let mut live: Option<LiveBlender> = None;
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
        let (mut report, failure) = run_shard(&shared, &dataset, w, t, &shard, &mut live).await;
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
    if let Some(live) = live.take() {
        live.retire().await;
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
            plan_pace(&shared.pace, take.dataset.as_ref(), &shards);
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
    t: usize,
    shard: &Shard,
    live: &mut Option<LiveBlender>,
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
        let mut blender = BlenderUse {
            shards_before: 0,
            resident_mb: None,
        };
        let work = ShardWork {
            t,
            camera: shard.camera,
            frames: &missing,
            log: &log,
        };
        let result = attempt_shard(shared, dataset, &work, live, &mut stages, &mut blender).await;
        let (finished, outcome) = match result {
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
            blender: shared.settings.keep_blender.then_some(blender),
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
                    "Blender ended the shard cleanly but left {} frame(s) unfinished, first {first_left}",
                    left.len()
                )),
            );
        }
        // A Blender kept from earlier shards that fails may fail for what it kept (its memory,
        // its state), not for this frame: the frame is tried again in a fresh Blender without
        // a try charged. A fresh Blender's failure is the frame's.
        if blender.shards_before == 0 {
            tries.charge(first_left);
        }
        if let Some((frame, n)) = tries.exhausted(shared.settings.retries) {
            return (report, Some(format!("frame {frame} failed {n} time(s)")));
        }
    }
}

/// Shards a long-lived Blender renders before it is replaced by a fresh one.
const SHARDS_PER_BLENDER: usize = 40;
/// A long-lived Blender whose resident memory has grown past this many times what it held
/// after its first shard is replaced by a fresh one (measured on the default take's SLAM
/// camera over 500 frames: 440 MB after the first shard, 537 MB from the 10th on, flat;
/// docs/SUPERVISOR.md).
const RESIDENT_GROWTH_LIMIT: f64 = 1.5;

/// A Blender started with `render_shard.py --serve` for one take and kept by one worker across
/// that take's shards (the scene is built and synced once), until the worker moves to another
/// take, it has rendered [`SHARDS_PER_BLENDER`] shards, its memory has grown past
/// [`RESIDENT_GROWTH_LIMIT`], or it fails. Killed when dropped.
struct LiveBlender {
    /// The take it renders (index into the pool's takes).
    take: usize,
    child: tokio::process::Child,
    /// Where shards are sent; none for a Blender started on one shard's spec.
    stdin: Option<tokio::process::ChildStdin>,
    lines: tokio::io::Lines<BufReader<tokio::process::ChildStdout>>,
    /// Shards rendered to their end.
    shards: usize,
    /// Its resident memory after its first shard (MB).
    first_mb: Option<f64>,
    /// It has grown past [`RESIDENT_GROWTH_LIMIT`].
    swollen: bool,
}

impl LiveBlender {
    /// A Blender for take `take`: kept across its shards (`--serve`), or else started on the
    /// one shard spec `spec` alone (it exits when that shard is done).
    fn start(
        shared: &Shared,
        take: usize,
        dataset: &dyn RenderTake,
        log: &std::path::Path,
        spec: Option<&std::path::Path>,
    ) -> std::io::Result<Self> {
        let stderr = std::fs::OpenOptions::new()
            .append(true)
            .create(true)
            .open(log)?;
        let (command, stdin) = match spec {
            None => (
                serve_command(&shared.runtime, dataset.folder()),
                Stdio::piped(),
            ),
            Some(spec) => (worker_command(&shared.runtime, spec), Stdio::null()),
        };
        let mut cmd = tokio::process::Command::from(command);
        cmd.stdout(Stdio::piped())
            .stderr(Stdio::from(stderr))
            .stdin(stdin)
            .kill_on_drop(true);
        let mut child = cmd.spawn()?;
        let stdin = child.stdin.take();
        let stdout = child.stdout.take().expect("piped");
        Ok(Self {
            take,
            child,
            stdin,
            lines: BufReader::new(stdout).lines(),
            shards: 0,
            first_mb: None,
            swollen: false,
        })
    }

    /// Lets it exit at the end of its input (killed if it has not within a few seconds).
    async fn retire(mut self) {
        drop(self.stdin.take());
        let _ = tokio::time::timeout(Duration::from_secs(5), self.child.wait()).await;
    }
}

/// What an attempt renders: frames of a camera of take `t`, its log.
struct ShardWork<'a> {
    t: usize,
    camera: usize,
    frames: &'a [u32],
    log: &'a std::path::Path,
}

/// Renders `work`'s frames in the worker's long-lived Blender (started, or replaced, as
/// needed); returns frames finished, or (finished, reason). Adds where its time went to
/// `stages` and which Blender ran it to `blender`; a Blender that failed, timed out or was
/// stopped is let go.
async fn attempt_shard(
    shared: &Shared,
    dataset: &Arc<dyn RenderTake>,
    work: &ShardWork<'_>,
    live: &mut Option<LiveBlender>,
    stages: &mut StageSeconds,
    blender: &mut BlenderUse,
) -> std::result::Result<usize, (usize, Outcome)> {
    let (camera, frames, log) = (work.camera, work.frames, work.log);
    let pace = shared
        .pace
        .attempt(dataset.camera_name(camera), frames.len() as u64);
    let fail = |n: usize, reason: String| (n, Outcome::Failed { reason });
    let spec = dataset
        .shard_spec_json(camera, frames)
        .map_err(|e| fail(0, format!("preparing the shard: {e}")))?;
    let spec_path = log.with_extension("json");
    let io = |e: std::io::Error| fail(0, format!("preparing the shard: {e}"));
    std::fs::create_dir_all(dataset.logs_dir()).map_err(io)?;
    std::fs::write(&spec_path, spec).map_err(io)?;
    std::fs::File::create(log).map_err(io)?;
    let request = serde_json::json!({ "spec": spec_path, "log": log }).to_string() + "\n";
    let_go_unfit_blender(live, work).await;
    // Without a kept Blender, one is started on this shard's spec alone.
    let keep = shared.settings.keep_blender;
    if !keep {
        *live = None;
    }
    let mut spawned = None;
    loop {
        if live.is_none() {
            let spec = (!keep).then_some(spec_path.as_path());
            let started =
                LiveBlender::start(shared, work.t, dataset.as_ref(), log, spec).map_err(|e| {
                    fail(
                        0,
                        format!("starting {}: {e}", shared.runtime.path.display()),
                    )
                })?;
            *live = Some(started);
            spawned = Some(Instant::now());
        }
        let l = live.as_mut().expect("started above");
        let Some(stdin) = l.stdin.as_mut() else {
            break;
        };
        match stdin.write_all(request.as_bytes()).await {
            Ok(()) => break,
            // It exited while idle: once more in a fresh one.
            Err(_) if spawned.is_none() => *live = None,
            Err(e) => {
                *live = None;
                return Err(fail(0, format!("sending the shard to Blender: {e}")));
            }
        }
    }
    let l = live.as_mut().expect("sent above");
    blender.shards_before = l.shards;
    let mut reported: BTreeSet<std::path::PathBuf> = BTreeSet::new();
    let mut finished = 0usize;
    let mut stop = shared.stop.clone();
    let deadline = tokio::time::sleep(shared.settings.shard_timeout);
    tokio::pin!(deadline);
    let ended = 'shard: loop {
        tokio::select! {
            line = l.lines.next_line() => {
                match line {
                    Ok(Some(line)) => {
                        if let Some(mb) = line.strip_prefix("EGOGEN_SHARD_END ") {
                            break Ok(Some(mb.trim().parse::<f64>().ok()));
                        }
                        if let Some((stage, s)) = worker_timing(&line) {
                            match (stage, spawned) {
                                ("ready", Some(t)) => add_stage(stages, "blender_start_up", t.elapsed().as_secs_f64()),
                                ("ready", None) => {}
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
                                    .map_err(|e| fail(finished, format!("finishing frame {f}: {e}")));
                                let done = result
                                    .and_then(|r| r.map_err(|e| fail(finished, format!("frame {f}: {e:#}"))));
                                let done = match done {
                                    Ok(done) => done,
                                    Err(e) => break 'shard Err(e),
                                };
                                for (stage, s) in done.seconds {
                                    add_stage(stages, stage, s);
                                }
                                finished += 1;
                                pace.frame_done();
                                shared.bar.inc(1);
                            }
                        }
                    }
                    Ok(None) => break Ok(None),
                    Err(e) => break Err(fail(finished, format!("reading worker output: {e}"))),
                }
            }
            _ = &mut deadline => {
                break Err(fail(finished, format!("timed out after {:?}", shared.settings.shard_timeout)));
            }
            _ = stop.changed() => break Err(fail(finished, "interrupted".into())),
        }
    };
    // A Blender that failed, timed out or was stopped is let go (killed).
    let ended = ended.inspect_err(|_| *live = None)?;
    let resident_mb = match ended {
        Some(mb) => mb,
        // Its output ended: Blender exited — the end of a one-shot Blender's shard when it
        // exited cleanly, else a failure.
        None => ended_blender(live, keep, finished, log).await?,
    };
    if let Some(l) = live.as_mut() {
        l.shards += 1;
        if let Some(mb) = resident_mb {
            let first = *l.first_mb.get_or_insert(mb);
            l.swollen = mb > RESIDENT_GROWTH_LIMIT * first;
        }
    }
    blender.resident_mb = resident_mb;
    let missing = frames
        .iter()
        .filter(|&&f| !dataset.frame_done(camera, f))
        .count();
    if missing > 0 {
        *live = None;
        return Err(fail(
            finished,
            format!("Blender ended the shard but {missing} frames are missing"),
        ));
    }
    Ok(finished)
}

/// Lets the live Blender go when it is of another take, has done its share, or has exited
/// while idle (the shard then starts a fresh one).
async fn let_go_unfit_blender(live: &mut Option<LiveBlender>, work: &ShardWork<'_>) {
    if let Some(l) = live.as_mut() {
        let exited = !matches!(l.child.try_wait(), Ok(None));
        if l.take != work.t || l.shards >= SHARDS_PER_BLENDER || l.swollen || exited {
            if let Some(l) = live.take() {
                l.retire().await;
            }
        }
    }
}

/// A Blender whose output ended: `Ok(None)` when it was a one-shot Blender (`keep` false)
/// that exited cleanly, else why it failed (its setup failure, or its exit status and last
/// words in `log`). It is let go either way.
async fn ended_blender(
    live: &mut Option<LiveBlender>,
    keep: bool,
    finished: usize,
    log: &std::path::Path,
) -> std::result::Result<Option<f64>, (usize, Outcome)> {
    let fail = |n: usize, reason: String| (n, Outcome::Failed { reason });
    let Some(mut gone) = live.take() else {
        return Err(fail(finished, "Blender is gone".into()));
    };
    let status = gone
        .child
        .wait()
        .await
        .map_err(|e| fail(finished, format!("waiting for Blender: {e}")))?;
    if status.success() && !keep {
        return Ok(None);
    }
    if status.code() == Some(EXIT_SETUP_FAILED) {
        return Err((finished, setup_failure(log)));
    }
    // The last thing the worker said is usually why.
    let said = std::fs::read_to_string(log).ok().and_then(|t| {
        t.lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .map(str::to_owned)
    });
    Err(fail(
        finished,
        match said {
            Some(line) => format!("Blender exited with {status}; its last words: {line}"),
            None => format!("Blender exited with {status}"),
        },
    ))
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
