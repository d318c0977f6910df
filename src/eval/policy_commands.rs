//! Jobs of the `egogen policy` commands: fitting and checking the pose prior (`pose-prior`),
//! drawing procedural floor plans as training draws them (`rooms`) and evaluating controllers
//! on held-out episodes (`eval`: box scenes, crossings, a scene's start/goal pairs), with their
//! walks drawn. `cli::policy_jobs` parses the flags, checks them into settings and loads the
//! configs.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::policy_tasks::{evaluate_with_paths, fit_pose_prior, HeldOutController};
use crate::atomic_file::refuse_existing;
use crate::body::BodyModel;
use crate::motion::cvae::train::{evaluation_sets, shipped_weights_path, TrainPlan};
use crate::motion::cvae::MotionModel;
use crate::policy::env::FixedScene;
use crate::policy::EnvSettings;
use crate::preview::RgbImage;
use crate::walker::ControllerSpec;

/// `egogen policy pose-prior`'s flags.
pub(crate) struct PosePriorJob {
    /// Motion training config whose clips (and held-out split) are used.
    pub(crate) config: PathBuf,
    /// Motion-model weights (default: the shipped ones).
    pub(crate) weights: Option<PathBuf>,
    /// Where to write the prior (JSON; refused if it exists).
    pub(crate) out: PathBuf,
    /// Mixture components.
    pub(crate) components: usize,
    /// EM iterations.
    pub(crate) iterations: usize,
    /// Quantile of the training primitives' mean scores taken as the plausibility limit.
    pub(crate) quantile: f64,
    /// Where to write the scores of the three groups (JSON), if anywhere.
    pub(crate) scores_json: Option<PathBuf>,
    pub(crate) seed: u64,
}

/// `egogen policy pose-prior`: the pose prior fitted on a config's training primitives
/// ([`fit_pose_prior`]) and written, with how it scores held-out mocap, random-latent
/// primitives and bent joints as a JSON line; `load_plan` reads the config.
pub(crate) fn pose_prior(
    job: PosePriorJob,
    load_plan: impl FnOnce(&Path) -> Result<TrainPlan>,
) -> Result<()> {
    let PosePriorJob {
        config,
        weights,
        out,
        components,
        iterations,
        quantile,
        scores_json,
        seed,
    } = job;
    refuse_existing(&out)?;
    if let Some(f) = &scores_json {
        refuse_existing(f)?;
    }
    if !(0.0..=1.0).contains(&quantile) || components == 0 {
        bail!("--quantile must lie in [0, 1] and --components be at least 1");
    }
    let plan = load_plan(&config)?;
    let body = BodyModel::load(&plan.body_model)?;
    let model = MotionModel::load(weights.unwrap_or_else(shipped_weights_path))?;
    let (train, held) = evaluation_sets(&plan, &body, true)?;
    let (prior, sep) = fit_pose_prior(
        &train,
        &held,
        &model,
        components,
        iterations,
        quantile,
        seed,
        &config.display().to_string(),
    );
    if let Some(parent) = out.parent() {
        std::fs::create_dir_all(parent)?;
    }
    prior.save(&out)?;
    let mut summary = serde_json::to_value(&sep)?;
    summary.as_object_mut().map(|o| o.remove("scores"));
    println!(
        "{}",
        serde_json::json!({"frames": prior.frames, "components": components, "separation": summary})
    );
    if let Some(f) = scores_json {
        crate::atomic_file::write_atomically(&f, serde_json::to_string(&sep.scores)?.as_bytes())?;
        println!("wrote {}", f.display());
    }
    println!("wrote {}", out.display());
    Ok(())
}

