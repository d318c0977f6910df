//! A take of agents from a checked synth plan ([`SynthPlan`], made by `cli` from a synth
//! config or a run config's agents): the walkable map of its scene or open floor, where the
//! agents start, the motion model, policy, pose prior and seed clips loaded, the crowd walked
//! ([`crate::synth::crowd`]), and, for `egogen synth`, the take's folder written
//! ([`crate::synth::crowd_dir`]); and any take's motion from its [`MotionPlan`] (agents, a
//! scripted walk, a motion file: [`make_motion`]). `egogen synth`, `egogen-run` and campaigns
//! make their motion here.

use std::path::PathBuf;

use anyhow::{Context, Result};
use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use crate::motion::cvae::train::TrainPlan;
use crate::motion::MotionSequence;
use crate::scene::{MovingObstacle, Obstacle2, ObstacleSolid, WalkableMap};
use crate::synth::crowd::{
    run_crowd_with_activities, sample_point, AgentPlan, CrowdParts, CrowdSettings, CrowdWorld,
};
use crate::walker::ControllerSpec;

/// Where agents come from before the map is known: given, or to be sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct AgentDraft {
    pub name: String,
    pub betas: Vec<f64>,
    /// Drawn by `[crowd]` (cut to what the body model has) rather than given (checked).
    pub betas_drawn: bool,
    pub start: Option<DVec2>,
    pub facing_rad: Option<f64>,
    pub goals: Vec<DVec2>,
    pub wander: bool,
    pub steering: ControllerSpec,
}

/// A checked synth config.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthPlan {
    pub config: PathBuf,
    pub body_model: PathBuf,
    pub scene: Option<PathBuf>,
    /// How the scene file's coordinates become the world's (`[scene] up_axis`, `unit_m`).
    pub scene_frame: crate::scene::SceneFrame,
    pub floor_m: f64,
    pub indoors: bool,
    /// The walkable map's settings (`[scene] floor_z_m`, `floor_steps_m`).
    pub walkable: crate::scene::WalkableSettings,
    pub weights: PathBuf,
    pub policy: Option<PathBuf>,
    pub pose_prior: PathBuf,
    /// The primitive training config whose training clips seed the agents' first
    /// primitives (`motion.train_config`), read.
    pub seed_clips: TrainPlan,
    pub settings: CrowdSettings,
    /// What people do besides walking (`[activities]`).
    pub activities: crate::synth::activity::ActivitySettings,
    pub duration_s: f64,
    pub agents: Vec<AgentDraft>,
    pub obstacles: Vec<Obstacle2>,
    pub moving: Vec<MovingObstacle>,
    /// Every `[[obstacles]]` box as a solid, in config order (what a rendered run draws).
    pub solids: Vec<ObstacleSolid>,
    pub out_dir: PathBuf,
}

/// The walkable map of the plan's scene, or its open floor.
pub fn synth_map(plan: &SynthPlan) -> Result<WalkableMap> {
    Ok(synth_scene(plan)?.0)
}

/// The walkable map of the plan's scene and the scene (`None`: an open floor).
fn synth_scene(plan: &SynthPlan) -> Result<(WalkableMap, Option<crate::scene::SceneMesh>)> {
    match &plan.scene {
        Some(path) => {
            let mesh = crate::scene::load_scene(path, plan.scene_frame)?;
            let map = crate::scene::walkable_map(&mesh, path, plan.walkable)?;
            if let Some(warning) = crate::scene::scene_frame_warning(&mesh, &map, path) {
                eprintln!("{warning}");
            }
            Ok((map, Some(mesh)))
        }
        None => {
            let cell = 0.1;
            let n = (plan.floor_m / cell).round().max(1.0) as usize;
            let origin = DVec2::splat(-(n as f64) * cell / 2.0);
            Ok((
                WalkableMap::from_walkable(origin, cell, n, n, vec![true; n * n]),
                None,
            ))
        }
    }
}

