//! Jobs of the `egogen motion` commands that measure the motion model: `eval` (held-out
//! error, foot contact, long random-latent chains, steering probes), `stats` (pace and turn
//! distributions of the training data) and `control` (CEM-chosen latents for a target pace and
//! heading). Each prints JSON lines and writes the files it is asked for; the binary parses the
//! flags and calls them. `head-stats` is `head_stats_jobs`'.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::body::BodyModel;
use crate::math::Vec3;
use crate::preview::MeshView;

use crate::atomic_file::refuse_existing;

/// Float precision of the motion network.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    F32,
    F16,
    Bf16,
}

/// Chains from different seeds in `egogen motion eval`.
const SHORT_CHAINS: usize = 20;

/// What `egogen motion eval` measures (its flags).
pub struct MotionEvalOptions {
    pub random_primitives: usize,
    pub chain_primitives: usize,
    pub short_chain_primitives: usize,
    pub seed: u64,
    pub walk_png: Option<PathBuf>,
    pub steer_goal_m: Option<f64>,
    pub chain_trace: Option<PathBuf>,
    pub precision: Precision,
    pub candidates: usize,
    pub lookahead: usize,
    pub export_npz: Option<PathBuf>,
    pub pace_json: Option<PathBuf>,
}

/// `egogen motion eval`: prints the measurements as JSON lines.
pub fn motion_eval(weights: &Path, config: &Path, opts: &MotionEvalOptions) -> Result<()> {
    let MotionEvalOptions {
        random_primitives,
        chain_primitives,
        short_chain_primitives,
        seed,
        precision,
        candidates,
        lookahead,
        ..
    } = *opts;
    if let Some(ahead) = opts.steer_goal_m {
        if !(ahead.is_finite() && ahead > 0.0) {
            bail!("--steer-goal-m: expected a positive distance in metres, got {ahead}");
        }
    }
    for out in [&opts.export_npz, &opts.pace_json].into_iter().flatten() {
        refuse_existing(out)?;
    }
    use crate::motion::cvae::measure::{
        latent_spread_mm, long_rollout, marker_mpjpe_mm, random_latent_contact,
    };
    use crate::motion::cvae::tensor_body::{RigGeometry, TensorRig};
    use crate::motion::cvae::train::{evaluation_sets, normal_samples};
    use crate::motion::cvae::{
        BestOfK, BodyContext, MotionModel, PlausibilityRules, PrimitiveSeed,
    };
    use rand_chacha::ChaCha8Rng;
    use rand_core::SeedableRng;

    let plan = crate::cli::train_primitive::load_train_plan(config)?;
    use burn::tensor::FloatDType;
    let model = match precision {
        Precision::F32 => MotionModel::load(weights)?,
        Precision::F16 => MotionModel::load(weights)?.with_precision(FloatDType::F16),
        Precision::Bf16 => MotionModel::load(weights)?.with_precision(FloatDType::BF16),
    };
    println!(
        "{}",
        serde_json::json!({"weights": weights, "precision": format!("{precision:?}")})
    );
    let body = BodyModel::load(&plan.body_model)?;
    let (train_set, held_set) = evaluation_sets(&plan, &body, true)?;
    let (_, held_all) = evaluation_sets(&plan, &body, false)?;
    let geo = RigGeometry::new(&body, &[])?;
    let rig = TensorRig::new(&geo, &Default::default());
    let started = std::time::Instant::now();
    let held_mm = marker_mpjpe_mm(&model.net, &rig, &held_set, 256);
    let held_all_mm = marker_mpjpe_mm(&model.net, &rig, &held_all, 256);
    let train_mm = marker_mpjpe_mm(&model.net, &rig, &train_set, 256);
    println!(
        "{}",
        serde_json::json!({
            "measure": "marker_mpjpe_mm",
            "held_out": held_mm,
            "held_out_primitives": held_set.len(),
            "held_out_unfiltered": held_all_mm,
            "held_out_unfiltered_primitives": held_all.len(),
            "train": train_mm,
            "train_primitives": train_set.len(),
            "seconds": started.elapsed().as_secs_f64(),
        })
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let l = model.latent_dim();
    for (name, set) in [("train_seeds", &train_set), ("held_out_seeds", &held_set)] {
        let z = normal_samples(&mut rng, random_primitives * l);
        let report = random_latent_contact(&model.net, &rig, set, &z);
        println!(
            "{}",
            serde_json::json!({"measure": "contact_score", "seeds": name, "report": report})
        );
    }
    let draws = 16;
    let z = normal_samples(&mut rng, 64 * draws * l);
    println!(
        "{}",
        serde_json::json!({
            "measure": "latent_spread_mm",
            "about": "RMS distance of the last frame's markers from their mean over 16 random latents, 64 training seeds",
            "value": latent_spread_mm(&model.net, &rig, &train_set, draws, &z),
        })
    );
    // The chain starts from the first two frames of the first training clip's walk.
    let clip = crate::motion::MotionSequence::read(&plan.clips[1].path)?;
    let ctx = BodyContext::new(&body, &[])?;
    let seed_frames = PrimitiveSeed {
        frames: [clip.frame(0), clip.frame(1)],
        floor_z: 0.0,
    };
    let mut sampler = BestOfK::new(&ctx, candidates, PlausibilityRules::default())?;
    sampler.horizon = lookahead;
    let (chain, prims) = long_rollout(
        &model,
        &ctx,
        seed_frames.clone(),
        chain_primitives,
        &sampler,
        &mut rng,
    )?;
    println!(
        "{}",
        serde_json::json!({"measure": "chain", "seed_clip": plan.clips[1].path.file_name().map(|s| s.to_string_lossy()), "report": chain})
    );
    // Shorter chains from many (filtered) training seeds, each in its canonical frame: how
    // long they stay upright.
    use crate::motion::cvae::pace::{set_paces, Pace, PaceSummary};
    let mut chain_paces: Vec<Pace> = prims.iter().map(|p| Pace::of_frames(&p.joints)).collect();
    short_chains(
        (&model, &ctx, &sampler),
        &train_set,
        short_chain_primitives,
        &mut rng,
        &mut chain_paces,
    )?;
    let train_paces = set_paces(&rig, &train_set, 256);
    println!(
        "{}",
        serde_json::json!({
            "measure": "pace",
            "about": "horizontal pelvis speed (m/s) and |heading change| (deg) per primitive: training primitives (contact-filtered, not mirrored) against every primitive of the random-latent chains above",
            "train_primitives": PaceSummary::of(&train_paces),
            "random_chains": PaceSummary::of(&chain_paces),
        })
    );
    write_eval_files(
        opts,
        (weights, config),
        (&train_paces, &chain_paces),
        &prims,
    )?;
    let walk = match opts.steer_goal_m {
        Some(ahead) => {
            let (report, prims) =
                steered_walk(&model, &ctx, &seed_frames, ahead, lookahead, &mut rng)?;
            println!("{}", report);
            let probes = steer_probes(&model, &ctx, &train_set, ahead, lookahead, &mut rng)?;
            println!("{}", probes);
            prims
        }
        None => prims,
    };
    if let Some(png) = &opts.walk_png {
        draw_walk(&walk, png)?;
        println!("wrote {}", png.display());
    }
    Ok(())
}

/// The files `egogen motion eval` was asked for: the paces (`--pace-json`), the long chain as
/// an AMASS-style npz (`--export-npz`) and its trace (`--chain-trace`).
fn write_eval_files(
    opts: &MotionEvalOptions,
    (weights, config): (&Path, &Path),
    (train_paces, chain_paces): (
        &[crate::motion::cvae::pace::Pace],
        &[crate::motion::cvae::pace::Pace],
    ),
    prims: &[crate::motion::cvae::DecodedPrimitive],
) -> Result<()> {
    use crate::motion::cvae::pace::Pace;
    if let Some(file) = &opts.pace_json {
        let values = |p: &[Pace]| {
            serde_json::json!({
                "speed_m_s": p.iter().map(|x| x.speed_m_s).collect::<Vec<_>>(),
                "turn_deg": p.iter().map(|x| x.turn_deg).collect::<Vec<_>>(),
            })
        };
        let doc = serde_json::json!({
            "weights": weights,
            "config": config,
            "train_primitives": values(train_paces),
            "random_chains": values(chain_paces),
        });
        crate::atomic_file::write_atomically(file, doc.to_string().as_bytes())?;
        println!("wrote {}", file.display());
    }
    if let Some(file) = &opts.export_npz {
        let refs: Vec<_> = prims.iter().collect();
        crate::motion::cvae::control::chain_sequence(&refs, &[]).write_amass(file)?;
        println!("wrote {}", file.display());
    }
    if let Some(file) = &opts.chain_trace {
        write_chain_trace(prims, file)?;
        println!("wrote {}", file.display());
    }
    Ok(())
}

/// Shorter chains from [`SHORT_CHAINS`] training seeds of `train_set`, each in its canonical
/// frame, `primitives` long: how long they stay upright (a JSON line); their paces added to
/// `chain_paces`.
fn short_chains(
    (model, ctx, sampler): (
        &crate::motion::cvae::MotionModel,
        &crate::motion::cvae::BodyContext,
        &crate::motion::cvae::BestOfK,
    ),
    train_set: &crate::motion::cvae::data::PrimitiveSet,
    primitives: usize,
    rng: &mut rand_chacha::ChaCha8Rng,
    chain_paces: &mut Vec<crate::motion::cvae::pace::Pace>,
) -> Result<()> {
    use crate::motion::cvae::measure::long_rollout;
    use crate::motion::cvae::pace::Pace;
    let short_chain_primitives = primitives;
    let mut upright = Vec::new();
    let mut on_floor = Vec::new();
    let mut moving = Vec::new();
    let mut pelvis_range = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..SHORT_CHAINS {
        let seed = set_seed(train_set, i * train_set.len() / SHORT_CHAINS);
        let (report, prims) = long_rollout(model, ctx, seed, short_chain_primitives, sampler, rng)?;
        chain_paces.extend(prims.iter().map(|p| Pace::of_frames(&p.joints)));
        upright.push(report.upright_primitives);
        on_floor.push(report.feet_on_floor_share);
        moving.push(report.moving_share);
        // Pelvis heights above the chain's floor (the seeds' floors differ).
        let floor = prims.first().map_or(0.0, |p| p.floor_z);
        pelvis_range.0 = pelvis_range.0.min(report.pelvis_z_min_m - floor);
        pelvis_range.1 = pelvis_range.1.max(report.pelvis_z_max_m - floor);
    }
    upright.sort_unstable();
    on_floor.sort_by(f64::total_cmp);
    moving.sort_by(f64::total_cmp);
    println!(
        "{}",
        serde_json::json!({
            "measure": "short_chains",
            "chains": SHORT_CHAINS,
            "primitives_each": short_chain_primitives,
            "all_upright": upright.iter().filter(|&&u| u == short_chain_primitives).count(),
            "pelvis_above_floor_m": [pelvis_range.0, pelvis_range.1],
            "feet_on_floor_share_min": on_floor[0],
            "feet_on_floor_share_median": on_floor[on_floor.len() / 2],
            "moving_share_median": moving[moving.len() / 2],
            "moving_share_min": moving[0],
            "upright_primitives_median": upright[upright.len() / 2],
            "upright_primitives_sorted": upright,
        })
    );
    Ok(())
}

/// `egogen motion stats`: pace and turn distributions of a config's primitives.
pub fn motion_stats(config: &Path, json: Option<&Path>) -> Result<()> {
    use crate::motion::cvae::pace::{set_paces, speed_by_turn, PaceSummary};
    use crate::motion::cvae::tensor_body::{RigGeometry, TensorRig};
    use crate::motion::cvae::train::evaluation_sets;
    let plan = crate::cli::train_primitive::load_train_plan(config)?;
    let body = BodyModel::load(&plan.body_model)?;
    let (train, held) = evaluation_sets(&plan, &body, true)?;
    let (train_all, _) = evaluation_sets(&plan, &body, false)?;
    let geo = RigGeometry::new(&body, &[])?;
    let rig = TensorRig::<crate::motion::cvae::infer::InferBackend>::new(&geo, &Default::default());
    let mut doc = serde_json::json!({"config": config});
    for (name, set) in [("train", &train), ("held_out", &held)] {
        let paces = set_paces(&rig, set, 256);
        println!(
            "{}",
            serde_json::json!({
                "set": name,
                "primitives": set.len(),
                "seconds_of_motion": set.len() as f64 * plan.stride_frames as f64 / 40.0,
                "summary": PaceSummary::of(&paces),
                "speed_by_turn": speed_by_turn(&paces),
            })
        );
        doc[name] = serde_json::json!({
            "speed_m_s": paces.iter().map(|p| p.speed_m_s).collect::<Vec<_>>(),
            "turn_deg": paces.iter().map(|p| p.turn_deg).collect::<Vec<_>>(),
        });
    }
    println!(
        "{}",
        serde_json::json!({
            "contact_filter": plan.min_contact_score,
            "train_primitives_before_filter": train_all.len(),
            "train_primitives_kept": train.len(),
        })
    );
    if let Some(file) = json {
        crate::atomic_file::write_atomically(file, doc.to_string().as_bytes())?;
        println!("wrote {}", file.display());
    }
    Ok(())
}

/// What `egogen motion control` measures (its flags).
#[derive(clap::Args, Debug)]
pub struct MotionControlOptions {
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

/// `egogen motion control`: sustained walks and turns with CEM-chosen latents, as JSON lines.
pub fn motion_control(opts: &MotionControlOptions) -> Result<()> {
    use crate::motion::cvae::control::chain_sequence;
    use crate::motion::cvae::pace::{PaceSummary, PACE_SPAN_S};
    use crate::motion::cvae::reach::{sustained_walk, turn};
    use crate::motion::cvae::tensor_body::{RigGeometry, TensorRig};
    use crate::motion::cvae::train::evaluation_sets;
    use crate::motion::cvae::{BodyContext, CemSettings, LatentController, MotionModel};
    use rand_chacha::ChaCha8Rng;
    use rand_core::SeedableRng;
    for &v in opts.speeds.iter().chain([&opts.turn_speed]) {
        if !(v.is_finite() && (0.0..=5.0).contains(&v)) {
            bail!("--speeds/--turn-speed: expected speeds in 0..=5 m/s, got {v}");
        }
    }
    if !(opts.walk_s.is_finite() && opts.walk_s > 0.0 && opts.walk_s <= 3600.0) {
        bail!(
            "--walk-s: expected 0 < seconds <= 3600, got {}",
            opts.walk_s
        );
    }
    if let Some(t) = opts
        .turns
        .iter()
        .find(|t| !t.is_finite() || t.abs() > 360.0)
    {
        bail!("--turns: expected angles within ±360°, got {t}");
    }
    if opts.samples == 0 || opts.iterations == 0 || opts.turn_primitives == 0 {
        bail!("--samples, --iterations and --turn-primitives must be at least 1");
    }
    let weights = opts
        .weights
        .clone()
        .unwrap_or_else(crate::motion::cvae::train::shipped_weights_path);
    let (weights, config) = (weights.as_path(), opts.config.as_path());
    if let Some(png) = &opts.walk_png {
        refuse_existing(png)?;
        if !opts.speeds.contains(&opts.png_speed) {
            bail!("--png-speed {} is not one of --speeds", opts.png_speed);
        }
    }
    let export = |name: &str| opts.export_dir.as_ref().map(|d| d.join(name));
    let names: Vec<String> = opts
        .speeds
        .iter()
        .map(|v| format!("walk_{v:.2}m_s.npz"))
        .chain(opts.turns.iter().map(|t| format!("turn_{t:+.0}deg.npz")))
        .collect();
    if let Some(dir) = &opts.export_dir {
        std::fs::create_dir_all(dir)?;
        for n in &names {
            refuse_existing(&dir.join(n))?;
        }
    }
    let plan = crate::cli::train_primitive::load_train_plan(config)?;
    let model = MotionModel::load(weights)?;
    let body = BodyModel::load(&plan.body_model)?;
    let ctx = BodyContext::new(&body, &[])?;
    let (train_set, _) = evaluation_sets(&plan, &body, true)?;
    let geo = RigGeometry::new(&body, &[])?;
    let rig = TensorRig::<crate::motion::cvae::infer::InferBackend>::new(&geo, &Default::default());
    let paces = crate::motion::cvae::pace::set_paces(&rig, &train_set, 256);
    let start = crate::motion::cvae::reach::steady_walk_index(&paces)
        .ok_or_else(|| anyhow::anyhow!("{}: no training primitives", config.display()))?;
    let seed = set_seed(&train_set, start);
    if !(opts.contact_weight.is_finite() && opts.contact_weight >= 0.0) {
        bail!(
            "--contact-weight: expected a weight ≥ 0, got {}",
            opts.contact_weight
        );
    }
    let settings = CemSettings {
        samples: opts.samples,
        iterations: opts.iterations,
        contact_weight: opts.contact_weight,
        ..CemSettings::default()
    };
    let controller = LatentController::new(&ctx, settings)?;
    println!(
        "{}",
        serde_json::json!({
            "weights": weights,
            "seed_primitive": {"item": start, "pace": paces[start]},
            "cem": {"samples": settings.samples, "elites": settings.elites, "iterations": settings.iterations, "contact_weight": settings.contact_weight},
        })
    );
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let primitives = (opts.walk_s / PACE_SPAN_S).ceil() as usize;
    for (i, &v) in opts.speeds.iter().enumerate() {
        let (report, steps) =
            sustained_walk(&controller, &model, &ctx, &seed, v, primitives, &mut rng)?;
        println!(
            "{}",
            serde_json::json!({"measure": "walk", "report": report})
        );
        let prims: Vec<_> = steps.iter().map(|s| &s.primitive).collect();
        if let Some(file) = export(&names[i]) {
            chain_sequence(&prims, &[]).write_amass(&file)?;
            println!("wrote {}", file.display());
        }
        if let Some(png) = opts.walk_png.as_ref().filter(|_| v == opts.png_speed) {
            let owned: Vec<_> = steps.iter().map(|s| s.primitive.clone()).collect();
            draw_walk(&owned, png)?;
            println!("wrote {}", png.display());
        }
        let paces: Vec<_> = steps.iter().map(|s| s.pace).collect();
        println!(
            "{}",
            serde_json::json!({"measure": "walk_paces", "target_speed_m_s": v, "summary": PaceSummary::of(&paces)})
        );
    }
    for (i, &angle) in opts.turns.iter().enumerate() {
        let (report, steps) = turn(
            &controller,
            &model,
            &ctx,
            &seed,
            angle,
            opts.turn_speed,
            opts.turn_primitives,
            &mut rng,
        )?;
        println!(
            "{}",
            serde_json::json!({"measure": "turn", "report": report})
        );
        if let Some(file) = export(&names[opts.speeds.len() + i]) {
            let prims: Vec<_> = steps.iter().map(|s| &s.primitive).collect();
            chain_sequence(&prims, &[]).write_amass(&file)?;
            println!("wrote {}", file.display());
        }
    }
    Ok(())
}

/// Latents drawn per primitive of the steered walk (`egogen motion eval --steer-goal-m`).
const STEER_CANDIDATES: usize = 16;

/// Primitives of the steered walk: 10 s at 40 Hz, 18 new frames each.
const STEER_PRIMITIVES: usize = 23;

/// Walks steered by [`steer_probes`]: 8 to each of 4 bearings.
const STEER_PROBES: usize = 32;

/// The seed (first two frames) of primitive `item` of a set, in its canonical frame.
fn set_seed(
    set: &crate::motion::cvae::data::PrimitiveSet,
    item: usize,
) -> crate::motion::cvae::PrimitiveSeed {
    use crate::motion::cvae::features::{frame_params, FRAME_DIM};
    let values = set.item(item);
    crate::motion::cvae::PrimitiveSeed {
        frames: std::array::from_fn(|k| {
            frame_params(&values[k * FRAME_DIM..(k + 1) * FRAME_DIM], &[])
        }),
        floor_z: set.floors(item)[0] as f64,
    }
}

/// A 10 s chain from `seed` steered to the floor point `goal`, the best of
/// [`STEER_CANDIDATES`] random latents kept per primitive: its report, primitives and the
/// pelvis's distance from the goal at the end (m).
fn walk_to_goal(
    model: &crate::motion::cvae::MotionModel,
    ctx: &crate::motion::cvae::BodyContext,
    seed: &crate::motion::cvae::PrimitiveSeed,
    goal: [f64; 2],
    lookahead: usize,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Result<(
    crate::motion::cvae::measure::ChainReport,
    Vec<crate::motion::cvae::DecodedPrimitive>,
    f64,
)> {
    use crate::body::joint;
    use crate::motion::cvae::measure::long_rollout;
    use crate::motion::cvae::{BestOfK, PlausibilityRules};
    let rules = PlausibilityRules {
        goal_xy: Some(goal),
        ..PlausibilityRules::default()
    };
    let mut sampler = BestOfK::new(ctx, STEER_CANDIDATES, rules)?;
    sampler.horizon = lookahead;
    let (chain, prims) = long_rollout(model, ctx, seed.clone(), STEER_PRIMITIVES, &sampler, rng)?;
    let Some(last) = prims.last() else {
        bail!("the steered walk decoded no primitives");
    };
    let left = last.joints[last.joints.len() - 1][joint::PELVIS]
        .truncate()
        .distance(goal.into());
    Ok((chain, prims, left))
}

/// [`STEER_PROBES`] walks steered to goals `distance` metres from spread training seeds, a
/// quarter each ahead of the body, to its left, right and behind: how much closer they got
/// (the JSON report line). One walk is chaotic; these are the statistics.
fn steer_probes(
    model: &crate::motion::cvae::MotionModel,
    ctx: &crate::motion::cvae::BodyContext,
    set: &crate::motion::cvae::data::PrimitiveSet,
    distance: f64,
    lookahead: usize,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Result<serde_json::Value> {
    use crate::motion::cvae::goal_toward;
    const BEARINGS: [(&str, f64); 4] = [
        ("ahead", 0.0),
        ("left", 90.0),
        ("right", -90.0),
        ("behind", 180.0),
    ];
    let mut progress = vec![Vec::new(); BEARINGS.len()];
    for i in 0..STEER_PROBES {
        let seed = set_seed(set, i * set.len() / STEER_PROBES);
        let b = i % BEARINGS.len();
        let goal = goal_toward(ctx, &seed, distance, BEARINGS[b].1.to_radians())?;
        let (_, _, left) = walk_to_goal(model, ctx, &seed, goal, lookahead, rng)?;
        progress[b].push(distance - left);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let all: Vec<f64> = progress.iter().flatten().copied().collect();
    let mut by_bearing = serde_json::Map::new();
    for ((name, _), p) in BEARINGS.iter().zip(&progress) {
        by_bearing.insert((*name).into(), serde_json::json!(mean(p)));
    }
    Ok(serde_json::json!({
        "measure": "steer_probes",
        "walks": STEER_PROBES,
        "goal_m": distance,
        "candidates": STEER_CANDIDATES,
        "progress_m_mean": mean(&all),
        "progress_m_mean_by_bearing": by_bearing,
        "closer_by_1m_share": all.iter().filter(|&&p| p >= 1.0).count() as f64 / all.len() as f64,
    }))
}

/// A 10 s chain from `seed` steered to a goal `ahead` metres in front of the seed's body (the
/// horizontal normal of its hip axis), the best of [`STEER_CANDIDATES`] random latents kept
/// per primitive: the JSON report line and the primitives.
fn steered_walk(
    model: &crate::motion::cvae::MotionModel,
    ctx: &crate::motion::cvae::BodyContext,
    seed: &crate::motion::cvae::PrimitiveSeed,
    ahead: f64,
    lookahead: usize,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Result<(
    serde_json::Value,
    Vec<crate::motion::cvae::DecodedPrimitive>,
)> {
    let goal = crate::motion::cvae::goal_ahead(ctx, seed, ahead)?;
    let (chain, prims, left) = walk_to_goal(model, ctx, seed, goal, lookahead, rng)?;
    let report = serde_json::json!({
        "measure": "steered_walk",
        "goal_ahead_m": ahead,
        "candidates": STEER_CANDIDATES,
        "progress_m": ahead - left,
        "goal_distance_end_m": left,
        "report": chain,
    });
    Ok((report, prims))
}

/// One JSON line per primitive of a chain: pelvis height above the floor (m, min and max),
/// the largest tilt of the trunk (pelvis → neck) from the vertical (deg), the mean horizontal
/// pelvis speed (m/s) and the lowest foot joint above the floor (m, min and max).
fn write_chain_trace(prims: &[crate::motion::cvae::DecodedPrimitive], file: &Path) -> Result<()> {
    use crate::body::joint;
    use crate::motion::primitive::{PRIMITIVE_RATE_HZ, SEED_FRAMES};
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::fs::File::create(file)?);
    for (i, p) in prims.iter().enumerate() {
        let frames = &p.joints[SEED_FRAMES..];
        let range = |v: Vec<f64>| {
            v.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                    (lo.min(x), hi.max(x))
                })
        };
        let pelvis = range(
            frames
                .iter()
                .map(|j| j[joint::PELVIS].z - p.floor_z)
                .collect(),
        );
        let foot = range(
            frames
                .iter()
                .map(|j| {
                    [
                        joint::LEFT_FOOT,
                        joint::RIGHT_FOOT,
                        joint::LEFT_ANKLE,
                        joint::RIGHT_ANKLE,
                    ]
                    .iter()
                    .map(|&k| j[k].z)
                    .fold(f64::INFINITY, f64::min)
                        - p.floor_z
                })
                .collect(),
        );
        let tilt_deg = frames
            .iter()
            .map(|j| {
                let up = (j[joint::NECK] - j[joint::PELVIS]).normalize();
                up.z.clamp(-1.0, 1.0).acos().to_degrees()
            })
            .fold(0.0, f64::max);
        let start = p.joints[SEED_FRAMES - 1][joint::PELVIS];
        let end = p.joints[p.joints.len() - 1][joint::PELVIS];
        let speed = ((end.x - start.x).powi(2) + (end.y - start.y).powi(2)).sqrt()
            * PRIMITIVE_RATE_HZ
            / frames.len() as f64;
        writeln!(
            out,
            "{}",
            serde_json::json!({
                "primitive": i,
                "pelvis_min_m": pelvis.0, "pelvis_max_m": pelvis.1,
                "trunk_tilt_max_deg": tilt_deg,
                "pelvis_speed_m_s": speed,
                "lowest_foot_min_m": foot.0, "lowest_foot_max_m": foot.1,
            })
        )?;
    }
    out.flush()?;
    Ok(())
}

/// Stick figures every 0.5 s over the first 10 s of a chain, from above (left) and from the
/// side (right), with the pelvis path.
fn draw_walk(prims: &[crate::motion::cvae::DecodedPrimitive], png: &Path) -> Result<()> {
    use crate::body::PARENTS;
    use crate::motion::primitive::SEED_FRAMES;
    use crate::preview::sticks::bone_mesh;
    let frames: Vec<&Vec<Vec3>> = prims
        .iter()
        .flat_map(|p| p.joints[SEED_FRAMES..].iter())
        .take(400)
        .collect();
    let mut bones = Vec::new();
    for f in frames.iter().step_by(20) {
        for j in 1..22 {
            bones.push((f[PARENTS[j].unwrap_or(0)], f[j]));
        }
    }
    let path: Vec<(Vec3, Vec3)> = frames.windows(2).map(|w| (w[0][0], w[1][0])).collect();
    // The floor under the walk (world z = 0 for mocap seeds, below the canonical origin for
    // seeds taken from training primitives).
    let floor_z = prims.first().map_or(0.0, |p| p.floor_z);
    let floor = {
        let (lo, hi) = frames.iter().fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), f| (lo.min(f[0]), hi.max(f[0])),
        );
        let (lo, hi) = (lo - Vec3::splat(0.5), hi + Vec3::splat(0.5));
        vec![
            (
                Vec3::new(lo.x, lo.y, floor_z),
                Vec3::new(hi.x, lo.y, floor_z),
            ),
            (
                Vec3::new(hi.x, lo.y, floor_z),
                Vec3::new(hi.x, hi.y, floor_z),
            ),
            (
                Vec3::new(hi.x, hi.y, floor_z),
                Vec3::new(lo.x, hi.y, floor_z),
            ),
            (
                Vec3::new(lo.x, hi.y, floor_z),
                Vec3::new(lo.x, lo.y, floor_z),
            ),
        ]
    };
    let (bv, bf) = bone_mesh(&bones, 0.015);
    let (pv, pf) = bone_mesh(&path, 0.01);
    let (fv, ff) = bone_mesh(&floor, 0.01);
    let meshes = [
        (&bv[..], &bf[..], [0.3, 0.45, 0.8]),
        (&pv[..], &pf[..], [0.85, 0.3, 0.2]),
        (&fv[..], &ff[..], [0.5, 0.5, 0.5]),
    ];
    let top = MeshView::looking_from(Vec3::Z, Vec3::Y).render(&meshes, 640, 640);
    // Side view: across the overall walking direction.
    let travel =
        frames.last().map_or(Vec3::X, |f| f[0]) - frames.first().map_or(Vec3::ZERO, |f| f[0]);
    let across = Vec3::new(-travel.y, travel.x, 0.0)
        .try_normalize()
        .unwrap_or(Vec3::NEG_Y);
    let side = MeshView::looking_from(across, Vec3::Z).render(&meshes, 960, 640);
    top.hconcat(&side, [255, 255, 255]).write_png(png)?;
    Ok(())
}
