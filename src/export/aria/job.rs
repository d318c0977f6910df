//! `egogen aria export`'s job: a finished take (an `egogen synth` folder, a motion folder, or
//! an `egogen-run` dataset) in, each wearer's Aria streams out, staged and then renamed into
//! place. `cli::aria_jobs` parses the flags and resolves the default rig and body model.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use super::{write_wearer_streams, AriaSettings, AriaStreams, Wearer};
use crate::atomic_file::{refuse_existing_folder, refuse_inside, StagedFolder};
use crate::export::take_folder::{read_take_heads, take_scene, TakeHead};
use crate::rig::Rig;

/// What `egogen aria export` was asked, its files resolved.
pub(crate) struct AriaExportJob {
    /// The take folder or dataset.
    pub(crate) take: PathBuf,
    /// The device: an egogen rig or an Aria device calibration JSON.
    pub(crate) rig: PathBuf,
    /// The new folder to write (must not exist).
    pub(crate) out: PathBuf,
    /// Streams to write, by name.
    pub(crate) streams: Vec<String>,
    /// Agents that wear the device; none: a dataset's wearers, else every agent of the take.
    pub(crate) wearer: Vec<String>,
    /// Rows per second of the device trajectory.
    pub(crate) trajectory_rate_hz: f64,
    /// Ideal IMUs: no noise, no bias, no saturation, an identity calibration.
    pub(crate) ideal_imu: bool,
    /// Seed of the IMU errors and the gaze.
    pub(crate) seed: u64,
    /// Eye gaze samples per second.
    pub(crate) gaze_rate_hz: f64,
    /// SMPL-X `.npz` model the take's bodies are posed with for the hands.
    pub(crate) model: PathBuf,
}

/// Runs `egogen aria export`.
pub(crate) fn aria_export(args: &AriaExportJob) -> Result<()> {
    let streams =
        AriaStreams::parse(&args.streams).map_err(|e| anyhow::anyhow!("--streams: {e}"))?;
    if !streams.any() {
        bail!(
            "--streams: no stream asked; expected any of {}",
            AriaStreams::NAMES.join(", ")
        );
    }
    let rig = Rig::load(&args.rig)?;
    let settings = AriaSettings {
        streams,
        trajectory_rate_hz: args.trajectory_rate_hz,
        imu_errors: !args.ideal_imu,
        seed: args.seed,
        gaze_rate_hz: args.gaze_rate_hz,
        ..Default::default()
    };
    if let Some(p) = settings.problem(&rig) {
        bail!("{p}");
    }
    refuse_existing_folder(&args.out, "--out")?;
    refuse_inside(&args.out, "--out", &args.take, "the take")?;
    let (wearers, everyone) = read_take_heads(&args.take, &args.wearer)?;
    // A `.partial` left by a killed export holds only what an export of this take writes (a
    // folder per wearer, the manifest).
    let names: Vec<&str> = wearers.iter().map(|&w| everyone[w].name.as_str()).collect();
    let staged = StagedFolder::begin(
        &args.out,
        "--out",
        "an export of this take",
        |name, is_dir| {
            (is_dir && names.contains(&name)) || (!is_dir && name.starts_with("manifest.json"))
        },
    )?;
    let rays = if settings.streams.gaze {
        match take_scene(&args.take)? {
            Some((path, frame)) => {
                let mesh = crate::scene::load_scene(&path, frame)?;
                crate::scene::mesh_distance::SceneRays::new(&mesh)
            }
            None => {
                eprintln!(
                    "egogen aria export: the take names no scene; gaze depths are to the fixated targets"
                );
                None
            }
        }
    } else {
        None
    };
    let hands = if settings.streams.hands {
        let model = crate::body::BodyModel::load(&args.model)?;
        wearers
            .iter()
            .map(|&w| wearer_hands(&model, &everyone[w], &args.take).map(Some))
            .collect::<Result<Vec<_>>>()?
    } else {
        vec![None; wearers.len()]
    };
    export_into(
        staged,
        &rig,
        &settings,
        (&wearers, &hands),
        &everyone,
        rays.as_ref(),
    )
}

/// Both hands' landmarks on every frame of `head`'s body (its `motion.npz`), in the world.
fn wearer_hands(
    model: &crate::body::BodyModel,
    head: &TakeHead,
    take: &Path,
) -> Result<Vec<[crate::body::hand_landmarks::HandLandmarks; 2]>> {
    let Some(path) = &head.motion else {
        bail!(
            "--streams hands: take {} has no motion.npz beside {}'s head trajectory; the hands need its body",
            take.display(),
            head.name
        );
    };
    let motion = crate::motion::MotionSequence::read(path)?;
    crate::body::hand_landmarks::hand_track(model, &motion.betas, &motion.poses, &motion.trans)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// Writes every wearer's streams and the manifest into `staged`, then renames it to its
/// output.
fn export_into(
    staged: StagedFolder,
    rig: &crate::rig::Rig,
    settings: &AriaSettings,
    (wearers, hands): (
        &[usize],
        &[Option<Vec<[crate::body::hand_landmarks::HandLandmarks; 2]>>],
    ),
    everyone: &[TakeHead],
    rays: Option<&crate::scene::mesh_distance::SceneRays>,
) -> Result<()> {
    let started = std::time::Instant::now();
    let staging = staged.path();
    for (index, head) in wearers.iter().map(|&w| &everyone[w]).enumerate() {
        let wearer = Wearer {
            name: &head.name,
            index,
            frame_rate_hz: head.frame_rate_hz,
            world_from_cpf: &head.world_from_cpf,
            cpf_from_headset: head.cpf_from_headset,
            others: everyone
                .iter()
                .filter(|o| o.name != head.name)
                .map(|o| o.world_from_cpf.as_slice())
                .collect(),
            goals: head.goals.clone(),
            looks: head.looks.clone(),
            rays,
            hands: hands[index].as_deref(),
        };
        let written = write_wearer_streams(&staging.join(&head.name), rig, settings, &wearer)?;
        let bytes: u64 = written.files.iter().map(|f| f.1).sum();
        eprintln!(
            "egogen aria export: {}: {} trajectory rows, {} IMU samples, {} files, {:.1} MB (spline off the head poses by at most {:.1e} rad)",
            head.name,
            written.trajectory_rows,
            written.imu_samples,
            written.files.len(),
            bytes as f64 / 1e6,
            written.spline_residual_rad
        );
        if let Some(note) = written.device_calibration_note {
            eprintln!("egogen aria export: {}: {note}", head.name);
        }
    }
    crate::manifest::write_manifest(staging)?;
    let out = staged.finish()?;
    println!(
        "wrote {} ({} wearers in {:.2} s)",
        out.display(),
        wearers.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
