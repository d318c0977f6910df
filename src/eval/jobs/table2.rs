//! Table 2: the apartment's held-out start/goal pairs walked by each policy, the guided row, the
//! sampling controller and the A* path follower.

use std::path::Path;

use anyhow::{Context, Result};

use super::policies::{policy_rows, write_policy_rows};
use super::{bar, EvalJob, SuiteParts};
use crate::eval::files::PolicyRow;
use crate::eval::scenarios::{ARRIVAL_M, SUCCESS_M};
use crate::eval::suite::{
    TABLE2_MAX_PRIMITIVES, TABLE2_PAIR_DISTANCE_M, TABLE2_POLICIES, TABLE2_SCENE,
};
use crate::policy::EnvSettings;

/// Table 2's row beyond the paper: the shipped policy guided round walls
/// (`guide_lookahead_m`, docs/POLICY.md "A guide round walls").
const TABLE2_GUIDED: (&str, &str, &str) = (
    "the shipped policy, guided round walls by an A* path (2 m ahead; not the paper's)",
    "assets/policy/scene_weights/policy.safetensors",
    "the shipped row's, walked with guide_lookahead_m = 2",
);

/// The guided row's lookahead (m).
const TABLE2_GUIDE_LOOKAHEAD_M: f64 = 2.0;

/// Table 2's apartment with its first `--episodes` held-out pairs and an SDF of `voxel_m`.
pub(super) fn table2_scene(args: &EvalJob, voxel_m: f64) -> Result<crate::policy::env::FixedScene> {
    crate::policy::fixed_scene::held_out_scene(
        &crate::paths::crate_root().join(TABLE2_SCENE),
        Default::default(),
        args.episodes,
        TABLE2_PAIR_DISTANCE_M,
        false,
        true,
        args.seed,
        voxel_m,
    )
}

/// Table 2's episodes: walks going on to 0.1 m, success within 0.3 m where they end, EgoGen's
/// 13 primitives in the apartment.
pub(super) fn table2_settings() -> EnvSettings {
    EnvSettings {
        walker: crate::walker::WalkerSettings {
            success_m: SUCCESS_M,
            max_primitives_per_goal: TABLE2_MAX_PRIMITIVES,
            ..crate::walker::WalkerSettings::PAPER
        },
        arrival_m: Some(ARRIVAL_M),
        ..EnvSettings::default()
    }
}

/// Table 2: the apartment's held-out start/goal pairs, walked by each policy of
/// [`TABLE2_POLICIES`] and by the sampling controller (`--k` latents, no policy).
pub(super) fn table2(args: &EvalJob, c: &SuiteParts, results: &Path) -> Result<()> {
    use crate::eval::policy_tasks::{evaluate, HeldOutController};
    use crate::motion::cvae::infer::InferBackend;
    use crate::policy::env::EnvParts;
    let t0 = std::time::Instant::now();
    let ctx = crate::motion::cvae::BodyContext::new(&c.body, &[])?;
    let fixed = table2_scene(args, crate::scene::sdf3d::DEFAULT_VOXEL_M)?;
    let parts = EnvParts {
        model: &c.model,
        body: &ctx,
        bank: &c.bank,
        prior: &c.prior,
        fixed: Some(&fixed),
        dwellings: &[],
    };
    let settings = table2_settings();
    // Each policy sampled and mean, the guided row likewise, sampling, path following.
    let progress = bar(args, TABLE2_POLICIES.len() * 2 + 4, "policy × actions rows");
    let mut rows = policy_rows(
        args,
        c,
        &parts,
        &TABLE2_POLICIES,
        &[("apartment", settings)],
        &progress,
    )?;
    // Beyond the paper: the shipped policy shown the way round walls by an A* path.
    let guided = EnvSettings {
        walker: crate::walker::WalkerSettings {
            guide_lookahead_m: TABLE2_GUIDE_LOOKAHEAD_M,
            ..settings.walker
        },
        ..settings
    };
    rows.extend(policy_rows(
        args,
        c,
        &parts,
        &[TABLE2_GUIDED],
        &[("apartment", guided)],
        &progress,
    )?);
    let sampling: HeldOutController<InferBackend> =
        HeldOutController::Walker(crate::walker::ControllerSpec::Sampling { k: args.k });
    let (report, _) = evaluate(
        &parts,
        settings,
        &sampling,
        (args.episodes, 50, args.seed),
        |_| {},
    )?;
    rows.push(PolicyRow::new(
        (
            "sampling controller (no policy)",
            "",
            "none: the motion model alone",
        ),
        "apartment",
        &format!("best of {}", args.k),
        &report,
        true,
    ));
    progress.inc(1);
    rows.push(path_follow_row(args, c, &fixed)?);
    progress.finish_and_clear();
    write_policy_rows(&results.join("table2.json"), args, c, t0, rows)
}

