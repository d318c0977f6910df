//! The synth config (`egogen synth CONFIG`): a scene (a glTF/OBJ/PLY file or an open square
//! floor), the motion model, policy and pose prior (shipped ones by default), agents given one
//! by one (`[[agents]]`) and/or made by `[crowd]` (on a circle walking to the opposite points,
//! or at sampled places), static and moving 2D obstacles, and the output folder. Parsed
//! strictly (unknown keys refused), checked value by value with the key named, then resolved
//! into a [`SynthPlan`] (the primitive training config whose clips seed the agents read with
//! it); [`crate::synth::take`] walks the plan and writes the take.

use std::path::{Path, PathBuf};

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

use super::config_file::{crate_root, resolve_body_model};
use super::config_file::{load_toml, Bad, ConfigError};
use crate::math::random::normal_samples;
use crate::plan::{AgentDraft, SynthPlan};
use crate::scene::{MovingObstacle, Obstacle2, ObstacleSolid, WalkableSettings};
use crate::synth::activity::ActivitySettings;
use crate::synth::crowd::CrowdSettings;
use crate::walker::WalkerSettings;
use crate::walker::{ControllerSpec, Steering};

/// Most agents in one take.
pub(crate) const MAX_AGENTS: usize = 32;

/// Most shape coefficients drawn per agent (SMPL-X's files hold 300; a body model uses as many
/// as it has).
pub(crate) const MAX_BETAS: usize = 400;
/// Longest take (s).
pub(crate) const MAX_DURATION_S: f64 = 3600.0;

/// `[scene]`.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSynthScene {
    /// Scene file (glTF, OBJ, PLY), relative to the config's folder; absent: an open floor.
    pub path: Option<PathBuf>,
    /// Side of the open square floor centred on the origin (m, default 8).
    pub floor_m: Option<f64>,
    /// Draw starts and goals inside the walls only, and block the ground around the walls in
    /// the map the agents sense (default true): the ground around a building is not where its
    /// people walk.
    pub indoors: Option<bool>,
    /// Walk the floor at this height (m): a building's upper storey (default: the lowest
    /// floor holding a quarter of the largest floor area).
    pub floor_z_m: Option<f64>,
    /// Walk floors that step up or down by at most this (m) from cell to cell as one floor:
    /// steps between rooms, a sunken room, a ramp (0 < steps ≤ 0.5; default: one flat
    /// floor). Bodies follow the floor under them.
    pub floor_steps_m: Option<f64>,
    /// Which axis of the scene file points up, `"y"` or `"z"` (default: glTF y, OBJ and PLY z).
    pub up_axis: Option<crate::scene::UpAxis>,
    /// Metres per unit of the scene file (default 1; 0.01 for centimetres, 0.001 for
    /// millimetres).
    pub unit_m: Option<f64>,
}

/// `[motion]`.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSynthMotion {
    pub weights: Option<PathBuf>,
    pub policy: Option<PathBuf>,
    pub pose_prior: Option<PathBuf>,
    /// Motion training config whose training clips give the start poses.
    pub train_config: Option<PathBuf>,
    /// Longest take (s, default 20); it ends earlier when every agent is done, unless
    /// `stop_when_done = false`.
    pub duration_s: Option<f64>,
    pub stop_when_done: Option<bool>,
    /// Distance range of wandering goals (m).
    pub wander_distance_m: Option<[f64; 2]>,
    /// Free space around sampled starts and goals (m).
    pub clearance_m: Option<f64>,
    pub seed: Option<u64>,
}

/// `[crowd]`: agents made by rule.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawCrowd {
    pub count: usize,
    #[serde(default)]
    pub layout: CrowdLayout,
    pub radius_m: Option<f64>,
    pub centre: Option<[f64; 2]>,
    #[serde(default)]
    pub steering: Steering,
    pub k: Option<usize>,
    /// Scale of the policy's sampled actions' standard deviation (default 1, as trained;
    /// smaller walks nearer the mean action: docs/POLICY.md, "Action spread").
    pub action_spread: Option<f32>,
    #[serde(default)]
    pub wander: bool,
    /// Betas drawn N(0, 1), clipped to ±`betas_sigma` (0: the neutral shape; default 2).
    pub betas_sigma: Option<f64>,
    /// Shape coefficients drawn (default 10, at most what the model has).
    pub betas_count: Option<usize>,
}

/// `[crowd] layout`: where the crowd's people start and go.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CrowdLayout {
    /// Evenly on a circle, each walking to the opposite point (paper Fig. S7).
    #[default]
    Circle,
    /// Sampled starts and goals on the walkable map.
    Random,
}

