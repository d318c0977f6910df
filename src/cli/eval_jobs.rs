//! `egogen eval`: its arguments, and the shipped parts every suite uses loaded from their
//! files; the suites themselves are [`crate::eval::jobs`].

use std::path::PathBuf;

use anyhow::Result;

use crate::body::BodyModel;
use crate::eval::jobs::{EvalJob, Suite, SuiteParts};

/// What `egogen eval` is asked.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct EvalArgs {
    /// Which table (Table 1 by default).
    #[arg(long, value_enum, default_value_t = Suite::Table1)]
    pub suite: Suite,
    /// Episodes per row (table1: per scenario and controller; table2 and table3: per policy,
    /// set and actions).
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
    /// Only these controllers of table1 and speed (comma-separated names, e.g.
    /// policy,policy_mean); `policy_spread_S` adds the policy with its sampled actions'
    /// standard deviation scaled by S (e.g. policy_spread_0.5), `policy_as_placed` and
    /// `policy_mean_as_placed` the policy in EgoGen's crowd loop (each person sees the others
    /// where they were last put, not where they will be).
    #[arg(long, value_delimiter = ',')]
    pub controllers: Vec<String>,
    /// Replace results already in OUT.
    #[arg(long)]
    pub force: bool,
    /// Table 1 only: run just the rows `--scenarios` and `--controllers` name and keep the
    /// others of OUT's table (same episodes, seed and K) — e.g. a new policy's rows beside
    /// the sampling and path-following rows, which do not read the policy. The table says
    /// which rows were kept and from which run; a kept row steered by another policy is
    /// refused.
    #[arg(long)]
    pub keep_other_rows: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

impl EvalArgs {
    /// The job these arguments ask for.
    pub(crate) fn job(&self) -> EvalJob {
        EvalJob {
            suite: self.suite,
            episodes: self.episodes,
            seed: self.seed,
            out: self.out.clone(),
            policy: self.policy.clone(),
            k: self.k,
            scenarios: self.scenarios.clone(),
            controllers: self.controllers.clone(),
            force: self.force,
            keep_other_rows: self.keep_other_rows,
            quiet: self.quiet,
            command_line: command_line(),
        }
    }
}

/// Runs the suite `args` ask for ([`crate::eval::jobs::run_eval`]).
pub(crate) fn run_eval(args: &EvalArgs) -> Result<()> {
    crate::eval::jobs::run_eval(&args.job(), load_common)
}

/// The command line as a user would retype it, for the report.
fn command_line() -> String {
    std::env::args()
        .enumerate()
        .map(|(i, a)| if i == 0 { "egogen".to_string() } else { a })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The shipped parts every suite uses: the body, the motion model, the pose prior, the
/// held-out seed poses and the pose norm's calibration on them.
fn load_common() -> Result<SuiteParts> {
    use crate::motion::cvae::train::evaluation_sets;
    let root = crate::paths::crate_root();
    let body = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz"))?;
    let model =
        crate::motion::cvae::MotionModel::load(crate::motion::cvae::train::shipped_weights_path())?;
    let prior =
        crate::walker::PosePrior::load(&crate::walker::pose_prior::shipped_pose_prior_path())?;
    let train_plan =
        super::train_primitive::load_train_plan(&root.join("configs/train_primitive.toml"))?;
    // Held-out seeds: whole clips never trained on.
    let (_, held_out) = evaluation_sets(&train_plan, &body, true)?;
    let bank = crate::walker::SeedBank::from_set(&held_out);
    let pose_norm = crate::eval::files::PoseNormCalibration::new(
        &prior,
        &crate::eval::policy_tasks::set_frames(&held_out),
    );
    Ok(SuiteParts {
        body,
        model,
        prior,
        bank,
        pose_norm,
    })
}
