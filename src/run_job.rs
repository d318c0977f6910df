//! The `egogen-run` job: a run config in, a dataset out. The config (with the command line's
//! overrides applied to it as written) is resolved into a plan; motion is made — agents
//! walking the scene (`synth`), a scripted walk or a motion file — and, with a `[render]`
//! section, rendered through the supervisor into a dataset folder, else written as a motion
//! folder. [`verify`] re-checks a finished dataset. The binary only parses arguments and calls
//! these.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::body::BodyModel;
use crate::cli::overrides::{
    effective_config_toml, resume_fingerprint, resume_fingerprint_anywhere, RunOverrides,
};
use crate::cli::{resolve_run, MotionPlan, RawRun, RunPlan};
use crate::supervisor::{run_pipeline, RunMotion, RunOptions, RunSummary};
use crate::synth::take::{make_motion, TakeMotion};
use crate::synth::{pose_meshes, track_body, write_sequence_dir};

/// How the job runs, beside its config.
#[derive(Debug, Clone, Default)]
pub(crate) struct RunRequest {
    /// Continue the interrupted run in `<output.dir>.partial`.
    pub resume: bool,
    /// Blender to use (else `EGOGEN_BLENDER`, else the managed install).
    pub blender: Option<PathBuf>,
}

/// A run config resolved with the command line's overrides: its plan, its body model, and
/// what the dataset records of it.
pub(crate) struct PreparedRun {
    pub plan: RunPlan,
    pub model: BodyModel,
    pub options: RunOptions,
}

/// The first key of `raw` (dotted, as in the file) holding an integer TOML cannot write (above
/// 2^63 − 1: a seed of 2^63, say), and its value.
fn integer_beyond_toml(raw: &RawRun) -> Option<(String, u64)> {
    fn find(v: &serde_json::Value, at: &str) -> Option<(String, u64)> {
        match v {
            serde_json::Value::Number(n) => n
                .as_u64()
                .filter(|&u| u > i64::MAX as u64)
                .map(|u| (at.to_string(), u)),
            serde_json::Value::Object(m) => m.iter().find_map(|(k, v)| {
                let key = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                find(v, &key)
            }),
            serde_json::Value::Array(a) => a
                .iter()
                .enumerate()
                .find_map(|(i, v)| find(v, &format!("{at}[{i}]"))),
            _ => None,
        }
    }
    find(&serde_json::to_value(raw).ok()?, "")
}

/// Reads `config`, applies `overrides` to it as written (so its checks apply to them too),
/// resolves it and loads its body model.
pub(crate) fn prepare(
    config: &Path,
    overrides: &RunOverrides,
    request: &RunRequest,
) -> Result<PreparedRun> {
    let mut raw = RawRun::load(config)?;
    overrides
        .apply(&mut raw)
        .with_context(|| format!("applying the command line to {}", config.display()))?;
    if let Some((key, v)) = integer_beyond_toml(&raw) {
        anyhow::bail!(
            "{}: {key} = {v}: expected at most 9223372036854775807 (2^63 − 1: a TOML \
             integer is 64-bit signed, and the effective config is written as TOML)",
            config.display()
        );
    }
    let config_toml = effective_config_toml(&raw, config, overrides)
        .context("writing out the effective config")?;
    let resume_fingerprint = resume_fingerprint(&raw).context("fingerprinting the config")?;
    let moved_fingerprint =
        resume_fingerprint_anywhere(&raw).context("fingerprinting the config")?;
    let plan = resolve_run(raw, config)?;
    if plan.output_dir.exists() && !plan.output_dir.is_dir() {
        anyhow::bail!(
            "output {} exists and is a file, not a folder; choose another `output.dir` or --out (nothing was written)",
            plan.output_dir.display()
        );
    }
    let options = RunOptions {
        resume: request.resume,
        blender: request.blender.clone(),
        config_toml,
        resume_fingerprint,
        moved_fingerprint,
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
    Ok(PreparedRun {
        plan,
        model,
        options,
    })
}

impl PreparedRun {
    /// Makes the take's motion ([`crate::synth::take::make_motion`]) and says what the agents
    /// did.
    pub(crate) fn make_motion(&self) -> Result<TakeMotion> {
        let motion = make_motion(&self.plan.motion, &self.plan.betas, &self.model)?;
        if let TakeMotion::Agents { walked, .. } = &motion {
            let reached: usize = walked
                .take
                .agents
                .iter()
                .map(|a| a.goals.iter().filter(|g| g.reached).count())
                .sum();
            eprintln!(
                "egogen-run: {} agents walked {} frames at {} Hz ({reached} goals reached) in {:.1} s",
                walked.take.agents.len(),
                walked.take.frames,
                walked.take.frame_rate_hz,
                walked.wall_s
            );
        }
        Ok(motion)
    }

    /// The motion as the supervisor renders it.
    pub(crate) fn run_motion<'a>(&'a self, motion: &'a TakeMotion) -> RunMotion<'a> {
        match (motion, &self.plan.motion) {
            (TakeMotion::Agents { walked, wearers }, MotionPlan::Agents { synth, .. }) => {
                RunMotion::Agents {
                    world: &walked.world,
                    obstacles: &synth.solids,
                    take: &walked.take,
                    wearers,
                    about: walked.about.clone(),
                }
            }
            (TakeMotion::One(m), _) => RunMotion::Placed(m),
            (TakeMotion::Agents { .. }, _) => unreachable!("agents are made from an agents plan"),
        }
    }
}

/// Runs the config at `config` with `overrides` (see the module docs).
pub(crate) fn run(config: &Path, overrides: &RunOverrides, request: RunRequest) -> Result<()> {
    let run = prepare(config, overrides, &request)?;
    let (plan, model) = (&run.plan, &run.model);
    if plan.render.is_none() && matches!(plan.motion, MotionPlan::Agents { .. }) {
        crate::synth::crowd_dir::check_out_dir(&plan.output_dir)?;
    }
    let motion = run.make_motion()?;
    if let TakeMotion::One(m) = &motion {
        eprintln!(
            "egogen-run: {} frames at {} Hz, body {} ({} vertices)",
            m.len(),
            m.frame_rate_hz,
            plan.body_model.display(),
            model.num_vertices()
        );
    }
    if let Some(render) = &plan.render {
        report(&run_pipeline(
            plan,
            render,
            run.run_motion(&motion),
            model,
            config,
            &run.options,
        )?);
        return Ok(());
    }
    match &motion {
        TakeMotion::Agents { walked, .. } => {
            let out = crate::synth::crowd_dir::write_crowd_dir(
                &plan.output_dir,
                &walked.world,
                model,
                &walked.take,
                Some(walked.wall_s),
                walked.about.clone(),
            )?;
            eprintln!("egogen-run: wrote {}", out.dir.display());
        }
        TakeMotion::One(motion) => {
            let track = track_body(model, motion)?;
            let meshes = pose_meshes(model, motion, plan.mesh_every_n_frames)?;
            let out = write_sequence_dir(&plan.output_dir, model, motion, &track, &meshes)?;
            eprintln!(
                "egogen-run: wrote {} ({} files, {} meshes)",
                out.dir.display(),
                out.files.len(),
                out.meshes
            );
        }
    }
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
