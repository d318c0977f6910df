//! The measurements of the motion model behind `egogen motion eval` and `egogen motion control`:
//! held-out error, foot contact, long random-latent chains and steering probes (here and
//! `steering`), CEM-chosen latents for a target pace and heading (`control`), and a chain shown
//! as a trace and a stick-figure picture (`chain_views`). Each prints JSON lines and writes the
//! files it is asked for; `cli::motion_jobs` parses the flags and loads the training config.

mod chain_views;
pub(crate) mod control;
mod steering;

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::atomic_file::refuse_existing;
use crate::body::BodyModel;
use crate::motion::cvae::train::TrainPlan;

use chain_views::{draw_walk, write_chain_trace};
use steering::{steer_probes, steered_walk};

/// Float precision of the motion network.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Precision {
    F32,
    F16,
    Bf16,
}

impl Precision {
    /// The motion model at `weights`, in this precision.
    fn load(self, weights: &Path) -> Result<crate::motion::cvae::MotionModel> {
        use burn::tensor::FloatDType;
        let model = crate::motion::cvae::MotionModel::load(weights)?;
        Ok(match self {
            Precision::F32 => model,
            Precision::F16 => model.with_precision(FloatDType::F16),
            Precision::Bf16 => model.with_precision(FloatDType::BF16),
        })
    }
}

/// Chains from different seeds in `egogen motion eval`.
const SHORT_CHAINS: usize = 20;

/// What `egogen motion eval` measures (its flags).
pub(crate) struct MotionEvalOptions {
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

/// `egogen motion eval`: prints the measurements as JSON lines; `load_plan` reads the training
/// config at `config`.
pub(crate) fn motion_eval(
    weights: &Path,
    config: &Path,
    opts: &MotionEvalOptions,
    load_plan: impl FnOnce(&Path) -> Result<TrainPlan>,
) -> Result<()> {
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
    use crate::motion::cvae::{BestOfK, BodyContext, PlausibilityRules, PrimitiveSeed};
    use rand_chacha::ChaCha8Rng;
    use rand_core::SeedableRng;

    let plan = load_plan(config)?;
    let model = precision.load(weights)?;
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

/// The seed (first two frames) of primitive `item` of a set, in its canonical frame.
pub(crate) fn set_seed(
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
