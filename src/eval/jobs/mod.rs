//! The evaluation suites (`egogen eval`): Table 1's scenarios walked by each controller, the
//! speed suite, Table 2 (policies observing rays or a local map, in the apartment) and Table 3
//! (the ablated policies on held-out box scenes and crossings); each writes its results under
//! `OUT/results/` — the rows as JSON, every episode as JSON lines, top views of the paths — then
//! `OUT/RESULTS.md` is rendered from every table's results there ([`super::report`]). A
//! table's existing results are refused unless `force` (nothing is overwritten unasked).
//! `cli::eval_jobs` parses the command line and loads the shipped parts.
//!
//! This file holds the job, its checks and the choice of scenarios and controllers; the suites
//! are `table1`, `speed`, `table2` and, with the rows of trained policies, `policies`.

mod policies;
mod speed;
mod table1;
mod table2;

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::report::results_markdown;
use super::scenarios::Scenario;
use super::suite::NamedController;
use crate::atomic_file::write_atomically;
use crate::body::BodyModel;
use policies::table3;
use speed::{speed, SPEED_SCENARIOS};
use table1::table1;
use table2::table2;

/// Which of `egogen eval`'s suites a run makes (`--suite`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Suite {
    /// Table 1: scenarios with moving obstacles and people, walked by each controller.
    Table1,
    /// Table 2: the apartment, egocentric sensing against a local map.
    Table2,
    /// Table 3: the ablated policies.
    Table3,
    /// The policy against sampling with K = 4, 8, 16, 32 latents, accuracy and time.
    Speed,
    /// Rewrites OUT/RESULTS.md from the results already in OUT/results; runs nothing.
    Report,
}

/// What an evaluation run is asked (`egogen eval`'s arguments, `cli::eval_jobs::EvalArgs`).
#[derive(Debug, Clone)]
pub(crate) struct EvalJob {
    pub suite: Suite,
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
pub(crate) struct SuiteParts {
    pub body: BodyModel,
    pub model: crate::motion::cvae::MotionModel,
    pub prior: crate::walker::PosePrior,
    pub bank: crate::walker::SeedBank,
    /// The pose embedding norm on the paper's scale, calibrated on the held-out mocap.
    pub pose_norm: Option<crate::eval::files::PoseNormCalibration>,
}

/// The files a suite writes under `OUT/results/`.
fn suite_files(out: &Path, suite: Suite) -> Vec<PathBuf> {
    let results = out.join("results");
    match suite {
        Suite::Table1 => vec![
            results.join("table1.json"),
            results.join("table1_episodes.jsonl"),
        ],
        Suite::Speed => vec![
            results.join("speed.json"),
            results.join("speed_episodes.jsonl"),
            results.join("rays.json"),
            results.join("width.json"),
            results.join("sdf.json"),
        ],
        Suite::Table2 => vec![results.join("table2.json")],
        Suite::Table3 => vec![results.join("table3.json")],
        Suite::Report => Vec::new(),
    }
}

fn bar(args: &EvalJob, total: usize, unit: &str) -> indicatif::ProgressBar {
    match !args.quiet {
        true => crate::progress::progress_bar("egogen eval", "evaluating", unit, total as u64, 0),
        false => indicatif::ProgressBar::hidden(),
    }
}

/// Runs the suite, writes its files and renders `OUT/RESULTS.md` from every suite's results
/// there (see the module docs).
pub(crate) fn run_eval(
    args: &EvalJob,
    load_parts: impl FnOnce() -> Result<SuiteParts>,
) -> Result<()> {
    if args.suite == Suite::Report {
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
    if args.keep_other_rows && args.suite != Suite::Table1 {
        bail!("--keep-other-rows: only Table 1 keeps rows (--suite table1)");
    }
    if !args.force && !args.keep_other_rows {
        if let Some(f) = suite_files(&args.out, args.suite)
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
    if args.suite == Suite::Speed && args.scenarios.is_empty() {
        scenarios.retain(|s| SPEED_SCENARIOS.contains(&s.name().as_str()));
    }
    let common = load_parts()?;
    let results = args.out.join("results");
    std::fs::create_dir_all(&results).with_context(|| format!("creating {}", results.display()))?;
    match args.suite {
        Suite::Table1 => table1(args, &common, &scenarios, &results)?,
        Suite::Speed => speed(args, &common, &scenarios, &results)?,
        Suite::Table2 => table2(args, &common, &results)?,
        Suite::Table3 => table3(args, &common, &results)?,
        Suite::Report => {} // Answered above: it runs nothing.
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
