//! `egogen eval`: runs a table of the paper's evaluation (`crate::eval`) and writes
//! `OUT/RESULTS.md` (the table, how it was made, what each measure means), the rows as JSON,
//! every episode as JSON lines and top views of the paths under `OUT/results/`. Existing
//! results are refused unless `--force` (nothing is overwritten unasked).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::atomic_file::write_atomically;
use crate::body::BodyModel;
use crate::eval::report::table1_markdown;
use crate::eval::scenarios::Scenario;
use crate::eval::suite::{run_table, Controller};

/// What `egogen eval` is asked.
#[derive(Debug, Clone, clap::Args)]
pub struct EvalArgs {
    /// Which table: table1.
    #[arg(long, default_value = "table1")]
    pub suite: String,
    /// Episodes per scenario and controller.
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

fn files(out: &Path) -> Vec<PathBuf> {
    vec![
        out.join("RESULTS.md"),
        out.join("results/table1.json"),
        out.join("results/table1_episodes.jsonl"),
    ]
}

/// Runs the suite and writes its files (see the module docs).
pub fn run_eval(args: &EvalArgs) -> Result<()> {
    use crate::motion::cvae::infer::InferBackend;
    use crate::motion::cvae::train::evaluation_sets;
    use crate::motion::cvae::MotionModel;
    use crate::policy::{PosePrior, SeedBank};
    if args.suite != "table1" {
        bail!(
            "--suite {}: expected \"table1\" (Tables 2 and 3 are `egogen policy eval` runs, docs/POLICY.md)",
            args.suite
        );
    }
    if args.episodes == 0 || args.k == 0 {
        bail!("--episodes and --k must be at least 1");
    }
    if !args.force {
        if let Some(f) = files(&args.out).iter().find(|f| f.exists()) {
            bail!(
                "{} exists: give --force to replace the results in {}",
                f.display(),
                args.out.display()
            );
        }
    }
    let all = Scenario::table1();
    let scenarios: Vec<Scenario> = if args.scenarios.is_empty() {
        all.clone()
    } else {
        args.scenarios
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
            .collect::<Result<_>>()?
    };
    let body_path = crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz");
    let body = BodyModel::load(&body_path)?;
    let model = MotionModel::load(crate::motion::cvae::train::shipped_weights_path())?;
    let prior = PosePrior::load(&crate::policy::pose_prior::shipped_pose_prior_path())?;
    let policy_path = args
        .policy
        .clone()
        .unwrap_or_else(crate::policy::ppo::shipped_policy_path);
    let (arch, net) =
        crate::policy::ppo::load_policy::<InferBackend>(&policy_path, &Default::default())?;
    if arch.latent_dim != model.latent_dim() {
        bail!(
            "{}: the policy acts in {} latent dimensions, the motion model has {}",
            policy_path.display(),
            arch.latent_dim,
            model.latent_dim()
        );
    }
    let train_plan = super::train::load_train_plan(
        &crate::paths::crate_root().join("configs/train_primitive.toml"),
    )?;
    // Held-out seeds: whole clips never trained on.
    let (_, held_out) = evaluation_sets(&train_plan, &body, true)?;
    let bank = SeedBank::from_set(&held_out);
    let parts = crate::synth::crowd::CrowdParts {
        model: &model,
        body_model: &body,
        prior: &prior,
        bank: &bank,
        policy: Some(&net),
    };
    let controllers = Controller::table1(args.k);
    let total = scenarios.len() * controllers.len();
    let bar = match !args.quiet {
        true => crate::progress::progress_bar(
            "egogen eval",
            "walking",
            "scenario × controller rows",
            total as u64,
            0,
        ),
        false => indicatif::ProgressBar::hidden(),
    };
    let run = run_table(
        &parts,
        &body,
        &scenarios,
        &controllers,
        args.episodes,
        args.seed,
        |done, _, what| {
            bar.set_message(what.to_string());
            bar.set_position(done as u64);
        },
    )?;
    bar.finish_and_clear();

    let results = args.out.join("results");
    std::fs::create_dir_all(&results).with_context(|| format!("creating {}", results.display()))?;
    let mut pictures = Vec::new();
    for p in &run.pictures {
        let name = format!("table1_{}_{}.png", p.scenario.name(), p.controller);
        let takes: Vec<_> = p.takes.iter().collect();
        let pic = crate::synth::crowd_dir::paths_picture(&p.world, &takes, 420);
        let file = results.join(&name);
        let partial = results.join(format!("{name}.partial"));
        pic.image.write_png(&partial)?;
        std::fs::rename(&partial, &file)
            .with_context(|| format!("renaming {}", partial.display()))?;
        pictures.push((p.scenario, p.controller.clone(), name));
    }
    let mut lines = String::new();
    for e in &run.episodes {
        lines.push_str(&serde_json::to_string(e)?);
        lines.push('\n');
    }
    write_atomically(&results.join("table1_episodes.jsonl"), lines.as_bytes())?;
    write_atomically(
        &results.join("table1.json"),
        serde_json::to_string_pretty(&serde_json::json!({
            "command": command_line(),
            "episodes": args.episodes,
            "seed": args.seed,
            "policy": policy_path,
            "k": args.k,
            "wall_s": run.wall_s,
            "rows": run.rows,
        }))?
        .as_bytes(),
    )?;
    let labels = |name: &str| {
        scenarios
            .iter()
            .find(|s| s.name() == name)
            .map_or(name.to_string(), |s| s.label())
    };
    let md = results_markdown(
        args,
        &policy_path,
        &run.rows,
        &labels,
        &pictures,
        run.wall_s,
    );
    write_atomically(&args.out.join("RESULTS.md"), md.as_bytes())?;
    println!(
        "{} rows, {} episodes each, in {:.0} s: wrote {} and {}",
        run.rows.len(),
        args.episodes,
        run.wall_s,
        args.out.join("RESULTS.md").display(),
        results.display()
    );
    Ok(())
}

fn results_markdown(
    args: &EvalArgs,
    policy: &Path,
    rows: &[crate::eval::metrics::Row],
    labels: &dyn Fn(&str) -> String,
    pictures: &[(Scenario, String, String)],
    wall_s: f64,
) -> String {
    let mut md = format!(
        "# Results: the paper's evaluation on egogen\n\n\
         Written by `egogen eval` — do not edit by hand; rerun:\n\n\
         ```\n{}\n```\n\n\
         {} episodes per row, seed {}, policy `{}`, K = {} latents per primitive for the \
         sampling controller and the path-following baseline; {:.0} s of wall time on the \
         machine that ran it (episodes two at a time on its cores).\n\n",
        command_line(),
        args.episodes,
        args.seed,
        policy
            .strip_prefix(crate::paths::crate_root())
            .unwrap_or(policy)
            .display(),
        args.k,
        wall_s
    );
    md.push_str("## Table 1: avoiding moving obstacles and other people\n\n");
    md.push_str(&table1_markdown(rows, labels));
    md.push_str(TABLE1_NOTES);
    md.push_str("\n## Paths (episode 0; every episode of the static box)\n\n");
    let mut last = None;
    for (scenario, controller, file) in pictures {
        if last != Some(*scenario) {
            md.push_str(&format!("\n**{}**\n\n", scenario.label()));
            last = Some(*scenario);
        }
        md.push_str(&format!(
            "![{} {}](results/{})\n",
            scenario.name(),
            controller,
            file
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
goal.

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
