//! The `egogen` binary's command line (`src/bin/egogen.rs` calls [`main`]): tools around the
//! pipeline (body model inspection, posing, previews, motion, policy, scenes, exports). Only
//! arguments are parsed here; each command calls its job.

// The doc comments of the arguments are the command's `--help` text, written for a terminal.
#![allow(rustdoc::invalid_html_tags)]

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

use crate::atomic_file::refuse_existing;
use crate::cli::motion_jobs::{
    motion_control, motion_eval, motion_stats, MotionControlOptions, MotionEvalOptions, Precision,
};
use crate::cli::policy_jobs::{run_policy, train_policy, PolicyCommand};
use crate::cli::resolve::{crate_root, DEFAULT_BODY_MODEL};
use crate::synth::body_pictures;

#[derive(Parser, Debug)]
#[command(version, about = "egogen tools: body models, motion files, previews")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Body model tools.
    #[command(subcommand)]
    Body(BodyCommand),
    /// Scene tools.
    #[command(subcommand)]
    Scene(SceneCommand),
    /// Motion tools.
    #[command(subcommand)]
    Motion(MotionCommand),
    /// Find (installing on first use) and check the Blender that renders; print its version.
    Blender {
        /// A Python with bpy 4.5, or a blender 4.5 executable (default: EGOGEN_BLENDER, else
        /// the managed environment in the egogen cache).
        #[arg(long)]
        blender: Option<PathBuf>,
    },
    /// Print an EXR file's parts, channels, types, compression and per-channel statistics
    /// (min/max/mean, NaN/Inf counts); optionally write a PNG contact sheet of its passes.
    Inspect {
        /// EXR files (Blender 4.5 single-part multilayer or 5.0 multi-part).
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// PNG contact sheet: one tile per pass, left to right in the order printed, file
        /// after file.
        #[arg(long)]
        preview: Option<PathBuf>,
        /// Only this pass (e.g. `rgb`), printed and in the sheet: with several files, the
        /// same view of each side by side.
        #[arg(long)]
        pass: Option<String>,
        /// Colour in the sheet: `none` (linear, clamped), `auto` (each file's automatic
        /// exposure, as the COLMAP images have it) or stops (e.g. `-2.5`).
        #[arg(long, default_value = "none")]
        exposure: String,
    },
    /// Camera rig tools (rig files and Aria device calibrations).
    #[command(subcommand)]
    Rig(crate::rig::RigCommand),
    /// Project Aria outputs of a take: device trajectory, calibration and IMU streams in the
    /// formats projectaria-tools reads (docs/ARIA.md).
    #[command(subcommand)]
    Aria(AriaCommand),
    /// A rendered take's wearer in the EuRoC MAV layout VIO/SLAM tools read: the SLAM cameras'
    /// grey images, the IMU, the ground truth and the sensors' YAML (docs/ARIA.md).
    #[command(subcommand)]
    Euroc(EurocCommand),
    /// Train learned models.
    #[command(subcommand)]
    Train(TrainCommand),
    /// Locomotion control: the pose prior of the reward, controller evaluation.
    #[command(subcommand)]
    Policy(Box<PolicyCommand>),
    /// Make motion without rendering: agents steered by the policy (or by sampling) walk to
    /// their goals in a scene, in turn, each sensing the others (paper Alg. 1). Writes per
    /// agent an AMASS-style SMPL-X .npz, eye-frame trajectory and markers, a top view of all
    /// paths (paths.png) and summary.json; see docs/SYNTH.md.
    Synth {
        /// Synth config (TOML), e.g. configs/crowd4.toml.
        config: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// The paper's evaluation: Table 1's scenarios (a moving obstacle, 2–16 people on a
    /// circle, a static box walked again and again) with the policy, the sampling controller
    /// and a path-planning baseline. Writes OUT/RESULTS.md and OUT/results/ (rows as JSON,
    /// every episode as JSON lines, top views of the paths).
    Eval(crate::cli::eval_jobs::EvalArgs),
}

#[derive(Subcommand, Debug)]
enum AriaCommand {
    /// Write each wearer's Aria streams of a finished take into a new folder.
    Export(crate::cli::aria_jobs::AriaExportArgs),
}

