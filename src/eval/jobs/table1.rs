//! Table 1: every scenario × controller walked as crowd takes, its rows, episodes and pictures,
//! and with `--keep-other-rows` the earlier rows this run keeps; the speed suite's scenario rows
//! run the same way.

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::{bar, chosen_controllers, EvalJob, SuiteParts};
use crate::atomic_file::write_atomically;
use crate::eval::files::{read_json, KeptRows, RowsFile};
use crate::eval::scenarios::Scenario;
use crate::eval::suite::{run_table, NamedController};

/// The rows and episodes of an earlier `table1.json` that a run keeps.
struct KeptTable {
    rows: Vec<crate::eval::metrics::Row>,
    /// Its episodes' JSON lines of the kept rows.
    episode_lines: Vec<String>,
    kept: Vec<KeptRows>,
}

fn row_key(scenario: &str, controller: &str) -> String {
    format!("{scenario}/{controller}")
}

/// With `--keep-other-rows`: the rows of `results/table1.json` this run does not measure
/// (every row but those of the scenarios × controllers run now), checked to be comparable —
/// same episodes, seed and K, and no row steered by a policy other than this run's.
fn kept_table1_rows(
    args: &EvalJob,
    results: &Path,
    scenarios: &[Scenario],
    controllers: &[NamedController],
    policy: &str,
) -> Result<KeptTable> {
    let json = results.join("table1.json");
    let earlier: RowsFile = read_json(&json)?.with_context(|| {
        format!(
            "--keep-other-rows: {} does not exist, there are no rows to keep",
            json.display()
        )
    })?;
    let differs = |field: &str, was: String, now: String| {
        anyhow::anyhow!(
            "--keep-other-rows: {}: field \"{field}\" is {was}, this run's is {now}; \
             rows are only kept beside rows measured alike",
            json.display()
        )
    };
    if earlier.episodes != args.episodes {
        return Err(differs(
            "episodes",
            earlier.episodes.to_string(),
            args.episodes.to_string(),
        ));
    }
    if earlier.seed != args.seed {
        return Err(differs(
            "seed",
            earlier.seed.to_string(),
            args.seed.to_string(),
        ));
    }
    if earlier.k != Some(args.k) {
        return Err(differs(
            "k",
            earlier.k.map_or("missing".into(), |k| k.to_string()),
            args.k.to_string(),
        ));
    }
    let run_now: std::collections::HashSet<String> = scenarios
        .iter()
        .flat_map(|s| controllers.iter().map(move |c| row_key(&s.name(), &c.name)))
        .collect();
    // Who measured each earlier row: a run it kept rows from, else the earlier run itself.
    let measured_by = |key: &str| -> (String, String, f64) {
        earlier
            .kept
            .iter()
            .find(|k| k.rows.iter().any(|r| r == key))
            .map_or(
                (
                    earlier.command.clone(),
                    earlier.policy.clone(),
                    earlier.wall_s,
                ),
                |k| (k.command.clone(), k.policy.clone(), k.wall_s),
            )
    };
    let mut kept: Vec<KeptRows> = Vec::new();
    let mut rows = Vec::new();
    for row in &earlier.rows {
        let key = row_key(&row.scenario, &row.controller);
        if run_now.contains(&key) {
            continue;
        }
        let (command, by_policy, wall_s) = measured_by(&key);
        if row.controller.starts_with("policy") && by_policy != policy {
            bail!(
                "--keep-other-rows: the row {key} of {} was steered by {by_policy}, this run's \
                 policy is {policy}: run it again (name {} in --controllers)",
                json.display(),
                row.controller
            );
        }
        match kept.iter_mut().find(|k| k.command == command) {
            Some(k) => k.rows.push(key),
            None => kept.push(KeptRows {
                command,
                policy: by_policy,
                wall_s,
                rows: vec![key],
            }),
        }
        rows.push(row.clone());
    }
    let episodes_path = results.join("table1_episodes.jsonl");
    let text = std::fs::read_to_string(&episodes_path)
        .with_context(|| format!("--keep-other-rows: reading {}", episodes_path.display()))?;
    let mut episode_lines = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let e: serde_json::Value = serde_json::from_str(line).with_context(|| {
            format!(
                "{} line {}: not an episode's JSON",
                episodes_path.display(),
                n + 1
            )
        })?;
        let (Some(s), Some(c)) = (e["scenario"].as_str(), e["controller"].as_str()) else {
            bail!(
                "{} line {}: expected the fields \"scenario\" and \"controller\"",
                episodes_path.display(),
                n + 1
            );
        };
        if rows.iter().any(|r| r.scenario == s && r.controller == c) {
            episode_lines.push(line.to_string());
        }
    }
    Ok(KeptTable {
        rows,
        episode_lines,
        kept,
    })
}

