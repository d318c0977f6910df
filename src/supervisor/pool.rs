//! What every backend shares: the [`ShardPool`] interface the pipeline runs shards through
//! (local processes or a Slurm array), the [`TakeFeed`] that hands a pool its takes (one for
//! `egogen-run`, many staged on demand for a campaign) and takes them back when rendered, the
//! report of what each shard attempt did, and the rendering progress bar (its ETA: [`super::pace`]).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result};
use indicatif::ProgressBar;
use serde::Serialize;

use super::pace::FramePace;
use super::staged::Shard;
use crate::render::BlenderRuntime;

/// Where shards run: renders the shards of every take `feed` hands out and reports every
/// attempt; an error when the run is stopped, or (with [`PoolRun::stop_on_failure`]) when a
/// shard fails past its retries.
pub trait ShardPool {
    fn run(
        &self,
        feed: Arc<Mutex<dyn TakeFeed>>,
        runtime: BlenderRuntime,
        run: &PoolRun,
    ) -> Result<PoolReport>;
}

/// What a pool needs of a staged take to render it: the spec a worker receives for some
/// frames of a camera, the raw renders each frame is made from, whether a frame is done, and
/// finishing a frame from its raw renders. [`super::Dataset`] is every real take; a stand-in
/// measures the pools and a campaign's bookkeeping alone (`benches/campaign_farm.rs`).
pub trait RenderTake: Send + Sync + std::fmt::Debug {
    /// The take's folder while it is made (attempt logs are named relative to it).
    fn folder(&self) -> &Path;
    /// This start's logs folder.
    fn logs_dir(&self) -> PathBuf;
    /// The name of camera `camera`.
    fn camera_name(&self, camera: usize) -> &str;
    /// Pixels Blender renders for a frame of camera `camera` (what prices a camera in the ETA
    /// before its first frame is done).
    fn camera_pixels(&self, camera: usize) -> u64;
    /// Planned frames over all cameras.
    fn total_frames(&self) -> usize;
    /// The spec file a worker renders `frames` of `camera` from (JSON bytes).
    fn shard_spec_json(&self, camera: usize, frames: &[u32]) -> Result<Vec<u8>>;
    /// The raw renders a frame is made from; the worker names each on a `EGOGEN_DONE` line
    /// once it is in place.
    fn raw_frame_files(&self, camera: usize, frame: u32) -> Vec<PathBuf>;
    /// Whether a frame is finished.
    fn frame_done(&self, camera: usize, frame: u32) -> bool;
    /// Finishes a frame whose raw renders are all in place.
    fn finish_frame(&self, camera: usize, frame: u32) -> Result<WrittenFrame>;
    /// A path inside the take as the pool report records it: relative to its folder.
    fn relative(&self, path: &Path) -> String {
        path.strip_prefix(self.folder())
            .unwrap_or(path)
            .display()
            .to_string()
    }
}

