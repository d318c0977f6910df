//! `egogen policy` and `egogen train policy`: their flags, `policy eval`'s checked into its
//! settings, controllers and scene, and thin calls into the jobs: fitting and checking the pose
//! prior, drawing floor plans and evaluating controllers on held-out episodes
//! (`eval::policy_commands`), and training the policy (`policy::train_job`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Subcommand;

use super::train_primitive::train_plan_for_job;
use crate::atomic_file::refuse_existing;
use crate::eval::policy_commands::{PolicyEvalJob, PosePriorJob};

// Parsed once per command; the evaluation's many options make its variant the largest.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
pub(crate) enum PolicyCommand {
    /// Fit the pose prior of the reward's pose term on a config's training primitives, and
    /// report how it scores held-out mocap, random-latent primitives and bent joints.
    PosePrior {
        /// Motion training config whose clips (and held-out split) are used.
        #[arg(long, default_value_os_t = crate::paths::crate_root().join("configs/train_primitive.toml"))]
        config: PathBuf,
        /// Motion-model weights (random-latent primitives; default: the shipped ones).
        #[arg(long)]
        weights: Option<PathBuf>,
        /// Where to write the prior (JSON; refused if it exists).
        #[arg(long)]
        out: PathBuf,
        /// Mixture components.
        #[arg(long, default_value_t = 16)]
        components: usize,
        /// EM iterations.
        #[arg(long, default_value_t = 60)]
        iterations: usize,
        /// Quantile of the training primitives' mean scores taken as the plausibility limit.
        #[arg(long, default_value_t = 0.99)]
        quantile: f64,
        /// Write the scores of the three groups (JSON) for `tools/plot_pose_prior.py`.
        #[arg(long)]
        scores_json: Option<PathBuf>,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Draw procedural floor plans as training draws them with the default `[stages.env.rooms]`
    /// settings (rooms, doorways, furniture, a start and a goal), side by side as a PNG.
    Rooms {
        /// The PNG to write (refused if it exists).
        #[arg(long)]
        out: PathBuf,
        /// How many plans, in rows of three.
        #[arg(long, default_value_t = 6)]
        count: usize,
        /// Plan k is drawn from this seed + k.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Also write each plan as a scene file, `DIR/plan_<seed>.obj` (metres, z up, floor at
        /// z = 0, walls 2.5 m and furniture 0.8 m high, one object per part), which `egogen
        /// synth` and `egogen-run` load as any OBJ scene (refused if a file exists).
        #[arg(long, value_name = "DIR")]
        obj_dir: Option<PathBuf>,
        /// Thickness of inner walls (m; training draws 0.15).
        #[arg(long, default_value_t = 0.15)]
        wall_m: f64,
    },
    /// Evaluate the sampling controller (best of K random latents by the reward) on held-out
    /// box-scene episodes; one JSON line per K.
    Eval(PolicyEvalArgs),
}

/// `egogen policy eval`'s flags.
#[derive(clap::Args, Debug)]
pub(crate) struct PolicyEvalArgs {
    #[arg(long, default_value_os_t = crate::paths::crate_root().join("configs/train_primitive.toml"))]
    pub config: PathBuf,
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Pose prior (default: the shipped one).
    #[arg(long)]
    pub prior: Option<PathBuf>,
    /// Candidates per step of the sampling controller (comma-separated: one evaluation
    /// each; default 1,16,64, none when --policy is given alone).
    #[arg(long, value_delimiter = ',')]
    pub k: Option<Vec<usize>>,
    /// Also evaluate these controllers of the walker layer, the very ones a take's people
    /// step with (comma-separated names: `sampling_kK`, `path_follow_kK`; `--k K` is
    /// `sampling_kK`).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub controller: Vec<String>,
    /// Also evaluate this trained policy (the shipped one:
    /// assets/policy/scene_weights/policy.safetensors).
    #[arg(long)]
    pub policy: Option<PathBuf>,
    /// The policy's mean action instead of a sample from it.
    #[arg(long)]
    pub mean_action: bool,
    /// Scale of the sampled actions' standard deviation: 1 draws as trained, smaller
    /// values draw nearer the mean (0 is the mean action).
    #[arg(long, default_value_t = 1.0)]
    pub action_spread: f32,
    /// Evaluate in this scene (e.g. assets/scenes/apartment.glb) on start/goal pairs
    /// instead of in box scenes.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// With --scene: up axis of the file (default: y for glTF, z otherwise).
    #[arg(long, value_parser = ["y", "z"])]
    pub up: Option<String>,
    /// With --scene: metres per unit of the file (default 1; 0.01 for centimetres).
    #[arg(long)]
    pub unit_m: Option<f64>,
    /// Distance range of the scene's start/goal pairs (m).
    #[arg(long, value_delimiter = ',', default_value = "2,7")]
    pub pair_distance_m: Vec<f64>,
    /// Measure --pair-distance-m on foot, as the walking distance round walls (the way round
    /// the report bins by), instead of straight: every pair within the walk a horizon allows.
    #[arg(long)]
    pub pair_distance_on_foot: bool,
    /// Draw the scene's starts and goals anywhere walkable, not only inside the walls.
    #[arg(long)]
    pub anywhere: bool,
    /// Primitives before an episode times out (default 11 in box scenes and crossings, 13
    /// in floor plans and scenes, EgoGen's apartment; given, it applies to all).
    #[arg(long)]
    pub max_primitives: Option<usize>,
    /// Share of procedural floor plans (rooms, doorways, furniture; drawn anew every
    /// episode) instead of box scenes and crossings: 0 (default) to 1.
    #[arg(long, default_value_t = 0.0)]
    pub rooms_share: f64,
    /// Share of crossing scenes (another person walking across the path) instead of box
    /// scenes: 0 (default) to 1.
    #[arg(long, default_value_t = 0.0)]
    pub crossing_share: f64,
    /// How many other people cross in a crossing scene: N, or MIN,MAX drawn per episode.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub crossing_people: Vec<usize>,
    /// Show the policy a guide's aim where a wall hides its goal: the point this many
    /// metres along the shortest path (0, the default: the goal itself, as EgoGen).
    #[arg(long, default_value_t = 0.0)]
    pub guide_lookahead_m: f64,
    /// With --guide-lookahead-m: the guide plans only on what the walker's own rays have
    /// shown it so far (the unknown taken as open), not on the whole map.
    #[arg(long)]
    pub guide_memory: bool,
    /// With --guide-lookahead-m: how strongly the guide's path keeps to the middle of
    /// doorways and corridors (0, the default: the shortest path at 0.3 m from walls).
    #[arg(long, default_value_t = 0.0)]
    pub guide_centre_weight: f64,
    /// With --guide-memory: a step onto ground the walker never saw costs this many times
    /// its length more than one onto ground seen open: the way round prefers the doorways
    /// its rays looked through (0, the default: the unknown taken as open).
    #[arg(long, default_value_t = 0.0)]
    pub guide_unknown_cost: f64,
    /// Give each indoor episode time for its way round walls: at least (walking distance
    /// round walls) / M primitives, never fewer than --max-primitives (7/13 ≈ 0.54: the
    /// time 13 primitives give a 7 m straight walk). Not given: --max-primitives alone.
    #[arg(long, value_name = "M")]
    pub time_by_way_round_m: Option<f64>,
    /// Show the walker the crossing people where they will stand when its primitive ends,
    /// as `egogen synth`'s crowds do (a policy trained with `people_seen_ahead`).
    #[arg(long)]
    pub people_seen_ahead: bool,
    #[arg(long, default_value_t = 200)]
    pub episodes: usize,
    /// Episodes run in parallel (one decode batch).
    #[arg(long, default_value_t = 50)]
    pub envs: usize,
    /// Success radius (m; the table's 0.3).
    #[arg(long, default_value_t = 0.3)]
    pub success_m: f64,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write every episode's summary (JSON lines).
    #[arg(long)]
    pub episodes_jsonl: Option<PathBuf>,
    /// Draw the walks of the first `--paths` episodes from above as a PNG (one controller
    /// only): the pelvis at every primitive boundary, green where the goal was reached,
    /// orange on a timeout, red where the walk ended in an obstacle.
    #[arg(long)]
    pub paths_png: Option<PathBuf>,
    /// How many walks `--paths-png` draws.
    #[arg(long, default_value_t = 6)]
    pub paths: usize,
}

/// Runs an `egogen policy` command.
pub(crate) fn run_policy(cmd: PolicyCommand) -> Result<()> {
    use crate::eval::policy_commands::{draw_room_plans, pose_prior};
    match cmd {
        PolicyCommand::PosePrior {
            config,
            weights,
            out,
            components,
            iterations,
            quantile,
            scores_json,
            seed,
        } => pose_prior(
            PosePriorJob {
                config,
                weights,
                out,
                components,
                iterations,
                quantile,
                scores_json,
                seed,
            },
            train_plan_for_job,
        )?,
        PolicyCommand::Rooms {
            out,
            count,
            seed,
            obj_dir,
            wall_m,
        } => draw_room_plans(&out, count, seed, obj_dir.as_deref(), wall_m)?,
        PolicyCommand::Eval(args) => policy_eval(args)?,
    }
    Ok(())
}

/// The walker-layer controllers `--controller` names: (kind, K, spec) each.
fn eval_controllers(
    names: &[String],
) -> Result<Vec<(&'static str, usize, crate::walker::ControllerSpec)>> {
    names
        .iter()
        .map(|name| {
            // Every controller but the policy's, which --policy FILE evaluates.
            crate::walker::ControllerSpec::from_name(name)
                .filter(|spec| !spec.needs_policy())
                .map(|spec| {
                    let (kind, k) = spec.kind_and_k();
                    (kind, k, spec)
                })
                .with_context(|| {
                    format!(
                        "--controller: \"{name}\": expected sampling_kK or path_follow_kK with K \
                         ≥ 1 (the policy: --policy FILE)"
                    )
                })
        })
        .collect()
}

/// The environment `egogen policy eval`'s flags ask for, checked: the walker's one settings
/// schema over the paper's walker, the shares of floor plans and crossings.
fn eval_settings(a: &PolicyEvalArgs) -> Result<crate::policy::EnvSettings> {
    use crate::policy::EnvSettings;
    let (rooms_share, crossing_share) = (a.rooms_share, a.crossing_share);
    if let Some(m) = a.time_by_way_round_m {
        if !(m.is_finite() && m > 0.0) {
            bail!("--time-by-way-round-m: expected metres per primitive > 0, got {m}");
        }
    }
    // The flags fill the walker's one settings schema, over the paper's walker.
    let paper = crate::walker::WalkerSettings::PAPER;
    let walker = crate::walker::WalkerSettings {
        success_m: a.success_m,
        max_primitives_per_goal: a.max_primitives.unwrap_or(paper.max_primitives_per_goal),
        guide_lookahead_m: a.guide_lookahead_m,
        guide_memory: a.guide_memory,
        guide_centre_weight: a.guide_centre_weight,
        guide_unknown_cost: a.guide_unknown_cost,
        anticipate_people: a.people_seen_ahead,
        ..paper
    };
    if let Some((field, what)) = walker.problem_over(&paper) {
        let flag = match field {
            "max_primitives_per_goal" => "max_primitives",
            "anticipate_people" => "people_seen_ahead",
            f => f,
        };
        bail!("--{}: {what}", flag.replace('_', "-"));
    }
    let defaults = EnvSettings::default();
    if a.scene.is_some() && (rooms_share > 0.0 || crossing_share > 0.0) {
        bail!("--scene walks the scene's pairs only: give no --rooms-share or --crossing-share with it");
    }
    if !(0.0..=1.0).contains(&rooms_share) {
        bail!("--rooms-share: expected a share in [0, 1], got {rooms_share}");
    }
    if !(0.0..=1.0).contains(&crossing_share) {
        bail!("--crossing-share: expected a share in [0, 1], got {crossing_share}");
    }
    let people = match *a.crossing_people.as_slice() {
        [n] => (n, n),
        [lo, hi] => (lo, hi),
        _ => bail!("--crossing-people: expected N or MIN,MAX"),
    };
    if !crate::scene::generated::crossing_scene::people_in_range(people) {
        bail!(
            "--crossing-people: expected 1 ≤ MIN ≤ MAX ≤ {}, got {},{}",
            crate::scene::generated::crossing_scene::MAX_PEOPLE,
            people.0,
            people.1
        );
    }
    let settings = EnvSettings {
        walker,
        crossing: crate::scene::generated::crossing_scene::CrossingSettings {
            share: crossing_share,
            people,
            ..defaults.crossing
        },
        rooms: crate::scene::generated::room_scene::RoomSettings {
            share: rooms_share,
            max_primitives: a.max_primitives.unwrap_or(defaults.rooms.max_primitives),
            ..defaults.rooms
        },
        time_by_way_round_m: a.time_by_way_round_m.unwrap_or(0.0),
        ..defaults
    };
    Ok(settings)
}

/// `--scene`'s held-out start/goal pairs, if a scene is given.
fn eval_scene(a: &PolicyEvalArgs) -> Result<Option<crate::policy::env::FixedScene>> {
    if a.scene.is_none() && (a.up.is_some() || a.unit_m.is_some() || a.pair_distance_on_foot) {
        bail!("--up, --unit-m and --pair-distance-on-foot are about a --scene file's pairs; give --scene FILE");
    }
    let frame = super::scene_jobs::scene_frame_flags(a.up.as_deref(), a.unit_m)?;
    let fixed = match &a.scene {
        None => None,
        Some(path) => {
            let &[lo, hi] = a.pair_distance_m.as_slice() else {
                bail!("--pair-distance-m: expected MIN,MAX in metres");
            };
            if !(lo >= 0.0 && hi >= lo) {
                bail!("--pair-distance-m: expected 0 ≤ MIN ≤ MAX, got {lo},{hi}");
            }
            let path = crate::scene::dwelling::scene_source(&path.to_string_lossy(), Path::new(""))
                .map_err(|m| anyhow::anyhow!("--scene: {m}"))?;
            Some(crate::policy::fixed_scene::held_out_scene(
                &path,
                frame,
                a.episodes,
                (lo, hi),
                a.pair_distance_on_foot,
                !a.anywhere,
                a.seed,
                crate::scene::sdf3d::DEFAULT_VOXEL_M,
            )?)
        }
    };
    Ok(fixed)
}

/// The sampling controllers' K of `policy eval` (default 1, 16 and 64 when neither a policy
/// nor a controller is given), with every count and scale of `a` checked.
fn eval_ks(
    a: &PolicyEvalArgs,
    controllers: &[(&'static str, usize, crate::walker::ControllerSpec)],
) -> Result<Vec<usize>> {
    let PolicyEvalArgs {
        k,
        episodes,
        envs,
        policy,
        action_spread,
        scene,
        ..
    } = a;
    let (episodes, envs, action_spread) = (*episodes, *envs, *action_spread);
    let k = k
        .clone()
        .unwrap_or_else(|| match policy.is_some() || !controllers.is_empty() {
            true => vec![],
            false => vec![1, 16, 64],
        });
    if k.contains(&0) || episodes == 0 || envs == 0 {
        bail!("--k, --episodes and --envs must be at least 1");
    }
    const MAX_EPISODES: usize = 1_000_000;
    const MAX_ENVS: usize = 65_536;
    const MAX_K: usize = 65_536;
    if episodes > MAX_EPISODES
        || envs > MAX_ENVS
        || k.iter()
            .chain(controllers.iter().map(|c| &c.1))
            .any(|&k| k > MAX_K)
    {
        bail!(
            "--episodes {episodes}, --envs {envs}, --k {k:?}: at most {MAX_EPISODES} episodes, \
             {MAX_ENVS} environments and K = {MAX_K} (every episode's record is kept in memory)"
        );
    }
    if !(action_spread.is_finite() && action_spread >= 0.0) {
        bail!("--action-spread: expected a scale ≥ 0, got {action_spread}");
    }
    if scene.is_some() && !(k.is_empty() && controllers.is_empty()) {
        match policy {
            None => bail!(
                "--scene evaluates a policy: give --policy FILE (the shipped one: {})",
                crate::policy::weights::SHIPPED_POLICY
            ),
            Some(_) => {
                bail!("--scene evaluates --policy only (give no --k or --controller)")
            }
        }
    }
    Ok(k)
}

/// `egogen policy eval`: its flags checked into the job, in the order they were checked
/// before (the episodes file, the controllers, the settings, the K, the scene).
fn policy_eval(a: PolicyEvalArgs) -> Result<()> {
    if let Some(f) = &a.episodes_jsonl {
        refuse_existing(f)?;
    }
    let controllers = eval_controllers(&a.controller)?;
    let settings = eval_settings(&a)?;
    let k = eval_ks(&a, &controllers)?;
    let fixed = eval_scene(&a)?;
    let job = PolicyEvalJob {
        config: a.config,
        weights: a.weights,
        prior: a.prior,
        episodes: a.episodes,
        envs: a.envs,
        seed: a.seed,
        episodes_jsonl: a.episodes_jsonl,
        paths_png: a.paths_png,
        paths: a.paths,
        policy: a.policy,
        mean_action: a.mean_action,
        action_spread: a.action_spread,
        scene: a.scene,
        settings,
        controllers,
        k,
        fixed,
    };
    crate::eval::policy_commands::policy_eval(job, train_plan_for_job)
}

/// `egogen train policy`: the training config at `config` loaded, the policy trained.
pub(crate) fn train_policy(config: &Path, quiet: bool, resume: bool, force: bool) -> Result<()> {
    let plan = super::train_policy::load_policy_plan(config)?;
    crate::policy::train_job::train_policy(plan, quiet, resume, force, train_plan_for_job)
}