/// `[[agents]]`: one agent.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawAgent {
    pub name: Option<String>,
    #[serde(default)]
    pub betas: Vec<f64>,
    /// Absent: sampled on the walkable map.
    pub start: Option<[f64; 2]>,
    /// Walking direction of the first step (degrees from +x); absent: towards the first goal.
    pub facing_deg: Option<f64>,
    #[serde(default)]
    pub goals: Vec<[f64; 2]>,
    #[serde(default)]
    pub wander: bool,
    /// Which controller steers (default `"policy"`).
    pub steering: Option<Steering>,
    /// Candidates of `"sampling"` and `"path_follow"` (default 16).
    pub k: Option<usize>,
    /// Scale of `"policy"`'s sampled actions' standard deviation (default 1, as trained).
    pub action_spread: Option<f32>,
}

/// `[[obstacles]]`: a 2D box, still or moving at constant velocity.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawObstacle {
    /// Centre at time 0 (m).
    pub centre: [f64; 2],
    /// Length and width (m).
    pub size_m: [f64; 2],
    #[serde(default)]
    pub yaw_deg: f64,
    #[serde(default)]
    pub velocity_m_s: [f64; 2],
    /// Height of the box a rendered run draws (m; default 1.0). The agents sense the footprint.
    pub height_m: Option<f64>,
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSynthOutput {
    /// Must not exist yet (or be empty).
    pub dir: PathBuf,
}

/// The whole config, as written.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSynth {
    pub body_model: Option<PathBuf>,
    #[serde(default)]
    pub scene: RawSynthScene,
    #[serde(default)]
    pub motion: RawSynthMotion,
    /// How every person steps (the one walker schema).
    #[serde(default)]
    pub walker: WalkerSettings,
    /// What people do besides walking (docs/ACTIVITIES.md).
    #[serde(default)]
    pub activities: ActivitySettings,
    pub crowd: Option<RawCrowd>,
    #[serde(default)]
    pub agents: Vec<RawAgent>,
    #[serde(default)]
    pub obstacles: Vec<RawObstacle>,
    pub output: RawSynthOutput,
}

