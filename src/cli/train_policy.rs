//! The policy training config (`egogen train policy --config FILE`): parsed strictly (unknown
//! keys refused), then resolved into a [`PolicyTrainPlan`].

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::config_file::resolve_body_model;
use super::config_file::{load_toml, Bad, ConfigError};
use crate::policy::env::EnvSettings;
use crate::policy::net::PolicyArch;
use crate::policy::ppo::{PolicyTrainPlan, PpoSettings, StagePlan, TrainScene};
use crate::sensing::SensingSpec;

/// `[[stages]]`: one training stage.
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawStage {
    pub name: String,
    pub env_steps: usize,
    #[serde(default)]
    pub env: EnvSettings,
}

/// `[validation]`.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawValidation {
    pub every_updates: usize,
    pub episodes: usize,
    /// Weights are selected only where the validation's mean KL(π ‖ N(0, I)) is at most this.
    #[serde(default)]
    pub max_prior_kl: Option<f64>,
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPolicyOutput {
    pub weights: PathBuf,
    pub log: PathBuf,
    pub checkpoint_every_s: Option<f64>,
}

/// `[policy]`: the network's sizes.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPolicyArch {
    pub hidden: usize,
    pub pe_frequencies: usize,
    pub residual_blocks: usize,
    /// `[policy.sensing]`: what the policy observes (default: the paper's 32 rays).
    pub sensing: Option<SensingSpec>,
}

/// `[scene]`: a fixed scene some episodes walk (each stage's `env.fixed_share`).
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTrainScene {
    pub path: PathBuf,
    /// How many start/goal pairs are drawn.
    pub pairs: usize,
    /// `[MIN, MAX]` start–goal distance (m).
    pub pair_distance_m: [f64; 2],
    pub clearance_m: Option<f64>,
    /// Starts and goals inside the walls only (default true).
    pub indoors: Option<bool>,
    pub seed: u64,
    /// Which axis of the scene file points up, `"y"` or `"z"` (default: glTF y, OBJ and PLY z).
    pub up_axis: Option<crate::scene::UpAxis>,
    /// Metres per unit of the scene file (default 1; 0.01 for centimetres).
    pub unit_m: Option<f64>,
}

/// `[dwellings]`: generated dwellings whose start/goal pairs some episodes walk (each stage's
/// `env.dwellings.share`), drawn like `[scene]`'s in each.
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDwellings {
    /// `[FIRST, END)`: the dwellings `dwelling:FIRST` … `dwelling:END − 1` (generated into the
    /// cache on first use; held-out seeds are refused).
    pub seeds: [u64; 2],
    /// How many start/goal pairs are drawn in each.
    pub pairs: usize,
    /// `[MIN, MAX]` start–goal distance (m).
    pub pair_distance_m: [f64; 2],
    pub clearance_m: Option<f64>,
    pub seed: u64,
}

/// Most dwellings a training config may walk (each is loaded with its map before training).
const MAX_DWELLINGS: u64 = 1000;

/// The whole config, as written.
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTrainPolicy {
    pub seed: u64,
    pub body_model: Option<PathBuf>,
    pub motion_weights: PathBuf,
    /// Motion training config whose training primitives seed the episodes.
    pub motion_config: PathBuf,
    pub pose_prior: PathBuf,
    /// Start from these policy weights (same `[policy]`), relative to the config's folder.
    pub init_weights: Option<PathBuf>,
    pub scene: Option<RawTrainScene>,
    pub dwellings: Option<RawDwellings>,
    pub policy: RawPolicyArch,
    #[serde(default)]
    pub ppo: PpoSettings,
    pub stages: Vec<RawStage>,
    pub validation: RawValidation,
    pub output: RawPolicyOutput,
}

