//! The evaluation suites (`egogen eval`): Table 1's scenarios walked by each controller, the
//! speed suite, Table 2 (policies observing rays or a local map, in the apartment) and Table 3
//! (the ablated policies on held-out box scenes and crossings); each writes its results under
//! `OUT/results/` — the rows as JSON, every episode as JSON lines, top views of the paths — then
//! `OUT/RESULTS.md` is rendered from every table's results there ([`super::report`]). A
//! table's existing results are refused unless `force` (nothing is overwritten unasked).
//! `cli::eval_jobs` parses the command line and loads the shipped parts.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::files::{read_json, KeptRows, PolicyRow, PolicyRowsFile, RowsFile};
use super::report::results_markdown;
use super::scenarios::{Scenario, ARRIVAL_M, SUCCESS_M};
use super::suite::{run_table, NamedController};
use super::suite::{
    TABLE2_MAX_PRIMITIVES, TABLE2_PAIR_DISTANCE_M, TABLE2_POLICIES, TABLE2_SCENE, TABLE3_POLICIES,
};
use crate::atomic_file::write_atomically;
use crate::body::BodyModel;
use crate::policy::EnvSettings;

/// What an evaluation run is asked (`egogen eval`'s arguments, `cli::eval_jobs::EvalArgs`).
#[derive(Debug, Clone)]
pub struct EvalJob {
    /// table1, table2, table3, speed or report.
    pub suite: String,
    pub episodes: usize,
    pub seed: u64,
    /// Folder of RESULTS.md and results/.
    pub out: PathBuf,
    /// Policy weights (default: the shipped policy).
    pub policy: Option<PathBuf>,
    pub k: usize,
    pub scenarios: Vec<String>,
    pub controllers: Vec<String>,
    pub force: bool,
    pub keep_other_rows: bool,
    pub quiet: bool,
    /// The command as a user would retype it, recorded in the result files.
    pub command_line: String,
}

/// The motion model, body, pose prior and the held-out seed poses every suite uses (loaded by
/// the caller from the shipped files).
pub struct SuiteParts {
    pub body: BodyModel,
    pub model: crate::motion::cvae::MotionModel,
    pub prior: crate::walker::PosePrior,
    pub bank: crate::walker::SeedBank,
    /// The pose embedding norm on the paper's scale, calibrated on the held-out mocap.
    pub pose_norm: Option<crate::eval::files::PoseNormCalibration>,
}

/// Table 2's row beyond the paper: the shipped policy guided round walls
/// (`guide_lookahead_m`, docs/POLICY.md "A guide round walls").
const TABLE2_GUIDED: (&str, &str, &str) = (
    "the shipped policy, guided round walls by an A* path (2 m ahead; not the paper's)",
    "assets/policy/scene_weights/policy.safetensors",
    "the shipped row's, walked with guide_lookahead_m = 2",
);

/// The guided row's lookahead (m).
const TABLE2_GUIDE_LOOKAHEAD_M: f64 = 2.0;

/// The speed suite's ray-count knob: policies trained with the budget and settings of
/// `configs/train_policy.toml` (whose policy is the 32-ray row), differing only in the rays
/// per scan. Label, weights, config.
const RAYS_POLICIES: [(&str, &str, &str); 4] = [
    (
        "8 rays",
        "assets/policy/knobs/rays_8.safetensors",
        "configs/knobs/rays_8.toml",
    ),
    (
        "16 rays",
        "assets/policy/knobs/rays_16.safetensors",
        "configs/knobs/rays_16.toml",
    ),
    (
        "32 rays (the paper's)",
        "assets/policy/policy.safetensors",
        "configs/train_policy.toml",
    ),
    (
        "64 rays",
        "assets/policy/knobs/rays_64.safetensors",
        "configs/knobs/rays_64.toml",
    ),
];