fn finite2(v: [f64; 2]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Reads and checks a synth config.
pub fn load_synth_plan(path: &Path) -> Result<SynthPlan, ConfigError> {
    resolve_synth(load_toml(path)?, path, "")
}

/// Checks a synth config read from `path` (relative paths resolve against its folder); keys
/// are named with `prefix` before the synth config's own names (`""` for a synth config).
pub(crate) fn resolve_synth(
    raw: RawSynth,
    path: &Path,
    prefix: &str,
) -> Result<SynthPlan, ConfigError> {
    let base = path.parent().unwrap_or(Path::new("."));
    let bad = |key: &str, message: String| ConfigError::Value {
        path: path.into(),
        key: format!("{prefix}{key}"),
        message,
    };
    let body_model = resolve_body_model(raw.body_model, base).map_err(|m| bad("body_model", m))?;
    let file = |key: &str, given: &Option<PathBuf>, default: &str| {
        let f = match given {
            Some(p) => base.join(p),
            None => crate_root().join(default),
        };
        match f.is_file() {
            true => Ok(f),
            false => Err(bad(key, format!("file {} not found", f.display()))),
        }
    };
    let m = &raw.motion;
    let weights = file(
        "motion.weights",
        &m.weights,
        "assets/motion/primitive_cvae.safetensors",
    )?;
    let pose_prior = file(
        "motion.pose_prior",
        &m.pose_prior,
        "assets/policy/pose_prior.json",
    )?;
    let train_config = file(
        "motion.train_config",
        &m.train_config,
        "configs/train_primitive.toml",
    )?;
    let (scene, floor_m) = synth_scene(&raw.scene, base, &bad)?;
    let scene_frame = scene_frame(raw.scene.up_axis, raw.scene.unit_m, &bad)?;
    let duration_s = m.duration_s.unwrap_or(20.0);
    if !(duration_s.is_finite() && duration_s > 0.0 && duration_s <= MAX_DURATION_S) {
        return Err(bad(
            "motion.duration_s",
            format!("expected a length in (0, {MAX_DURATION_S}] s, got {duration_s}"),
        ));
    }
    let primitives = crate::synth::crowd::primitives_for(duration_s);
    let settings = crowd_settings(m, &raw.walker, primitives, &bad)?;
    let mut agents = listed_agents(&raw.agents, &bad)?;
    if let Some(c) = &raw.crowd {
        agents.extend(crowd_agents(c, settings.seed, &bad)?);
    }
    if agents.is_empty() || agents.len() > MAX_AGENTS {
        return Err(bad(
            "agents",
            format!(
                "expected 1–{MAX_AGENTS} agents ([[agents]] and [crowd] count together), got {}",
                agents.len()
            ),
        ));
    }
    check_agent_names(&agents, &bad)?;
    let frames = crate::synth::crowd::frames_of(primitives);
    let betas = agents.iter().map(|a| a.betas.len()).max().unwrap_or(0);
    let bytes =
        agents.len() as f64 * frames as f64 * crate::synth::crowd::bytes_per_agent_frame(betas);
    crate::memory::check_fits(
        &format!(
            "{} agents × {frames} frames (motion.duration_s = {duration_s} s) with {betas} shape \
             coefficients",
            agents.len()
        ),
        bytes,
    )
    .map_err(|m| bad("motion.duration_s", m))?;
    let policy = if agents
        .iter()
        .any(|a| matches!(a.steering, ControllerSpec::Policy { .. }))
    {
        Some(file(
            "motion.policy",
            &m.policy,
            crate::policy::weights::SHIPPED_POLICY,
        )?)
    } else {
        None
    };
    let (obstacles, moving, solids) = synth_obstacles(&raw.obstacles, &bad)?;
    if let Some((field, what)) = raw.activities.problem() {
        return Err(bad(&format!("activities.{field}"), what));
    }
    Ok(SynthPlan {
        config: path.into(),
        body_model,
        scene,
        scene_frame,
        floor_m,
        indoors: raw.scene.indoors.unwrap_or(true),
        walkable: floor_settings(raw.scene.floor_z_m, raw.scene.floor_steps_m, &bad)?,
        weights,
        policy,
        pose_prior,
        seed_clips: super::train_primitive::load_train_plan(&train_config)?,
        settings,
        activities: raw.activities,
        duration_s,
        agents,
        obstacles,
        solids,
        moving,
        out_dir: base.join(&raw.output.dir),
    })
}

/// `[scene]`: a scene file (relative to `base`), or an open floor's size.
fn synth_scene(
    raw: &RawSynthScene,
    base: &Path,
    bad: Bad,
) -> Result<(Option<PathBuf>, f64), ConfigError> {
    let scene = match &raw.path {
        Some(p) => {
            let f = crate::scene::dwelling::scene_source(&p.to_string_lossy(), base)
                .map_err(|m| bad("scene.path", m))?;
            if !f.is_file() {
                return Err(bad("scene.path", format!("file {} not found", f.display())));
            }
            Some(f)
        }
        None => None,
    };
    let floor_m = raw.floor_m.unwrap_or(8.0);
    if !(floor_m.is_finite() && (1.0..=200.0).contains(&floor_m)) {
        return Err(bad(
            "scene.floor_m",
            format!("expected 1–200 m, got {floor_m}"),
        ));
    }
    if scene.is_none() {
        for (key, given) in [
            ("scene.floor_z_m", raw.floor_z_m.is_some()),
            ("scene.floor_steps_m", raw.floor_steps_m.is_some()),
            ("scene.up_axis", raw.up_axis.is_some()),
            ("scene.unit_m", raw.unit_m.is_some()),
        ] {
            if given {
                return Err(bad(key, "only with a scene `path`".into()));
            }
        }
    }
    if scene.is_some() && raw.floor_m.is_some() {
        return Err(bad(
            "scene.floor_m",
            "an open floor's size; give either `path` or `floor_m`".into(),
        ));
    }
    Ok((scene, floor_m))
}

/// How the scene file is read, from `[scene] up_axis` and `unit_m`, checked.
pub(crate) fn scene_frame(
    up_axis: Option<crate::scene::UpAxis>,
    unit_m: Option<f64>,
    bad: Bad,
) -> Result<crate::scene::SceneFrame, ConfigError> {
    crate::scene::SceneFrame::new(up_axis, unit_m).map_err(|m| bad("scene.unit_m", m))
}

/// The walkable map's settings from `[scene] floor_z_m` and `floor_steps_m`, checked.
pub(crate) fn floor_settings(
    floor_z_m: Option<f64>,
    floor_steps_m: Option<f64>,
    bad: Bad,
) -> Result<WalkableSettings, ConfigError> {
    let settings = WalkableSettings {
        floor_z_m,
        floor_steps_m,
        ..Default::default()
    };
    match settings.floor_problem() {
        Some((field, what)) => Err(bad(&format!("scene.{field}"), what)),
        None => Ok(settings),
    }
}

/// `[motion]`'s and `[walker]`'s stepping settings for a take of `primitives` primitives.
fn crowd_settings(
    m: &RawSynthMotion,
    walker: &WalkerSettings,
    primitives: usize,
    bad: Bad,
) -> Result<CrowdSettings, ConfigError> {
    let defaults = CrowdSettings::default();
    let settings = CrowdSettings {
        walker: *walker,
        arrival_m: defaults.arrival_m,
        primitives,
        stop_when_done: m.stop_when_done.unwrap_or(true),
        wander_distance_m: m
            .wander_distance_m
            .map_or(defaults.wander_distance_m, |[a, b]| (a, b)),
        clearance_m: m.clearance_m.unwrap_or(defaults.clearance_m),
        seed: m.seed.unwrap_or(0),
    };
    if let Some((field, what)) = walker.problem() {
        return Err(bad(&format!("walker.{field}"), what));
    }
    let (lo, hi) = settings.wander_distance_m;
    if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi) {
        return Err(bad(
            "motion.wander_distance_m",
            format!("expected [MIN, MAX] with 0 < MIN ≤ MAX (m), got [{lo}, {hi}]"),
        ));
    }
    if !(settings.clearance_m.is_finite() && settings.clearance_m >= 0.0) {
        return Err(bad(
            "motion.clearance_m",
            format!("expected a distance ≥ 0 m, got {}", settings.clearance_m),
        ));
    }
    Ok(settings)
}

