//! `egogen-run`: the pipeline — config in, dataset out.
//!
//! Body model + motion (scripted walk or a motion file) → posed bodies, eye-anchor (CPF)
//! trajectory, meshes and a preview; with a `[render]` section, the motion is placed in the
//! scene and rendered by the rig's cameras through Blender workers into a dataset folder
//! (`egogen::supervisor`). `egogen-run verify DATASET` re-checks a finished dataset.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;

use egogen::body::BodyModel;
use egogen::cli::config::Backend;
use egogen::cli::overrides::{effective_config_toml, RunOverrides};
use egogen::cli::{resolve_run, MotionPlan, RawRun};
use egogen::motion::scripted::WalkCycle;
use egogen::motion::MotionSequence;
use egogen::synth::{pose_meshes, track_body, write_sequence_dir};

/// Generate an egocentric dataset from a config file.
#[derive(Parser, Debug)]
#[command(version, about, args_conflicts_with_subcommands = true)]
struct Args {
    #[command(subcommand)]
    command: Option<Command>,
    /// Run config (TOML), e.g. `configs/default.toml`.
    config: Option<PathBuf>,
    /// Continue the interrupted run in `<output.dir>.partial` (same config only).
    #[arg(long)]
    resume: bool,
    /// Output folder, overriding `output.dir`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Every seed of the config (motion, scene placement, lighting, headset wear, depth
    /// noise): another variant of the same run.
    #[arg(long)]
    seed: Option<u64>,
    /// Camera rig to render with, overriding `render.rig`.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// Where shards run, overriding `supervisor.backend`: `local` (Blender processes here) or
    /// `slurm` (a job array; resources in `[supervisor.slurm]`).
    #[arg(long, value_enum)]
    backend: Option<BackendArg>,
    /// Parallel Blender workers (with Slurm: array tasks at once), overriding `supervisor.workers`.
    #[arg(long)]
    workers: Option<usize>,
    /// Blender to use (Python with bpy 4.5, or a blender executable); else `EGOGEN_BLENDER`,
    /// else the managed install.
    #[arg(long)]
    blender: Option<PathBuf>,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum BackendArg {
    Local,
    Slurm,
}

#[derive(clap::Subcommand, Debug)]
enum Command {
    /// Re-check a finished dataset against its manifest (sizes, checksums, frame files).
    Verify { dataset: PathBuf },
}

fn main() -> ExitCode {
    egogen::cli::exit_quietly_on_closed_pipe();
    let args = Args::parse();
    let result = match &args.command {
        Some(Command::Verify { dataset }) => verify(dataset),
        None => run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn verify(dataset: &std::path::Path) -> Result<()> {
    let report = egogen::supervisor::verify(dataset)?;
    println!(
        "{}: OK — {} files ({} frame files, {:.1} MB) match the manifest",
        dataset.display(),
        report.files,
        report.frames,
        report.bytes as f64 / 1e6
    );
    Ok(())
}

fn run(args: Args) -> Result<()> {
    let Some(config) = args.config.clone() else {
        anyhow::bail!("no config given: egogen-run CONFIG (e.g. configs/default.toml), or egogen-run verify DATASET");
    };
    let mut raw = RawRun::load(&config)?;
    // Overrides go into the config as written, so its checks apply to them too.
    let overrides = RunOverrides {
        out: args.out.clone(),
        seed: args.seed,
        rig: args.rig.clone(),
        workers: args.workers,
        backend: args.backend.map(|b| match b {
            BackendArg::Local => Backend::Local,
            BackendArg::Slurm => Backend::Slurm,
        }),
    };
    overrides
        .apply(&mut raw)
        .context("resolving a path given on the command line")?;
    let config_toml = effective_config_toml(&raw, &config, &overrides)
        .context("writing out the effective config")?;
    let resume_fingerprint =
        egogen::cli::overrides::resume_fingerprint(&raw).context("fingerprinting the config")?;
    let plan = resolve_run(raw, &config)?;
    let options = egogen::supervisor::RunOptions {
        resume: args.resume,
        blender: args.blender,
        config_toml,
        resume_fingerprint,
    };
    let model = BodyModel::load(&plan.body_model)?;
    if plan.betas.len() > model.num_betas() {
        anyhow::bail!(
            "config {}: key `body.betas`: {} betas given but the model {} has {}",
            config.display(),
            plan.betas.len(),
            plan.body_model.display(),
            model.num_betas()
        );
    }
    let motion = match &plan.motion {
        MotionPlan::Agents { synth, wearers } => {
            return run_agents(&plan, synth, wearers, &model, &config, &options)
        }
        MotionPlan::ScriptedWalk {
            duration_s,
            frame_rate_hz,
            speed_m_per_s,
        } => {
            let shaped = model.shape(&plan.betas, &[])?;
            let walk = WalkCycle {
                speed_m_per_s: *speed_m_per_s,
                ..Default::default()
            };
            walk.sequence(
                *duration_s,
                *frame_rate_hz,
                &plan.betas,
                shaped.rest_joints[0],
                shaped.rest_sole_y(),
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
    if let Some(render) = &plan.render {
        let motion = egogen::supervisor::RunMotion::Placed(&motion);
        let summary =
            egogen::supervisor::run_pipeline(&plan, render, motion, &model, &config, &options)?;
        report(&summary);
        return Ok(());
    }
    let track = track_body(&model, &motion)?;
    let meshes = pose_meshes(&model, &motion, plan.mesh_every_n_frames)?;
    let out = write_sequence_dir(&plan.output_dir, &model, &motion, &track, &meshes)?;
    eprintln!(
        "egogen-run: wrote {} ({} files, {} meshes)",
        out.dir.display(),
        out.files.len(),
        out.meshes
    );
    Ok(())
}

fn report(summary: &egogen::supervisor::RunSummary) {
    eprintln!(
        "egogen-run: wrote {} ({} frames, {} rendered now, {} files in the manifest)",
        summary.dir.display(),
        summary.frames,
        summary.rendered_now,
        summary.files
    );
}

/// Agents walk the scene (as `egogen synth`), then the take is rendered, or written alone
/// without `[render]`.
fn run_agents(
    plan: &egogen::cli::RunPlan,
    synth: &egogen::plan::SynthPlan,
    wearers: &[usize],
    model: &BodyModel,
    config: &std::path::Path,
    options: &egogen::supervisor::RunOptions,
) -> Result<()> {
    if plan.render.is_none() {
        egogen::synth::crowd_dir::check_out_dir(&plan.output_dir)?;
    }
    let s = egogen::cli::synth::synthesize(synth, model, true)?;
    let reached: usize = s
        .take
        .agents
        .iter()
        .map(|a| a.goals.iter().filter(|g| g.reached).count())
        .sum();
    eprintln!(
        "egogen-run: {} agents walked {} frames at {} Hz ({reached} goals reached) in {:.1} s",
        s.take.agents.len(),
        s.take.frames,
        s.take.frame_rate_hz,
        s.wall_s
    );
    match &plan.render {
        Some(render) => {
            let motion = egogen::supervisor::RunMotion::Agents {
                world: &s.world,
                obstacles: &synth.solids,
                take: &s.take,
                wearers,
                wall_s: s.wall_s,
                about: s.about,
            };
            let summary =
                egogen::supervisor::run_pipeline(plan, render, motion, model, config, options)?;
            report(&summary);
        }
        None => {
            let out = egogen::synth::crowd_dir::write_crowd_dir(
                &plan.output_dir,
                &s.world,
                model,
                &s.take,
                s.wall_s,
                s.about,
            )?;
            eprintln!("egogen-run: wrote {}", out.dir.display());
        }
    }
    Ok(())
}
