//! `egogen motion control`: sustained walks and turns with CEM-chosen latents
//! (`motion::cvae::reach`), as JSON lines, with their AMASS-style files and a picture when asked.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::atomic_file::refuse_existing;
use crate::body::BodyModel;
use crate::motion::cvae::train::TrainPlan;

use super::chain_views::draw_walk;
use super::set_seed;

/// What `egogen motion control` measures (its flags, `cli::motion_jobs::MotionControlOptions`).
pub(crate) struct MotionControl {
    /// Weights (default: the shipped assets/motion/primitive_cvae.safetensors).
    pub(crate) weights: Option<PathBuf>,
    /// The training config, for its clips (the walks start from a training seed).
    pub(crate) config: PathBuf,
    /// Target speeds of the straight walks (m/s).
    pub(crate) speeds: Vec<f64>,
    /// Length of each straight walk (s of motion; 0.45 s per primitive).
    pub(crate) walk_s: f64,
    /// Turn angles (degrees, positive to the left).
    pub(crate) turns: Vec<f64>,
    /// Walking speed asked for during the turns (m/s).
    pub(crate) turn_speed: f64,
    /// Primitives allowed per turn.
    pub(crate) turn_primitives: usize,
    /// Latents decoded per CEM iteration.
    pub(crate) samples: usize,
    /// CEM iterations per primitive.
    pub(crate) iterations: usize,
    /// Cost per unit of −ln(foot-contact score), against 4 per m/s of speed error.
    pub(crate) contact_weight: f64,
    pub(crate) seed: u64,
    /// PNG of the first 10 s of the walk at `png_speed`, from above and from the side.
    pub(crate) walk_png: Option<PathBuf>,
    /// Which walk `walk_png` draws (m/s; one of `speeds`).
    pub(crate) png_speed: f64,
    /// Folder to write every walk and turn into as AMASS-style `.npz`.
    pub(crate) export_dir: Option<PathBuf>,
}

/// `egogen motion control`: sustained walks and turns with CEM-chosen latents, as JSON lines;
/// `load_plan` reads the training config.
pub(crate) fn motion_control(
    opts: &MotionControl,
    load_plan: impl FnOnce(&Path) -> Result<TrainPlan>,
) -> Result<()> {
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
    let plan = load_plan(config)?;
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