/// The speed suite's policy-width knob: policies trained with the budget and settings of
/// `configs/train_policy.toml` (whose policy is the 128-wide row), differing only in the GRU
/// width H (the MLPs are 2H + 4F wide). Label, weights, config.
const WIDTH_POLICIES: [(&str, &str, &str); 3] = [
    (
        "H = 64",
        "assets/policy/knobs/width_64.safetensors",
        "configs/knobs/width_64.toml",
    ),
    (
        "H = 128 (shipped width)",
        "assets/policy/policy.safetensors",
        "configs/train_policy.toml",
    ),
    (
        "H = 256",
        "assets/policy/knobs/width_256.safetensors",
        "configs/knobs/width_256.toml",
    ),
];

/// The speed suite's SDF-resolution knob: voxel sizes of the apartment's 3D SDF (m).
const SDF_VOXELS_M: [f64; 4] = [0.2, 0.1, 0.05, 0.025];

/// The files a suite writes under `OUT/results/`.
fn suite_files(out: &Path, suite: &str) -> Vec<PathBuf> {
    let results = out.join("results");
    match suite {
        "table1" => vec![
            results.join("table1.json"),
            results.join("table1_episodes.jsonl"),
        ],
        "speed" => vec![
            results.join("speed.json"),
            results.join("speed_episodes.jsonl"),
            results.join("rays.json"),
            results.join("width.json"),
            results.join("sdf.json"),
        ],
        "table2" => vec![results.join("table2.json")],
        _ => vec![results.join("table3.json")],
    }
}

/// The speed suite's scenarios unless `--scenarios` names others, and its sampling K.
const SPEED_SCENARIOS: [&str; 2] = ["moving_obstacle", "circle_4"];
const SPEED_KS: [usize; 4] = [4, 8, 16, 32];