/// Reads and resolves a policy training config.
pub fn load_policy_plan(path: &Path) -> Result<PolicyTrainPlan, ConfigError> {
    let raw: RawTrainPolicy = load_toml(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let bad = |key: &str, message: String| ConfigError::Value {
        path: path.into(),
        key: key.into(),
        message,
    };
    let body_model =
        resolve_body_model(raw.body_model.clone(), base).map_err(|m| bad("body_model", m))?;
    let existing = |key: &str, p: &Path| {
        let f = base.join(p);
        match f.is_file() {
            true => Ok(f),
            false => Err(bad(key, format!("file {} not found", f.display()))),
        }
    };
    let motion_weights = existing("motion_weights", &raw.motion_weights)?;
    let motion_config = existing("motion_config", &raw.motion_config)?;
    let pose_prior = existing("pose_prior", &raw.pose_prior)?;
    let init_weights = match &raw.init_weights {
        Some(p) => Some(existing("init_weights", p)?),
        None => None,
    };
    check_numbers(&raw, &bad)?;
    let p = raw.ppo;
    if raw.stages.is_empty() {
        return Err(bad("stages", "expected at least one [[stages]]".into()));
    }
    let mut stages = Vec::with_capacity(raw.stages.len());
    let has_scene = raw.scene.is_some();
    let has_dwellings = raw.dwellings.is_some();
    for (i, s) in raw.stages.into_iter().enumerate() {
        stages.push(resolve_stage(i, s, has_scene, has_dwellings, &bad)?);
    }
    if has_dwellings && stages.iter().all(|s| s.env.dwellings.share <= 0.0) {
        return Err(bad(
            "dwellings",
            "no stage walks the dwellings: give some stage env.dwellings.share > 0".into(),
        ));
    }
    let dwellings = match &raw.dwellings {
        Some(d) => resolve_dwellings(d, base, &bad)?,
        None => Vec::new(),
    };
    let scene = raw
        .scene
        .map(|sc| {
            let named = sc.path.to_string_lossy();
            refuse_held_out_dwelling(&named, &base.join(&sc.path), &bad)?;
            let path = if named.starts_with(crate::scene::dwelling::DWELLING_SOURCE) {
                crate::scene::dwelling::scene_source(&named, base).map_err(|m| bad("scene.path", m))
            } else {
                existing("scene.path", &sc.path)
            };
            resolve_train_scene(sc, path, "scene", &bad)
        })
        .transpose()?;
    if scene.is_some() && stages.iter().all(|s| s.env.fixed_share <= 0.0) {
        return Err(bad(
            "scene",
            "no stage walks the scene: give some stage env.fixed_share > 0".into(),
        ));
    }
    let sensing = raw.policy.sensing.unwrap_or_default();
    if let Some(message) = sensing.problem() {
        return Err(bad("policy.sensing", message));
    }
    let checkpoint_every_s = raw.output.checkpoint_every_s.unwrap_or(300.0);
    if !(checkpoint_every_s.is_finite() && checkpoint_every_s >= 0.0) {
        return Err(bad(
            "output.checkpoint_every_s",
            format!("expected seconds ≥ 0, got {checkpoint_every_s}"),
        ));
    }
    let arch = PolicyArch {
        hidden: raw.policy.hidden,
        pe_frequencies: raw.policy.pe_frequencies,
        residual_blocks: raw.policy.residual_blocks,
        latent_dim: 128,
        sensing,
    };
    if let Some(problem) = arch.problem() {
        return Err(bad("policy", problem));
    }
    check_training_memory(&arch, &p, &bad)?;
    Ok(PolicyTrainPlan {
        seed: raw.seed,
        body_model,
        motion_weights,
        motion_config,
        pose_prior,
        arch,
        ppo: p,
        stages,
        eval_every_updates: raw.validation.every_updates,
        eval_episodes: raw.validation.episodes,
        select_max_prior_kl: raw.validation.max_prior_kl,
        init_weights,
        scene,
        dwellings,
        weights_out: base.join(raw.output.weights),
        log_out: base.join(raw.output.log),
        checkpoint_every_s,
    })
}

/// Most environments stepped together, steps per environment and update, passes per update
/// and validation episodes a training config may ask for.
const MAX_ENVS: usize = 65_536;
const MAX_STEPS_PER_ENV: usize = 4096;
const MAX_EPOCHS: usize = 1000;
const MAX_VALIDATION_EPISODES: usize = 100_000;

/// What a training run holds at least, against the memory it may use: the network with its
/// gradients and the optimiser's two moments, and an update's rollout (each environment's
/// observation, action, log-probability, value, reward and end flag at each step).
fn check_training_memory(arch: &PolicyArch, p: &PpoSettings, bad: Bad) -> Result<(), ConfigError> {
    let f32_bytes = std::mem::size_of::<f32>() as f64;
    let network = 4.0 * arch.parameter_count() * f32_bytes;
    let obs = crate::walker::state::ObsLayout::of(&arch.sensing).dim();
    let per_step = (obs + arch.latent_dim + 4) as f64 * f32_bytes;
    let rollout = p.envs as f64 * p.steps_per_env as f64 * per_step;
    let (key, what) = match network > rollout {
        true => (
            "policy.hidden",
            format!(
                "the network (hidden = {}, residual_blocks = {}) with its gradients and the \
                 optimiser's moments",
                arch.hidden, arch.residual_blocks
            ),
        ),
        false => (
            "ppo.envs",
            format!(
                "an update's rollout (ppo.envs = {} × ppo.steps_per_env = {} steps × {} values)",
                p.envs,
                p.steps_per_env,
                obs + arch.latent_dim + 4
            ),
        ),
    };
    crate::memory::check_fits(&what, network + rollout).map_err(|m| bad(key, m))
}

/// The whole numbers, shares and weights of `[ppo]`, `[policy]` and `[validation]`.
fn check_numbers(raw: &RawTrainPolicy, bad: Bad) -> Result<(), ConfigError> {
    let p = &raw.ppo;
    // Upper bounds keep every buffer a run allocates (environments × steps × observation,
    // validation episodes) within a machine's memory: refused here, not aborted later.
    let positive = [
        ("ppo.envs", p.envs, MAX_ENVS),
        ("ppo.steps_per_env", p.steps_per_env, MAX_STEPS_PER_ENV),
        ("ppo.minibatch", p.minibatch, MAX_ENVS * MAX_STEPS_PER_ENV),
        ("ppo.epochs", p.epochs, MAX_EPOCHS),
        (
            "policy.hidden",
            raw.policy.hidden,
            crate::policy::net::MAX_HIDDEN,
        ),
        (
            "policy.pe_frequencies",
            raw.policy.pe_frequencies,
            crate::policy::net::MAX_PE_FREQUENCIES,
        ),
        (
            "validation.episodes",
            raw.validation.episodes,
            MAX_VALIDATION_EPISODES,
        ),
    ];
    for (key, v, max) in positive {
        if !(1..=max).contains(&v) {
            return Err(bad(
                key,
                format!("expected a whole number 1–{max}, got {v}"),
            ));
        }
    }
    let unit = [
        ("ppo.gamma", p.gamma),
        ("ppo.gae_lambda", p.gae_lambda),
        ("ppo.clip", p.clip),
    ];
    for (key, v) in unit {
        if !(v > 0.0 && v <= 1.0) {
            return Err(bad(key, format!("expected a number in (0, 1], got {v}")));
        }
    }
    // Adam's steps are about the learning rate whatever the gradient: from 1 up they throw the
    // weights far off without a NaN to stop them (1e10 trained to weights of 1e10).
    if !(p.learning_rate.is_finite() && p.learning_rate > 0.0 && p.learning_rate < 1.0) {
        return Err(bad(
            "ppo.learning_rate",
            format!(
                "expected a learning rate in (0, 1), got {}",
                p.learning_rate
            ),
        ));
    }
    let non_negative = [
        ("ppo.weight_decay", p.weight_decay),
        ("ppo.value_coef", p.value_coef),
        ("ppo.entropy_coef", p.entropy_coef),
        ("ppo.prior_kl_coef", p.prior_kl_coef),
        ("ppo.max_grad_norm", p.max_grad_norm),
        ("ppo.target_kl", p.target_kl),
    ];
    for (key, v) in non_negative {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad(key, format!("expected a number ≥ 0, got {v}")));
        }
    }
    if let Some(kl) = raw.validation.max_prior_kl {
        if !(kl.is_finite() && kl > 0.0) {
            return Err(bad(
                "validation.max_prior_kl",
                format!("expected a number > 0, got {kl}"),
            ));
        }
    }
    Ok(())
}