#[derive(Subcommand, Debug)]
enum EurocCommand {
    /// Write one wearer of a rendered take as a EuRoC MAV folder (`OUT/mav0/…`).
    Export(crate::cli::euroc_jobs::EurocExportArgs),
}

#[derive(Subcommand, Debug)]
enum TrainCommand {
    /// Train the locomotion policy with PPO in the box environment (stages as configured);
    /// writes safetensors weights, the last weights of every stage and a JSON-lines log.
    Policy {
        /// Training config (TOML), e.g. configs/train_policy.toml.
        #[arg(long)]
        config: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Continue the interrupted run from its checkpoint, exactly where it stopped.
        #[arg(long)]
        resume: bool,
        /// Replace the weights and log of an earlier run at the config's `output.weights` (and
        /// its stages' last weights) and `output.log`; without it they are refused.
        #[arg(long)]
        force: bool,
    },
    /// Train the motion-primitive C-VAE on mocap clips; writes safetensors weights (atomically)
    /// and a JSON-lines loss log, as named in the config.
    Primitive {
        /// Training config (TOML), e.g. configs/train_primitive.toml.
        #[arg(long)]
        config: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Continue the interrupted run whose checkpoint (`<weights>.checkpoint/`, written
        /// every `output.checkpoint_every_s`) is there, exactly where it stopped.
        #[arg(long)]
        resume: bool,
    },
}

#[derive(Subcommand, Debug)]
enum MotionCommand {
    /// Retarget a mocap clip onto the body model and write an AMASS-style `.npz`: a CMU BVH
    /// (`.bvh`) or a DeepMimic humanoid3d clip (`.txt`, from PyPI pybullet's motions).
    Import {
        /// Clip file, e.g. /usr/share/assimp/models/BVH/01_01.bvh or humanoid3d_walk.txt.
        bvh: PathBuf,
        /// Output `.npz` (must not exist).
        #[arg(long)]
        out: PathBuf,
        #[arg(long)]
        model: Option<PathBuf>,
        /// Output frame rate (Hz).
        #[arg(long, default_value_t = 40.0)]
        rate_hz: f64,
        /// Also write the left-right mirrored clip next to `--out` (`*_mirror.npz`).
        #[arg(long)]
        mirror: bool,
        /// PNG strip of the retargeted body every 0.5 s (under the source skeleton for BVH).
        #[arg(long)]
        strip: Option<PathBuf>,
        /// Number of frames in the strip.
        #[arg(long, default_value_t = 8)]
        strip_frames: usize,
        /// Source frames to drop at the start (CMU clips open with a T-pose calibration frame).
        #[arg(long, default_value_t = 0)]
        skip_frames: usize,
    },
    /// Measure a trained primitive model: held-out marker error, foot-contact score of random
    /// latents next to the mocap's, a long chain of primitives; optionally draw a walk.
    Eval {
        /// Weights (default: the shipped assets/motion/primitive_cvae.safetensors).
        #[arg(long)]
        weights: Option<PathBuf>,
        /// The training config, for its clips and held-out split.
        #[arg(long, default_value_os_t = crate::paths::crate_root().join("configs/train_primitive.toml"))]
        config: PathBuf,
        /// Primitives decoded from random latents for the contact score.
        #[arg(long, default_value_t = 1000)]
        random_primitives: usize,
        /// Primitives in the long chain.
        #[arg(long, default_value_t = 1000)]
        chain_primitives: usize,
        /// Primitives in each of the 20 chains from spread training seeds.
        #[arg(long, default_value_t = 50)]
        short_chain_primitives: usize,
        /// Seed of the random latents.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// PNG of the first 10 s of the chain, from above and from the side (of the steered
        /// walk with --steer-goal-m).
        #[arg(long)]
        walk_png: Option<PathBuf>,
        /// Also decode a 10 s walk steered to a goal this many metres ahead of the seed, the
        /// best of 16 random latents kept per primitive (a stand-in for the locomotion policy),
        /// and report how far it got; then 32 such walks from spread training seeds to goals
        /// this far ahead of, left of, right of and behind the body (their mean progress).
        #[arg(long)]
        steer_goal_m: Option<f64>,
        /// JSON lines, one per primitive of the long chain: pelvis height, trunk tilt, root
        /// speed and lowest foot (what goes first when a chain falls).
        #[arg(long)]
        chain_trace: Option<PathBuf>,
        /// Float precision the network runs in (the speed/accuracy knob).
        #[arg(long, value_enum, default_value_t = Precision::F32)]
        precision: Precision,
        /// Latents drawn per primitive of the chains, the most plausible kept (best-of-K
        /// sampling; 1 for plain random latents).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
        candidates: u32,
        /// Primitives each candidate is continued for before choosing (with --candidates > 1).
        #[arg(long, default_value_t = 0)]
        lookahead: usize,
        /// Write the long random-latent chain as an AMASS-style `.npz` (40 Hz, world
        /// coordinates; must not exist), for checking the numbers with other tools.
        #[arg(long)]
        export_npz: Option<PathBuf>,
        /// JSON file with the pace (speed, turn) of every primitive of the random-latent
        /// chains and of the training primitives, for `tools/plot_motion_paces.py` (must not
        /// exist).
        #[arg(long)]
        pace_json: Option<PathBuf>,
    },
    /// Pace (horizontal pelvis speed) and turn (heading change) of the primitives a training
    /// config trains on and holds out: quantiles as JSON lines, optionally every value as JSON
    /// for `tools/plot_motion_paces.py`.
    Stats {
        /// The training config (its clips, held-out split and contact filter).
        #[arg(long, default_value_os_t = crate::paths::crate_root().join("configs/train_primitive.toml"))]
        config: PathBuf,
        /// JSON file with every primitive's speed and turn (must not exist).
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// How a head moves (docs/MOTION.md, "Head motion"): linear acceleration where motion
    /// primitives join against inside them, angular speed, yaw sway, vertical bob, step
    /// frequency and a true IMU's specific force and angular rate, for take folders, AMASS-style
    /// clips (or folders of them: each clip's head by the body model) and projectaria-tools MPS
    /// trajectories (the device poses moved to the CPF by the Aria rig); JSON lines, then a
    /// table on standard error.
    HeadStats {
        /// Take folders, `.npz` clips, folders of `.npz` clips, MPS trajectory `.csv` files.
        #[arg(required = true)]
        sources: Vec<PathBuf>,
        /// SMPL-X `.npz` model the clips are posed with (default: the shipped CC0 neutral model).
        #[arg(long)]
        model: Option<PathBuf>,
        /// Rig whose device frame an MPS trajectory is in.
        #[arg(long, default_value_os_t = crate::paths::crate_root().join("camera_rigs/aria_gen1.json"))]
        rig: PathBuf,
        /// Rate of the IMU computed from each head (Hz; the Aria exports' is 1000 for EuRoC).
        #[arg(long, default_value_t = 1000.0)]
        imu_rate_hz: f64,
        /// JSON file with every source's statistics (must not exist).
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// How the fingers move in AMASS-style SMPL-X files and takes (each joint's flexion against
    /// its range, speed, acceleration, how closed the hands are; docs/HANDS.md): JSON lines,
    /// then a table on standard error.
    HandStats {
        /// `.npz` motion files and take folders (their agents/*/motion.npz).
        #[arg(required = true)]
        sources: Vec<PathBuf>,
        /// SMPL-X `.npz` model whose rest hand the flexion is measured from (default: the
        /// shipped CC0 neutral model).
        #[arg(long)]
        model: Option<PathBuf>,
        /// JSON file with every file's statistics (must not exist).
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// What the latent space can reach: latents chosen per primitive by a cross-entropy-method
    /// optimiser for a target pelvis speed and heading; sustained straight walks at each
    /// `--speeds` value and turns by each `--turns` angle, with foot contact and plausibility
    /// (JSON lines).
    Control(MotionControlOptions),
}

#[derive(Subcommand, Debug)]
enum SceneCommand {
    /// Load a scene, build its walkable map, print a summary and draw the map with sample
    /// sensing rays as PNG.
    Inspect {
        /// Scene file (.glb, .gltf, .obj, .ply), `dwelling:SEED` (a generated dwelling) or
        /// `scenario:empty_floor|single_box|moving_box`.
        scene: String,
        /// Up axis of the file (default: y for glTF, z otherwise), as `[scene] up_axis`.
        #[arg(long, value_parser = ["y", "z"])]
        up: Option<String>,
        /// Metres per unit of the file (default 1; 0.01 for centimetres), as `[scene] unit_m`.
        #[arg(long)]
        unit_m: Option<f64>,
        /// Walkable-map cell size (m).
        #[arg(long, default_value_t = 0.1)]
        cell_m: f64,
        /// Walk the floor at this height (m: an upper storey), as `[scene] floor_z_m`.
        #[arg(long)]
        floor_z_m: Option<f64>,
        /// Walk floors that step by at most this (m) as one floor, as `[scene] floor_steps_m`.
        #[arg(long)]
        floor_steps_m: Option<f64>,
        /// Output PNG (must not exist).
        #[arg(long)]
        out: PathBuf,
        /// Number of sample agents whose 32 rays are drawn.
        #[arg(long, default_value_t = 3)]
        agents: usize,
        /// Seed for the sample agents.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Also draw each sample agent's egocentric depth image (16 × 32, looking at its
        /// goal; Table 3's ablation sees it), to the right of the map.
        #[arg(long)]
        depth_images: bool,
    },
    /// Generate furnished dwellings from the shipped CC0 furniture catalogue: `dwelling.glb`
    /// (one named node per object) and `dwelling.json` (each object's class, room, model,
    /// creator and licence; the rooms) in --out (--count 1) or in --out/seed_<N>/ per seed.
    Generate(crate::cli::scene_jobs::GenerateArgs),
}

#[derive(Subcommand, Debug)]
enum BodyCommand {
    /// Print a model's sizes, shape space and eye anchor.
    Info {
        /// SMPL-X `.npz` model (default: the shipped CC0 neutral model).
        #[arg(long)]
        model: Option<PathBuf>,
    },
    /// Pose a body from a motion file frame and write it as OBJ.
    Pose {
        #[arg(long)]
        model: Option<PathBuf>,
        /// AMASS- or SAMP-style `.npz`; without it, the scripted walk is used.
        #[arg(long)]
        motion: Option<PathBuf>,
        /// Frame index in the motion.
        #[arg(long, default_value_t = 0)]
        frame: usize,
        /// Output OBJ path (must not exist).
        #[arg(long)]
        out: PathBuf,
    },
    /// Render a PNG of the body in rest pose and in a walking pose (front and side).
    Preview {
        #[arg(long)]
        model: Option<PathBuf>,
        /// Shape coefficients, comma separated (e.g. `--betas 2,0,-1`).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        betas: Vec<f64>,
        /// Output PNG path.
        #[arg(long)]
        out: PathBuf,
        /// Image height in pixels.
        #[arg(long, default_value_t = 480)]
        height_px: usize,
    },
    /// Render a PNG sheet of the right hand doing each thing a hand does (walking, standing,
    /// seated, reaching, holding) for a few people, beside the body model's rest hand.
    Hands {
        #[arg(long)]
        model: Option<PathBuf>,
        /// How many people's hands (each drawn from its own seed).
        #[arg(long, default_value_t = 3)]
        people: usize,
        /// Output PNG path (must not exist).
        #[arg(long)]
        out: PathBuf,
        /// Size of each picture in pixels.
        #[arg(long, default_value_t = 200)]
        cell_px: usize,
    },
    /// Render a PNG sheet of people dressed as takes dress them (`[render.outfits]`'s
    /// defaults: a shape, skin and outfit each from the seed), front and back, with Blender.
    Outfits {
        #[arg(long)]
        model: Option<PathBuf>,
        /// How many people.
        #[arg(long, default_value_t = 12)]
        people: usize,
        /// Draws the people's shapes, skins and outfits.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Each picture's height in pixels (its width is half of it).
        #[arg(long, default_value_t = 320)]
        cell_px: u32,
        /// Cycles samples per pixel.
        #[arg(long, default_value_t = 32)]
        samples: u32,
        /// A Python with bpy or a blender executable (default: the managed one).
        #[arg(long)]
        blender: Option<PathBuf>,
        /// Output PNG path (must not exist).
        #[arg(long)]
        out: PathBuf,
    },
    /// Render a PNG row of rest-pose bodies, one per value of one beta (front views).
    Shapes {
        #[arg(long)]
        model: Option<PathBuf>,
        /// Which beta to vary (0-based).
        #[arg(long, default_value_t = 0)]
        beta: usize,
        /// Values of that beta, comma separated.
        #[arg(
            long,
            value_delimiter = ',',
            allow_hyphen_values = true,
            default_value = "-3,0,3"
        )]
        values: Vec<f64>,
        /// Output PNG path.
        #[arg(long)]
        out: PathBuf,
    },
}

/// The command and every subcommand below it taking `-1` as a value, not as a flag: a
/// negative number reaches its option's parser and range check, which name the option.
fn with_negative_numbers(cmd: clap::Command) -> clap::Command {
    let names: Vec<String> = cmd
        .get_subcommands()
        .map(|s| s.get_name().to_owned())
        .collect();
    names
        .iter()
        .fold(cmd.allow_negative_numbers(true), |cmd, name| {
            cmd.mut_subcommand(name, with_negative_numbers)
        })
}

/// Parses `egogen`'s arguments and runs the command; an error is printed and exits non-zero.
pub fn main() -> ExitCode {
    use clap::{CommandFactory, FromArgMatches};
    crate::cli::exit_quietly_on_closed_pipe();
    let matches = with_negative_numbers(Cli::command()).get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn model_path(p: Option<PathBuf>) -> PathBuf {
    p.unwrap_or_else(|| crate_root().join(DEFAULT_BODY_MODEL))
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Blender { blender } => {
            let rt = crate::render::BlenderRuntime::resolve(blender.as_deref())?;
            println!(
                "Blender {} ({:?}) at {}",
                rt.version,
                rt.kind,
                rt.path.display()
            );
        }
        Command::Inspect {
            files,
            preview,
            pass,
            exposure,
        } => crate::inspect::report::inspect_exr(
            &files,
            preview.as_deref(),
            pass.as_deref(),
            &exposure,
        )?,
        Command::Policy(cmd) => run_policy(*cmd)?,
        Command::Eval(args) => crate::cli::eval_jobs::run_eval(&args)?,
        Command::Synth { config, quiet } => {
            let plan = crate::cli::synth_config::load_synth_plan(&config)?;
            let out = crate::synth::take::run_synth(&plan, !quiet)?;
            let t = &out.summary.totals;
            println!(
                "{} agents, {:.1} s of motion each: {}/{} goals reached, {} fell, contact {:.3}, human overlap {:.2}%, {:.0} agent-s of motion per wall s",
                t.agents,
                out.summary.frames as f64 / out.summary.frame_rate_hz,
                t.goals_reached,
                t.goals,
                t.agents_fallen,
                t.contact_mean,
                100.0 * t.human_overlap_share,
                t.agent_seconds_per_wall_s.unwrap_or(f64::NAN)
            );
            println!("wrote {}", out.dir.display());
        }
        Command::Rig(cmd) => crate::rig::run_command(&cmd, &mut std::io::stdout().lock())?,
        Command::Aria(AriaCommand::Export(args)) => crate::cli::aria_jobs::aria_export(&args)?,
        Command::Euroc(EurocCommand::Export(args)) => crate::cli::euroc_jobs::euroc_export(&args)?,
        Command::Motion(cmd) => run_motion(cmd)?,
        Command::Scene(cmd) => run_scene(cmd)?,
        Command::Body(cmd) => run_body(cmd)?,
        Command::Train(cmd) => run_train(cmd)?,
    }
    Ok(())
}

/// Runs `egogen motion …`.
fn run_motion(cmd: MotionCommand) -> Result<()> {
    match cmd {
        MotionCommand::Eval {
            weights,
            config,
            random_primitives,
            chain_primitives,
            short_chain_primitives,
            seed,
            walk_png,
            steer_goal_m,
            chain_trace,
            precision,
            candidates,
            lookahead,
            export_npz,
            pace_json,
        } => {
            let weights = weights.unwrap_or_else(crate::motion::cvae::train::shipped_weights_path);
            motion_eval(
                &weights,
                &config,
                &MotionEvalOptions {
                    random_primitives,
                    chain_primitives,
                    short_chain_primitives,
                    seed,
                    walk_png,
                    steer_goal_m,
                    chain_trace,
                    precision,
                    candidates: candidates as usize,
                    lookahead,
                    export_npz,
                    pace_json,
                },
            )?;
        }
        MotionCommand::Stats { config, json } => {
            if let Some(j) = &json {
                refuse_existing(j)?;
            }
            motion_stats(&config, json.as_deref())?;
        }
        MotionCommand::HandStats {
            sources,
            model,
            json,
        } => {
            if let Some(j) = &json {
                refuse_existing(j)?;
            }
            crate::motion::jobs::motion_hand_stats(&sources, &model_path(model), json.as_deref())?;
        }
        MotionCommand::HeadStats {
            sources,
            model,
            rig,
            imu_rate_hz,
            json,
        } => {
            if let Some(j) = &json {
                refuse_existing(j)?;
            }
            crate::export::head_stats::motion_head_stats(
                &sources,
                &model_path(model),
                &rig,
                imu_rate_hz,
                json.as_deref(),
            )?;
        }
        MotionCommand::Control(opts) => motion_control(&opts)?,
        MotionCommand::Import {
            bvh,
            out,
            model,
            rate_hz,
            mirror,
            strip,
            strip_frames,
            skip_frames,
        } => {
            crate::cli::import_jobs::import_bvh(
                &bvh,
                &out,
                &model_path(model),
                rate_hz,
                mirror,
                strip.as_deref(),
                strip_frames,
                skip_frames,
            )?;
        }
    }
    Ok(())
}

/// Runs `egogen scene …`.
fn run_scene(cmd: SceneCommand) -> Result<()> {
    match cmd {
        SceneCommand::Inspect {
            scene,
            up,
            unit_m,
            cell_m,
            floor_z_m,
            floor_steps_m,
            out,
            agents,
            seed,
            depth_images,
        } => {
            refuse_existing(&out)?;
            crate::synth::scene_inspect::scene_inspect(
                &scene,
                crate::cli::scene_jobs::scene_frame_flags(up.as_deref(), unit_m)?,
                crate::scene::WalkableSettings {
                    cell_m,
                    floor_z_m,
                    floor_steps_m,
                    ..Default::default()
                },
                &out,
                agents,
                seed,
                depth_images,
            )?;
        }
        SceneCommand::Generate(args) => crate::cli::scene_jobs::scene_generate(&args)?,
    }
    Ok(())
}

/// Runs `egogen body …`.
fn run_body(cmd: BodyCommand) -> Result<()> {
    match cmd {
        BodyCommand::Info { model } => crate::body::info::body_info(&model_path(model))?,
        BodyCommand::Shapes {
            model,
            beta,
            values,
            out,
        } => body_pictures::body_shapes(&model_path(model), beta, &values, &out)?,
        BodyCommand::Pose {
            model,
            motion,
            frame,
            out,
        } => crate::motion::jobs::body_pose(&model_path(model), motion.as_deref(), frame, &out)?,
        BodyCommand::Preview {
            model,
            betas,
            out,
            height_px,
        } => body_pictures::body_preview(&model_path(model), &betas, &out, height_px)?,
        BodyCommand::Hands {
            model,
            people,
            out,
            cell_px,
        } => body_pictures::body_hands(&model_path(model), people, &out, cell_px)?,
        BodyCommand::Outfits {
            model,
            people,
            seed,
            cell_px,
            samples,
            blender,
            out,
        } => crate::render::outfit_sheet(
            &model_path(model),
            people,
            seed,
            cell_px,
            samples,
            blender.as_deref(),
            &out,
        )?,
    }
    Ok(())
}

/// Runs `egogen train …`.
fn run_train(cmd: TrainCommand) -> Result<()> {
    match cmd {
        TrainCommand::Policy {
            config,
            quiet,
            resume,
            force,
        } => train_policy(&config, quiet, resume, force)?,
        TrainCommand::Primitive {
            config,
            quiet,
            resume,
        } => {
            let plan = crate::cli::train_primitive::load_train_plan(&config)?;
            let report = crate::motion::cvae::train(&plan, !quiet, resume)?;
            println!(
                "trained on {} primitives ({} chains) in {:.0} s; final loss {:.4}; held-out marker error {}",
                report.train_primitives,
                report.train_chains,
                report.seconds,
                report.final_loss,
                report
                    .held_out_mpjpe_mm
                    .map_or("n/a (nothing held out)".into(), |e| format!("{e:.1} mm ({} primitives)", report.held_out_primitives)),
            );
            println!(
                "wrote {} and {}",
                plan.weights_out.display(),
                plan.log_out.display()
            );
        }
    }
    Ok(())
}
