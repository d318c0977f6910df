//! Runs a table: every scenario × controller for `episodes` episodes each (episodes in
//! parallel, each deterministic by its seed), measured per episode and summed up per row.

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::metrics::{measure, row, EpisodeResult, Row};
use super::scenarios::{episode, open_floor, Scenario, WALK_M};
use crate::body::BodyModel;
use crate::synth::crowd::{
    run_crowd, CrowdError, CrowdParts, CrowdSettings, CrowdTake, CrowdWorld,
};
use crate::walker::ControllerSpec;

/// A named way of steering every person of a scenario.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct NamedController {
    pub name: String,
    pub steering: ControllerSpec,
    /// How each person sees the others ([`crate::walker::WalkerSettings::anticipate_people`]; `false`:
    /// EgoGen's crowd loop).
    pub anticipate_people: bool,
}

impl NamedController {
    /// Table 1's controllers: the policy (sampled actions and mean action), the sampling
    /// controller and the path-following baseline, both with `k` latents per primitive.
    pub(crate) fn table1(k: usize) -> Vec<NamedController> {
        let mut out = NamedController::policies();
        out.push(NamedController::sampling(k));
        out.push(NamedController::of(ControllerSpec::PathFollow { k }));
        out
    }

    /// The speed/accuracy trade of steering: the policy (sampled and mean action) against the
    /// sampling controller with each of `ks` latents per primitive.
    pub(crate) fn speed(ks: &[usize]) -> Vec<NamedController> {
        let mut out = NamedController::policies();
        out.extend(ks.iter().map(|&k| NamedController::sampling(k)));
        out
    }

    /// The policy with sampled actions and with the mean action.
    fn policies() -> Vec<NamedController> {
        vec![
            NamedController::of(ControllerSpec::POLICY),
            NamedController::of(ControllerSpec::POLICY_MEAN),
        ]
    }

    /// The policy with sampled actions (`policy_as_placed`) and with the mean action
    /// (`policy_mean_as_placed`) in EgoGen's crowd loop: each person sees the others where they
    /// were last put ([`crate::walker::WalkerSettings::anticipate_people`] off).
    pub(crate) fn policies_as_placed() -> Vec<NamedController> {
        NamedController::policies()
            .into_iter()
            .map(|c| NamedController {
                name: format!("{}_as_placed", c.name),
                anticipate_people: false,
                ..c
            })
            .collect()
    }

    /// A controller by its own name ([`ControllerSpec::name`]), the others anticipated
    /// (egogen's default).
    fn of(steering: ControllerSpec) -> NamedController {
        NamedController::new(steering.name(), steering)
    }

    /// A controller with the others anticipated (egogen's default).
    fn new(name: String, steering: ControllerSpec) -> NamedController {
        NamedController {
            name,
            steering,
            anticipate_people: CrowdSettings::default().walker.anticipate_people,
        }
    }

    /// The policy's sampled actions with their standard deviation scaled by `spread`.
    pub(crate) fn policy_spread(name: &str, spread: f32) -> NamedController {
        NamedController::new(
            name.into(),
            ControllerSpec::Policy {
                mean_action: false,
                spread,
            },
        )
    }

    /// The sampling controller with `k` latents per primitive.
    fn sampling(k: usize) -> NamedController {
        NamedController::of(ControllerSpec::Sampling { k })
    }
}

/// Takes kept for pictures: episode 0 of a scenario and controller (every episode of the
/// static box, whose paths are drawn together).
pub(crate) struct Picture {
    pub scenario: Scenario,
    pub controller: String,
    pub world: CrowdWorld,
    pub takes: Vec<CrowdTake>,
}

/// A finished table.
pub(crate) struct TableRun {
    pub rows: Vec<Row>,
    pub episodes: Vec<EpisodeResult>,
    pub pictures: Vec<Picture>,
    pub wall_s: f64,
}

/// Why a table could not be run.
#[derive(Debug, thiserror::Error)]
pub(crate) enum EvalError {
    #[error("{scenario}, {controller}, episode {episode}: {source}")]
    Crowd {
        scenario: String,
        controller: String,
        episode: u64,
        source: CrowdError,
    },
    #[error("{scenario}, {controller}, episode {episode}: posing for Pene-H: {source}")]
    Pose {
        scenario: String,
        controller: String,
        episode: u64,
        source: crate::body::PoseError,
    },
}

/// The static box scenario's start and goal: every walk's line, for diversity.
fn diversity_line(s: Scenario) -> Option<(glam::DVec2, glam::DVec2)> {
    (s == Scenario::StaticBox).then(|| {
        (
            glam::DVec2::new(-0.5 * WALK_M, 0.0),
            glam::DVec2::new(0.5 * WALK_M, 0.0),
        )
    })
}

