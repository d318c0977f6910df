//! The supervisor: from a checked run plan and its motion (made by `synth`, handed over by
//! `run_job`) to a finished dataset. Stages a take (`pipeline`: its sequence folder, the
//! bodies' caches, the rendering work of `staged`), plans shards (camera × frame block), runs
//! them on a pool (`local` or `slurm`; one take's shards or many takes' through one feed,
//! `pool`; the time left at each camera's pace, `pace`), finishes and validates frames
//! (`dataset`, `frame_record`), writes the take's outputs (`export::take_exports`:
//! annotations, the COLMAP export, the manifest), resumes an interrupted run where it stopped,
//! and re-checks a finished dataset against its manifest (`verify`). `render_tests`: real
//! Blender renders of a shard checked against geometry computed here (tests only).

pub(crate) mod dataset;
pub(crate) mod frame_record;
pub(crate) mod local;
pub(crate) mod pace;
pub(crate) mod pipeline;
pub mod pool;
#[cfg(test)]
mod render_tests;
pub(crate) mod slurm;
pub(crate) mod staged;
pub mod verify;

pub use crate::manifest::Manifest;
pub use local::{LocalPool, PoolSettings};
pub(crate) use pipeline::{
    run_pipeline, shard_pool, stage_take, RunMotion, RunOptions, RunSummary, Staged, StagedTake,
};
pub use pool::{PoolReport, PoolRun, PoolTake, ShardPool, TakeFailure, TakeFeed};
pub use slurm::{SlurmPool, SlurmSettings};
pub use staged::{CameraWork, Dataset, RenderedAgent, Shard};
pub use verify::{verify, VerifyReport};
