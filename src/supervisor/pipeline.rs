//! `egogen-run` with a `[render]` section: the whole pipeline into a dataset folder, built in
//! `<dir>.partial/` and renamed when complete. A `.partial` folder left by an interrupted run is
//! continued by `--resume` (finished frames are kept, partial ones redone) as long as the config
//! is byte-identical; otherwise nothing is touched.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{bail, Context, Result};

use super::local::{LocalPool, PoolSettings};
use super::pool::{OneTake, PoolRun, PoolTake, ShardPool};
use super::slurm::{check_slurm_tools, SlurmPool, SlurmSettings};
use super::staged::{next_start, CameraWork, Dataset, RenderedAgent};
use crate::atomic_file::write_atomically;
use crate::body::BodyModel;
use crate::export::annotations::SegmentationId;
use crate::export::aria::{AriaExport, AriaWearer};
use crate::export::gaze::GazeGoal;
use crate::export::{take_exports, FinishedTake};
use crate::manifest::{dataset_files, remove_temporaries, sha256_hex, MANIFEST};
use crate::motion::MotionSequence;
use crate::plan::{Backend, RenderPlan, RunPlan};
use crate::render::lens_polynomial::{native_error, ERROR_GRID};
use crate::render::materials::{MaterialsMode, SurfaceFacts};
use crate::render::protocol::{
    ObstacleKey, ShardCeiling, ShardObstacle, ShardSceneSplit, ShardSkinRegion, CEILING_OBJECT,
};
use crate::render::render_camera::RenderCamera;
use crate::render::shard_plan::{blender_fps, AGENT_ID_BASE};
use crate::render::skin_tone::{SkinRegion, SKIN_DETAIL_FILE, SKIN_REGIONS};
use crate::render::{BlenderRuntime, ShardBody, ShardRgb, ShardSpec};
use crate::scene::ceiling::ceiling_to_add;
use crate::scene::{load_scene, walkable_map};
use crate::scene::{Obstacle2, ObstacleSolid};
use crate::synth::body_cache::{body_cache_at, playback_keys, rendered_sample_indices};
use crate::synth::crowd::{CrowdTake, CrowdWorld};
use crate::synth::crowd_dir::write_crowd_dir;
use crate::synth::placement::place_motion;
use crate::synth::{pose_meshes, track_body, write_sequence_dir};
use crate::vertex_cache::{write_corner_uvs_npy, write_faces_npy, write_rest_vertices_npy};

/// Command-line choices that are not in the config, and the effective config.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
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
pub struct RunSummary {
    pub dir: PathBuf,
    pub frames: usize,
    pub rendered_now: usize,
    pub files: usize,
}

fn is_non_empty_dir(p: &Path) -> bool {
    std::fs::read_dir(p)
        .map(|mut d| d.next().is_some())
        .unwrap_or(false)
}

