//! Command-line and configuration plumbing: clap arguments, TOML configs, resolved plans.
//!
//! No domain logic lives here: configs are only parsed and checked, then resolved into the typed
//! plans the stages consume, and each `*_jobs` file holds a command's clap arguments and thin
//! functions that turn them into a typed job (defaults resolved, configs loaded, flags checked)
//! and call the module whose data the job is. A command whose flags need nothing but parsing
//! (`egogen body …`, `inspect`, `motion hand-stats|head-stats`, `scene inspect`) is called by
//! `commands::egogen` straight into its module's job: `body::info`, `synth::body_pictures`,
//! `motion::jobs`, `inspect::report`, `export::head_stats`, `synth::scene_inspect`.
//!
//! Configs: `config_file` (what every config file shares: the error naming file and key, strict
//! TOML loading, shipped defaults), `config` (the run config as written), `overrides`
//! (`egogen-run`'s command-line overrides applied to it), `resolve` (a run config into a checked
//! `RunPlan`), `synth_config` (`egogen synth`'s config into a `SynthPlan`), `train_primitive`
//! and `train_policy` (the two training configs into their plans).
//!
//! Commands, each with the jobs it calls: `aria_jobs` (`egogen aria export`:
//! `export::aria::job`), `euroc_jobs` (`egogen euroc export`: `export::euroc::job`),
//! `eval_jobs` (`egogen eval`: `eval::jobs`), `import_jobs` (`egogen motion import`:
//! `motion::clip_import`, `synth::body_pictures`), `motion_jobs` (`egogen motion
//! eval|stats|control`: `eval::motion_model`, `motion::jobs`), `policy_jobs` (`egogen policy`
//! and `egogen train policy`: `eval::policy_commands`, `policy::train_job`), `scene_jobs`
//! (`egogen scene generate`: `scene::dwelling::batch`; the scene frame flags).

pub(crate) mod aria_jobs;
pub mod config;
pub(crate) mod config_file;
pub(crate) mod euroc_jobs;
pub(crate) mod eval_jobs;
pub(crate) mod import_jobs;
pub(crate) mod motion_jobs;
pub(crate) mod overrides;
pub(crate) mod policy_jobs;
pub mod resolve;
pub mod scene_jobs;
pub mod synth_config;
pub mod train_policy;
pub mod train_primitive;

pub use config::RawRun;

/// Lets a closed standard output end the process quietly, as Unix tools do (`egogen inspect
/// FILE | head -1`), instead of a panic in `println!`. Binaries call it first thing.
pub(crate) fn exit_quietly_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: restores the default disposition of SIGPIPE (terminate) before any thread or
    // handler exists; Rust's runtime set it to "ignore" at start-up.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

pub(crate) use resolve::MotionPlan;
pub(crate) use resolve::{resolve_run, RunPlan};
