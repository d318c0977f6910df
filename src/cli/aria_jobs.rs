//! `egogen aria export`: a finished take (an `egogen synth` folder, a motion folder, or an
//! `egogen-run` dataset) in, each wearer's Aria streams out (`export::aria`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::export::aria::{write_wearer_streams, AriaSettings, AriaStreams, Wearer};
use crate::export::gaze::GazeGoal;
use crate::math::{affine_from_row_major, Affine3};
use crate::rig::Rig;
use crate::synth::activity::LookAt;
use crate::synth::sequence_dir::read_cpf_trajectory;

/// What `egogen aria export` was asked.
#[derive(Debug, Clone, clap::Args)]
pub struct AriaExportArgs {
    /// The take: a folder written by `egogen synth`, `egogen-run` without `[render]`, or an
    /// `egogen-run` dataset (its `sequence/` is read, and each camera's headset offset).
    pub take: PathBuf,
    /// The device: an egogen rig or an Aria device calibration JSON (default: the shipped
    /// Aria gen1 rig, with imu-left and imu-right).
    #[arg(long)]
    pub rig: Option<PathBuf>,
    /// The new folder to write (must not exist): `OUT/<wearer>/…` and `OUT/manifest.json`.
    #[arg(long)]
    pub out: PathBuf,
    /// Streams to write (comma-separated): trajectory, calibration, imu, gaze.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "trajectory,calibration,imu,gaze"
    )]
    pub streams: Vec<String>,
    /// Agents that wear the device (repeat or comma-separate); default: a dataset's wearers,
    /// else every agent of the take.
    #[arg(long, value_delimiter = ',')]
    pub wearer: Vec<String>,
    /// Rows per second of the device trajectory.
    #[arg(long, default_value_t = 1000.0)]
    pub trajectory_rate_hz: f64,
    /// Ideal IMUs: no noise, no bias, no saturation, an identity calibration.
    #[arg(long)]
    pub ideal_imu: bool,
    /// Seed of the IMU errors and the gaze.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Eye gaze samples per second.
    #[arg(long, default_value_t = 30.0)]
    pub gaze_rate_hz: f64,
}

/// One agent's head through a take, as read from its folder.
struct TakeHead {
    name: String,
    frame_rate_hz: f64,
    world_from_cpf: Vec<Affine3>,
    cpf_from_headset: Affine3,
    goals: Vec<GazeGoal>,
    looks: Vec<LookAt>,
}

/// Runs `egogen aria export`.
pub fn aria_export(args: &AriaExportArgs) -> Result<()> {
    let streams =
        AriaStreams::parse(&args.streams).map_err(|e| anyhow::anyhow!("--streams: {e}"))?;
    if !streams.any() {
        bail!(
            "--streams: no stream asked; expected any of {}",
            AriaStreams::NAMES.join(", ")
        );
    }
    let rig_path = args
        .rig
        .clone()
        .unwrap_or_else(|| crate::paths::crate_root().join("camera_rigs/aria_gen1.json"));
    let rig = Rig::load(&rig_path)?;
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
    if args.out.exists() {
        bail!(
            "--out {} already exists; choose a new folder (nothing was written)",
            args.out.display()
        );
    }
    let staging = PathBuf::from(format!("{}.partial", args.out.display()));
    let (wearers, everyone) = read_take_heads(&args.take, &args.wearer)?;
    if staging.exists() {
        // Left by an export that was killed: started again when it holds only what an export
        // of this take writes (a folder per wearer, the manifest); anything else is not ours.
        let names: Vec<&str> = wearers.iter().map(|&w| everyone[w].name.as_str()).collect();
        if !holds_only_export_entries(&staging, &names) {
            bail!(
                "{} exists and holds files an export of this take does not write; move it away first (nothing was written)",
                staging.display()
            );
        }
        eprintln!(
            "egogen aria export: {} is left by an interrupted export; exporting again",
            staging.display()
        );
        std::fs::remove_dir_all(&staging)
            .with_context(|| format!("removing {}", staging.display()))?;
    }
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
    std::fs::create_dir_all(&staging).with_context(|| format!("creating {}", staging.display()))?;
    let exported = export_into(
        &staging,
        &args.out,
        &rig,
        &settings,
        &wearers,
        &everyone,
        rays.as_ref(),
    );
    if exported.is_err() {
        // Nothing half-written is left: the staging folder is this run's own.
        let _ = std::fs::remove_dir_all(&staging);
    }
    exported
}