/// The `[[agents]]` as given.
fn listed_agents(raw: &[RawAgent], bad: Bad) -> Result<Vec<AgentDraft>, ConfigError> {
    let mut agents = Vec::new();
    for (i, a) in raw.iter().enumerate() {
        let key = |k: &str| format!("agents[{i}].{k}");
        let steer = a
            .steering
            .unwrap_or_default()
            .spec(a.k, a.action_spread)
            .map_err(|e| bad(&key("steering"), e))?;
        if let Some((b, v)) = a
            .betas
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite() || v.abs() > 10.0)
        {
            return Err(bad(
                &key(&format!("betas[{b}]")),
                format!("expected a value within ±10 standard deviations, got {v}"),
            ));
        }
        if a.start.is_some_and(|s| !finite2(s)) {
            return Err(bad(
                &key("start"),
                "expected two finite numbers [x, y] (m)".into(),
            ));
        }
        if let Some((g, _)) = a.goals.iter().enumerate().find(|(_, g)| !finite2(**g)) {
            return Err(bad(
                &key(&format!("goals[{g}]")),
                "expected two finite numbers [x, y] (m)".into(),
            ));
        }
        if a.facing_deg.is_some_and(|f| !f.is_finite()) {
            return Err(bad(&key("facing_deg"), "expected a finite angle".into()));
        }
        agents.push(AgentDraft {
            name: a.name.clone().unwrap_or_else(|| format!("agent_{i:02}")),
            betas: a.betas.clone(),
            betas_drawn: false,
            start: a.start.map(DVec2::from_array),
            facing_rad: a.facing_deg.map(f64::to_radians),
            goals: a.goals.iter().copied().map(DVec2::from_array).collect(),
            wander: a.wander,
            steering: steer,
        });
    }
    Ok(agents)
}