/// A frame file written by [`RenderTake::finish_frame`], and where its time went (stages of
/// [`StageSeconds`]).
#[derive(Debug, Clone)]
pub struct WrittenFrame {
    pub path: PathBuf,
    pub seconds: Vec<(&'static str, f64)>,
}

/// One staged take as a pool renders it: its frames' work and the shards still to render.
#[derive(Debug, Clone)]
pub struct PoolTake {
    /// The take's name in reports and messages (empty for `egogen-run`'s single take).
    pub name: String,
    pub dataset: Arc<dyn RenderTake>,
    pub shards: Vec<Shard>,
}

/// A take that could not be staged, rendered or finished, and why.
#[derive(Debug, Clone, Serialize, PartialEq, Eq)]
pub struct TakeFailure {
    pub take: String,
    pub reason: String,
}

/// Where a pool's takes come from and where they go: staged when a worker runs out of shards
/// (so motion is made ahead of rendering but scratch is held only for takes in flight), and
/// handed back when all their frames are rendered, or when they failed.
pub trait TakeFeed: Send {
    /// Frames planned over all takes, and those finished before this start (the progress bar).
    fn frames(&self) -> (usize, usize);
    /// Stages the next take; `None` when none is left. An error is that take's failure: the
    /// pool records it and goes on (or stops, with [`PoolRun::stop_on_failure`]).
    fn next_take(&mut self) -> Option<Result<PoolTake, TakeFailure>>;
    /// `Some(wait)` while no take should be staged yet (the feed says why): the pool asks again
    /// after `wait`, without holding the feed, so that takes already staged render and finish
    /// meanwhile (finishing one may be what ends the wait). `None`: stage now.
    fn pause(&mut self) -> Option<std::time::Duration> {
        None
    }
    /// Every frame of `take` is rendered: finish it (annotations, exports, manifest).
    fn take_rendered(&mut self, take: &PoolTake) -> Result<()>;
    /// `take` failed; the pool renders no more of it.
    fn take_failed(&mut self, failure: &TakeFailure);
}

/// A feed of one staged take, finished by its caller after the pool returns.
pub(crate) struct OneTake {
    take: Option<PoolTake>,
    total: usize,
    done: usize,
}

impl OneTake {
    /// `take`, with `done` of its dataset's frames finished before this start.
    pub(crate) fn new(take: PoolTake, done: usize) -> Self {
        let total = take.dataset.total_frames();
        OneTake {
            take: Some(take),
            total,
            done,
        }
    }
}

impl TakeFeed for OneTake {
    fn frames(&self) -> (usize, usize) {
        (self.total, self.done)
    }
    fn next_take(&mut self) -> Option<Result<PoolTake, TakeFailure>> {
        self.take.take().map(Ok)
    }
    fn take_rendered(&mut self, _: &PoolTake) -> Result<()> {
        Ok(())
    }
    fn take_failed(&mut self, _: &TakeFailure) {}
}

/// Where a pool run keeps its records, and what a failed take does to it.
#[derive(Debug, Clone)]
pub struct PoolRun {
    /// `pool_report.json` and Slurm's task logs: the dataset's (or the campaign's)
    /// `logs/start_<n>/`.
    pub logs_dir: PathBuf,
    /// Scratch of the backend (Slurm's specs and array scripts under `slurm/`).
    pub work_dir: PathBuf,
    /// A shard failed past its retries stops the whole run (`egogen-run`'s one take), or only
    /// its take, recorded in the report while the others go on (a campaign).
    pub stop_on_failure: bool,
}

/// One attempt at a shard.
#[derive(Debug, Clone, Serialize)]
pub struct Attempt {
    pub attempt: u32,
    pub frames: usize,
    pub finished: usize,
    /// `ok`, or why it failed (written as that text).
    pub outcome: Outcome,
    pub seconds: f64,
    /// The attempt's log, relative to the dataset folder.
    pub log: String,
    /// Where its seconds went, stage by stage (docs/RENDERING.md, "Where a frame's time
    /// goes"); on Slurm the worker's own stages from its log, without start-up and Rust's.
    #[serde(skip_serializing_if = "StageSeconds::is_empty")]
    pub stages: StageSeconds,
    /// The long-lived Blender it ran in (local backend); none on Slurm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blender: Option<BlenderUse>,
}

/// Which long-lived Blender an attempt ran in, and its memory after it.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct BlenderUse {
    /// Shards that Blender had rendered to their end before this one (0: started for it).
    pub shards_before: usize,
    /// Its resident memory when the shard ended (MB, as it measured itself); none when the
    /// attempt did not end cleanly.
    pub resident_mb: Option<f64>,
}

/// Seconds per stage of an attempt, summed over its frames: `blender_start_up` (process start
/// to `bpy` imported), `scene_import`, `camera_setup`, per render kind (`colour`,
/// `ground_truth`) `_frame_update` (Blender's scene update), `_render` (the whole render call)
/// and within it Cycles' own `_sync` and `_path_tracing` (from the raw file's header), and
/// Rust's `assemble` (read, remap) and `finish` (encode, check, record, write).
pub(crate) type StageSeconds = std::collections::BTreeMap<String, f64>;

