//! `egogen-run` with a `[render]` section: the whole pipeline into a dataset folder, built in
//! `<dir>.partial/` and renamed when complete. A `.partial` folder left by an interrupted run is
//! continued by `--resume` (finished frames are kept, partial ones redone) as long as the config
//! is byte-identical; otherwise nothing is touched.
//!
//! The job's steps live here and in: `output` (whether `<dir>` and `<dir>.partial` may be
//! written or resumed, the partial folder staged with its stamp, and the take's attribution
//! where its dwelling places CC-BY furniture), `bodies` (the take's
//! people staged: bodies, tracks, the wearer, the `sequence/` folder and Blender's body inputs),
//! `spec` (the take's rendering work: cameras, segmentation ids, ceiling, obstacles, held
//! objects, surfaces, the shard spec, and the repair of what an interrupted run left).

mod bodies;
mod output;
mod spec;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{Context, Result};

use super::local::{LocalPool, PoolSettings};
use super::pool::{OneTake, PoolRun, PoolTake, ShardPool};
use super::slurm::{check_slurm_tools, SlurmPool, SlurmSettings};
use super::staged::{next_start, Dataset};
use crate::body::BodyModel;
use crate::export::annotations::SegmentationId;
use crate::export::{take_exports, FinishedTake};
use crate::manifest::{dataset_files, remove_temporaries, sha256_hex};
use crate::motion::MotionSequence;
use crate::plan::{Backend, RenderPlan, RunPlan};
use crate::render::protocol::ShardSceneSplit;
use crate::render::BlenderRuntime;
use crate::scene::load_scene;
use crate::scene::ObstacleSolid;
use crate::synth::crowd::{CrowdTake, CrowdWorld};
use bodies::{aria_export, rendered_agents, write_body_inputs, write_sequence};
use output::{check_output, restamp_moved, stage_run, write_attribution, OutputState};
use spec::{base_spec, camera_work, repair, scene_objects, segmentation_ids};

/// Command-line choices that are not in the config, and the effective config.
#[derive(Debug, Clone, Default)]
pub(crate) struct RunOptions {
    pub resume: bool,
    /// `--blender`; else `EGOGEN_BLENDER`; else the managed install.
    pub blender: Option<PathBuf>,
    /// The effective config (the file with the command line's overrides), written into the
    /// dataset as `config.toml` (`cli::overrides::effective_config_toml`).
    pub config_toml: String,
    /// What a resume must find unchanged (`cli::overrides::resume_fingerprint`); hashed.
    pub resume_fingerprint: String,
    /// The same without the output folder (`cli::overrides::resume_fingerprint_anywhere`): a
    /// `.partial` moved to another folder is resumed where it lies; hashed.
    pub moved_fingerprint: String,
}

/// What a run produced.
#[derive(Debug, Clone)]
pub(crate) struct RunSummary {
    pub dir: PathBuf,
    pub frames: usize,
    pub rendered_now: usize,
    pub files: usize,
}

/// What `work/run.json` records of a run, so that a resume continues only the same run.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub(crate) struct RunState {
    /// The config file the run was started from, and the SHA-256 of its effective values
    /// (command-line overrides applied; `[supervisor]` left out).
    pub config: String,
    pub config_sha256: String,
    /// SHA-256 of the resolved rig (a `--rig` override included); absent in runs started
    /// before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig_sha256: Option<String>,
    /// SHA-256 of the effective values without the output folder: the same run moved to
    /// another folder. Absent in runs started before it was recorded (those resume only where
    /// they were started).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moved_sha256: Option<String>,
}

/// What moves in a run's scene.
pub(crate) enum RunMotion<'a> {
    /// One motion (a scripted walk or a motion file) placed rigidly in the scene by
    /// `scene.seed`, worn by the rig.
    Placed(&'a MotionSequence),
    /// A synthesized take: every agent rendered, the rig on the `wearers` (indices into the
    /// take's agents). `about` goes into the take's summary (its wall time does not: the
    /// dataset stays the same bytes run after run).
    Agents {
        world: &'a CrowdWorld,
        /// The `[[obstacles]]` boxes, drawn standing on the walkable map's floor.
        obstacles: &'a [ObstacleSolid],
        take: &'a CrowdTake,
        wearers: &'a [usize],
        about: serde_json::Value,
    },
}

