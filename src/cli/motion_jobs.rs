//! `egogen motion eval|stats|control`: `control`'s flags, and thin calls into the jobs that
//! measure the motion model (`eval::motion_model`: held-out error, foot contact, long
//! random-latent chains, steering probes; CEM-chosen latents for a target pace and heading)
//! and its training data (`motion::jobs::motion_stats`: pace and turn distributions), with the
//! training config loaded here. `head-stats` is `export::head_stats`'.

use std::path::{Path, PathBuf};

use anyhow::Result;

use super::train_primitive::train_plan_for_job;
use crate::eval::motion_model::control::MotionControl;
pub(crate) use crate::eval::motion_model::{MotionEvalOptions, Precision};

/// `egogen motion eval`: prints the measurements as JSON lines
/// (`eval::motion_model`).
pub(crate) fn motion_eval(weights: &Path, config: &Path, opts: &MotionEvalOptions) -> Result<()> {
    crate::eval::motion_model::motion_eval(weights, config, opts, train_plan_for_job)
}

/// `egogen motion stats`: pace and turn distributions of a config's primitives.
pub(crate) fn motion_stats(config: &Path, json: Option<&Path>) -> Result<()> {
    crate::motion::jobs::motion_stats(config, json, train_plan_for_job)
}

/// What `egogen motion control` measures (its flags).
#[derive(clap::Args, Debug)]
pub(crate) struct MotionControlOptions {
    /// Weights (default: the shipped assets/motion/primitive_cvae.safetensors).
    #[arg(long)]
    weights: Option<PathBuf>,
    /// The training config, for its clips (the walks start from a training seed).
    #[arg(long, default_value_os_t = crate::paths::crate_root().join("configs/train_primitive.toml"))]
    config: PathBuf,
    /// Target speeds of the straight walks (m/s), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "0.6,1.0,1.3,1.6")]
    speeds: Vec<f64>,
    /// Length of each straight walk (s of motion; 0.45 s per primitive).
    #[arg(long, default_value_t = 60.0)]
    walk_s: f64,
    /// Turn angles (degrees, positive to the left), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "45,90,180"
    )]
    turns: Vec<f64>,
    /// Walking speed asked for during the turns (m/s).
    #[arg(long, default_value_t = 1.0)]
    turn_speed: f64,
    /// Primitives allowed per turn.
    #[arg(long, default_value_t = 6)]
    turn_primitives: usize,
    /// Latents decoded per CEM iteration.
    #[arg(long, default_value_t = 128)]
    samples: usize,
    /// CEM iterations per primitive.
    #[arg(long, default_value_t = 4)]
    iterations: usize,
    /// Cost per unit of −ln(foot-contact score), against 4 per m/s of speed error.
    #[arg(long, default_value_t = 20.0)]
    contact_weight: f64,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// PNG of the first 10 s of the walk at --png-speed, from above and from the side.
    #[arg(long)]
    walk_png: Option<PathBuf>,
    /// Which walk --walk-png draws (m/s; one of --speeds).
    #[arg(long, default_value_t = 1.3)]
    png_speed: f64,
    /// Folder to write every walk and turn into as AMASS-style `.npz` (created; files in
    /// it must not exist).
    #[arg(long)]
    export_dir: Option<PathBuf>,
}

impl MotionControlOptions {
    /// The job these flags ask for.
    fn job(&self) -> MotionControl {
        MotionControl {
            weights: self.weights.clone(),
            config: self.config.clone(),
            speeds: self.speeds.clone(),
            walk_s: self.walk_s,
            turns: self.turns.clone(),
            turn_speed: self.turn_speed,
            turn_primitives: self.turn_primitives,
            samples: self.samples,
            iterations: self.iterations,
            contact_weight: self.contact_weight,
            seed: self.seed,
            walk_png: self.walk_png.clone(),
            png_speed: self.png_speed,
            export_dir: self.export_dir.clone(),
        }
    }
}

/// `egogen motion control`: sustained walks and turns with CEM-chosen latents, as JSON lines.
pub(crate) fn motion_control(opts: &MotionControlOptions) -> Result<()> {
    crate::eval::motion_model::control::motion_control(&opts.job(), train_plan_for_job)
}