/// One `[[stages]]` entry, checked (`has_scene`: the config has a `[scene]`).
fn resolve_stage(
    i: usize,
    s: RawStage,
    has_scene: bool,
    has_dwellings: bool,
    bad: Bad,
) -> Result<StagePlan, ConfigError> {
    let key = |k: &str| format!("stages[{i}].{k}");
    if s.env_steps == 0 {
        return Err(bad(
            &key("env_steps"),
            "expected a whole number ≥ 1, got 0".into(),
        ));
    }
    let e = &s.env;
    if let Some((field, what)) = e.walker.problem_over(&crate::walker::WalkerSettings::PAPER) {
        return Err(bad(&key(&format!("env.walker.{field}")), what));
    }
    if let Some((field, as_trained)) = e.walker.take_only_given() {
        return Err(bad(
            &key(&format!("env.walker.{field}")),
            format!("a take's setting, not training's ({as_trained}): leave it out"),
        ));
    }
    if e.fixed_max_primitives == Some(0) {
        return Err(bad(
            &key("env.fixed_max_primitives"),
            "expected a whole number ≥ 1, got 0".into(),
        ));
    }
    if !(0.0..=1.0).contains(&e.fixed_share) {
        return Err(bad(
            &key("env.fixed_share"),
            format!("expected a share in [0, 1], got {}", e.fixed_share),
        ));
    }
    if !has_scene && e.scene_test_vertices > 0 {
        return Err(bad(
            &key("env.scene_test_vertices"),
            "Eq. 11 is tested in a fixed scene: it needs a [scene] section".into(),
        ));
    }
    if e.scene_test_keeps_cells && e.scene_test_vertices == 0 {
        return Err(bad(
            &key("env.scene_test_keeps_cells"),
            "keeps Eq. 7 beside Eq. 11: it needs scene_test_vertices > 0".into(),
        ));
    }
    if !has_scene && e.fixed_share < 1.0 {
        return Err(bad(
            &key("env.fixed_share"),
            "a share of episodes in a fixed scene needs a [scene] section".into(),
        ));
    }
    let d = &e.dwellings;
    if !((0.0..=1.0).contains(&d.share) && d.max_primitives >= 1) {
        return Err(bad(
            &key("env.dwellings"),
            format!(
                "expected share in [0, 1] and max_primitives ≥ 1, got {} and {}",
                d.share, d.max_primitives
            ),
        ));
    }
    if !has_dwellings && d.share > 0.0 {
        return Err(bad(
            &key("env.dwellings.share"),
            "a share of episodes in generated dwellings needs a [dwellings] section".into(),
        ));
    }
    let (lo, hi) = e.scene.box_side_m;
    if !(lo > 0.0
        && hi >= lo
        && e.scene.floor_m > 2.0 * (hi + e.scene.start_margin_m)
        && e.scene.cell_m > 0.0)
    {
        return Err(bad(
                &key("env.scene"),
                "expected 0 < box_side_m.0 ≤ box_side_m.1, cell_m > 0 and a floor wider than the box and its start margin".into(),
            ));
    }
    let c = &e.crossing;
    let ordered = |(a, b): (f64, f64)| a > 0.0 && b >= a && b.is_finite();
    if !((0.0..=1.0).contains(&c.share)
        && ordered(c.distance_m)
        && ordered(c.speed_m_s)
        && ordered(c.footprint_m)
        && c.floor_m > c.distance_m.1
        && c.walker_speed_m_s > 0.0
        && c.timing_jitter_s >= 0.0
        && c.cross_angle_rad.abs() < std::f64::consts::FRAC_PI_2
        && crate::scene::generated::crossing_scene::people_in_range(c.people))
    {
        return Err(bad(
                &key("env.crossing"),
                format!("expected share in [0, 1], 0 < MIN ≤ MAX ranges (distance_m, speed_m_s, footprint_m), a floor longer than the longest start–goal distance, walker_speed_m_s > 0, timing_jitter_s ≥ 0, |cross_angle_rad| < π/2 and 1 ≤ people.0 ≤ people.1 ≤ {}", crate::scene::generated::crossing_scene::MAX_PEOPLE),
            ));
    }
    if !e.rooms.is_valid() {
        return Err(bad(
            &key("env.rooms"),
            "expected share in [0, 1], 0 < MIN ≤ MAX ranges (size_m ≤ 1 000 cells a side, door_m, furniture_side_m, distance_m), 1 ≤ rooms.0 ≤ rooms.1, furniture.0 ≤ furniture.1, min_room_m, wall_m and cell_m > 0, door_clearance_m and clearance_m ≥ 0, max_primitives ≥ 1".into(),
        ));
    }
    Ok(StagePlan {
        name: s.name,
        env_steps: s.env_steps,
        env: s.env,
    })
}