/// The agents with every start and goal placed: sampled ones on the walkable map (in
/// `region` when given, with the clearance, at least 1 m from every other start); given ones
/// checked to stand on it.
pub(crate) fn place_agents(
    plan: &SynthPlan,
    map: &WalkableMap,
    region: Option<&[bool]>,
) -> Result<Vec<AgentPlan>> {
    let s = &plan.settings;
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed ^ 0x57A27);
    let mut out: Vec<AgentPlan> = Vec::with_capacity(plan.agents.len());
    let on_map = |p: DVec2| map.is_walkable_at(p);
    // `[[obstacles]]` where they stand when the take starts (the still ones and the moving
    // ones at time 0), by config order among the still ones first.
    let at_start: Vec<Obstacle2> = plan
        .obstacles
        .iter()
        .copied()
        .chain(plan.moving.iter().map(|m| m.at(0.0)))
        .collect();
    let inside_obstacle = |p: DVec2, clearance_m: f64| {
        at_start
            .iter()
            .position(|o| o.grown(clearance_m).contains(p))
    };
    let floor = if region.is_some() {
        "walkable floor inside the walls ([scene] indoors = false walks outside too)"
    } else {
        "walkable floor"
    };
    for a in &plan.agents {
        let start = match a.start {
            Some(p) => {
                if !on_map(p) {
                    anyhow::bail!(
                        "{}: agent {}: start [{}, {}] is not on the {floor}",
                        plan.config.display(),
                        a.name,
                        p.x,
                        p.y
                    );
                }
                if inside_obstacle(p, 0.0).is_some() {
                    anyhow::bail!(
                        "{}: agent {}: start [{}, {}] lies inside an [[obstacles]] box (where it \
                         stands when the take starts); move the start or the obstacle",
                        plan.config.display(),
                        a.name,
                        p.x,
                        p.y
                    );
                }
                p
            }
            None => {
                let mut found = None;
                for _ in 0..200 {
                    let Some(p) = sample_point(map, region, s.clearance_m, &mut rng) else {
                        break;
                    };
                    if out.iter().all(|o| o.start.distance(p) >= 1.0)
                        && inside_obstacle(p, s.clearance_m).is_none()
                    {
                        found = Some(p);
                        break;
                    }
                }
                found.with_context(|| {
                    let storey = match plan.walkable.floor_z_m {
                        Some(z) => format!(
                            "; `[scene] floor_z_m = {z}` walks the floor at that height: check \
                             the scene has a floor there (`egogen scene inspect --floor-z-m {z}`)"
                        ),
                        None => String::new(),
                    };
                    format!(
                        "{}: agent {}: no free start on the walkable floor ({} m clearance, `[motion] clearance_m`; 1 m from the other agents){storey}",
                        plan.config.display(),
                        a.name,
                        s.clearance_m
                    )
                })?
            }
        };
        for g in &a.goals {
            if !on_map(*g) {
                anyhow::bail!(
                    "{}: agent {}: goal [{}, {}] is not on the {floor}",
                    plan.config.display(),
                    a.name,
                    g.x,
                    g.y
                );
            }
            if plan.obstacles.iter().any(|o| o.contains(*g)) {
                anyhow::bail!(
                    "{}: agent {}: goal [{}, {}] lies inside a standing [[obstacles]] box; \
                     move the goal or the obstacle",
                    plan.config.display(),
                    a.name,
                    g.x,
                    g.y
                );
            }
        }
        out.push(AgentPlan {
            name: a.name.clone(),
            betas: a.betas.clone(),
            start,
            facing_rad: a.facing_rad,
            goals: a.goals.clone(),
            wander: a.wander,
            steering: a.steering,
        });
    }
    Ok(out)
}

/// Where a run's motion comes from, checked.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionPlan {
    ScriptedWalk {
        duration_s: f64,
        frame_rate_hz: f64,
        speed_m_s: f64,
    },
    File {
        path: PathBuf,
    },
    /// Agents steered through the scene (`egogen synth`'s crowd), the cameras on the
    /// `wearers` (indices into the plan's agents).
    Agents {
        synth: Box<SynthPlan>,
        wearers: Vec<usize>,
    },
}

/// A take's motion, made: agents walked through the scene, or one motion (a scripted walk or a
/// motion file).
pub(crate) enum TakeMotion {
    Agents {
        walked: Synthesized,
        wearers: Vec<usize>,
    },
    One(MotionSequence),
}

/// Makes a take's motion: agents walk the scene (as `egogen synth`), a scripted walk of a body
/// of shape `betas`, or a motion file read.
pub(crate) fn make_motion(
    motion: &MotionPlan,
    betas: &[f64],
    body: &crate::body::BodyModel,
) -> Result<TakeMotion> {
    Ok(match motion {
        MotionPlan::Agents { synth, wearers } => TakeMotion::Agents {
            walked: synthesize(synth, body, true)?,
            wearers: wearers.clone(),
        },
        MotionPlan::ScriptedWalk {
            duration_s,
            frame_rate_hz,
            speed_m_s,
        } => {
            let shaped = body.shape(betas, &[])?;
            let walk = crate::motion::scripted::WalkCycle {
                speed_m_s: *speed_m_s,
                ..Default::default()
            };
            TakeMotion::One(walk.sequence(
                *duration_s,
                *frame_rate_hz,
                betas,
                shaped.rest_joints[0],
                shaped.rest_sole_y(),
            ))
        }
        MotionPlan::File { path } => TakeMotion::One(MotionSequence::read(path)?),
    })
}

/// A synthesized take and the world it was walked in.
pub(crate) struct Synthesized {
    pub world: CrowdWorld,
    pub take: crate::synth::crowd::CrowdTake,
    pub wall_s: f64,
    /// What was asked, for the take's summary.
    pub about: serde_json::Value,
}

