//! `egogen eval`: runs a table of the paper's evaluation and writes its results under
//! `OUT/results/` — Table 1 (`crate::eval`): the rows as JSON, every episode as JSON lines, top
//! views of the paths; Table 3: the ablated policies on held-out box scenes and crossings —
//! then renders `OUT/RESULTS.md` from every table's results there (how each was made, what each
//! measure means). A table's existing results are refused unless `--force` (nothing is
//! overwritten unasked; `RESULTS.md` is only ever derived from them).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::atomic_file::write_atomically;
use crate::body::BodyModel;
use crate::eval::report::table1_markdown;
use crate::eval::scenarios::Scenario;
use crate::eval::suite::{run_table, Controller};
use crate::policy::EnvSettings;

/// What `egogen eval` is asked.
#[derive(Debug, Clone, clap::Args)]
pub struct EvalArgs {
    /// Which table: table1 (scenarios with moving obstacles and people), table3 (ablations) or
    /// speed (the policy against sampling with K = 4, 8, 16, 32 latents, accuracy and time).
    #[arg(long, default_value = "table1")]
    pub suite: String,
    /// Episodes per row (table1: per scenario and controller; table3: per policy, set and
    /// actions).
    #[arg(long, default_value_t = 100)]
    pub episodes: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Folder of RESULTS.md and results/ (e.g. docs).
    #[arg(long)]
    pub out: PathBuf,
    /// Policy weights (default: the shipped policy).
    #[arg(long)]
    pub policy: Option<PathBuf>,
    /// Latents per primitive of the sampling controller and the path-following baseline.
    #[arg(long, default_value_t = 16)]
    pub k: usize,
    /// Only these scenarios (comma-separated names: moving_obstacle, circle_2, circle_4,
    /// circle_8, circle_16, static_box).
    #[arg(long, value_delimiter = ',')]
    pub scenarios: Vec<String>,
    /// Replace results already in OUT.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// The command line as a user would retype it, for the report.
fn command_line() -> String {
    std::env::args()
        .enumerate()
        .map(|(i, a)| if i == 0 { "egogen".to_string() } else { a })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The shipped policy's training run and its ablations (paper Tab. 3), each trained with the
/// same budget: label, weights, the config that trains them.
const TABLE3_POLICIES: [(&str, &str, &str); 3] = [
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
];

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
        ],
        _ => vec![results.join("table3.json")],
    }
}

/// The speed suite's scenarios unless `--scenarios` names others, and its sampling K.
const SPEED_SCENARIOS: [&str; 2] = ["moving_obstacle", "circle_4"];
const SPEED_KS: [usize; 4] = [4, 8, 16, 32];

/// `results/table1.json` and `results/speed.json`: scenario × controller rows.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct RowsFile {
    command: String,
    episodes: usize,
    seed: u64,
    policy: String,
    /// Latents per primitive of Table 1's sampling and path-following rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    k: Option<usize>,
    wall_s: f64,
    rows: Vec<crate::eval::metrics::Row>,
}

/// One row of Table 3: a policy on held-out box scenes or crossings.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Table3Row {
    policy: String,
    weights: String,
    config: String,
    set: String,
    actions: String,
    episodes: usize,
    success_rate: f64,
    contact: f64,
    penetration_share: f64,
    view_cos: f64,
    final_distance_median_m: f64,
    speed_successful_median_m_s: f64,
    wall_s: f64,
}

/// `results/table3.json`.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Table3File {
    command: String,
    episodes: usize,
    seed: u64,
    wall_s: f64,
    rows: Vec<Table3Row>,
}

/// The motion model, body, pose prior and the held-out seed poses every suite uses.
struct Common {
    body: BodyModel,
    model: crate::motion::cvae::MotionModel,
    prior: crate::policy::PosePrior,
    bank: crate::policy::SeedBank,
}

