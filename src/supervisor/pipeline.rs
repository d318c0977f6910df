//! `egogen-run` with a `[render]` section: the whole pipeline into a dataset folder, built in
//! `<dir>.partial/` and renamed when complete. A `.partial` folder left by an interrupted run is
//! continued by `--resume` (finished frames are kept, partial ones redone) as long as the config
//! is byte-identical; otherwise nothing is touched.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{bail, Context, Result};

use super::colmap::write_colmap;
use super::dataset::{next_start, write_annotations, CameraWork, Dataset, RenderedAgent};
use super::local::{LocalPool, PoolSettings};
use super::manifest::{remove_temporaries, sha256_hex, write_manifest, MANIFEST};
use super::pool::ShardPool;
use super::slurm::{check_slurm_tools, SlurmPool, SlurmSettings};
use crate::atomic_file::write_atomically;
use crate::body::BodyModel;
use crate::motion::MotionSequence;
use crate::plan::{Backend, RenderPlan, RunPlan};
use crate::render::lens_polynomial::{native_error, ERROR_GRID};
use crate::render::passes::Pass;
use crate::render::protocol::{ObstacleKey, ShardCeiling, ShardObstacle, CEILING_OBJECT};
use crate::render::render_camera::RenderCamera;
use crate::render::shard_plan::{blender_fps, AGENT_ID_BASE};
use crate::render::{BlenderRuntime, ShardBody, ShardRgb, ShardSpec};
use crate::scene::ceiling::ceiling_to_add;
use crate::scene::{load_scene, walkable_map, WalkableSettings};
use crate::scene::{Obstacle2, ObstacleSolid};
use crate::synth::crowd::{CrowdTake, CrowdWorld};
use crate::synth::crowd_dir::write_crowd_dir;
use crate::synth::placement::place_motion;
use crate::synth::{body_cache, pose_meshes, track_body, write_sequence_dir};
use crate::vertex_cache::{write_faces_npy, write_rest_vertices_npy};

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
}

/// What moves in a run's scene.
pub enum RunMotion<'a> {
    /// One motion (a scripted walk or a motion file) placed rigidly in the scene by
    /// `scene.seed`, worn by the rig.
    Placed(&'a MotionSequence),
    /// A synthesized take: every agent rendered, the rig on the `wearers` (indices into the
    /// take's agents). `wall_s` and `about` go into the take's summary.
    Agents {
        world: &'a CrowdWorld,
        /// The `[[obstacles]]` boxes, drawn standing on the walkable map's floor.
        obstacles: &'a [ObstacleSolid],
        take: &'a CrowdTake,
        wearers: &'a [usize],
        wall_s: f64,
        about: serde_json::Value,
    },
}

