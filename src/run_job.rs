//! The `egogen-run` job: a run config in, a dataset out. The config (with the command line's
//! overrides applied to it as written) is resolved into a plan; motion is made — agents
//! walking the scene (`synth`), a scripted walk or a motion file — and, with a `[render]`
//! section, rendered through the supervisor into a dataset folder, else written as a motion
//! folder. [`verify`] re-checks a finished dataset. The binary only parses arguments and calls
//! these.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::body::BodyModel;
use crate::cli::overrides::{effective_config_toml, resume_fingerprint, RunOverrides};
use crate::cli::{resolve_run, MotionPlan, RawRun, RunPlan};
use crate::motion::scripted::WalkCycle;
use crate::motion::MotionSequence;
use crate::plan::SynthPlan;
use crate::supervisor::{run_pipeline, RunMotion, RunOptions, RunSummary};
use crate::synth::{pose_meshes, track_body, write_sequence_dir};

/// How the job runs, beside its config.
#[derive(Debug, Clone, Default)]
pub struct RunRequest {
    /// Continue the interrupted run in `<output.dir>.partial`.
    pub resume: bool,
    /// Blender to use (else `EGOGEN_BLENDER`, else the managed install).
    pub blender: Option<PathBuf>,
}

/// Runs the config at `config` with `overrides` (see the module docs).
pub fn run(config: &Path, overrides: &RunOverrides, request: RunRequest) -> Result<()> {
    let mut raw = RawRun::load(config)?;
    // Overrides go into the config as written, so its checks apply to them too.
    overrides
        .apply(&mut raw)
        .context("resolving a path given on the command line")?;
    let config_toml = effective_config_toml(&raw, config, overrides)
        .context("writing out the effective config")?;
    let resume_fingerprint = resume_fingerprint(&raw).context("fingerprinting the config")?;
    let plan = resolve_run(raw, config)?;
    if plan.output_dir.exists() && !plan.output_dir.is_dir() {
        anyhow::bail!(
            "output {} exists and is a file, not a folder; choose another `output.dir` or --out (nothing was written)",
            plan.output_dir.display()
        );
    }
    let options = RunOptions {
        resume: request.resume,
        blender: request.blender,
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
            return run_agents(&plan, synth, wearers, &model, config, &options)
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
        let motion = RunMotion::Placed(&motion);
        report(&run_pipeline(
            &plan, render, motion, &model, config, &options,
        )?);
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

/// Re-checks a finished dataset against its manifest and says what it found.
pub fn verify(dataset: &Path) -> Result<()> {
    let report = crate::supervisor::verify(dataset)?;
    println!(
        "{}: OK — {} files ({} frame files, {:.1} MB) match the manifest",
        dataset.display(),
        report.files,
        report.frames,
        report.bytes as f64 / 1e6
    );
    Ok(())
}

fn report(summary: &RunSummary) {
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
    plan: &RunPlan,
    synth: &SynthPlan,
    wearers: &[usize],
    model: &BodyModel,
    config: &Path,
    options: &RunOptions,
) -> Result<()> {
    if plan.render.is_none() {
        crate::synth::crowd_dir::check_out_dir(&plan.output_dir)?;
    }
    let s = crate::cli::synth::synthesize(synth, model, true)?;
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
            let motion = RunMotion::Agents {
                world: &s.world,
                obstacles: &synth.solids,
                take: &s.take,
                wearers,
                about: s.about,
            };
            report(&run_pipeline(plan, render, motion, model, config, options)?);
        }
        None => {
            let out = crate::synth::crowd_dir::write_crowd_dir(
                &plan.output_dir,
                &s.world,
                model,
                &s.take,
                Some(s.wall_s),
                s.about,
            )?;
            eprintln!("egogen-run: wrote {}", out.dir.display());
        }
    }
    Ok(())
}