/// Adds `seconds` to `stage`.
pub(crate) fn add_stage(stages: &mut StageSeconds, stage: &str, seconds: f64) {
    *stages.entry(stage.to_owned()).or_default() += seconds;
}

/// A worker's `EGOGEN_TIMING <stage> <seconds>` line, if `line` is one: `Some((stage,
/// seconds))` (`ready` comes with 0: the supervisor times the start-up itself).
pub(crate) fn worker_timing(line: &str) -> Option<(&str, f64)> {
    let (stage, seconds) = line.strip_prefix("EGOGEN_TIMING ")?.split_once(' ')?;
    Some((stage, seconds.trim().parse().ok()?))
}

/// The stages a worker reported in its log (a Slurm task's), its start-up excepted.
pub(crate) fn stages_from_worker_log(text: &str) -> StageSeconds {
    let mut stages = StageSeconds::new();
    for (stage, seconds) in text.lines().filter_map(worker_timing) {
        if stage != "ready" {
            add_stage(&mut stages, stage, seconds);
        }
    }
    stages
}

/// What happened to a shard.
#[derive(Debug, Clone, Serialize)]
pub struct ShardReport {
    /// The take the shard belongs to (absent for `egogen-run`'s single take).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub take: String,
    pub shard: usize,
    pub camera: String,
    pub frames: Vec<u32>,
    pub attempts: Vec<Attempt>,
}

/// What a pool run did.
#[derive(Debug, Clone, Serialize)]
pub struct PoolReport {
    pub shards: Vec<ShardReport>,
    pub frames_finished: usize,
    pub wall_seconds: f64,
    /// Workers of the pool (Slurm: array tasks at once).
    pub workers: usize,
    /// Seconds each local worker spent in Blender attempts (empty for Slurm, whose tasks'
    /// times are in their attempts).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub busy_seconds: Vec<f64>,
    /// Busy time over `workers × wall_seconds`: the local workers' Blender attempts, or the
    /// Slurm tasks' run times as Slurm reports them (whole seconds).
    pub utilisation: f64,
    /// Takes given up (a campaign goes on without them).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub failed_takes: Vec<TakeFailure>,
}