fn load_common() -> Result<Common> {
    use crate::motion::cvae::train::evaluation_sets;
    let root = crate::paths::crate_root();
    let body = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz"))?;
    let model =
        crate::motion::cvae::MotionModel::load(crate::motion::cvae::train::shipped_weights_path())?;
    let prior =
        crate::policy::PosePrior::load(&crate::policy::pose_prior::shipped_pose_prior_path())?;
    let train_plan = super::train::load_train_plan(&root.join("configs/train_primitive.toml"))?;
    // Held-out seeds: whole clips never trained on.
    let (_, held_out) = evaluation_sets(&train_plan, &body, true)?;
    let bank = crate::policy::SeedBank::from_set(&held_out);
    Ok(Common {
        body,
        model,
        prior,
        bank,
    })
}

fn bar(args: &EvalArgs, total: usize, unit: &str) -> indicatif::ProgressBar {
    match !args.quiet {
        true => crate::progress::progress_bar("egogen eval", "evaluating", unit, total as u64, 0),
        false => indicatif::ProgressBar::hidden(),
    }
}

/// Runs the suite, writes its files and renders `OUT/RESULTS.md` from every suite's results
/// there (see the module docs).
pub fn run_eval(args: &EvalArgs) -> Result<()> {
    if !matches!(args.suite.as_str(), "table1" | "table3" | "speed") {
        bail!(
            "--suite {}: expected \"table1\", \"table3\" or \"speed\" (Table 2's apartment rows are `egogen policy eval --scene`, docs/POLICY.md)",
            args.suite
        );
    }
    if args.episodes == 0 || args.k == 0 {
        bail!("--episodes and --k must be at least 1");
    }
    if !args.force {
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
    let common = load_common()?;
    let results = args.out.join("results");
    std::fs::create_dir_all(&results).with_context(|| format!("creating {}", results.display()))?;
    match args.suite.as_str() {
        "table1" => table1(args, &common, &scenarios, &results)?,
        "speed" => speed(args, &common, &scenarios, &results)?,
        _ => table3(args, &common, &results)?,
    }
    let md = results_markdown(&args.out)?;
    write_atomically(&args.out.join("RESULTS.md"), md.as_bytes())?;
    println!("wrote {}", args.out.join("RESULTS.md").display());
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

/// Runs every scenario × controller with the policy of `--policy` (default the shipped one),
/// writes `<name>_episodes.jsonl` and then `<name>.json` (after `before_summary`, given the
/// run: Table 1 draws its pictures there); `k` is recorded when the rows use one.
#[allow(clippy::too_many_arguments)]
fn run_rows(
    args: &EvalArgs,
    c: &Common,
    scenarios: &[Scenario],
    controllers: &[Controller],
    results: &Path,
    name: &str,
    k: Option<usize>,
    before_summary: impl FnOnce(&crate::eval::suite::TableRun) -> Result<()>,
) -> Result<()> {
    let policy_path = args
        .policy
        .clone()
        .unwrap_or_else(crate::policy::ppo::shipped_policy_path);
    let net = super::policy_jobs::load_policy_for(&policy_path, &c.model)?;
    let parts = crate::synth::crowd::CrowdParts {
        model: &c.model,
        body_model: &c.body,
        prior: &c.prior,
        bank: &c.bank,
        policy: Some(&net),
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
        command: command_line(),
        episodes: args.episodes,
        seed: args.seed,
        policy: relative(&policy_path),
        k,
        wall_s: run.wall_s,
        rows: run.rows,
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

fn speed(args: &EvalArgs, c: &Common, scenarios: &[Scenario], results: &Path) -> Result<()> {
    let controllers = Controller::speed(&SPEED_KS);
    run_rows(
        args,
        c,
        scenarios,
        &controllers,
        results,
        "speed",
        None,
        |_| Ok(()),
    )
}

fn table1(args: &EvalArgs, c: &Common, scenarios: &[Scenario], results: &Path) -> Result<()> {
    let controllers = Controller::table1(args.k);
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

fn table3(args: &EvalArgs, c: &Common, results: &Path) -> Result<()> {
    use crate::motion::cvae::infer::InferBackend;
    use crate::policy::tasks::{evaluate, Controller as PolicyController, EvalParts};
    let root = crate::paths::crate_root();
    let ctx = crate::motion::cvae::BodyContext::new(&c.body, &[])?;
    let parts = EvalParts {
        model: &c.model,
        body: &ctx,
        bank: &c.bank,
        prior: &c.prior,
        fixed: None,
    };
    let t0 = std::time::Instant::now();
    let progress = bar(
        args,
        TABLE3_POLICIES.len() * 4,
        "policy × set × actions rows",
    );
    let mut rows = Vec::new();
    for (label, weights, config) in TABLE3_POLICIES {
        let path = root.join(weights);
        if !path.is_file() {
            bail!(
                "{}: not found; train it with `egogen train policy --config {config}`",
                path.display()
            );
        }
        let net = super::policy_jobs::load_policy_for(&path, &c.model)?;
        for (set, crossing_share) in [("box scenes", 0.0), ("crossings", 1.0)] {
            let defaults = EnvSettings::default();
            let settings = EnvSettings {
                success_m: 0.3,
                crossing: crate::policy::crossing_scene::CrossingSettings {
                    share: crossing_share,
                    ..defaults.crossing
                },
                ..defaults
            };
            for mean_action in [false, true] {
                let controller: PolicyController<InferBackend> = PolicyController::Policy {
                    net: &net,
                    mean_action,
                };
                let (report, _) = evaluate(
                    &parts,
                    settings,
                    &controller,
                    (args.episodes, 50, args.seed),
                    |_| {},
                )?;
                rows.push(Table3Row {
                    policy: label.into(),
                    weights: weights.into(),
                    config: config.into(),
                    set: set.into(),
                    actions: if mean_action { "mean" } else { "sampled" }.into(),
                    episodes: report.episodes,
                    success_rate: report.success_rate,
                    contact: report.contact_mean,
                    penetration_share: report.penetration_share_mean,
                    view_cos: report.view_cos_mean,
                    final_distance_median_m: report.final_distance_m.p50,
                    speed_successful_median_m_s: report.speed_successful_m_s.p50,
                    wall_s: report.wall_s,
                });
                progress.inc(1);
            }
        }
    }
    progress.finish_and_clear();
    let file = Table3File {
        command: command_line(),
        episodes: args.episodes,
        seed: args.seed,
        wall_s: t0.elapsed().as_secs_f64(),
        rows,
    };
    write_atomically(
        &results.join("table3.json"),
        serde_json::to_string_pretty(&file)?.as_bytes(),
    )?;
    println!("{} rows in {:.0} s", file.rows.len(), file.wall_s);
    Ok(())
}

/// A path as shown in the report: relative to the crate's folder when it is inside it.
fn relative(path: &Path) -> String {
    path.strip_prefix(crate::paths::crate_root())
        .unwrap_or(path)
        .display()
        .to_string()
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Option<T>> {
    if !path.is_file() {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Ok(Some(serde_json::from_str(&text).with_context(|| {
        format!("{}: not a results file of this egogen", path.display())
    })?))
}

/// `RESULTS.md` from the results files in `out/results/`.
/// A scenario's label in the tables (its name where none is known).
fn scenario_label(name: &str) -> String {
    Scenario::table1()
        .iter()
        .find(|s| s.name() == name)
        .map_or(name.to_string(), |s| s.label())
}

fn results_markdown(out: &Path) -> Result<String> {
    let results = out.join("results");
    let mut md = String::from(
        "# Results: the paper's evaluation on egogen\n\n\
         Written by `egogen eval` from the files in `results/` — do not edit by hand; each \
         table names the command that reproduces it. Wall times are of the machine that ran it \
         (2 cores; episodes run two at a time).\n\n",
    );
    if let Some(t) = read_json::<RowsFile>(&results.join("table1.json"))? {
        let labels = scenario_label;
        md.push_str(&format!(
            "## Table 1: avoiding moving obstacles and other people\n\n```\n{}\n```\n\n\
             {} episodes per row, seed {}, policy `{}`, K = {} latents per primitive for the \
             sampling controller and the path-following baseline; {:.0} s of wall time.\n\n",
            t.command,
            t.episodes,
            t.seed,
            t.policy,
            t.k.map_or("?".into(), |k| k.to_string()),
            t.wall_s
        ));
        md.push_str(&table1_markdown(&t.rows, &labels));
        md.push_str(TABLE1_NOTES);
        md.push_str("\n### Paths (episode 0; every episode of the static box)\n");
        let mut last = String::new();
        for r in &t.rows {
            let file = format!("table1_{}_{}.png", r.scenario, r.controller);
            if !results.join(&file).is_file() {
                continue;
            }
            if r.scenario != last {
                md.push_str(&format!("\n**{}**\n\n", labels(&r.scenario)));
                last = r.scenario.clone();
            }
            md.push_str(&format!(
                "![{} {}](results/{file})\n",
                r.scenario, r.controller
            ));
        }
        md.push('\n');
    }
    if let Some(t) = read_json::<RowsFile>(&results.join("speed.json"))? {
        md.push_str(&format!(
            "## Speed and accuracy: the policy against sampling with K latents\n\n```\n{}\n```\n\n\
             {} episodes per row, seed {}, policy `{}`; {:.0} s of wall time. Wall per episode \
             is the episode's own time (two episodes run at once on the 2 cores); the ratio is \
             to the policy with sampled actions in the same scenario. The other knobs of the \
             trade (ray count, SDF resolution, policy width) need policies trained for them \
             and are not measured here.\n\n",
            t.command, t.episodes, t.seed, t.policy, t.wall_s
        ));
        md.push_str(&speed_markdown(&t.rows, &scenario_label));
        md.push('\n');
    }
    if let Some(t) = read_json::<Table3File>(&results.join("table3.json"))? {
        md.push_str(&format!(
            "## Table 3: ablations\n\n```\n{}\n```\n\n\
             Each policy trained from scratch with the budget of `configs/train_policy.toml` \
             (2.0 M environment steps, seed 0; the shipped policy is that run's, fine-tuned \
             further in the apartment, docs/POLICY.md), evaluated on the first {} held-out box \
             scenes and crossings (seed {}; success within 0.3 m, 11 primitives, episodes not \
             ended by penetration); {:.0} s of wall time.\n\n",
            t.command, t.episodes, t.seed, t.wall_s
        ));
        md.push_str(
            "| policy | set | actions | success | foot contact | penetration | cos(view, goal) | final distance (median) | speed, successful (median) | trained by |\n\
             | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
        );
        for r in &t.rows {
            md.push_str(&format!(
                "| {} | {} | {} | {:.1} % | {:.3} | {:.2} % | {:.3} | {:.2} m | {:.2} m/s | `{}` |\n",
                r.policy,
                r.set,
                r.actions,
                100.0 * r.success_rate,
                r.contact,
                100.0 * r.penetration_share,
                r.view_cos,
                r.final_distance_median_m,
                r.speed_successful_median_m_s,
                r.config
            ));
        }
        md.push_str(TABLE3_NOTES);
    }
    md.push_str(
        "\n## Table 2\n\nThe apartment with egocentric sensing is in docs/POLICY.md \
         (`egogen policy eval --scene assets/scenes/apartment.glb`); its local-map baseline \
         (a policy observing a 0.8 m or 7 m occupancy patch instead of the rays) is not \
         trained yet.\n",
    );
    Ok(md)
}

const TABLE3_NOTES: &str = "
Penetration: share of frames with a body marker inside the box's or the other person's
footprint. Foot contact: paper Eq. 12 with 3-D foot-marker speed. The paper's own Table 3
values are not set beside these: they could not be read on the machine that wrote this file.
";

/// The speed suite's rows: accuracy beside the wall time per episode and its ratio to the
/// policy's (sampled actions) in the same scenario.
fn speed_markdown(rows: &[crate::eval::metrics::Row], labels: &dyn Fn(&str) -> String) -> String {
    let mut md = String::from(
        "| scenario | controller | SR | Dist (m) | Cont | Pene-S | Pene-H | wall per episode (s) | × policy |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let pct = |v: Option<f64>| v.map_or("–".into(), |v| format!("{:.1} %", 100.0 * v));
    for r in rows {
        let per = r.wall_s / r.episodes.max(1) as f64;
        let policy = rows
            .iter()
            .find(|p| p.scenario == r.scenario && p.controller == "policy")
            .map(|p| p.wall_s / p.episodes.max(1) as f64);
        md.push_str(&format!(
            "| {} | {} | {} | {:.2} | {:.3} | {} | {} | {:.2} | {} |\n",
            labels(&r.scenario),
            r.controller,
            pct(Some(r.success_rate)),
            r.final_distance_m,
            r.contact,
            pct(r.obstacle_penetration_share),
            pct(r.human_penetration_share),
            per,
            policy.map_or("–".into(), |p| format!("{:.2}", per / p)),
        ));
    }
    md
}

const TABLE1_NOTES: &str = "
Scenarios (`src/eval/scenarios.rs`), each on an open 14 × 14 m floor, starts on the held-out
mocap clips' seed poses: **moving obstacle** — one person walks 5 m; a box of side 0.5–1 m
crosses the line at right angles (± 30°) at 0.5–1 m/s through a point 35–65 % of the way,
timed to meet a walker at 0.7 m/s (± 1 s); **N people** — evenly on a circle (random phase),
each walking to the opposite point, as EgoGen's `main_crowd_eval.py`; **static box** — one
person walks 5 m along the x axis past a 1 × 1 m box at the midpoint, the same scene every
episode. Each person may take as many primitives as the longest walk needs at 0.5 m/s, plus
2 s.

Measures (`src/eval/metrics.rs`), means over every person of every episode: **SR** pelvis
within 0.3 m of the goal; **Dist** final pelvis–goal distance; **Cont** paper Eq. 12 with
3-D foot-marker speed (EgoGen's and DIMOS's code); **Pene-S** share of frames with a body
marker inside an obstacle's footprint; **Pene-H** share of person-frames (every 4th frame)
with a body vertex inside another body's volume, modelled as capsules along the skeleton's
bones with radius the median skin distance (`body::volume`, a lower bound); **2D overlap**
share of person-frames with a marker inside another person's 2D box (what the policy
senses); **Std** the standard deviation over episodes of the lateral offset from the
start–goal line at 9 stations (10–90 % of the way), averaged, and **left** the share of
walks passing the box on the left; **cos** between the viewing direction and the goal
direction at primitive ends; **pose score** the pose prior's −ln p / 63 (lower is more
plausible; its limit is −0.874, docs/POLICY.md); **speed** of the people who reached the
goal; **wall** the row's episodes' wall times summed (two episodes run at once, so the row
took about half of it).

Controllers: **policy** actions sampled from the shipped policy, **policy_mean** its mean
action; **sampling_kK** the best of K random latents by the training reward; **path_follow_kK**
the baseline in the spirit of GAMMA*/DIMOS*: an A* path on the 0.1 m walkable grid around
the other people's current 2D boxes and the moving obstacles where they stand (0.3 m
clearance), replanned every primitive, and of K random latents the one whose primitive ends
nearest the point 0.8 m ahead on it (+1 m for a primitive that penetrates). Same motion
model, no policy.

The paper's own Table 1 values are not set beside these: they could not be read on the
machine that wrote this file.
";
