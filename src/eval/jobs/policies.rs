//! Rows of trained policies over held-out episodes: a table's policy loaded, a row per policy ×
//! set × actions and their file; the held-out box scenes and crossings of Table 3 and the speed
//! suite's knobs.

use std::path::Path;

use anyhow::{bail, Result};

use super::{bar, EvalJob, SuiteParts};
use crate::atomic_file::write_atomically;
use crate::eval::files::{PolicyRow, PolicyRowsFile};
use crate::eval::scenarios::{ARRIVAL_M, SUCCESS_M};
use crate::eval::suite::TABLE3_POLICIES;
use crate::policy::EnvSettings;

/// A trained policy of a table, or an error saying which config trains it.
pub(super) fn table_policy(
    c: &SuiteParts,
    (weights, config): (&str, &str),
) -> Result<crate::policy::net::ActorCritic<crate::motion::cvae::infer::InferBackend>> {
    let path = crate::paths::crate_root().join(weights);
    if !path.is_file() {
        bail!(
            "{}: not found; it is trained by `egogen train policy --config` with {config}",
            path.display()
        );
    }
    Ok(crate::policy::weights::load_policy_for(&path, &c.model)?)
}

/// Every policy on every set of episodes, with sampled and with mean actions: a row each.
pub(super) fn policy_rows(
    args: &EvalJob,
    c: &SuiteParts,
    parts: &crate::policy::env::EnvParts,
    policies: &[(&str, &str, &str)],
    sets: &[(&str, EnvSettings)],
    progress: &indicatif::ProgressBar,
) -> Result<Vec<PolicyRow>> {
    use crate::eval::policy_tasks::{evaluate, HeldOutController};
    use crate::motion::cvae::infer::InferBackend;
    let mut rows = Vec::new();
    for &(label, weights, config) in policies {
        let net = table_policy(c, (weights, config))?;
        for &(set, settings) in sets {
            for mean_action in [false, true] {
                let controller: HeldOutController<InferBackend> = HeldOutController::Policy {
                    net: &net,
                    mean_action,
                    spread: 1.0,
                };
                let (report, _) = evaluate(
                    parts,
                    settings,
                    &controller,
                    (args.episodes, 50, args.seed),
                    |_| {},
                )?;
                let actions = if mean_action { "mean" } else { "sampled" };
                let scene = parts.fixed.is_some();
                rows.push(PolicyRow::new(
                    (label, weights, config),
                    set,
                    actions,
                    &report,
                    scene,
                ));
                progress.inc(1);
            }
        }
    }
    Ok(rows)
}

pub(super) fn write_policy_rows(
    path: &Path,
    args: &EvalJob,
    c: &SuiteParts,
    t0: std::time::Instant,
    rows: Vec<PolicyRow>,
) -> Result<()> {
    let file = PolicyRowsFile {
        command: args.command_line.clone(),
        episodes: args.episodes,
        seed: args.seed,
        wall_s: t0.elapsed().as_secs_f64(),
        rows,
        pose_norm: c.pose_norm,
    };
    write_atomically(path, serde_json::to_string_pretty(&file)?.as_bytes())?;
    println!("{} rows in {:.0} s", file.rows.len(), file.wall_s);
    Ok(())
}

/// The evaluation's parts for held-out box scenes and crossings.
fn box_scene_parts<'m>(
    c: &'m SuiteParts,
    ctx: &'m crate::motion::cvae::BodyContext<'m>,
) -> crate::policy::env::EnvParts<'m> {
    crate::policy::env::EnvParts {
        model: &c.model,
        body: ctx,
        bank: &c.bank,
        prior: &c.prior,
        fixed: None,
        dwellings: &[],
    }
}

/// Held-out box scenes and held-out crossings, walks going on to 0.1 m, success within 0.3 m
/// where they end.
fn box_and_crossing_sets() -> Vec<(&'static str, EnvSettings)> {
    [("box scenes", 0.0), ("crossings", 1.0)]
        .into_iter()
        .map(|(set, crossing_share)| {
            let defaults = EnvSettings::default();
            let settings = EnvSettings {
                walker: crate::walker::WalkerSettings {
                    success_m: SUCCESS_M,
                    ..defaults.walker
                },
                arrival_m: Some(ARRIVAL_M),
                crossing: crate::scene::generated::crossing_scene::CrossingSettings {
                    share: crossing_share,
                    ..defaults.crossing
                },
                ..defaults
            };
            (set, settings)
        })
        .collect()
}

/// Table 3: the ablated policies of [`TABLE3_POLICIES`] on held-out box scenes and crossings.
pub(super) fn table3(args: &EvalJob, c: &SuiteParts, results: &Path) -> Result<()> {
    box_and_crossing_rows(args, c, &TABLE3_POLICIES, &results.join("table3.json"))
}

/// Each of `policies` (label, weights, config) on held-out box scenes and crossings, sampled
/// and mean actions, written to `file`.
pub(super) fn box_and_crossing_rows(
    args: &EvalJob,
    c: &SuiteParts,
    policies: &[(&str, &str, &str)],
    file: &Path,
) -> Result<()> {
    let t0 = std::time::Instant::now();
    let ctx = crate::motion::cvae::BodyContext::new(&c.body, &[])?;
    let sets = box_and_crossing_sets();
    let progress = bar(
        args,
        policies.len() * sets.len() * 2,
        "policy × set × actions rows",
    );
    let rows = policy_rows(
        args,
        c,
        &box_scene_parts(c, &ctx),
        policies,
        &sets,
        &progress,
    )?;
    progress.finish_and_clear();
    write_policy_rows(file, args, c, t0, rows)
}