/// A generated dwelling whose seed is held out for measuring policies
/// ([`crate::scene::dwelling::HELD_OUT_SEEDS_FROM`] and up) is refused as a training scene.
fn refuse_held_out_dwelling(source: &str, path: &Path, bad: Bad) -> Result<(), ConfigError> {
    use crate::scene::dwelling::{dwelling_seed, HELD_OUT_SEEDS_FROM};
    match dwelling_seed(source, path) {
        Some(seed) if seed >= HELD_OUT_SEEDS_FROM => Err(bad(
            "scene.path",
            format!(
                "the dwelling of seed {seed} is held out: policies are measured on seeds \
                 {HELD_OUT_SEEDS_FROM} and up and never trained on them; train on a seed below \
                 {HELD_OUT_SEEDS_FROM}"
            ),
        )),
        _ => Ok(()),
    }
}

/// `[dwellings]` as one training scene per dwelling, each generated into the cache if it is
/// not there yet; a held-out seed, an empty range or more than [`MAX_DWELLINGS`] is refused.
fn resolve_dwellings(
    d: &RawDwellings,
    base: &Path,
    bad: Bad,
) -> Result<Vec<TrainScene>, ConfigError> {
    use crate::scene::dwelling::{scene_source, DWELLING_SOURCE, HELD_OUT_SEEDS_FROM};
    let [first, end] = d.seeds;
    if !(first < end && end - first <= MAX_DWELLINGS) {
        return Err(bad(
            "dwellings.seeds",
            format!(
                "expected [FIRST, END) with FIRST < END and at most {MAX_DWELLINGS} seeds, \
                 got [{first}, {end}]"
            ),
        ));
    }
    if end > HELD_OUT_SEEDS_FROM {
        return Err(bad(
            "dwellings.seeds",
            format!(
                "seeds {HELD_OUT_SEEDS_FROM} and up are held out: policies are measured on them \
                 and never trained on them; end the range at {HELD_OUT_SEEDS_FROM} or below"
            ),
        ));
    }
    (first..end)
        .map(|seed| {
            let source = format!("{DWELLING_SOURCE}{seed}");
            let path = scene_source(&source, base).map_err(|m| bad("dwellings.seeds", m));
            let raw = RawTrainScene {
                path: source.into(),
                pairs: d.pairs,
                pair_distance_m: d.pair_distance_m,
                clearance_m: d.clearance_m,
                indoors: Some(true),
                seed: d.seed ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15),
                up_axis: None,
                unit_m: None,
            };
            resolve_train_scene(raw, path, "dwellings", bad)
        })
        .collect()
}

