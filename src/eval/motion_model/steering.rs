//! Walks steered to goals (`egogen motion eval --steer-goal-m`): one 10 s walk to a goal ahead,
//! and probes to goals ahead, left, right and behind from spread training seeds.

use anyhow::{bail, Result};

use super::set_seed;

/// Latents drawn per primitive of the steered walk (`egogen motion eval --steer-goal-m`).
const STEER_CANDIDATES: usize = 16;

/// Primitives of the steered walk: 10 s at 40 Hz, 18 new frames each.
const STEER_PRIMITIVES: usize = 23;

/// Walks steered by [`steer_probes`]: 8 to each of 4 bearings.
const STEER_PROBES: usize = 32;

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
pub(super) fn steer_probes(
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
pub(super) fn steered_walk(
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
