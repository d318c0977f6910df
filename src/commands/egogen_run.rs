//! The `egogen-run` binary's command line (`src/bin/egogen-run.rs` calls [`main`]): the
//! pipeline — config in, dataset out (`crate::run_job`). Agents walking the scene, a scripted
//! walk or a motion file, rendered by the rig's cameras through Blender
//! workers into a dataset folder with a `[render]` section, else written as a motion folder.
//! `egogen-run verify DATASET` re-checks a finished dataset; `egogen-run CAMPAIGN.toml` (a file
//! with a `[campaign]` section) makes many takes (`crate::campaign`). Only arguments are
//! parsed here.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use crate::cli::config::Backend;
use crate::cli::overrides::RunOverrides;
use crate::render::materials::MaterialsMode;
use crate::run_job::RunRequest;
use crate::synth::activity::ActivityWeights;

fn parse_activity_weights(text: &str) -> Result<ActivityWeights, String> {
    ActivityWeights::parse(text)
}

/// Generate an egocentric dataset from a config file.
#[derive(Parser, Debug)]
#[command(
    version,
    about,
    args_conflicts_with_subcommands = true,
    allow_negative_numbers = true
)]
struct Args {
    #[command(subcommand)]
    command: Option<Command>,
    /// Run config (TOML), e.g. `configs/default.toml`.
    config: Option<PathBuf>,
    /// Continue the interrupted run in `<output.dir>.partial` (same config only).
    #[arg(long)]
    resume: bool,
    /// With `--resume` of a campaign: verify every finished take in full (every checksum,
    /// every frame file opened), not only those whose files changed since they were finished.
    #[arg(long, requires = "resume")]
    rehash: bool,
    /// Output folder, overriding `output.dir`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Every seed of the config (motion, scene placement, lighting, headset wear, depth
    /// noise): another variant of the same run. 0 to 2⁶³ − 1 (a config holds it as a TOML
    /// integer).
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=i64::MAX as u64))]
    seed: Option<u64>,
    /// Camera rig to render with, overriding `render.rig`.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// Scene to walk and render (glTF/GLB, OBJ or PLY), overriding `scene.path`.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Which axis of the scene file points up, `y` or `z`, overriding `scene.up_axis`
    /// (default: glTF y, OBJ and PLY z).
    #[arg(long)]
    up: Option<String>,
    /// Metres per unit of the scene file, overriding `scene.unit_m` (0.01 for centimetres,
    /// 0.001 for millimetres; default 1).
    #[arg(long)]
    unit_m: Option<f64>,
    /// People in the crowd, overriding `crowd.count` (a config with a `[crowd]`).
    #[arg(long)]
    crowd_count: Option<usize>,
    /// Seconds of motion, overriding `motion.duration_s`.
    #[arg(long = "duration")]
    duration_s: Option<f64>,
    /// What people do when a walk ends, overriding `activities.weights`: `walk=2,sit=1`
    /// (weights not named are 0; docs/ACTIVITIES.md).
    #[arg(long, value_parser = parse_activity_weights)]
    activity_weights: Option<ActivityWeights>,
    /// Which scene objects get drawn materials, overriding `render.materials.mode`: `keep`
    /// (the scene's own), `fill` (objects without a texture of their own) or `all`.
    #[arg(long, value_enum)]
    materials: Option<MaterialsArg>,
    /// Where shards run, overriding `supervisor.backend`: `local` (Blender processes here) or
    /// `slurm` (a job array; resources in `[supervisor.slurm]`).
    #[arg(long, value_enum)]
    backend: Option<BackendArg>,
    /// Parallel Blender workers (with Slurm: array tasks at once), overriding `supervisor.workers`.
    #[arg(long)]
    workers: Option<usize>,
    /// Blender to use (Python with bpy 4.5, or a blender executable); else `EGOGEN_BLENDER`,
    /// else the managed install.
    #[arg(long)]
    blender: Option<PathBuf>,
    /// A campaign: state its takes, frames, disk and time, and render nothing.
    #[arg(long)]
    dry_run: bool,
    /// A campaign: estimate its time and disk from the pool reports and datasets of this
    /// campaign or dataset folder (default: the campaign's own earlier starts).
    #[arg(long)]
    throughput_from: Option<PathBuf>,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum MaterialsArg {
    Keep,
    Fill,
    All,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum BackendArg {
    Local,
    Slurm,
}

#[derive(clap::Subcommand, Debug)]
enum Command {
    /// Re-check a finished dataset against its manifest (sizes, checksums, frame files).
    Verify { dataset: PathBuf },
}

/// Parses `egogen-run`'s arguments and runs the config, campaign or check.
pub fn main() -> ExitCode {
    crate::cli::exit_quietly_on_closed_pipe();
    let args = Args::parse();
    let result = match &args.command {
        Some(Command::Verify { dataset }) => crate::run_job::verify(dataset),
        None => run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<()> {
    let Some(config) = args.config else {
        anyhow::bail!("no config given: egogen-run CONFIG (e.g. configs/default.toml), or egogen-run verify DATASET");
    };
    let backend = args.backend.map(|b| match b {
        BackendArg::Local => Backend::Local,
        BackendArg::Slurm => Backend::Slurm,
    });
    // Checked here to name the flags; the config's own keys are checked as it is resolved.
    let frame = crate::cli::scene_jobs::scene_frame_flags(args.up.as_deref(), args.unit_m)?;
    let overrides = RunOverrides {
        out: args.out,
        seed: args.seed,
        rig: args.rig,
        scene: args.scene,
        up_axis: frame.up,
        unit_m: args.unit_m,
        crowd_count: args.crowd_count,
        duration_s: args.duration_s,
        activity_weights: args.activity_weights,
        materials: args.materials.map(|m| match m {
            MaterialsArg::Keep => MaterialsMode::Keep,
            MaterialsArg::Fill => MaterialsMode::Fill,
            MaterialsArg::All => MaterialsMode::All,
        }),
        workers: args.workers,
        backend,
    };
    if crate::campaign::is_campaign(&config) {
        if let Some(flag) = overrides.take_flags().first() {
            anyhow::bail!(
                "{flag} sets one take; a campaign ({}) says what varies per take in its [campaign] section",
                config.display()
            );
        }
        let request = crate::campaign::CampaignRequest {
            resume: args.resume,
            rehash: args.rehash,
            dry_run: args.dry_run,
            blender: args.blender,
            workers: args.workers,
            backend,
            throughput_from: args.throughput_from,
        };
        return crate::campaign::run(&config, &request);
    }
    if args.dry_run || args.throughput_from.is_some() || args.rehash {
        // A file that does not parse says so, not that it is no campaign.
        crate::cli::config_file::load_toml::<toml::Table>(&config)?;
        anyhow::bail!(
            "--dry-run, --throughput-from and --rehash are for campaigns; {} has no [campaign] section",
            config.display()
        );
    }
    let request = RunRequest {
        resume: args.resume,
        blender: args.blender,
    };
    crate::run_job::run(&config, &overrides, request)
}