/// Runs `episodes` episodes of every scenario with every controller; `progress(done, total)`
/// after each scenario × controller.
pub(crate) fn run_table(
    parts: &CrowdParts,
    body: &BodyModel,
    scenarios: &[Scenario],
    controllers: &[NamedController],
    episodes: usize,
    seed: u64,
    progress: impl Fn(usize, usize, &str),
) -> Result<TableRun, EvalError> {
    let t0 = Instant::now();
    let floor = open_floor();
    let mut out = TableRun {
        rows: Vec::new(),
        episodes: Vec::new(),
        pictures: Vec::new(),
        wall_s: 0.0,
    };
    let total = scenarios.len() * controllers.len();
    for &scenario in scenarios {
        for c in controllers {
            let name = scenario.name();
            let results: Vec<(EpisodeResult, Option<CrowdTake>, CrowdWorld)> = (0..episodes as u64)
                .into_par_iter()
                .map(|n| {
                    let mut ep = episode(scenario, &floor, c.steering, seed, n);
                    ep.settings.walker.anticipate_people = c.anticipate_people;
                    let t = Instant::now();
                    let take = run_crowd(parts, &ep.world, &ep.agents, &ep.settings, |_, _| {})
                        .map_err(|source| EvalError::Crowd {
                            scenario: name.clone(),
                            controller: c.name.clone(),
                            episode: n,
                            source,
                        })?;
                    let wall_s = t.elapsed().as_secs_f64();
                    let mut r = measure(
                        body,
                        &ep.world,
                        &take,
                        name.clone(),
                        c.name.clone(),
                        n,
                        wall_s,
                    )
                    .map_err(|source| EvalError::Pose {
                        scenario: name.clone(),
                        controller: c.name.clone(),
                        episode: n,
                        source,
                    })?;
                    let line = diversity_line(scenario).is_some();
                    if !line {
                        r.pelvis_path.clear();
                    }
                    let keep = n == 0 || line;
                    Ok((r, keep.then_some(take), ep.world))
                })
                .collect::<Result<_, EvalError>>()?;
            let mut takes = Vec::new();
            let mut world = None;
            let mut eps = Vec::with_capacity(results.len());
            for (r, take, w) in results {
                if let Some(t) = take {
                    takes.push(t);
                    world.get_or_insert(w);
                }
                eps.push(r);
            }
            out.rows.push(row(&eps, diversity_line(scenario)));
            out.episodes.extend(eps);
            if let Some(world) = world {
                out.pictures.push(Picture {
                    scenario,
                    controller: c.name.clone(),
                    world,
                    takes,
                });
            }
            progress(out.rows.len(), total, &format!("{name} {}", c.name));
        }
    }
    out.wall_s = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// Table 2's apartment: held-out start/goal pairs this far apart (m), and EgoGen's 13
/// primitives per walk.
pub(crate) const TABLE2_SCENE: &str = "assets/scenes/apartment.glb";
pub(crate) const TABLE2_PAIR_DISTANCE_M: (f64, f64) = (2.0, 7.0);
pub(crate) const TABLE2_MAX_PRIMITIVES: usize = 13;

/// Table 2's policies (paper Tab. 2: egocentric sensing against a local map, in the
/// apartment): the shipped policy's apartment stage and the same two runs observing a local
/// map instead of the rays; then the continuations that led to the shipped policy (pace,
/// crowds, doors closed, then floor plans with or without the cost for looking off the goal,
/// with one set of weights or weights by scene) and the Eq. 11 one beside them. Label,
/// weights, configs.
pub(crate) const TABLE2_POLICIES: [(&str, &str, &str); 10] = [
    (
        "egocentric sensing (32 rays)",
        "assets/policy/apartment/policy.safetensors",
        "configs/train_policy.toml, then configs/train_policy_apartment.toml",
    ),
    (
        "local map 0.8 m",
        "assets/policy/table2/local_map_0.8m.safetensors",
        "configs/table2/local_map_0.8m.toml, then configs/table2/local_map_0.8m_apartment.toml",
    ),
    (
        "local map 7 m",
        "assets/policy/table2/local_map_7m.safetensors",
        "configs/table2/local_map_7m.toml, then configs/table2/local_map_7m_apartment.toml",
    ),
    (
        "egocentric sensing, + pace",
        "assets/policy/pace/policy.safetensors",
        "the 32-ray policy's configs, then configs/train_policy_pace.toml",
    ),
    (
        "egocentric sensing, + pace + crowds",
        "assets/policy/crowd/policy.safetensors",
        "the pace policy's configs, then configs/train_policy_crowd.toml",
    ),
    (
        "egocentric sensing, + pace + crowds + doors closed",
        "assets/policy/indoors/policy.safetensors",
        "the crowd policy's configs, then configs/train_policy_indoors.toml",
    ),
    (
        "egocentric sensing, + pace + crowds + doors closed + floor plans",
        "assets/policy/rooms/policy.safetensors",
        "the doors-closed policy's configs, then configs/train_policy_rooms.toml",
    ),
    (
        "egocentric sensing, + pace + crowds + doors closed + floor plans, looking at the goal",
        "assets/policy/gaze/policy.safetensors",
        "the doors-closed policy's configs, then configs/train_policy_gaze.toml",
    ),
    (
        "egocentric sensing, + pace + crowds + doors closed + floor plans, looking at the goal, weights by scene (shipped)",
        "assets/policy/scene_weights/policy.safetensors",
        "the doors-closed policy's configs, then configs/train_policy_scene_weights.toml",
    ),
    (
        "egocentric sensing, + pace + crowds + doors closed + Eq. 11",
        "assets/policy/eq11/policy.safetensors",
        "the doors-closed policy's configs, then configs/train_policy_eq11.toml",
    ),
];

/// The shipped policy's training run and its ablations (paper Tab. 3), each trained with the
/// same budget: label, weights, the config that trains them.
pub(crate) const TABLE3_POLICIES: [(&str, &str, &str); 4] = [
    (
        "full (pretraining + attention reward)",
        "assets/policy/policy.safetensors",
        "configs/train_policy.toml",
    ),
    (
        "no pretraining",
        "assets/policy/ablations/no_pretraining.safetensors",
        "configs/ablations/no_pretraining.toml",
    ),
    (
        "no attention reward",
        "assets/policy/ablations/no_attention.safetensors",
        "configs/ablations/no_attention.toml",
    ),
    (
        "egocentric depth (16 × 32 depth image, CNN)",
        "assets/policy/ablations/egocentric_depth.safetensors",
        "configs/ablations/egocentric_depth.toml",
    ),
];