/// Table 2's baseline (GAMMA*/DIMOS* in spirit): each apartment pair walked by the A*
/// path follower (`--k` latents per primitive, the one that follows the planned path best
/// kept; no policy), through the crowd stepping of Table 1 with one person. Its seed poses
/// and draws are the crowd's, not the environment's; Eq. 11 is not measured there.
fn path_follow_row(
    args: &EvalJob,
    c: &SuiteParts,
    fixed: &crate::policy::env::FixedScene,
) -> Result<PolicyRow> {
    use crate::eval::metrics::AgentResult;
    use crate::math::Quantiles;
    use crate::synth::crowd::{run_crowd, AgentPlan, CrowdParts, CrowdSettings, CrowdWorld};
    use crate::walker::ControllerSpec;
    use rayon::prelude::*;
    let t0 = std::time::Instant::now();
    let parts = CrowdParts {
        model: &c.model,
        body_model: &c.body,
        prior: &c.prior,
        bank: &c.bank,
        policy: None,
    };
    let world = CrowdWorld {
        map: fixed.map.clone(),
        region: None,
        obstacles: Vec::new(),
        moving: Vec::new(),
    };
    let pairs = &fixed.pairs[..args.episodes.min(fixed.pairs.len())];
    let agents: Vec<AgentResult> = pairs
        .par_iter()
        .enumerate()
        .map(|(n, pair)| {
            let plan = AgentPlan {
                name: "person".into(),
                betas: Vec::new(),
                start: pair.start,
                facing_rad: None,
                goals: vec![pair.goal],
                wander: false,
                steering: ControllerSpec::PathFollow { k: args.k },
            };
            let settings = CrowdSettings {
                walker: crate::walker::WalkerSettings {
                    success_m: SUCCESS_M,
                    max_primitives_per_goal: TABLE2_MAX_PRIMITIVES,
                    ..crate::walker::WalkerSettings::default().unguided()
                },
                arrival_m: Some(ARRIVAL_M),
                primitives: TABLE2_MAX_PRIMITIVES,
                stop_when_done: true,
                seed: args.seed.rotate_left(24) ^ n as u64,
                ..CrowdSettings::default()
            };
            let take = run_crowd(&parts, &world, &[plan], &settings, |_, _| {})
                .with_context(|| format!("Table 2, path following, pair {n}"))?;
            let r = crate::eval::metrics::measure(
                &c.body,
                &world,
                &take,
                "apartment".into(),
                "path_follow".into(),
                n as u64,
                0.0,
            )?;
            Ok(r.agents.into_iter().next().expect("one person"))
        })
        .collect::<Result<_>>()?;
    let n = agents.len().max(1) as f64;
    let mean = |f: &dyn Fn(&AgentResult) -> f64| agents.iter().map(f).sum::<f64>() / n;
    // The same quantiles as the environment's evaluation reports.
    let distance = Quantiles::of(agents.iter().map(|a| a.final_distance_m));
    let speed = Quantiles::of(agents.iter().filter(|a| a.reached).map(|a| a.speed_m_s));
    Ok(PolicyRow {
        policy: "A* path following (no policy)".into(),
        weights: String::new(),
        config: "none: the motion model and the walkable map".into(),
        set: "apartment".into(),
        actions: format!("best of {}", args.k),
        episodes: agents.len(),
        success_rate: mean(&|a| f64::from(u8::from(a.reached))),
        contact: mean(&|a| a.contact),
        penetration_share: 0.0,
        scene_penetration_share: None,
        view_cos: mean(&|a| a.view_cos),
        final_distance_median_m: distance.p50,
        final_distance_mean_m: Some(distance.mean),
        pose_norm_max_mean: None,
        speed_successful_median_m_s: speed.p50,
        wall_s: t0.elapsed().as_secs_f64(),
        setup_s: None,
    })
}