/// What `work/run.json` records of a run, so that a resume continues only the same run.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RunState {
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
pub enum RunMotion<'a> {
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
pub fn run_pipeline(
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
pub fn shard_pool(sup: &crate::plan::SupervisorPlan) -> Box<dyn ShardPool> {
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
pub enum Staged {
    /// Its output folder is this run's finished dataset (under `--resume`).
    Complete(PathBuf),
    /// Staged in `<dir>.partial`, with its frames left to render.
    Take(Box<StagedTake>),
}

/// A take staged in `<dir>.partial`: what its shards render and what finishing it needs.
pub struct StagedTake {
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
pub fn stage_take(
    plan: &RunPlan,
    render: &RenderPlan,
    motion: RunMotion,
    model: &BodyModel,
    config_path: &Path,
    opts: &RunOptions,
    before_staging: impl FnOnce() -> Result<()>,
) -> Result<Staged> {
    let dir = &plan.output_dir;
    let staging = PathBuf::from(format!("{}.partial", dir.display()));
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
    let aria = aria_export(render, &wearers, &motion, &scene)?;
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
    let objects = scene_objects(plan, &scene, &motion, &agents);
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

/// What the output folder holds for a run.
enum OutputState {
    /// Neither `<dir>` nor `<dir>.partial`: a new run.
    Fresh,
    /// `<dir>.partial` of this same run, and `--resume` asked to continue it.
    Resume,
    /// `<dir>` is this run's finished dataset, and `--resume` was asked.
    Complete,
    /// `<dir>.partial` of this same run started in another folder (moved or copied here), and
    /// `--resume` asked to continue it.
    Moved,
}

/// Checks that the run may write where it is told: `<dir>` empty or absent (or finished, under
/// `--resume`), and a `<dir>.partial` continued only by `--resume` of the same run (`state`).
/// Nothing is touched either way.
fn check_output(
    dir: &Path,
    staging: &Path,
    state: &RunState,
    opts: &RunOptions,
) -> Result<OutputState> {
    if is_non_empty_dir(dir) {
        if opts.resume && dir.join(MANIFEST).is_file() {
            return Ok(OutputState::Complete);
        }
        bail!(
            "output folder {} already exists and is not empty; choose another `output.dir` (nothing was written)",
            dir.display()
        );
    }
    if !staging.exists() {
        return Ok(OutputState::Fresh);
    }
    if !opts.resume {
        bail!(
            "{} holds an interrupted run; rerun with --resume to continue it, or delete it (nothing was written)",
            staging.display()
        );
    }
    let state_path = staging.join("work/run.json");
    let found: RunState = std::fs::read_to_string(&state_path)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .with_context(|| {
            format!(
                "{}: missing or unreadable; cannot resume",
                state_path.display()
            )
        })?;
    let moved = found.config_sha256 != state.config_sha256
        && found.moved_sha256.is_some()
        && found.moved_sha256 == state.moved_sha256;
    if found.config_sha256 != state.config_sha256 && !moved {
        bail!(
            "{} was started from a different config than {} with these options (its values, or those the first run's command line set: --out, --seed, --scene, --up, --unit-m, --crowd-count, --duration-s, --activity-weights, --materials — give the same again); resuming would mix two runs (nothing was touched)",
            staging.display(),
            state.config
        );
    }
    if found.rig_sha256.is_some() && found.rig_sha256 != state.rig_sha256 {
        bail!(
            "{} was started with a different camera rig (a --rig override or a changed rig file); resuming would mix two runs (nothing was touched)",
            staging.display()
        );
    }
    Ok(match moved {
        true => OutputState::Moved,
        false => OutputState::Resume,
    })
}

/// A `.partial` moved here from another folder: its effective config (which names the output
/// folder) and `work/run.json` are written again for where it lies now, each atomically, and
/// it says so.
fn restamp_moved(staging: &Path, state: &RunState, opts: &RunOptions) -> Result<()> {
    eprintln!(
        "egogen-run: {} was started in another folder (moved or copied here); its config.toml and work/run.json now name this one",
        staging.display()
    );
    write_run_stamp(staging, state, opts)
}

/// Writes what says which run a folder holds: its effective config (`config.toml`) and
/// `work/run.json`, each atomically.
fn write_run_stamp(folder: &Path, state: &RunState, opts: &RunOptions) -> Result<()> {
    write_atomically(&folder.join("config.toml"), opts.config_toml.as_bytes())
        .with_context(|| format!("writing the effective config of {}", state.config))?;
    let run_json = folder.join("work/run.json");
    write_atomically(&run_json, serde_json::to_string_pretty(state)?.as_bytes())
        .with_context(|| format!("writing {}", run_json.display()))
}

/// Creates `<dir>.partial` with the effective config and `work/run.json`, whole or not at all:
/// both are written into `<dir>.partial.new` and that folder renamed, so a run killed while
/// staging never leaves a `.partial` that no `--resume` can read. A `<dir>.partial.new` left by
/// such a run holds only those two files and is replaced.
fn stage_run(staging: &Path, state: &RunState, opts: &RunOptions) -> Result<()> {
    let fresh = PathBuf::from(format!("{}.new", staging.display()));
    if fresh.exists() {
        std::fs::remove_dir_all(&fresh).with_context(|| {
            format!(
                "removing {}, left by a run killed while staging",
                fresh.display()
            )
        })?;
    }
    std::fs::create_dir_all(fresh.join("work"))
        .with_context(|| format!("creating {}", fresh.display()))?;
    write_run_stamp(&fresh, state, opts)?;
    std::fs::rename(&fresh, staging)
        .with_context(|| format!("renaming {} to {}", fresh.display(), staging.display()))?;
    Ok(())
}

/// The bodies the run renders, each with its track, and which of them wear the rig.
fn rendered_agents(
    plan: &RunPlan,
    scene: &crate::scene::SceneMesh,
    motion: &RunMotion,
    model: &BodyModel,
) -> Result<(Vec<RenderedAgent>, Vec<usize>)> {
    match motion {
        RunMotion::Placed(m) => {
            let map = walkable_map(scene, &plan.scene, plan.walkable)?;
            if let Some(warning) = crate::scene::scene_frame_warning(scene, &map, &plan.scene) {
                eprintln!("{warning}");
            }
            let (placed, _) = place_motion(model, m, &map, plan.scene_seed)
                .with_context(|| format!("placing the motion in {}", plan.scene.display()))?;
            let track = track_body(model, &placed)?;
            let agent = RenderedAgent {
                name: "agent_0".into(),
                id: AGENT_ID_BASE,
                motion: placed,
                track,
                activities: None,
            };
            Ok((vec![agent], vec![0]))
        }
        RunMotion::Agents { take, wearers, .. } => {
            // A take with activities labels every frame of every agent.
            let with_activities = take
                .agents
                .iter()
                .any(|a| !a.activity_segments.is_empty() || !a.skipped_activities.is_empty());
            let agents = take
                .agents
                .iter()
                .enumerate()
                .map(|(k, a)| {
                    let motion = a.motion_sequence(take.frame_rate_hz);
                    let track = track_body(model, &motion)?;
                    Ok(RenderedAgent {
                        name: a.name.clone(),
                        id: AGENT_ID_BASE + k as u32,
                        motion,
                        track,
                        activities: with_activities.then(|| a.activity_segments.clone()),
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            Ok((agents, wearers.to_vec()))
        }
    }
}

/// Writes the dataset's `sequence/` folder: the take's folder, or a placed motion's.
fn write_sequence(
    sequence: &Path,
    motion: &RunMotion,
    agents: &[RenderedAgent],
    model: &BodyModel,
    plan: &RunPlan,
) -> Result<()> {
    match motion {
        RunMotion::Placed(_) => {
            let a = &agents[0];
            let meshes = pose_meshes(model, &a.motion, plan.mesh_every_n_frames)?;
            write_sequence_dir(sequence, model, &a.motion, &a.track, &meshes).map(drop)
        }
        RunMotion::Agents {
            world, take, about, ..
        } => write_crowd_dir(sequence, world, model, take, None, about.clone()).map(drop),
    }
}

/// The Aria streams' output of the take (`[render.aria]`), written when it is finished: each
/// wearer with its goals and headset offset, and the scene's rays when the gaze is asked.
/// Settings the rig cannot serve fail here, before anything renders.
fn aria_export(
    render: &RenderPlan,
    wearers: &[usize],
    motion: &RunMotion,
    scene: &crate::scene::SceneMesh,
) -> Result<Option<AriaExport>> {
    let Some(settings) = &render.aria else {
        return Ok(None);
    };
    if let Some(p) = settings.problem(&render.rig) {
        bail!("aria streams: {p}");
    }
    let wearers = wearers
        .iter()
        .map(|&w| AriaWearer {
            agent: w,
            goals: match motion {
                RunMotion::Agents { take, .. } => take.agents[w]
                    .goals
                    .iter()
                    .map(|g| GazeGoal {
                        xy: g.goal,
                        until_frame: g.end_frame,
                    })
                    .collect(),
                RunMotion::Placed(_) => Vec::new(),
            },
            looks: match motion {
                RunMotion::Agents { take, .. } => take.agents[w]
                    .activities
                    .iter()
                    .filter_map(|a| a.look_at)
                    .collect(),
                RunMotion::Placed(_) => Vec::new(),
            },
            cpf_from_headset: render
                .headset_wear
                .map_or(crate::math::Affine3::IDENTITY, |h| {
                    h.draw(w).cpf_from_headset()
                }),
        })
        .collect();
    Ok(Some(AriaExport {
        settings: settings.clone(),
        wearers,
        rays: settings
            .streams
            .gaze
            .then(|| crate::scene::mesh_distance::SceneRays::new(scene))
            .flatten(),
    }))
}

/// Writes what Blender reads of each body into `work` (a PC2 cache of the times the renders
/// of `frames` read, faces, rest vertices), rewritten identically on every (re)start; returns
/// the bodies as shard specs name them and the files written (scratch, removed when the
/// dataset is finished).
fn write_body_inputs(
    work: &Path,
    agents: &[RenderedAgent],
    model: &BodyModel,
    render: &RenderPlan,
    frames: &[u32],
) -> Result<(Vec<ShardBody>, Vec<PathBuf>)> {
    std::fs::create_dir_all(work).with_context(|| format!("creating {}", work.display()))?;
    let masks = skin_region_masks(model)?;
    let skin_detail = match masks.is_empty() {
        true => None,
        false => skin_detail_map(model)?,
    };
    let mut scratch = Vec::new();
    // One UV file for every agent: they share the model's layout.
    let uvs_npy = match (&model.uvs, masks.is_empty()) {
        (Some(uvs), false) => {
            let path = work.join("body_uvs.npy");
            write_corner_uvs_npy(&path, &uvs.per_corner())?;
            scratch.push(path.clone());
            Some(std::fs::canonicalize(&path)?)
        }
        _ => None,
    };
    let mut bodies = Vec::with_capacity(agents.len());
    for (k, a) in agents.iter().enumerate() {
        let pc2 = work.join(format!("agent_{k}.pc2"));
        let faces = work.join(format!("agent_{k}_faces.npy"));
        let vertices = work.join(format!("agent_{k}_vertices.npy"));
        // Only what is rendered: the shutter around each rendered frame, the neighbours the
        // flow reads (with the colour pass off, no shutter).
        let shutter = if render.passes.needs_colour_render() {
            render.shutter_frames
        } else {
            0.0
        };
        let indices = rendered_sample_indices(
            frames,
            render.every_n_frames as u32,
            shutter,
            render.cache_samples_per_frame,
            a.motion.len(),
        );
        let cache = body_cache_at(
            model,
            &a.motion,
            render.cache_samples_per_frame,
            Some(&indices),
        )?;
        cache.write(&pc2)?;
        write_faces_npy(&faces, &model.faces)?;
        write_rest_vertices_npy(&vertices, &cache)?;
        drop(cache);
        let skin = render.skin.draw(k);
        let skin_regions: Vec<ShardSkinRegion> = masks
            .iter()
            .map(|(region, mask)| ShardSkinRegion {
                paint: region.paint(&skin),
                mask: mask.clone(),
            })
            .collect();
        bodies.push(ShardBody {
            name: a.name.clone(),
            pass_index: a.id,
            faces_npy: std::fs::canonicalize(&faces)?,
            vertices_npy: std::fs::canonicalize(&vertices)?,
            pc2: std::fs::canonicalize(&pc2)?,
            samples_per_frame: render.cache_samples_per_frame,
            cache_keys: playback_keys(&indices, render.cache_samples_per_frame),
            motion_steps: crate::render::shard_plan::deform_motion_steps(
                render.shutter_frames,
                render.cache_samples_per_frame,
            ),
            skin,
            uvs_npy: uvs_npy.clone(),
            skin_regions,
            skin_detail: skin_detail.clone(),
        });
        scratch.extend([pc2, faces, vertices]);
    }
    Ok((bodies, scratch))
}

/// `textures/` beside a body model with UVs (what is painted there is in its UV layout).
fn body_textures(model: &BodyModel) -> Option<PathBuf> {
    match (&model.uvs, model.source.parent()) {
        (Some(_), Some(parent)) => Some(parent.join("textures")),
        _ => None,
    }
}

/// The skin detail map beside a body model that has region masks, when it is there
/// ([`SKIN_DETAIL_FILE`]).
fn skin_detail_map(model: &BodyModel) -> Result<Option<PathBuf>> {
    let Some(path) = body_textures(model).map(|d| d.join(SKIN_DETAIL_FILE)) else {
        return Ok(None);
    };
    if !path.is_file() {
        return Ok(None);
    }
    Ok(Some(std::fs::canonicalize(&path).with_context(|| {
        format!("resolving {}", path.display())
    })?))
}

/// The skin regions' masks for `model`: in `textures/` beside the model file, painted in the
/// UV layout the model carries (ours: MakeHuman's). None when the model has no UVs or no masks
/// lie beside it (the official SMPL-X files: another layout); all of them, or an error naming
/// the first one missing.
fn skin_region_masks(model: &BodyModel) -> Result<Vec<(SkinRegion, PathBuf)>> {
    let Some(dir) = body_textures(model) else {
        return Ok(Vec::new());
    };
    let masks: Vec<(SkinRegion, PathBuf)> = SKIN_REGIONS
        .iter()
        .map(|r| (*r, dir.join(r.mask_file)))
        .collect();
    let present = masks.iter().filter(|(_, p)| p.is_file()).count();
    if present == 0 {
        return Ok(Vec::new());
    }
    if let Some((region, path)) = masks.iter().find(|(_, p)| !p.is_file()) {
        bail!(
            "{}: the skin region mask for `{}` is missing ({present} of {} masks are there); \
             masks beside a body model are used all together",
            path.display(),
            region.name,
            masks.len()
        );
    }
    masks
        .into_iter()
        .map(|(r, p)| {
            let p =
                std::fs::canonicalize(&p).with_context(|| format!("resolving {}", p.display()))?;
            Ok((r, p))
        })
        .collect()
}

/// The rig's cameras on every wearer (each camera set named after its wearer when there are
/// several), posed along the wearer's track with the headset's drawn offset on the head.
fn camera_work(
    render: &RenderPlan,
    agents: &[RenderedAgent],
    wearers: &[usize],
    frames: &[u32],
) -> Vec<CameraWork> {
    let mut cameras = Vec::new();
    for &w in wearers {
        let track = &agents[w].track;
        let wear = render.headset_wear.map(|h| h.draw(w));
        let cpf_from_headset =
            wear.map_or(crate::math::Affine3::IDENTITY, |o| o.cpf_from_headset());
        for ((cam, rendered), noise) in render
            .cameras
            .iter()
            .zip(&render.render_cameras)
            .zip(&render.depth_noise)
        {
            let mut camera = cam.clone();
            if wearers.len() > 1 {
                camera.name = format!("{}_{}", agents[w].name, cam.name);
            }
            cameras.push(CameraWork {
                camera,
                render: *rendered,
                depth_noise: *noise,
                world_from_cam: track
                    .frames
                    .iter()
                    .map(|f| cam.world_from_cam(f.world_from_cpf * cpf_from_headset))
                    .collect(),
                headset_wear: wear,
                frames: frames.to_vec(),
                wearer: w,
            });
        }
    }
    cameras
}

/// What the renders hold besides the bodies: the scene's objects, a ceiling where the scene
/// has none and the plan asks for one, the `[[obstacles]]` boxes; with their segmentation ids.
struct SceneObjects {
    /// Every segmentation id but the agents': scene objects, ceiling, obstacles.
    ids: Vec<(String, u32)>,
    ceiling: Option<ShardCeiling>,
    obstacles: Vec<ShardObstacle>,
}

fn scene_objects(
    plan: &RunPlan,
    scene: &crate::scene::SceneMesh,
    motion: &RunMotion,
    agents: &[RenderedAgent],
) -> SceneObjects {
    let mut ids: Vec<(String, u32)> = scene
        .objects
        .iter()
        .map(|o| (o.name.clone(), o.id.0))
        .collect();
    let next_id = |ids: &[(String, u32)]| ids.iter().map(|o| o.1).max().unwrap_or(0) + 1;
    let ceiling = plan.ceiling.then(|| ceiling_to_add(scene)).flatten();
    if let Some(c) = ceiling {
        eprintln!(
            "egogen-run: {} has no ceiling; closing its rooms with one at z = {:.2} m (scene.ceiling = false leaves it open)",
            plan.scene.display(),
            c.z_m
        );
        ids.push((CEILING_OBJECT.into(), next_id(&ids)));
    }
    let obstacles: Vec<ShardObstacle> = match motion {
        RunMotion::Agents {
            world, obstacles, ..
        } => {
            let rate = agents[0].motion.frame_rate_hz;
            let frames = agents[0].motion.len() as f64;
            obstacle_boxes(obstacles, &world.map, next_id(&ids), rate, frames)
        }
        RunMotion::Placed(_) => Vec::new(),
    };
    ids.extend(obstacles.iter().map(|o| (o.name.clone(), o.pass_index)));
    SceneObjects {
        ids,
        ceiling: ceiling.map(|c| ShardCeiling {
            z_m: c.z_m,
            min_xy: c.min_xy,
            max_xy: c.max_xy,
        }),
        obstacles,
    }
}

/// Everything of a shard spec but its cameras; the lighting is drawn around the middle of the
/// first wearer's path.
fn base_spec(
    plan: &RunPlan,
    render: &RenderPlan,
    scene: &crate::scene::SceneMesh,
    first_wearer: &RenderedAgent,
    bodies: Vec<ShardBody>,
    objects: &SceneObjects,
) -> Result<ShardSpec> {
    let (fps, fps_base) = blender_fps(first_wearer.motion.frame_rate_hz);
    let (lo, hi) = scene_bounds(scene);
    let track = &first_wearer.track;
    let mid = 0.5 * (track.frames[0].joints[0] + track.frames[track.frames.len() - 1].joints[0]);
    Ok(ShardSpec {
        scene_file: std::fs::canonicalize(&plan.scene)?,
        scene_up_axis: plan.scene_frame.up_for(&plan.scene).name().into(),
        scene_unit_m: plan.scene_frame.unit_m,
        object_ids: objects.ids.clone(),
        fps,
        fps_base,
        bodies,
        lighting: render
            .lighting
            .draw([mid.x, mid.y, lo.z + 0.85 * (hi.z - lo.z)]),
        materials: render.materials.draw(&surface_facts(plan, scene, objects)),
        rgb: render.passes.needs_colour_render().then_some(ShardRgb {
            samples: render.samples,
            adaptive_threshold: render.adaptive_threshold,
            denoise: render.denoise,
            shutter_frames: render.shutter_frames,
            seed: 0,
        }),
        ground_truth_passes: render
            .passes
            .ground_truth_render_passes()
            .into_iter()
            .map(String::from)
            .collect(),
        ground_truth_frame_step: render.every_n_frames as u32,
        device: render.device,
        cameras: Vec::new(),
        body_probe: None,
        ceiling: objects.ceiling,
        obstacles: objects.obstacles.clone(),
        scene_split: None,
    })
}

/// Repairs what an interrupted run left (damaged frames, missing records) and says how a
/// camera with Cycles' polynomial fisheye differs from its model.
fn repair(dataset: &Dataset) -> Result<()> {
    for work in &dataset.cameras {
        if let RenderCamera::PolynomialFisheye(lens) = &work.render {
            let e = native_error(&work.camera.model, lens, ERROR_GRID);
            eprintln!(
                "egogen-run: {} renders with Cycles' polynomial fisheye (render.fisheye = \"native\"): off its Fisheye624 model by max {:.2} px, mean {:.2} px, 95% ≤ {:.2} px",
                work.camera.name, e.max_px, e.mean_px, e.p95_px
            );
        }
    }
    for (path, reason) in dataset.check_finished_frames()? {
        eprintln!(
            "egogen-run: {} is damaged ({reason}); rendering it again",
            path.display()
        );
    }
    Ok(())
}

impl StagedTake {
    /// Removes the scratch only Blender read (raw renders, body inputs) and the temporaries of
    /// killed writes, writes the take's outputs from the frames' records (annotations, the
    /// COLMAP model, the manifest last: `export::take_exports`) and renames `<dir>.partial` to
    /// `<dir>`; returns how many files the manifest lists.
    pub fn finish(&self) -> Result<usize> {
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

/// The scene objects' segmentation ids (the added ceiling and obstacles among them), each with
/// its class where the scene file gives one.
fn segmentation_ids(ids: &[(String, u32)], scene: &crate::scene::SceneMesh) -> Vec<SegmentationId> {
    let labels: std::collections::BTreeMap<u32, &String> = scene
        .objects
        .iter()
        .filter_map(|o| Some((o.id.0, o.label.as_ref()?)))
        .collect();
    ids.iter()
        .map(|(name, id)| SegmentationId {
            name: name.clone(),
            id: *id,
            label: labels.get(id).map(|l| l.to_string()),
        })
        .collect()
}

/// The `[[obstacles]]` as boxes standing on the map's floor under their centres (at its
/// keys, for a moving one), named `obstacle_NN` with ids
/// from `first_id`; a moving one keyed one frame before the take and one after its last frame
/// (`frames` at `rate_hz`), so that blur and motion vectors see it move at the ends too.
fn obstacle_boxes(
    solids: &[ObstacleSolid],
    map: &crate::scene::WalkableMap,
    first_id: u32,
    rate_hz: f64,
    frames: f64,
) -> Vec<ShardObstacle> {
    solids
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let (half, yaw_rad) = match s.motion.at_start {
                Obstacle2::Box {
                    half_extents,
                    yaw_rad,
                    ..
                } => (half_extents, yaw_rad),
                Obstacle2::Circle { radius_m, .. } => (glam::DVec2::splat(radius_m), 0.0),
            };
            let key = |frame: f64| {
                let c = s.motion.at(frame / rate_hz).centre();
                ObstacleKey {
                    frame,
                    centre: [c.x, c.y, map.floor_under(c) + 0.5 * s.height_m],
                }
            };
            let still = s.motion.velocity_m_per_s == glam::DVec2::ZERO;
            ShardObstacle {
                name: format!("obstacle_{k:02}"),
                pass_index: first_id + k as u32,
                size_m: [2.0 * half.x, 2.0 * half.y, s.height_m],
                yaw_rad,
                keys: if still {
                    vec![key(0.0)]
                } else {
                    vec![key(-1.0), key(frames)]
                },
            }
        })
        .collect()
}

/// What `[render.materials]` classes each scene object by (the added ceiling among them): its
/// name, label, own texture and how its surfaces face above the walked floor.
fn surface_facts(
    plan: &RunPlan,
    scene: &crate::scene::SceneMesh,
    objects: &SceneObjects,
) -> Vec<SurfaceFacts> {
    if plan
        .render
        .as_ref()
        .is_none_or(|r| r.materials.mode == MaterialsMode::Keep)
    {
        return Vec::new();
    }
    let floor_z = plan
        .walkable
        .floor_z_m
        .or_else(|| crate::scene::floor::detect_floor_z(scene))
        .unwrap_or(0.0);
    let mut facts: Vec<SurfaceFacts> = scene
        .objects
        .iter()
        .zip(scene.object_orientations())
        .map(|(o, f)| SurfaceFacts {
            name: o.name.clone(),
            label: o.label.clone(),
            textured: o.textured,
            see_through: o.see_through,
            area_up: f.area_up,
            area_down: f.area_down,
            area_side: f.area_side,
            z_min_m: f.z_min - floor_z,
            z_max_m: f.z_max - floor_z,
        })
        .collect();
    if let Some(c) = objects.ceiling {
        facts.push(SurfaceFacts {
            name: CEILING_OBJECT.into(),
            label: None,
            textured: false,
            see_through: false,
            area_up: 0.0,
            area_down: 1.0,
            area_side: 0.0,
            z_min_m: c.z_m - floor_z,
            z_max_m: c.z_m - floor_z,
        });
    }
    facts
}

fn scene_bounds(scene: &crate::scene::SceneMesh) -> (crate::math::Vec3, crate::math::Vec3) {
    scene.vertices.iter().fold(
        (
            crate::math::Vec3::splat(f64::INFINITY),
            crate::math::Vec3::splat(f64::NEG_INFINITY),
        ),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A start killed while staging left `<dir>.partial.new` (the config written, no
    /// `work/run.json`) and no `.partial`: the next start stages afresh, and its `.partial`
    /// is whole and resumable.
    #[test]
    fn staging_killed_half_way_leaves_nothing_a_resume_cannot_read() {
        let a = tempfile::tempdir().unwrap();
        let dir = a.path().join("take");
        let staging = a.path().join("take.partial");
        let left = a.path().join("take.partial.new");
        std::fs::create_dir_all(left.join("work")).unwrap();
        std::fs::write(left.join("config.toml"), "half").unwrap();
        let state = RunState {
            config: "run.toml".into(),
            config_sha256: "abc".into(),
            rig_sha256: None,
            moved_sha256: None,
        };
        let opts = RunOptions {
            resume: true,
            blender: None,
            config_toml: "[scene]\n".into(),
            resume_fingerprint: "abc".into(),
            moved_fingerprint: "ab".into(),
        };
        assert!(matches!(
            check_output(&dir, &staging, &state, &opts).unwrap(),
            OutputState::Fresh
        ));
        stage_run(&staging, &state, &opts).unwrap();
        assert!(!left.exists());
        assert_eq!(
            std::fs::read_to_string(staging.join("config.toml")).unwrap(),
            "[scene]\n"
        );
        assert!(matches!(
            check_output(&dir, &staging, &state, &opts).unwrap(),
            OutputState::Resume
        ));
    }

    #[test]
    fn skin_masks_are_used_all_together_beside_a_model_with_uvs() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let shipped = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
        let masks = skin_region_masks(&shipped).unwrap();
        assert_eq!(masks.len(), SKIN_REGIONS.len());
        assert!(masks.iter().all(|(_, p)| p.is_absolute() && p.is_file()));
        // The detail map ships beside them.
        let detail = skin_detail_map(&shipped).unwrap().unwrap();
        assert!(detail.is_absolute() && detail.ends_with(SKIN_DETAIL_FILE));

        // The same model in a directory without masks: no regions.
        let dir = tempfile::tempdir().unwrap();
        let mut elsewhere = shipped.clone();
        elsewhere.source = dir.path().join("SMPLX_NEUTRAL.npz");
        assert!(skin_region_masks(&elsewhere).unwrap().is_empty());
        assert_eq!(skin_detail_map(&elsewhere).unwrap(), None);
        // Some of them: an error naming the first one missing.
        let textures = dir.path().join("textures");
        std::fs::create_dir(&textures).unwrap();
        std::fs::copy(
            root.join("assets/body/textures/mpfb_lips.jpg"),
            textures.join("mpfb_lips.jpg"),
        )
        .unwrap();
        let msg = format!("{:#}", skin_region_masks(&elsewhere).unwrap_err());
        assert!(
            msg.contains("mpfb_eyelids.jpg") && msg.contains("`eyelids`") && msg.contains("1 of 7"),
            "{msg}"
        );
        // A model without UVs never looks for them.
        elsewhere.uvs = None;
        assert!(skin_region_masks(&elsewhere).unwrap().is_empty());
    }
}
