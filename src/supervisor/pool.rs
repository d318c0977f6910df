//! What every backend shares: the [`ShardPool`] interface the pipeline runs shards through
//! (local processes or a Slurm array), the report of what each shard attempt did, and the
//! rendering progress bar.

use std::sync::Arc;

use anyhow::{Context, Result};
use indicatif::ProgressBar;
use serde::Serialize;

use super::staged::{Dataset, Shard};
use crate::render::BlenderRuntime;

/// Where shards run: renders `shards` of `dataset` (`already_done` frames finished before) and
/// reports every attempt; an error when a shard fails past its retries or the run is stopped.
pub trait ShardPool {
    fn run(
        &self,
        dataset: Arc<Dataset>,
        runtime: BlenderRuntime,
        shards: Vec<Shard>,
        already_done: usize,
    ) -> Result<PoolReport>;
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
}

/// What happened to a shard.
#[derive(Debug, Clone, Serialize)]
pub struct ShardReport {
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
}

impl PoolReport {
    /// Writes `logs/start_<n>/pool_report.json`.
    pub fn write(&self, dataset: &Dataset) -> Result<()> {
        let path = dataset.logs_dir().join("pool_report.json");
        std::fs::create_dir_all(dataset.logs_dir())
            .with_context(|| format!("creating {}", dataset.logs_dir().display()))?;
        crate::atomic_file::write_atomically(&path, &serde_json::to_vec_pretty(self)?)
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// The rendering progress bar: frames done of all planned, ETA, and a status message.
pub fn frames_bar(total: u64, done: u64) -> Result<ProgressBar> {
    Ok(crate::progress::progress_bar(
        "egogen-run",
        "rendering",
        "frames",
        total,
        done,
    ))
}

/// Exit status of `render_shard.py` when the spec or the scene cannot be loaded: a failure
/// that would repeat on every try.
pub const EXIT_SETUP_FAILED: i32 = 3;
/// Failed tries charged to the frames of a shard: retries count frames, not attempts. A failed
/// attempt charges one try to the first frame it left unfinished (the one it was rendering
/// when it died), so an attempt killed after writing its frames costs nothing; the shard is
/// given up when a frame has failed more than `retries` times. Both backends use it.
#[derive(Debug, Default, Clone)]
pub struct FrameTries(std::collections::BTreeMap<u32, u32>);

impl FrameTries {
    /// Charges a failed attempt to `frame`, the first it left unfinished.
    pub fn charge(&mut self, frame: u32) {
        *self.0.entry(frame).or_insert(0) += 1;
    }

    /// The frame that has failed more than `retries` times (the most tried), with its count.
    pub fn exhausted(&self, retries: u32) -> Option<(u32, u32)> {
        self.0
            .iter()
            .map(|(&f, &t)| (f, t))
            .filter(|&(_, t)| t > retries)
            .max_by_key(|&(_, t)| t)
    }
}

/// How such an attempt's outcome starts; backends do not retry it.
pub const SETUP_FAILED: &str = "Blender could not set up the scene (not retried)";

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
    pub fn is_ok(&self) -> bool {
        matches!(self, Outcome::Ok)
    }

    /// Whether it fails the same way on every try (backends do not retry it).
    pub fn repeats(&self) -> bool {
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
pub fn setup_failure(log: &std::path::Path) -> Outcome {
    let reason = std::fs::read_to_string(log)
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("EGOGEN_SETUP_FAILED ").map(str::to_owned))
        })
        .unwrap_or_else(|| format!("exit status {EXIT_SETUP_FAILED}"));
    Outcome::SetupFailed { reason }
}