/// Whether `dir` holds only what an export of wearers `names` writes.
fn holds_only_export_entries(dir: &Path, names: &[&str]) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    entries.flatten().all(|e| {
        let name = e.file_name().to_string_lossy().into_owned();
        let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
        (is_dir && names.contains(&name.as_str())) || (!is_dir && name.starts_with("manifest.json"))
    })
}

/// Writes every wearer's streams and the manifest into `staging`, then renames it to `out`.
fn export_into(
    staging: &Path,
    out: &Path,
    rig: &crate::rig::Rig,
    settings: &AriaSettings,
    wearers: &[usize],
    everyone: &[TakeHead],
    rays: Option<&crate::scene::mesh_distance::SceneRays>,
) -> Result<()> {
    let started = std::time::Instant::now();
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
    std::fs::rename(staging, out)
        .with_context(|| format!("renaming {} to {}", staging.display(), out.display()))?;
    println!(
        "wrote {} ({} wearers in {:.2} s)",
        out.display(),
        wearers.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The take's folder of motion: a dataset's `sequence/`, else the take itself.
fn motion_root(take: &Path) -> PathBuf {
    if take.join("sequence").is_dir() {
        take.join("sequence")
    } else {
        take.to_path_buf()
    }
}

/// The scene a take was made in (`summary.json`'s `about.scene`), if it names one.
fn take_scene(take: &Path) -> Result<Option<(PathBuf, crate::scene::SceneFrame)>> {
    let path = motion_root(take).join("summary.json");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(None);
    };
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let about = &v["about"];
    let Some(scene) = about["scene"].as_str() else {
        return Ok(None);
    };
    // How the take read its scene file (absent: as its format says).
    let up = match about["scene_up_axis"].as_str() {
        None => None,
        Some(name) => Some(crate::scene::UpAxis::from_name(name).ok_or_else(|| {
            anyhow::anyhow!(
                "{}: about.scene_up_axis is `{name}`; expected \"y\" or \"z\"",
                path.display()
            )
        })?),
    };
    let frame = crate::scene::SceneFrame::new(up, about["scene_unit_m"].as_f64())
        .map_err(|m| anyhow::anyhow!("{}: about.scene_unit_m: {m}", path.display()))?;
    Ok(Some((PathBuf::from(scene), frame)))
}

/// Each agent's goals and what its activities act on, from `summary.json`
/// (`agents[].goals[]`: `goal` [x, y], `end_frame`; `agents[].activities[].look_at`).
fn take_targets(take: &Path) -> Result<Vec<(String, Vec<GazeGoal>, Vec<LookAt>)>> {
    let path = motion_root(take).join("summary.json");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Vec::new());
    };
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let mut out = Vec::new();
    for a in v["agents"].as_array().into_iter().flatten() {
        let name = a["name"].as_str().unwrap_or_default().to_string();
        let goals = a["goals"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|g| {
                Some(GazeGoal {
                    xy: [g["goal"][0].as_f64()?, g["goal"][1].as_f64()?],
                    until_frame: g["end_frame"].as_u64()? as usize,
                })
            })
            .collect();
        let mut looks = Vec::new();
        for (k, act) in a["activities"].as_array().into_iter().flatten().enumerate() {
            if act.get("look_at").is_none() {
                continue;
            }
            let look: LookAt =
                serde_json::from_value(act["look_at"].clone()).with_context(|| {
                    format!(
                        "{}: agent {name}: key activities[{k}].look_at: expected {{ point: [x, y, z], start_frame, end_frame }}",
                        path.display()
                    )
                })?;
            looks.push(look);
        }
        out.push((name, goals, looks));
    }
    Ok(out)
}