/// Loads the parts and writes the take (see [`crate::synth::crowd_dir`]).
pub fn run_synth(
    plan: &SynthPlan,
    progress: bool,
) -> Result<crate::synth::crowd_dir::CrowdOutputs> {
    crate::synth::crowd_dir::check_out_dir(&plan.out_dir)?;
    let body = crate::body::BodyModel::load(&plan.body_model)?;
    let s = synthesize(plan, &body, progress)?;
    crate::synth::crowd_dir::write_crowd_dir(
        &plan.out_dir,
        &s.world,
        &body,
        &s.take,
        Some(s.wall_s),
        s.about,
    )
}

/// Loads the motion model, policy, pose prior and start poses, places the agents and walks
/// the take (nothing is written).
pub(crate) fn synthesize(
    plan: &SynthPlan,
    body: &crate::body::BodyModel,
    progress: bool,
) -> Result<Synthesized> {
    use crate::motion::cvae::MotionModel;
    use crate::walker::PosePrior;
    use crate::walker::SeedBank;
    let (map, mesh) = synth_scene(plan)?;
    let (map, region) = crate::scene::indoor_map(map, plan.indoors);
    let agents = place_agents(plan, &map, region.as_deref())?;
    for (a, draft) in agents.iter().zip(&plan.agents) {
        if !draft.betas_drawn && a.betas.len() > body.num_betas() {
            anyhow::bail!(
                "{}: agent {}: {} betas given, the body model {} has {}",
                plan.config.display(),
                a.name,
                a.betas.len(),
                plan.body_model.display(),
                body.num_betas()
            );
        }
    }
    // Drawn shapes keep the coefficients the model has.
    let agents: Vec<AgentPlan> = agents
        .into_iter()
        .map(|mut a| {
            a.betas.truncate(body.num_betas());
            a
        })
        .collect();
    let model = MotionModel::load(&plan.weights)?;
    let prior = PosePrior::load(&plan.pose_prior)?;
    let actor = match &plan.policy {
        Some(p) => Some(crate::policy::Actor::of(
            &crate::policy::weights::load_policy_for(p, &model)?,
        )),
        None => None,
    };
    let (train_set, _) = crate::motion::cvae::train::evaluation_sets(&plan.seed_clips, body, true)?;
    let bank = SeedBank::from_set(&train_set);
    let parts = CrowdParts {
        model: &model,
        body_model: body,
        prior: &prior,
        bank: &bank,
        policy: actor.as_ref(),
    };
    // Activities only where asked: the seats, clips and the scene's distances they need.
    let acts = match plan.activities.walk_only() {
        true => None,
        false => Some(crate::synth::activity::ActivityWorld::new(
            plan.activities,
            mesh.map(std::sync::Arc::new),
            &map,
            &crate::motion::activity_clip::activity_clip_dir(),
        )?),
    };
    if acts.as_ref().is_some_and(|a| {
        a.settings
            .weights
            .weight(crate::synth::activity::Activity::Sit)
            > 0.0
            && a.seats.is_empty()
    }) {
        eprintln!(
            "warning: {}: activities.weights.sit > 0 but the scene has no seat people can reach \
             (`egogen scene inspect` lists what it finds); every sit drawn is skipped",
            plan.config.display()
        );
    }
    let world = CrowdWorld {
        map: std::sync::Arc::new(map),
        region,
        obstacles: plan.obstacles.clone(),
        moving: plan.moving.clone(),
    };
    let bar = crate::synth::crowd_dir::progress_bar(progress, plan.settings.primitives);
    let started = std::time::Instant::now();
    let take =
        run_crowd_with_activities(&parts, &world, &agents, &plan.settings, acts, |done, _| {
            bar.set_position(done as u64)
        })
        .with_context(|| format!("{}", plan.config.display()))?;
    let wall_s = started.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let about = serde_json::json!({
        "config": plan.config,
        "scene": plan.scene,
        // How the scene file was read, where not as its format says (`egogen aria export`
        // reads the scene again for gaze depths).
        "scene_up_axis": plan.scene_frame.up.map(crate::scene::UpAxis::name),
        "scene_unit_m": (plan.scene_frame.unit_m != 1.0).then_some(plan.scene_frame.unit_m),
        "floor_m": plan.scene.is_none().then_some(plan.floor_m),
        "motion_weights": plan.weights,
        "policy": plan.policy,
        "pose_prior": plan.pose_prior,
        "duration_s": plan.duration_s,
        "settings": plan.settings,
    });
    let mut about = about;
    if !plan.activities.is_default() {
        about["activities"] = serde_json::to_value(plan.activities)?;
    }
    Ok(Synthesized {
        world,
        take,
        wall_s,
        about,
    })
}