/// Runs the pipeline for a plan with a render section; `config_path` is hashed so that a
/// resumed run is known to be the same run: [`stage_take`], the missing frames rendered on the
/// plan's backend, [`StagedTake::finish`].
pub(crate) fn run_pipeline(
    plan: &RunPlan,
    render: &RenderPlan,
    motion: RunMotion,
    model: &BodyModel,
    config_path: &Path,
    opts: &RunOptions,
) -> Result<RunSummary> {
    // A new run fails on a missing Blender or Slurm before anything is staged.
    let mut runtime = None;
    let before_staging = || -> Result<()> {
        let found = BlenderRuntime::resolve(opts.blender.as_deref())?;
        if plan.supervisor.backend == Backend::Slurm {
            check_slurm_tools()?;
        } else {
            // On Slurm the GPU is the compute node's: the worker checks it there.
            crate::render::shard::check_device(&found, render.device)
                .map_err(anyhow::Error::msg)?;
        }
        runtime = Some(found);
        Ok(())
    };
    let staged = match stage_take(
        plan,
        render,
        motion,
        model,
        config_path,
        opts,
        before_staging,
    )? {
        Staged::Complete(dir) => {
            eprintln!(
                "egogen-run: {} is already complete; nothing to do",
                dir.display()
            );
            return Ok(RunSummary {
                dir,
                frames: 0,
                rendered_now: 0,
                files: 0,
            });
        }
        Staged::Take(take) => take,
    };
    let dataset = staged.dataset.clone();
    let total = dataset.total_frames();
    let shards = dataset.pending_shards();
    let pending: usize = shards.iter().map(|s| s.frames.len()).sum();
    eprintln!(
        "egogen-run: {} camera(s) × {} frames = {total} frames; {pending} to render in {} shard(s) on {} worker(s)",
        render.cameras.len(),
        total / dataset.cameras.len().max(1),
        shards.len(),
        plan.supervisor.workers
    );
    let mut rendered_now = 0;
    if !shards.is_empty() {
        let runtime = match runtime {
            Some(r) => r,
            None => BlenderRuntime::resolve(opts.blender.as_deref())?,
        };
        let take = PoolTake {
            name: String::new(),
            dataset: dataset.clone(),
            shards,
        };
        let run = PoolRun {
            logs_dir: dataset.logs_dir(),
            work_dir: dataset.staging.join("work"),
            stop_on_failure: true,
        };
        let feed = Arc::new(Mutex::new(OneTake::new(take, total - pending)));
        let report = shard_pool(&plan.supervisor).run(feed, runtime, &run)?;
        let retried = report
            .shards
            .iter()
            .filter(|s| s.attempts.len() > 1)
            .count();
        eprintln!(
            "egogen-run: rendered {} frames in {:.1} s ({retried} shard(s) retried)",
            report.frames_finished, report.wall_seconds
        );
        rendered_now = report.frames_finished;
    }
    let files = staged.finish()?;
    Ok(RunSummary {
        dir: plan.output_dir.clone(),
        frames: total,
        rendered_now,
        files,
    })
}

/// The backend the supervisor settings name, as a pool.
pub(crate) fn shard_pool(sup: &crate::plan::SupervisorPlan) -> Box<dyn ShardPool> {
    let shard_timeout = Duration::from_secs_f64(sup.shard_timeout_s);
    match sup.backend {
        Backend::Local => Box::new(LocalPool(PoolSettings {
            workers: sup.workers,
            shard_timeout,
            retries: sup.retries,
            keep_blender: sup.keep_blender,
        })),
        Backend::Slurm => Box::new(SlurmPool(SlurmSettings {
            plan: sup.slurm.clone(),
            max_running: sup.workers,
            shard_timeout,
            retries: sup.retries,
        })),
    }
}

/// What staging a take found.
pub(crate) enum Staged {
    /// Its output folder is this run's finished dataset (under `--resume`).
    Complete(PathBuf),
    /// Staged in `<dir>.partial`, with its frames left to render.
    Take(Box<StagedTake>),
}

/// A take staged in `<dir>.partial`: what its shards render and what finishing it needs.
pub(crate) struct StagedTake {
    pub dataset: Arc<Dataset>,
    /// The finished dataset's folder.
    pub dir: PathBuf,
    rig: crate::rig::Rig,
    /// The scene's objects' segmentation ids, with the class where the scene file says.
    scene_ids: Vec<SegmentationId>,
    /// Files only Blender reads (body inputs), removed when the take is finished.
    scratch: Vec<PathBuf>,
}