/// Runs every scenario × controller with the policy of `--policy` (default the shipped one),
/// writes `<name>_episodes.jsonl` and then `<name>.json` (after `before_summary`, given the
/// run: Table 1 draws its pictures there); `k` is recorded when the rows use one.
#[allow(clippy::too_many_arguments)]
pub(super) fn run_rows(
    args: &EvalJob,
    c: &SuiteParts,
    scenarios: &[Scenario],
    controllers: &[NamedController],
    results: &Path,
    name: &str,
    k: Option<usize>,
    before_summary: impl FnOnce(&crate::eval::suite::TableRun) -> Result<()>,
) -> Result<()> {
    let policy_path = args
        .policy
        .clone()
        .unwrap_or_else(crate::policy::weights::shipped_policy_path);
    let keep = if args.keep_other_rows {
        Some(kept_table1_rows(
            args,
            results,
            scenarios,
            controllers,
            &relative(&policy_path),
        )?)
    } else {
        None
    };
    let net = crate::policy::weights::load_policy_for(&policy_path, &c.model)?;
    let actor = crate::policy::Actor::of(&net);
    let parts = crate::synth::crowd::CrowdParts {
        model: &c.model,
        body_model: &c.body,
        prior: &c.prior,
        bank: &c.bank,
        policy: Some(&actor),
    };
    let progress = bar(
        args,
        scenarios.len() * controllers.len(),
        "scenario × controller rows",
    );
    let run = run_table(
        &parts,
        &c.body,
        scenarios,
        controllers,
        args.episodes,
        args.seed,
        |done, _, what| {
            progress.set_message(what.to_string());
            progress.set_position(done as u64);
        },
    )?;
    progress.finish_and_clear();
    let mut lines = String::new();
    for line in keep.iter().flat_map(|k| &k.episode_lines) {
        lines.push_str(line);
        lines.push('\n');
    }
    for e in &run.episodes {
        lines.push_str(&serde_json::to_string(e)?);
        lines.push('\n');
    }
    write_atomically(
        &results.join(format!("{name}_episodes.jsonl")),
        lines.as_bytes(),
    )?;
    before_summary(&run)?;
    let file = RowsFile {
        command: args.command_line.clone(),
        episodes: args.episodes,
        seed: args.seed,
        policy: relative(&policy_path),
        k,
        wall_s: run.wall_s,
        rows: merged_rows(keep.as_ref(), run.rows, k),
        kept: keep.map(|k| k.kept).unwrap_or_default(),
    };
    write_atomically(
        &results.join(format!("{name}.json")),
        serde_json::to_string_pretty(&file)?.as_bytes(),
    )?;
    println!(
        "{} rows, {} episodes each, in {:.0} s",
        file.rows.len(),
        args.episodes,
        file.wall_s
    );
    Ok(())
}

/// The rows run now beside those kept, in the table's order: scenarios as
/// `Scenario::table1`, controllers as `NamedController::table1`, any others after.
fn merged_rows(
    keep: Option<&KeptTable>,
    run: Vec<crate::eval::metrics::Row>,
    k: Option<usize>,
) -> Vec<crate::eval::metrics::Row> {
    let Some(keep) = keep else {
        return run;
    };
    let scenarios: Vec<String> = Scenario::table1().iter().map(|s| s.name()).collect();
    let controllers: Vec<String> = NamedController::table1(k.unwrap_or(16))
        .into_iter()
        .map(|c| c.name)
        .collect();
    let place = |names: &[String], name: &str| names.iter().position(|n| n == name);
    let mut rows: Vec<_> = keep.rows.iter().cloned().chain(run).collect();
    rows.sort_by_key(|r| {
        (
            place(&scenarios, &r.scenario).unwrap_or(usize::MAX),
            place(&controllers, &r.controller).unwrap_or(usize::MAX),
        )
    });
    rows
}

pub(super) fn table1(
    args: &EvalJob,
    c: &SuiteParts,
    scenarios: &[Scenario],
    results: &Path,
) -> Result<()> {
    let controllers = chosen_controllers(NamedController::table1(args.k), &args.controllers)?;
    run_rows(
        args,
        c,
        scenarios,
        &controllers,
        results,
        "table1",
        Some(args.k),
        |run| {
            for p in &run.pictures {
                let name = format!("table1_{}_{}.png", p.scenario.name(), p.controller);
                let takes: Vec<_> = p.takes.iter().collect();
                let pic = crate::synth::crowd_dir::paths_picture(&p.world, &takes, 420);
                let partial = results.join(format!("{name}.partial"));
                pic.image.write_png(&partial)?;
                std::fs::rename(&partial, results.join(&name))
                    .with_context(|| format!("renaming {}", partial.display()))?;
            }
            Ok(())
        },
    )
}

/// A path as shown in the report: relative to the crate's folder when it is inside it.
fn relative(path: &Path) -> String {
    path.strip_prefix(crate::paths::crate_root())
        .unwrap_or(path)
        .display()
        .to_string()
}