/// `[crowd]`'s agents: `count` bodies with betas drawn from the take's `seed`, on a circle or
/// at sampled places.
fn crowd_agents(c: &RawCrowd, seed: u64, bad: Bad) -> Result<Vec<AgentDraft>, ConfigError> {
    let mut agents = Vec::new();
    let steer = c
        .steering
        .spec(c.k, c.action_spread)
        .map_err(|e| bad("crowd.steering", e))?;
    let sigma = c.betas_sigma.unwrap_or(2.0);
    if !(sigma.is_finite() && (0.0..=10.0).contains(&sigma)) {
        return Err(bad(
            "crowd.betas_sigma",
            format!("expected 0–10, got {sigma}"),
        ));
    }
    if c.count > MAX_AGENTS {
        return Err(bad(
            "crowd.count",
            format!(
                "expected 1–{MAX_AGENTS} agents ([[agents]] and [crowd] count together), got {}",
                c.count
            ),
        ));
    }
    let n_betas = if sigma == 0.0 {
        0
    } else {
        c.betas_count.unwrap_or(10)
    };
    if n_betas > MAX_BETAS {
        return Err(bad(
            "crowd.betas_count",
            format!(
                "expected at most {MAX_BETAS} shape coefficients (SMPL-X has 300), got {n_betas}"
            ),
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xBE7A5);
    let centre = DVec2::from_array(c.centre.unwrap_or([0.0, 0.0]));
    if !centre.is_finite() {
        return Err(bad("crowd.centre", "expected two finite numbers".into()));
    }
    for i in 0..c.count {
        let betas: Vec<f64> = normal_samples(&mut rng, n_betas)
            .into_iter()
            .map(|b| (b as f64).clamp(-sigma, sigma))
            .collect();
        let (start, goals) = match c.layout {
            CrowdLayout::Circle => {
                let r = c.radius_m.unwrap_or(2.0);
                if !(r.is_finite() && r > 0.0) {
                    return Err(bad(
                        "crowd.radius_m",
                        format!("expected a radius > 0 m, got {r}"),
                    ));
                }
                let a = std::f64::consts::TAU * i as f64 / c.count as f64;
                let p = DVec2::from_angle(a) * r;
                (Some(centre + p), vec![centre - p])
            }
            CrowdLayout::Random => {
                if c.radius_m.is_some() || c.centre.is_some() {
                    return Err(bad("crowd.radius_m", "for layout = \"circle\" only".into()));
                }
                (None, Vec::new())
            }
        };
        agents.push(AgentDraft {
            name: format!("crowd_{i:02}"),
            betas,
            betas_drawn: true,
            start,
            facing_rad: None,
            goals,
            wander: c.wander,
            steering: steer,
        });
    }
    Ok(agents)
}

/// Agent names name folders: letters, digits, `_` and `-`, each used once.
fn check_agent_names(agents: &[AgentDraft], bad: Bad) -> Result<(), ConfigError> {
    let mut names = std::collections::BTreeSet::new();
    for a in agents {
        let ok = !a.name.is_empty()
            && a.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !ok {
            return Err(bad(
                "agents.name",
                format!(
                    "\"{}\": expected letters, digits, _ and - only (it names a folder)",
                    a.name
                ),
            ));
        }
        if !names.insert(a.name.clone()) {
            return Err(bad("agents.name", format!("\"{}\" is used twice", a.name)));
        }
    }
    Ok(())
}

/// `[[obstacles]]`: the still ones, the moving ones, and all as solids standing on the floor.
#[allow(clippy::type_complexity)]
fn synth_obstacles(
    raw: &[RawObstacle],
    bad: Bad,
) -> Result<(Vec<Obstacle2>, Vec<MovingObstacle>, Vec<ObstacleSolid>), ConfigError> {
    let (mut obstacles, mut moving, mut solids) = (Vec::new(), Vec::new(), Vec::new());
    for (i, o) in raw.iter().enumerate() {
        let key = |k: &str| format!("obstacles[{i}].{k}");
        if !finite2(o.centre) {
            return Err(bad(
                &key("centre"),
                "expected two finite numbers [x, y] (m)".into(),
            ));
        }
        if !(finite2(o.size_m) && o.size_m.iter().all(|&s| s > 0.0)) {
            return Err(bad(
                &key("size_m"),
                "expected [length, width] > 0 (m)".into(),
            ));
        }
        if !o.yaw_deg.is_finite() || !finite2(o.velocity_m_s) {
            return Err(bad(&key("velocity_m_s"), "expected finite numbers".into()));
        }
        let shape = Obstacle2::Box {
            centre: DVec2::from_array(o.centre),
            half_extents: DVec2::from_array(o.size_m) / 2.0,
            yaw_rad: o.yaw_deg.to_radians(),
        };
        let height_m = o.height_m.unwrap_or(1.0);
        if !(height_m.is_finite() && height_m > 0.0 && height_m <= 10.0) {
            return Err(bad(
                &key("height_m"),
                format!("expected a height in (0, 10] m, found {height_m}"),
            ));
        }
        let v = DVec2::from_array(o.velocity_m_s);
        solids.push(ObstacleSolid {
            motion: MovingObstacle {
                at_start: shape,
                velocity_m_per_s: v,
            },
            height_m,
        });
        if v == DVec2::ZERO {
            obstacles.push(shape);
        } else {
            moving.push(MovingObstacle {
                at_start: shape,
                velocity_m_per_s: v,
            });
        }
    }
    Ok((obstacles, moving, solids))
}