/// Stages a take: checks the output folder and what a resume continues; everything that can
/// fail on bad input before anything is staged (then `before_staging`, for a new take only:
/// Blender and the backend's tools are there); stages the run; writes the sequence, the Aria
/// streams and Blender's inputs; plans the cameras and the scene's objects; repairs what an
/// interrupted run left (damaged frames, missing records).
///
/// `work/run.json`, [`RunState`], says which run a `.partial` folder holds.
pub(crate) fn stage_take(
    plan: &RunPlan,
    render: &RenderPlan,
    motion: RunMotion,
    model: &BodyModel,
    config_path: &Path,
    opts: &RunOptions,
    before_staging: impl FnOnce() -> Result<()>,
) -> Result<Staged> {
    let dir = &plan.output_dir;
    let staging = crate::atomic_file::partial_of(dir);
    let state = RunState {
        config: config_path.display().to_string(),
        config_sha256: sha256_hex(opts.resume_fingerprint.as_bytes()),
        // The rig as resolved (a --rig override included): a resume must render with the same one.
        rig_sha256: Some(sha256_hex(render.rig.to_json().as_bytes())),
        moved_sha256: Some(sha256_hex(opts.moved_fingerprint.as_bytes())),
    };
    let fresh = match check_output(dir, &staging, &state, opts)? {
        OutputState::Complete => return Ok(Staged::Complete(dir.clone())),
        OutputState::Fresh => true,
        OutputState::Resume => false,
        OutputState::Moved => {
            restamp_moved(&staging, &state, opts)?;
            false
        }
    };

    // Everything that can fail on bad input, before anything is staged: the scene, where the
    // motion happens in it.
    let scene = load_scene(&plan.scene, plan.scene_frame)?;
    let (agents, wearers) = rendered_agents(plan, &scene, &motion, model)?;
    if fresh {
        before_staging()?;
        stage_run(&staging, &state, opts)?;
    } else {
        eprintln!("egogen-run: resuming {}", staging.display());
    }
    let sequence = staging.join("sequence");
    if !sequence.exists() {
        write_sequence(&sequence, &motion, &agents, model, plan)?;
    }
    write_attribution(&staging, &plan.scene)?;
    let aria = aria_export(render, &wearers, &motion, &agents, model, &scene)?;
    let frames: Vec<u32> = (0..agents[0].motion.len() as u32)
        .step_by(render.every_n_frames)
        .collect();
    let (bodies, mut scratch) =
        write_body_inputs(&staging.join("work"), &agents, model, render, &frames)?;
    let scene_split = match &scene.file_face_objects {
        Some(faces) => {
            let path = staging.join("work/scene_face_objects.npy");
            crate::vertex_cache::write_face_objects_npy(&path, faces)?;
            let split = ShardSceneSplit {
                face_objects: std::fs::canonicalize(&path)?,
                names: scene.objects.iter().map(|o| o.name.clone()).collect(),
            };
            scratch.push(path);
            Some(split)
        }
        None => None,
    };
    let cameras = camera_work(render, &agents, &wearers, &frames);
    let n_cameras = cameras.len();
    let objects = scene_objects(plan, render, &scene, &motion, &agents, &frames);
    let mut base_spec = base_spec(plan, render, &scene, &agents[wearers[0]], bodies, &objects)?;
    base_spec.scene_split = scene_split;
    let dataset = Arc::new(Dataset {
        staging: std::fs::canonicalize(&staging)?,
        base_spec,
        cameras,
        passes: render.passes,
        keys_per_frame: render.cache_samples_per_frame,
        frames_per_shard: render.frames_per_shard,
        near_clip_m: render.near_clip_m,
        agents,
        exports: take_exports(render.colmap, aria),
        start: next_start(&staging),
        remaps: (0..n_cameras).map(|_| Default::default()).collect(),
    });
    repair(&dataset)?;
    Ok(Staged::Take(Box::new(StagedTake {
        dataset,
        dir: dir.clone(),
        rig: render.rig.clone(),
        scene_ids: segmentation_ids(&objects.ids, &scene),
        scratch,
    })))
}

impl StagedTake {
    /// Removes the scratch only Blender read (raw renders, body inputs) and the temporaries of
    /// killed writes, writes the take's outputs from the frames' records (annotations, the
    /// COLMAP model, the manifest last: `export::take_exports`) and renames `<dir>.partial` to
    /// `<dir>`; returns how many files the manifest lists.
    pub(crate) fn finish(&self) -> Result<usize> {
        let dataset = &self.dataset;
        let staging = &dataset.staging;
        let records = dataset.records()?;
        let _ = std::fs::remove_dir_all(dataset.raw_dir());
        for f in &self.scratch {
            let _ = std::fs::remove_file(f);
        }
        for p in remove_temporaries(staging)? {
            eprintln!(
                "egogen-run: removed {}, left by an interrupted run",
                p.display()
            );
        }
        let take = FinishedTake {
            folder: staging,
            rig: &self.rig,
            cameras: &dataset.cameras,
            agents: &dataset.agents,
            records: &records,
            scene_ids: &self.scene_ids,
            spec: &dataset.base_spec,
        };
        for export in dataset.exports.iter() {
            export.finish(&take).with_context(|| {
                format!("writing the {} of {}", export.name(), staging.display())
            })?;
        }
        let files = dataset_files(staging)?.len();
        let dir = &self.dir;
        if dir.exists() {
            std::fs::remove_dir(dir)
                .with_context(|| format!("replacing empty {}", dir.display()))?;
        }
        std::fs::rename(staging, dir)
            .with_context(|| format!("renaming {} to {}", staging.display(), dir.display()))?;
        Ok(files)
    }
}