/// `[scene]` (or one of `[dwellings]`, `table` naming which in errors): the fixed scene and
/// its start/goal pairs (`path`: its file, checked).
fn resolve_train_scene(
    sc: RawTrainScene,
    path: Result<PathBuf, ConfigError>,
    table: &str,
    bad: Bad,
) -> Result<TrainScene, ConfigError> {
    let path = path?;
    let [lo, hi] = sc.pair_distance_m;
    if !(lo >= 0.0 && hi >= lo && hi.is_finite()) {
        return Err(bad(
            &format!("{table}.pair_distance_m"),
            format!("expected [MIN, MAX] with 0 ≤ MIN ≤ MAX, got [{lo}, {hi}]"),
        ));
    }
    let clearance_m = sc.clearance_m.unwrap_or(0.4);
    if !(clearance_m.is_finite() && clearance_m >= 0.0) {
        return Err(bad(
            &format!("{table}.clearance_m"),
            format!("expected metres ≥ 0, got {clearance_m}"),
        ));
    }
    if sc.pairs == 0 {
        return Err(bad(
            &format!("{table}.pairs"),
            "expected a whole number ≥ 1, got 0".into(),
        ));
    }
    Ok(TrainScene {
        path,
        frame: super::synth_config::scene_frame(sc.up_axis, sc.unit_m, bad)?,
        pairs: sc.pairs,
        pair_distance_m: (lo, hi),
        clearance_m,
        indoors: sc.indoors.unwrap_or(true),
        seed: sc.seed,
    })
}
