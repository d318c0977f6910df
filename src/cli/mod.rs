//! Command-line and configuration plumbing: clap arguments, TOML configs, resolved plans.
//!
//! No domain logic lives here: `config` only parses and checks values, `resolve` turns them
//! into typed plans the stages consume, and each `*_jobs` file holds a command's clap
//! arguments and thin functions that turn them into a typed job (defaults resolved, configs
//! loaded, flags checked) and call the module whose data the job is: `eval::jobs`,
//! `eval::motion_model`, `eval::policy_commands`, `motion::jobs`, `motion::clip_import`,
//! `policy::train_job`, `scene::dwelling::batch`, `synth::scene_inspect`, `synth::body_pictures`,
//! `body::info`, `export::head_stats`, `export::aria::job`, `export::euroc::job`,
//! `inspect::report`.

pub mod aria_jobs;
pub mod body_jobs;
pub mod config;
pub mod config_file;
pub mod euroc_jobs;
pub mod eval_jobs;
pub mod hand_stats_jobs;
pub mod head_stats_jobs;
pub mod import_jobs;
pub mod inspect_jobs;
pub mod motion_jobs;
pub mod overrides;
pub mod policy_jobs;
pub mod resolve;
pub mod scene_jobs;
pub mod synth_config;
pub mod train_policy;
pub mod train_primitive;

pub use config::{ConfigError, RawRun};

/// Lets a closed standard output end the process quietly, as Unix tools do (`egogen inspect
/// FILE | head -1`), instead of a panic in `println!`. Binaries call it first thing.
pub fn exit_quietly_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: restores the default disposition of SIGPIPE (terminate) before any thread or
    // handler exists; Rust's runtime set it to "ignore" at start-up.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

pub use resolve::{resolve_run, MotionPlan, RenderPlan, RunPlan, SlurmPlan, SupervisorPlan};