impl PoolReport {
    /// Writes `pool_report.json` into the run's logs folder.
    pub(crate) fn write(&self, run: &PoolRun) -> Result<()> {
        let path = run.logs_dir.join("pool_report.json");
        std::fs::create_dir_all(&run.logs_dir)
            .with_context(|| format!("creating {}", run.logs_dir.display()))?;
        crate::atomic_file::write_atomically(&path, &serde_json::to_vec_pretty(self)?)
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// The message of a shard given up: which shard of which take, why, and its last attempt
/// with its log.
pub(crate) fn shard_failure_message(
    dataset: &dyn RenderTake,
    report: &ShardReport,
    why: &str,
) -> String {
    let last = report.attempts.last();
    format!(
        "{}shard {} ({} frames {:?}): {why} after {} attempt(s); last: {} (log: {})",
        if report.take.is_empty() {
            String::new()
        } else {
            format!("take {}: ", report.take)
        },
        report.shard,
        report.camera,
        report.frames,
        report.attempts.len(),
        last.map_or_else(|| "none".into(), |a| a.outcome.to_string()),
        last.map_or_else(
            || "none".into(),
            |a| dataset.folder().join(&a.log).display().to_string()
        )
    )
}

/// The rendering progress bar: frames done of all planned, the time left at each camera's
/// pace ([`FramePace`]), and a status message.
pub(crate) fn frames_bar(total: u64, done: u64, pace: Arc<FramePace>) -> ProgressBar {
    let eta: crate::progress::Eta = Arc::new(move |pos: u64, len: u64, elapsed| {
        pace.time_left(elapsed, len.saturating_sub(pos))
    });
    crate::progress::progress_bar_with_eta("egogen-run", "rendering", "frames", total, done, eta)
}

/// Plans `shards` of `take` (its pending shards: frames not done yet) on `pace`.
pub(crate) fn plan_pace(pace: &FramePace, take: &dyn RenderTake, shards: &[Shard]) {
    for shard in shards {
        pace.plan(
            take.camera_name(shard.camera),
            take.camera_pixels(shard.camera),
            shard.frames.len() as u64,
        );
    }
}

/// Exit status of `render_shard.py` when the spec or the scene cannot be loaded: a failure
/// that would repeat on every try.
pub(crate) const EXIT_SETUP_FAILED: i32 = 3;
/// Failed tries charged to the frames of a shard: retries count frames, not attempts. A failed
/// attempt charges one try to the first frame it left unfinished (the one it was rendering
/// when it died), so an attempt killed after writing its frames costs nothing; the shard is
/// given up when a frame has failed more than `retries` times. Both backends use it.
#[derive(Debug, Default, Clone)]
pub(crate) struct FrameTries(std::collections::BTreeMap<u32, u32>);

impl FrameTries {
    /// Charges a failed attempt to `frame`, the first it left unfinished.
    pub(crate) fn charge(&mut self, frame: u32) {
        *self.0.entry(frame).or_insert(0) += 1;
    }

    /// The frame that has failed more than `retries` times (the most tried), with its count.
    pub(crate) fn exhausted(&self, retries: u32) -> Option<(u32, u32)> {
        self.0
            .iter()
            .map(|(&f, &t)| (f, t))
            .filter(|&(_, t)| t > retries)
            .max_by_key(|&(_, t)| t)
    }
}

/// How such an attempt's outcome starts; backends do not retry it.
pub(crate) const SETUP_FAILED: &str = "Blender could not set up the scene (not retried)";

/// How an attempt at a shard ended. Written to the pool report as text: `ok`, the setup
/// failure ([`SETUP_FAILED`] and the worker's reason), or why it failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    Ok,
    /// The worker could not set up the scene: it would fail again on every try.
    SetupFailed {
        reason: String,
    },
    /// Anything else (a crash, a kill, a timeout, a bad frame): worth another try.
    Failed {
        reason: String,
    },
}

impl Outcome {
    pub(crate) fn is_ok(&self) -> bool {
        matches!(self, Outcome::Ok)
    }

    /// Whether it fails the same way on every try (backends do not retry it).
    pub(crate) fn repeats(&self) -> bool {
        matches!(self, Outcome::SetupFailed { .. })
    }
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Outcome::Ok => f.write_str("ok"),
            Outcome::SetupFailed { reason } => write!(f, "{SETUP_FAILED}: {reason}"),
            Outcome::Failed { reason } => f.write_str(reason),
        }
    }
}

impl Serialize for Outcome {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// The outcome of an attempt that exited with [`EXIT_SETUP_FAILED`], with the reason the
/// worker wrote to its log (`EGOGEN_SETUP_FAILED <reason>`).
pub(crate) fn setup_failure(log: &std::path::Path) -> Outcome {
    let reason = std::fs::read_to_string(log)
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("EGOGEN_SETUP_FAILED ").map(str::to_owned))
        })
        .unwrap_or_else(|| format!("exit status {EXIT_SETUP_FAILED}"));
    Outcome::SetupFailed { reason }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worker_timing_lines_add_up_by_stage() {
        let log = "Fra:1 Mem:8M | Sample 1/4\nEGOGEN_TIMING ready 0.000000\n\
                   EGOGEN_TIMING colour_render 1.500000\nEGOGEN_DONE /x.exr\n\
                   EGOGEN_TIMING colour_render 0.250000\nEGOGEN_TIMING scene_import x\n\
                   EGOGEN_TIMING\n";
        let stages = stages_from_worker_log(log);
        assert_eq!(stages.len(), 1, "{stages:?}");
        assert!((stages["colour_render"] - 1.75).abs() < 1e-12);
        assert_eq!(worker_timing("EGOGEN_TIMING ready 0"), Some(("ready", 0.0)));
        assert_eq!(worker_timing("EGOGEN_DONE /x.exr"), None);
    }
}