/// The agents' heads of a take folder: the `wanted` ones (all, or a dataset's wearers, when
/// empty) as indices into everyone's.
fn read_take_heads(take: &Path, wanted: &[String]) -> Result<(Vec<usize>, Vec<TakeHead>)> {
    if !take.is_dir() {
        bail!("take {}: not a folder", take.display());
    }
    let dataset_wear = read_dataset_wear(take)?;
    let root = motion_root(take);
    let mut found: Vec<(String, PathBuf)> = Vec::new();
    if root.join("agents").is_dir() {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(root.join("agents"))
            .with_context(|| format!("reading {}", root.join("agents").display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.join("cpf_trajectory.json").is_file())
            .collect();
        entries.sort();
        for p in entries {
            let name = p
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            found.push((name, p.join("cpf_trajectory.json")));
        }
    } else if root.join("cpf_trajectory.json").is_file() {
        found.push(("agent_0".into(), root.join("cpf_trajectory.json")));
    }
    if found.is_empty() {
        bail!(
            "take {}: no head trajectory found; expected agents/<name>/cpf_trajectory.json (egogen synth), cpf_trajectory.json (a motion folder) or sequence/ (an egogen-run dataset)",
            take.display()
        );
    }
    let names: Vec<String> = if !wanted.is_empty() {
        wanted.to_vec()
    } else if !dataset_wear.is_empty() {
        dataset_wear.iter().map(|w| w.0.clone()).collect()
    } else {
        found.iter().map(|f| f.0.clone()).collect()
    };
    for name in &names {
        if !found.iter().any(|f| &f.0 == name) {
            bail!(
                "--wearer {name}: take {} has no agent `{name}`; it has {}",
                take.display(),
                found
                    .iter()
                    .map(|f| f.0.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    let targets = take_targets(take)?;
    let everyone = found
        .iter()
        .map(|(name, path)| {
            let (frame_rate_hz, world_from_cpf) = read_cpf_trajectory(path)?;
            let cpf_from_headset = dataset_wear
                .iter()
                .find(|w| &w.0 == name)
                .map_or(Affine3::IDENTITY, |w| w.1);
            Ok(TakeHead {
                name: name.clone(),
                frame_rate_hz,
                world_from_cpf,
                cpf_from_headset,
                goals: targets
                    .iter()
                    .find(|g| &g.0 == name)
                    .map(|g| g.1.clone())
                    .unwrap_or_default(),
                looks: targets
                    .iter()
                    .find(|g| &g.0 == name)
                    .map(|g| g.2.clone())
                    .unwrap_or_default(),
            })
        })
        .collect::<Result<Vec<TakeHead>>>()?;
    let wearers = names
        .iter()
        .filter_map(|n| everyone.iter().position(|h| &h.name == n))
        .collect();
    Ok((wearers, everyone))
}

/// A dataset's wearers with their headset offsets (`cameras/*/annotations.json`), in the
/// order first seen; empty for a take that is not a dataset.
fn read_dataset_wear(take: &Path) -> Result<Vec<(String, Affine3)>> {
    let cameras = take.join("cameras");
    let mut wear: Vec<(String, Affine3)> = Vec::new();
    let Ok(dir) = std::fs::read_dir(&cameras) else {
        return Ok(wear);
    };
    let mut files: Vec<PathBuf> = dir
        .filter_map(|e| e.ok().map(|e| e.path().join("annotations.json")))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    for path in files {
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        let v: serde_json::Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
        let Some(name) = v["wearer"].as_str() else {
            bail!(
                "{}: key `wearer`: expected the wearer's name",
                path.display()
            );
        };
        let raw = &v["headset_wear"]["t_cpf_headset"];
        let pose = match raw.is_null() {
            true => Affine3::IDENTITY,
            false => serde_json::from_value::<[[f64; 4]; 4]>(raw.clone())
                .ok()
                .and_then(|rows| affine_from_row_major(&rows))
                .with_context(|| {
                format!("{}: key `headset_wear.t_cpf_headset`: expected a row-major 4×4 rigid transform", path.display())
            })?,
        };
        if !wear.iter().any(|w| w.0 == name) {
            wear.push((name.to_string(), pose));
        }
    }
    Ok(wear)
}
