//! `egogen-run`: the pipeline — config in, sequence folder out.
//!
//! Today's stages: body model + motion (scripted walk or a motion file) → posed bodies, eye
//! anchor (CPF) trajectory, meshes and a preview. Rendering joins as later stages land.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};

use egogen::body::BodyModel;
use egogen::cli::{resolve_run, MotionPlan, RawRun};
use egogen::motion::scripted::WalkCycle;
use egogen::motion::MotionSequence;
use egogen::synth::{track_body, write_sequence_dir};

/// Generate an egocentric sequence from a config file.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Run config (TOML), e.g. `configs/default.toml`.
    config: PathBuf,
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<()> {
    let raw = RawRun::load(&args.config)?;
    let plan = resolve_run(raw, &args.config)?;
    let model = BodyModel::load(&plan.body_model)?;
    if plan.betas.len() > model.num_betas() {
        anyhow::bail!(
            "config {}: key `body.betas`: {} betas given but the model {} has {}",
            args.config.display(),
            plan.betas.len(),
            plan.body_model.display(),
            model.num_betas()
        );
    }
    let motion = match &plan.motion {
        MotionPlan::ScriptedWalk {
            duration_s,
            frame_rate_hz,
            speed_m_per_s,
        } => {
            let shaped = model.shape(&plan.betas, &[])?;
            let sole_y = shaped
                .v_shaped
                .iter()
                .map(|v| v.y)
                .fold(f64::INFINITY, f64::min);
            let walk = WalkCycle {
                speed_m_per_s: *speed_m_per_s,
                ..Default::default()
            };
            walk.sequence(
                *duration_s,
                *frame_rate_hz,
                &plan.betas,
                shaped.rest_joints[0],
                sole_y,
            )
        }
        MotionPlan::File { path } => MotionSequence::read(path)?,
    };
    eprintln!(
        "egogen-run: {} frames at {} Hz, body {} ({} vertices)",
        motion.len(),
        motion.frame_rate_hz,
        plan.body_model.display(),
        model.num_vertices()
    );
    let track = track_body(&model, &motion)?;
    let mesh_frames: Vec<usize> = match plan.mesh_every_n_frames {
        0 => Vec::new(),
        n => (0..motion.len()).step_by(n).collect(),
    };
    let bar = ProgressBar::new(mesh_frames.len() as u64).with_style(
        ProgressStyle::with_template(
            "posing meshes {bar:30} {pos}/{len} [{elapsed_precise} < {eta_precise}]",
        )
        .context("progress template")?,
    );
    let shaped = model.shape(&motion.betas, &[])?;
    let mut meshes = Vec::with_capacity(mesh_frames.len());
    for &i in &mesh_frames {
        meshes.push((i, shaped.pose(&motion.poses[i], motion.trans[i])?));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let out = write_sequence_dir(&plan.output_dir, &model, &motion, &track, &meshes)?;
    eprintln!(
        "egogen-run: wrote {} ({} files, {} meshes)",
        out.dir.display(),
        out.files.len(),
        out.meshes
    );
    Ok(())
}