/// Runs the pipeline for a plan with a render section; `config_path` is hashed so that a
/// resumed run is known to be the same run.
///
/// `work/run.json`, [`RunState`], says which run a `.partial` folder holds.
pub fn run_pipeline(
    plan: &RunPlan,
    render: &RenderPlan,
    motion: RunMotion,
    model: &BodyModel,
    config_path: &Path,
    opts: &RunOptions,
) -> Result<RunSummary> {
    let dir = &plan.output_dir;
    let staging = PathBuf::from(format!("{}.partial", dir.display()));
    let config_sha = sha256_hex(opts.resume_fingerprint.as_bytes());
    // The rig as resolved (a --rig override included): a resume must render with the same one.
    let rig_sha = sha256_hex(render.rig.to_json().as_bytes());
    if is_non_empty_dir(dir) {
        if opts.resume && dir.join(MANIFEST).is_file() {
            eprintln!(
                "egogen-run: {} is already complete; nothing to do",
                dir.display()
            );
            return Ok(RunSummary {
                dir: dir.clone(),
                frames: 0,
                rendered_now: 0,
                files: 0,
            });
        }
        bail!(
            "output folder {} already exists and is not empty; choose another `output.dir` (nothing was written)",
            dir.display()
        );
    }
    let state_path = staging.join("work/run.json");
    let fresh = !staging.exists();
    if !fresh {
        if !opts.resume {
            bail!(
                "{} holds an interrupted run; rerun with --resume to continue it, or delete it (nothing was written)",
                staging.display()
            );
        }
        let state: RunState = std::fs::read_to_string(&state_path)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .with_context(|| {
                format!(
                    "{}: missing or unreadable; cannot resume",
                    state_path.display()
                )
            })?;
        if state.config_sha256 != config_sha {
            bail!(
                "{} was started from a different config than {} with these options (its values or the command line's --out, --seed, --rig); resuming would mix two runs (nothing was touched)",
                staging.display(),
                config_path.display()
            );
        }
        if state.rig_sha256.as_ref().is_some_and(|s| *s != rig_sha) {
            bail!(
                "{} was started with a different camera rig (a --rig override or a changed rig file); resuming would mix two runs (nothing was touched)",
                staging.display()
            );
        }
    }

    // Everything that can fail on bad input or a missing Blender, before anything is staged:
    // the scene, where the motion happens in it, and (for a new run) the renderer.
    let scene = load_scene(&plan.scene, None)?;
    let (agents, wearers): (Vec<RenderedAgent>, Vec<usize>) = match &motion {
        RunMotion::Placed(m) => {
            let map = walkable_map(&scene, &plan.scene, WalkableSettings::default())?;
            let (placed, _) = place_motion(model, m, &map, plan.scene_seed)
                .with_context(|| format!("placing the motion in {}", plan.scene.display()))?;
            let track = track_body(model, &placed)?;
            let agent = RenderedAgent {
                name: "agent_0".into(),
                id: AGENT_ID_BASE,
                motion: placed,
                track,
            };
            (vec![agent], vec![0])
        }
        RunMotion::Agents { take, wearers, .. } => {
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
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            (agents, wearers.to_vec())
        }
    };
    let mut runtime = if fresh {
        Some(BlenderRuntime::resolve(opts.blender.as_deref())?)
    } else {
        None
    };
    if plan.supervisor.backend == Backend::Slurm {
        check_slurm_tools()?;
    }

    if fresh {
        std::fs::create_dir_all(staging.join("work"))
            .with_context(|| format!("creating {}", staging.display()))?;
        write_atomically(&staging.join("config.toml"), opts.config_toml.as_bytes()).with_context(
            || format!("writing the effective config of {}", config_path.display()),
        )?;
        write_atomically(
            &state_path,
            serde_json::to_string_pretty(&RunState {
                config: config_path.display().to_string(),
                config_sha256: config_sha.clone(),
                rig_sha256: Some(rig_sha.clone()),
            })?
            .as_bytes(),
        )?;
    } else {
        eprintln!("egogen-run: resuming {}", staging.display());
    }

    let sequence = staging.join("sequence");
    if !sequence.exists() {
        match &motion {
            RunMotion::Placed(_) => {
                let a = &agents[0];
                let meshes = pose_meshes(model, &a.motion, plan.mesh_every_n_frames)?;
                write_sequence_dir(&sequence, model, &a.motion, &a.track, &meshes)?;
            }
            RunMotion::Agents {
                world,
                take,
                wall_s,
                about,
                ..
            } => {
                write_crowd_dir(&sequence, world, model, take, *wall_s, about.clone())?;
            }
        }
    }

    // Inputs Blender reads, rewritten identically on every (re)start.
    let work = staging.join("work");
    std::fs::create_dir_all(&work).with_context(|| format!("creating {}", work.display()))?;
    let mut bodies = Vec::with_capacity(agents.len());
    let mut scratch = Vec::new();
    for (k, a) in agents.iter().enumerate() {
        let pc2 = work.join(format!("agent_{k}.pc2"));
        let faces = work.join(format!("agent_{k}_faces.npy"));
        let vertices = work.join(format!("agent_{k}_vertices.npy"));
        let cache = body_cache(model, &a.motion, render.cache_samples_per_frame)?;
        cache.write(&pc2)?;
        write_faces_npy(&faces, &model.faces)?;
        write_rest_vertices_npy(&vertices, &cache)?;
        drop(cache);
        bodies.push(ShardBody {
            name: a.name.clone(),
            pass_index: a.id,
            faces_npy: std::fs::canonicalize(&faces)?,
            vertices_npy: std::fs::canonicalize(&vertices)?,
            pc2: std::fs::canonicalize(&pc2)?,
            cache_frame_start: 0.0,
            samples_per_frame: render.cache_samples_per_frame,
            motion_steps: 2,
            skin: render.skin.draw(k),
        });
        scratch.extend([pc2, faces, vertices]);
    }

    let frame_count = agents[0].motion.len();
    let frames: Vec<u32> = (0..frame_count as u32)
        .step_by(render.every_n_frames)
        .collect();
    let mut cameras: Vec<CameraWork> = Vec::new();
    for &w in &wearers {
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
                // Several camera sets: each named after its wearer.
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
                frames: frames.clone(),
                wearer: w,
            });
        }
    }
    let mut object_ids: Vec<(String, u32)> = scene
        .objects
        .iter()
        .map(|o| (o.name.clone(), o.id.0))
        .collect();
    let ceiling = plan.ceiling.then(|| ceiling_to_add(&scene)).flatten();
    if let Some(c) = ceiling {
        eprintln!(
            "egogen-run: {} has no ceiling; closing its rooms with one at z = {:.2} m (scene.ceiling = false leaves it open)",
            plan.scene.display(),
            c.z_m
        );
        let id = object_ids.iter().map(|o| o.1).max().unwrap_or(0) + 1;
        object_ids.push((CEILING_OBJECT.into(), id));
    }
    let obstacles: Vec<ShardObstacle> = match &motion {
        RunMotion::Agents {
            world, obstacles, ..
        } => {
            let first = object_ids.iter().map(|o| o.1).max().unwrap_or(0) + 1;
            let rate = agents[0].motion.frame_rate_hz;
            let frames = agents[0].motion.len() as f64;
            obstacle_boxes(obstacles, world.map.floor_z_m, first, rate, frames)
        }
        RunMotion::Placed(_) => Vec::new(),
    };
    object_ids.extend(obstacles.iter().map(|o| (o.name.clone(), o.pass_index)));
    let (fps, fps_base) = blender_fps(agents[0].motion.frame_rate_hz);
    let (lo, hi) = scene_bounds(&scene);
    let track = &agents[wearers[0]].track;
    let mid = 0.5 * (track.frames[0].joints[0] + track.frames[track.frames.len() - 1].joints[0]);
    let base_spec = ShardSpec {
        scene_glb: std::fs::canonicalize(&plan.scene)?,
        object_ids: object_ids.clone(),
        fps,
        fps_base,
        bodies,
        lighting: render
            .lighting
            .draw([mid.x, mid.y, lo.z + 0.85 * (hi.z - lo.z)]),
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
        ceiling: ceiling.map(|c| ShardCeiling {
            z_m: c.z_m,
            min_xy: c.min_xy,
            max_xy: c.max_xy,
        }),
        obstacles,
    };
    let dataset = Arc::new(Dataset {
        staging: std::fs::canonicalize(&staging)?,
        base_spec,
        cameras,
        passes: render.passes,
        keys_per_frame: render.cache_samples_per_frame,
        frames_per_shard: render.frames_per_shard,
        near_clip_m: render.near_clip_m,
        start: next_start(&staging),
    });
    for work in &dataset.cameras {
        if let RenderCamera::PolynomialFisheye(lens) = &work.render {
            let e = native_error(&work.camera.model, lens, ERROR_GRID);
            eprintln!(
                "egogen-run: {} renders with Cycles' polynomial fisheye (render.fisheye = \"native\"): off its Fisheye624 model by max {:.2} px, mean {:.2} px, 95% ≤ {:.2} px",
                work.camera.name, e.max_px, e.mean_px, e.p95_px
            );
        }
    }
    for (path, reason) in dataset.remove_invalid_frames()? {
        eprintln!(
            "egogen-run: {} is damaged ({reason}); rendering it again",
            path.display()
        );
    }
    let total = dataset.total_frames();
    let shards = dataset.pending_shards();
    let pending: usize = shards.iter().map(|s| s.frames.len()).sum();
    eprintln!(
        "egogen-run: {} camera(s) × {} frames = {total} frames; {pending} to render in {} shard(s) on {} worker(s)",
        render.cameras.len(),
        frames.len(),
        shards.len(),
        plan.supervisor.workers
    );
    let mut rendered_now = 0;
    if !shards.is_empty() {
        let runtime = match runtime.take() {
            Some(r) => r,
            None => BlenderRuntime::resolve(opts.blender.as_deref())?,
        };
        let sup = &plan.supervisor;
        let shard_timeout = Duration::from_secs_f64(sup.shard_timeout_s);
        let pool: Box<dyn ShardPool> = match sup.backend {
            Backend::Local => Box::new(LocalPool(PoolSettings {
                workers: sup.workers,
                shard_timeout,
                retries: sup.retries,
            })),
            Backend::Slurm => Box::new(SlurmPool(SlurmSettings {
                plan: sup.slurm.clone(),
                max_running: sup.workers,
                shard_timeout,
                retries: sup.retries,
            })),
        };
        let report = pool.run(dataset.clone(), runtime, shards, total - pending)?;
        rendered_now = report.frames_finished;
        let retried = report
            .shards
            .iter()
            .filter(|s| s.attempts.len() > 1)
            .count();
        eprintln!(
            "egogen-run: rendered {rendered_now} frames in {:.1} s ({retried} shard(s) retried)",
            report.wall_seconds
        );
    }
    write_annotations(&dataset, &render.rig, &agents, &object_ids)?;
    if render.passes.has(Pass::Colmap) {
        write_colmap(&dataset)?;
    }
    // Scratch that only Blender read: the raw renders and the body cache (large).
    let _ = std::fs::remove_dir_all(dataset.raw_dir());
    for f in &scratch {
        let _ = std::fs::remove_file(f);
    }
    for p in remove_temporaries(&staging)? {
        eprintln!(
            "egogen-run: removed {}, left by an interrupted run",
            p.display()
        );
    }
    let manifest = write_manifest(&staging)?;
    if dir.exists() {
        std::fs::remove_dir(dir).with_context(|| format!("replacing empty {}", dir.display()))?;
    }
    std::fs::rename(&staging, dir)
        .with_context(|| format!("renaming {} to {}", staging.display(), dir.display()))?;
    Ok(RunSummary {
        dir: dir.clone(),
        frames: total,
        rendered_now,
        files: manifest.files.len(),
    })
}

/// The `[[obstacles]]` as boxes on the floor at `floor_z_m`, named `obstacle_NN` with ids
/// from `first_id`; a moving one keyed one frame before the take and one after its last frame
/// (`frames` at `rate_hz`), so that blur and motion vectors see it move at the ends too.
fn obstacle_boxes(
    solids: &[ObstacleSolid],
    floor_z_m: f64,
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
                    centre: [c.x, c.y, floor_z_m + 0.5 * s.height_m],
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

fn scene_bounds(scene: &crate::scene::SceneMesh) -> (crate::math::Vec3, crate::math::Vec3) {
    scene.vertices.iter().fold(
        (
            crate::math::Vec3::splat(f64::INFINITY),
            crate::math::Vec3::splat(f64::NEG_INFINITY),
        ),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    )
}