/// `egogen policy rooms`: `count` procedural floor plans from seeds `seed`, `seed + 1`, … drawn
/// side by side to `out` (PNG), each written as a scene file into `obj_dir` when given.
pub(crate) fn draw_room_plans(
    out: &Path,
    count: usize,
    seed: u64,
    obj_dir: Option<&Path>,
    wall_m: f64,
) -> Result<()> {
    use crate::scene::generated::room_scene::RoomSettings;
    refuse_existing(out)?;
    if count == 0 {
        bail!("--count must be at least 1");
    }
    if count > MAX_ROOM_PLANS {
        bail!("--count {count}: at most {MAX_ROOM_PLANS} plans are drawn at once");
    }
    let settings = RoomSettings {
        wall_m,
        ..RoomSettings::default()
    };
    if !settings.is_valid() {
        bail!("--wall-m: expected a thickness > 0 m, got {wall_m}");
    }
    let plans = room_plans(&settings, count, seed);
    if let Some(dir) = obj_dir {
        let files: Vec<PathBuf> = (0..count as u64)
            .map(|k| dir.join(format!("plan_{}.obj", seed.wrapping_add(k))))
            .collect();
        for f in &files {
            refuse_existing(f)?;
        }
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        for (plan, f) in plans.iter().zip(&files) {
            plan.params
                .scene_mesh(&settings)
                .write_obj(f)
                .with_context(|| format!("writing {}", f.display()))?;
            println!("wrote {}", f.display());
        }
    }
    rooms_sheet(&plans).write_png(out)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// `egogen policy eval`'s job: its flags checked into the environment's settings, the
/// controllers and the scene.
pub(crate) struct PolicyEvalJob {
    /// Motion training config (its held-out seeds and body model).
    pub(crate) config: PathBuf,
    /// Motion-model weights (default: the shipped ones).
    pub(crate) weights: Option<PathBuf>,
    /// Pose prior (default: the shipped one).
    pub(crate) prior: Option<PathBuf>,
    pub(crate) episodes: usize,
    /// Episodes run in parallel (one decode batch).
    pub(crate) envs: usize,
    pub(crate) seed: u64,
    /// Where to write every episode's summary (JSON lines), if anywhere.
    pub(crate) episodes_jsonl: Option<PathBuf>,
    /// Where to draw the walks of the first `paths` episodes (PNG), if anywhere.
    pub(crate) paths_png: Option<PathBuf>,
    pub(crate) paths: usize,
    /// A trained policy to evaluate too.
    pub(crate) policy: Option<PathBuf>,
    /// The policy's mean action instead of a sample from it.
    pub(crate) mean_action: bool,
    /// Scale of the sampled actions' standard deviation.
    pub(crate) action_spread: f32,
    /// The scene file of `fixed`, as named (for the report).
    pub(crate) scene: Option<PathBuf>,
    /// The environment's settings.
    pub(crate) settings: EnvSettings,
    /// The walker-layer controllers: (kind, K, spec) each.
    pub(crate) controllers: Vec<(&'static str, usize, ControllerSpec)>,
    /// The sampling controllers' K.
    pub(crate) k: Vec<usize>,
    /// The scene's held-out start/goal pairs, if a scene is given.
    pub(crate) fixed: Option<FixedScene>,
}

/// `egogen policy eval`: controllers on held-out episodes, one JSON line each; `load_plan` reads
/// the motion training config.
pub(crate) fn policy_eval(
    job: PolicyEvalJob,
    load_plan: impl FnOnce(&Path) -> Result<TrainPlan>,
) -> Result<()> {
    use crate::motion::cvae::BodyContext;
    use crate::walker::pose_prior::shipped_pose_prior_path;
    use crate::walker::{PosePrior, SeedBank};
    let PolicyEvalJob {
        config,
        weights,
        prior,
        episodes,
        envs,
        seed,
        episodes_jsonl,
        paths_png,
        paths,
        policy,
        mean_action,
        action_spread,
        scene,
        settings,
        controllers,
        k,
        fixed,
    } = job;
    let plan = load_plan(&config)?;
    let body = BodyModel::load(&plan.body_model)?;
    let ctx = BodyContext::new(&body, &[])?;
    let model = MotionModel::load(weights.clone().unwrap_or_else(shipped_weights_path))?;
    let prior = PosePrior::load(&prior.clone().unwrap_or_else(shipped_pose_prior_path))?;
    let (_, held) = evaluation_sets(&plan, &body, true)?;
    let bank = SeedBank::from_set(&held);
    if let Some(png) = &paths_png {
        refuse_existing(png)?;
        if k.len() + controllers.len() + usize::from(policy.is_some()) != 1 || paths == 0 {
            bail!("--paths-png draws one controller's walks: give one --k or --policy alone, and --paths ≥ 1");
        }
    }
    use crate::motion::cvae::infer::InferBackend;
    use crate::policy::env::EnvParts;
    let loaded = match &policy {
        None => None,
        Some(path) => Some(crate::policy::weights::load_policy_for(path, &model)?),
    };
    let mut runs: Vec<(serde_json::Value, HeldOutController<InferBackend>)> = k
        .iter()
        .map(|&kk| {
            (
                serde_json::json!({"controller": "sampling", "k": kk}),
                HeldOutController::Walker(ControllerSpec::Sampling { k: kk }),
            )
        })
        .collect();
    runs.extend(controllers.iter().map(|&(kind, k, spec)| {
        (
            serde_json::json!({"controller": kind, "k": k}),
            HeldOutController::Walker(spec),
        )
    }));
    if let Some(net) = &loaded {
        let name = if mean_action { "policy_mean" } else { "policy" };
        let mut about = serde_json::json!({"controller": name, "weights": policy, "scene": scene});
        if action_spread != 1.0 && !mean_action {
            about["action_spread"] = action_spread.into();
        }
        runs.push((
            about,
            HeldOutController::Policy {
                net,
                mean_action,
                spread: action_spread,
            },
        ));
    }
    let parts = EnvParts {
        model: &model,
        body: &ctx,
        bank: &bank,
        prior: &prior,
        fixed: fixed.as_ref(),
        dwellings: &[],
    };
    let mut lines = String::new();
    for (label, controller) in &runs {
        let bar = indicatif::ProgressBar::new(episodes as u64).with_message(label.to_string());
        let drawn = if paths_png.is_some() { paths } else { 0 };
        let (report, summaries, walks) = evaluate_with_paths(
            &parts,
            settings,
            controller,
            (episodes, envs, seed),
            drawn,
            |_| bar.inc(1),
        )?;
        bar.finish_and_clear();
        if let Some(png) = &paths_png {
            paths_sheet(&walks).write_png(png)?;
            println!("wrote {}", png.display());
        }
        let mut line = label.clone();
        line["report"] = serde_json::to_value(&report)?;
        println!("{line}");
        for s in summaries {
            let mut e = label.clone();
            e["episode"] = serde_json::to_value(&s)?;
            lines.push_str(&e.to_string());
            lines.push('\n');
        }
    }
    if let Some(f) = &episodes_jsonl {
        crate::atomic_file::write_atomically(f, lines.as_bytes())?;
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// Side of a picture's tile (px).
const TILE_PX: usize = 320;
const WHITE: [u8; 3] = [255, 255, 255];
const START_RGB: [u8; 3] = [40, 160, 60];
const GOAL_RGB: [u8; 3] = [200, 50, 50];

/// `count` floor plans with their start (green), goal (red) and the line between, three to a
/// row.
/// Most plans `egogen policy rooms` draws at once (a sheet of 1 000 tiles is 54 MB).
const MAX_ROOM_PLANS: usize = 1000;

/// Plans `seed`, `seed + 1`, … drawn with `settings`.
fn room_plans(
    settings: &crate::scene::generated::room_scene::RoomSettings,
    count: usize,
    seed: u64,
) -> Vec<crate::scene::generated::room_scene::RoomScene> {
    use rand_core::SeedableRng;
    (0..count as u64)
        .map(|k| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed.wrapping_add(k));
            crate::scene::generated::room_scene::RoomScene::sample(settings, &mut rng)
        })
        .collect()
}

fn rooms_sheet(plans: &[crate::scene::generated::room_scene::RoomScene]) -> RgbImage {
    use crate::preview::map::MapPicture;
    let tiles: Vec<RgbImage> = plans
        .iter()
        .map(|scene| {
            let mut pic = MapPicture::new(&scene.map, TILE_PX - 16);
            pic.line(scene.start, scene.goal, [120, 120, 220]);
            pic.dot(scene.start, 5, START_RGB);
            pic.dot(scene.goal, 5, GOAL_RGB);
            pic.image
        })
        .collect();
    RgbImage::contact_sheet(&tiles, TILE_PX, 3, WHITE)
}

/// Evaluated walks over their courses (see `--paths-png`), three to a row.
fn paths_sheet(walks: &[super::policy_tasks::EpisodePath]) -> RgbImage {
    use crate::policy::env::Ending;
    use crate::preview::map::MapPicture;
    let tiles: Vec<RgbImage> = walks
        .iter()
        .map(|w| {
            let c = &w.course;
            let mut pic = MapPicture::new(&c.map, TILE_PX - 16);
            if let Some(o) = &c.obstacle {
                pic.obstacle(o, [90, 90, 200]);
            }
            for m in &c.moving {
                pic.obstacle(&m.at_start, [150, 150, 230]);
            }
            let rgb = match w.ending {
                Some(Ending::Success) => [30, 150, 60],
                Some(Ending::Timeout) | None => [230, 140, 20],
                Some(Ending::Penetration | Ending::Failure) => [210, 40, 40],
            };
            for seg in w.pelvis_xy.windows(2) {
                pic.line(seg[0], seg[1], rgb);
            }
            for &p in &w.pelvis_xy {
                pic.dot(p, 2, rgb);
            }
            pic.dot(c.start, 5, START_RGB);
            pic.dot(c.goal, 5, GOAL_RGB);
            pic.image
        })
        .collect();
    RgbImage::contact_sheet(&tiles, TILE_PX, 3, WHITE)
}
