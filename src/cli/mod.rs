//! Command-line and configuration plumbing: clap arguments, TOML configs, resolved plans.
//!
//! No domain logic lives here: `config` only parses and checks values, `resolve` turns them
//! into typed plans the stages consume.

pub mod config;
pub mod resolve;
pub mod train;

pub use config::{ConfigError, RawRun};
pub use resolve::{resolve_run, MotionPlan, RenderPlan, RunPlan, SlurmPlan, SupervisorPlan};