/// The rows and episodes of an earlier `table1.json` that a run keeps.
struct KeptTable {
    rows: Vec<super::metrics::Row>,
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

fn bar(args: &EvalJob, total: usize, unit: &str) -> indicatif::ProgressBar {
    match !args.quiet {
        true => crate::progress::progress_bar("egogen eval", "evaluating", unit, total as u64, 0),
        false => indicatif::ProgressBar::hidden(),
    }
}

/// Runs the suite, writes its files and renders `OUT/RESULTS.md` from every suite's results
/// there (see the module docs).
pub fn run_eval(args: &EvalJob, load_parts: impl FnOnce() -> Result<SuiteParts>) -> Result<()> {
    if !matches!(
        args.suite.as_str(),
        "table1" | "table2" | "table3" | "speed" | "report"
    ) {
        bail!(
            "--suite {}: expected \"table1\", \"table2\", \"table3\", \"speed\" or \"report\"",
            args.suite
        );
    }
    if args.suite == "report" {
        if !args.out.join("results").is_dir() {
            bail!(
                "--suite report: {} has no results/ folder to report (run a suite first)",
                args.out.display()
            );
        }
        return write_results_markdown(&args.out);
    }
    if args.episodes == 0 || args.k == 0 {
        bail!("--episodes and --k must be at least 1");
    }
    if args.keep_other_rows && args.suite != "table1" {
        bail!("--keep-other-rows: only Table 1 keeps rows (--suite table1)");
    }
    if !args.force && !args.keep_other_rows {
        if let Some(f) = suite_files(&args.out, &args.suite)
            .iter()
            .find(|f| f.exists())
        {
            bail!(
                "{} exists: give --force to replace the results in {}",
                f.display(),
                args.out.display()
            );
        }
    }
    let mut scenarios = chosen_scenarios(&args.scenarios)?;
    if args.suite == "speed" && args.scenarios.is_empty() {
        scenarios.retain(|s| SPEED_SCENARIOS.contains(&s.name().as_str()));
    }
    let common = load_parts()?;
    let results = args.out.join("results");
    std::fs::create_dir_all(&results).with_context(|| format!("creating {}", results.display()))?;
    match args.suite.as_str() {
        "table1" => table1(args, &common, &scenarios, &results)?,
        "speed" => speed(args, &common, &scenarios, &results)?,
        "table2" => table2(args, &common, &results)?,
        _ => table3(args, &common, &results)?,
    }
    write_results_markdown(&args.out)
}

/// Rewrites OUT/RESULTS.md from the results in OUT/results.
fn write_results_markdown(out: &Path) -> Result<()> {
    let md = results_markdown(out)?;
    write_atomically(&out.join("RESULTS.md"), md.as_bytes())?;
    println!("wrote {}", out.join("RESULTS.md").display());
    Ok(())
}

fn chosen_scenarios(names: &[String]) -> Result<Vec<Scenario>> {
    let all = Scenario::table1();
    if names.is_empty() {
        return Ok(all);
    }
    names
        .iter()
        .map(|name| {
            all.iter()
                .copied()
                .find(|s| &s.name() == name)
                .with_context(|| {
                    format!(
                        "--scenarios: no scenario \"{name}\"; expected some of {}",
                        all.iter().map(|s| s.name()).collect::<Vec<_>>().join(", ")
                    )
                })
        })
        .collect()
}

/// The controllers named (all when none is), or an error naming the unknown one. Besides the
/// suite's own, `policy_spread_S` names the policy with its sampled actions' standard deviation
/// scaled by S (e.g. `policy_spread_0.5`; 1 is `policy`, 0 draws the mean), and
/// `policy_as_placed` and `policy_mean_as_placed` the policy in EgoGen's crowd loop.
fn chosen_controllers(
    mut all: Vec<NamedController>,
    names: &[String],
) -> Result<Vec<NamedController>> {
    for c in NamedController::policies_as_placed() {
        if names.contains(&c.name) && !all.iter().any(|a| a.name == c.name) {
            all.push(c);
        }
    }
    for name in names {
        let Some(s) = name.strip_prefix("policy_spread_") else {
            continue;
        };
        let spread: f32 = s
            .parse()
            .ok()
            .filter(|x: &f32| x.is_finite() && *x >= 0.0)
            .with_context(|| {
                format!("--controllers: \"{name}\": expected policy_spread_S with a scale S ≥ 0")
            })?;
        if !all.iter().any(|c| &c.name == name) {
            all.push(NamedController::policy_spread(name, spread));
        }
    }
    if let Some(name) = names.iter().find(|n| !all.iter().any(|c| &&c.name == n)) {
        bail!(
            "--controllers: no controller \"{name}\" in this suite; expected some of {}",
            all.iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(all
        .into_iter()
        .filter(|c| names.is_empty() || names.contains(&c.name))
        .collect())
}

/// Runs every scenario × controller with the policy of `--policy` (default the shipped one),
/// writes `<name>_episodes.jsonl` and then `<name>.json` (after `before_summary`, given the
/// run: Table 1 draws its pictures there); `k` is recorded when the rows use one.
#[allow(clippy::too_many_arguments)]
fn run_rows(
    args: &EvalJob,
    c: &SuiteParts,
    scenarios: &[Scenario],
    controllers: &[NamedController],
    results: &Path,
    name: &str,
    k: Option<usize>,
    before_summary: impl FnOnce(&super::suite::TableRun) -> Result<()>,
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

fn speed(args: &EvalJob, c: &SuiteParts, scenarios: &[Scenario], results: &Path) -> Result<()> {
    let controllers = chosen_controllers(NamedController::speed(&SPEED_KS), &args.controllers)?;
    run_rows(
        args,
        c,
        scenarios,
        &controllers,
        results,
        "speed",
        None,
        |_| Ok(()),
    )?;
    // The ray-count knob: each policy on held-out box scenes and crossings.
    box_and_crossing_rows(args, c, &RAYS_POLICIES, &results.join("rays.json"))?;
    // The policy-width knob, the same way.
    box_and_crossing_rows(args, c, &WIDTH_POLICIES, &results.join("width.json"))?;
    let ctx = crate::motion::cvae::BodyContext::new(&c.body, &[])?;
    sdf_rows(args, c, &ctx, results)
}

/// The speed suite's SDF-resolution knob: the shipped policy (mean action) on Table 2's
/// apartment pairs, scene penetration (Eq. 11) measured on 3D SDFs of each voxel size.
fn sdf_rows(
    args: &EvalJob,
    c: &SuiteParts,
    ctx: &crate::motion::cvae::BodyContext,
    results: &Path,
) -> Result<()> {
    use crate::eval::policy_tasks::{evaluate, HeldOutController};
    use crate::motion::cvae::infer::InferBackend;
    use crate::policy::env::EnvParts;
    let t0 = std::time::Instant::now();
    let shipped = crate::policy::weights::SHIPPED_POLICY;
    let config = crate::policy::weights::SHIPPED_POLICY_CONFIG;
    let net = table_policy(c, (shipped, config))?;
    let controller: HeldOutController<InferBackend> = HeldOutController::Policy {
        net: &net,
        mean_action: true,
        spread: 1.0,
    };
    let progress = bar(args, SDF_VOXELS_M.len(), "SDF resolutions");
    let mut rows = Vec::new();
    for voxel_m in SDF_VOXELS_M {
        let built = std::time::Instant::now();
        let fixed = table2_scene(args, voxel_m)?;
        let setup_s = built.elapsed().as_secs_f64();
        let parts = EnvParts {
            model: &c.model,
            body: ctx,
            bank: &c.bank,
            prior: &c.prior,
            fixed: Some(&fixed),
        };
        let (report, _) = evaluate(
            &parts,
            table2_settings(),
            &controller,
            (args.episodes, 50, args.seed),
            |_| {},
        )?;
        let mut row = PolicyRow::new(
            ("shipped policy", shipped, config),
            &format!("apartment, SDF voxel {voxel_m} m"),
            "mean",
            &report,
            true,
        );
        row.setup_s = Some(setup_s);
        rows.push(row);
        progress.inc(1);
    }
    progress.finish_and_clear();
    write_policy_rows(&results.join("sdf.json"), args, c, t0, rows)
}

/// The rows run now beside those kept, in the table's order: scenarios as
/// `Scenario::table1`, controllers as `NamedController::table1`, any others after.
fn merged_rows(
    keep: Option<&KeptTable>,
    run: Vec<super::metrics::Row>,
    k: Option<usize>,
) -> Vec<super::metrics::Row> {
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

fn table1(args: &EvalJob, c: &SuiteParts, scenarios: &[Scenario], results: &Path) -> Result<()> {
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

/// A trained policy of a table, or an error saying which config trains it.
fn table_policy(
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
fn policy_rows(
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

fn write_policy_rows(
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

/// Table 2's apartment with its first `--episodes` held-out pairs and an SDF of `voxel_m`.
fn table2_scene(args: &EvalJob, voxel_m: f64) -> Result<crate::policy::env::FixedScene> {
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
fn table2_settings() -> EnvSettings {
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
fn table2(args: &EvalJob, c: &SuiteParts, results: &Path) -> Result<()> {
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

/// Table 2's baseline (GAMMA*/DIMOS* in spirit): each apartment pair walked by the A*
/// path follower (`--k` latents per primitive, the one that follows the planned path best
/// kept; no policy), through the crowd stepping of Table 1 with one person. Its seed poses
/// and draws are the crowd's, not the environment's; Eq. 11 is not measured there.
fn path_follow_row(
    args: &EvalJob,
    c: &SuiteParts,
    fixed: &crate::policy::env::FixedScene,
) -> Result<PolicyRow> {
    use super::metrics::AgentResult;
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
            let r = super::metrics::measure(
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

/// Table 3: the ablated policies of [`TABLE3_POLICIES`] on held-out box scenes and crossings.
fn table3(args: &EvalJob, c: &SuiteParts, results: &Path) -> Result<()> {
    box_and_crossing_rows(args, c, &TABLE3_POLICIES, &results.join("table3.json"))
}

/// Each of `policies` (label, weights, config) on held-out box scenes and crossings, sampled
/// and mean actions, written to `file`.
fn box_and_crossing_rows(
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

/// A path as shown in the report: relative to the crate's folder when it is inside it.
fn relative(path: &Path) -> String {
    path.strip_prefix(crate::paths::crate_root())
        .unwrap_or(path)
        .display()
        .to_string()
}
