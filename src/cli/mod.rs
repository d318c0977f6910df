//! Command-line and configuration plumbing: clap arguments, TOML configs, resolved plans.
//!
//! No domain logic lives here: `config` only parses and checks values, `resolve` turns them
//! into typed plans the stages consume.

pub mod aria_jobs;
pub mod body_jobs;
pub mod config;
pub mod config_file;
pub mod eval_jobs;
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

/// What is wrong with a guide's settings, if anything: the setting's name (a config key's
/// last part; a flag is it with dashes) and what was expected. One check for `egogen synth`,
/// `egogen-run`, training configs and `egogen policy eval`.
pub fn guide_settings_problem(
    guide: &crate::scene::Guide,
    memory: bool,
) -> Option<(&'static str, String)> {
    let crate::scene::Guide {
        lookahead_m,
        centre_weight,
        unknown_cost,
    } = *guide;
    if !(lookahead_m.is_finite() && lookahead_m >= 0.0) {
        return Some((
            "guide_lookahead_m",
            format!("expected a distance ≥ 0 m, got {lookahead_m}"),
        ));
    }
    if !(centre_weight.is_finite() && centre_weight >= 0.0) {
        return Some((
            "guide_centre_weight",
            format!("expected a weight ≥ 0, got {centre_weight}"),
        ));
    }
    if !(unknown_cost.is_finite() && unknown_cost >= 0.0) {
        return Some((
            "guide_unknown_cost",
            format!("expected a weight ≥ 0, got {unknown_cost}"),
        ));
    }
    let needs_lookahead = |what: &str| {
        format!("a guide {what} only with a lookahead > 0 m (e.g. 1 or 2): give one too")
    };
    if lookahead_m == 0.0 && memory {
        return Some(("guide_memory", needs_lookahead("plans on memory")));
    }
    if lookahead_m == 0.0 && centre_weight > 0.0 {
        return Some((
            "guide_centre_weight",
            needs_lookahead("keeps to the middle of doorways"),
        ));
    }
    if unknown_cost > 0.0 && !memory {
        return Some((
            "guide_unknown_cost",
            "a cost of unseen ground applies only to a guide that plans on the walker's memory: \
             turn memory on too (with a lookahead > 0 m)"
                .into(),
        ));
    }
    None
}

pub use resolve::{resolve_run, MotionPlan, RenderPlan, RunPlan, SlurmPlan, SupervisorPlan};
