//! A take's folder read back, for the exports made of a finished take (`egogen aria export`,
//! `egogen euroc export`): its agents' head poses (an `egogen synth` folder's
//! `agents/<name>/cpf_trajectory.json`, a motion folder's `cpf_trajectory.json`, or an
//! `egogen-run` dataset's `sequence/`), a dataset's rendered cameras with their wearers and
//! headset offsets (`cameras/<camera>/annotations.json`, the `annotations` types), the scene it
//! was made in and each agent's goals (`summary.json`). Errors name the file and the key.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::annotations::CameraAnnotations;
use super::gaze::GazeGoal;
use crate::math::{affine_from_row_major, Affine3};
use crate::rig::{AriaRgbResolution, Rig, RigCamera};
use crate::synth::activity::LookAt;
use crate::synth::sequence_dir::read_cpf_trajectory;

/// One agent's head through a take, as read from its folder.
pub(crate) struct TakeHead {
    pub name: String,
    pub frame_rate_hz: f64,
    /// `world_from_cpf` of every motion frame.
    pub world_from_cpf: Vec<Affine3>,
    /// How the headset sat on this head (a dataset's annotations; identity elsewhere).
    pub cpf_from_headset: Affine3,
    pub goals: Vec<GazeGoal>,
    pub looks: Vec<LookAt>,
    /// Its body's motion file (`motion.npz` beside its head trajectory), when there is one.
    pub motion: Option<PathBuf>,
}

/// One camera a dataset rendered, from its `cameras/<camera>/annotations.json`.
#[derive(Debug, Clone)]
pub(crate) struct RenderedCamera {
    /// The camera as rendered (its name in the dataset, the model at the rendered size, its
    /// pose on the CPF).
    pub camera: RigCamera,
    /// The agent wearing it.
    pub wearer: String,
    /// The motion's frame rate (frame `f` is at `f / frame_rate_hz`).
    pub frame_rate_hz: f64,
    /// How the headset sat on the wearer's head (identity: as the rig places it).
    pub cpf_from_headset: Affine3,
    /// Every rendered frame: its motion frame and `T_world_cam` (OpenCV camera frame).
    pub frames: Vec<(u32, Affine3)>,
    /// The annotations file it was read from.
    pub source: PathBuf,
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
pub(crate) fn take_scene(take: &Path) -> Result<Option<(PathBuf, crate::scene::SceneFrame)>> {
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
pub(crate) fn read_take_heads(
    take: &Path,
    wanted: &[String],
) -> Result<(Vec<usize>, Vec<TakeHead>)> {
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
            let target = targets.iter().find(|g| &g.0 == name);
            let motion = path
                .parent()
                .map(|d| d.join("motion.npz"))
                .filter(|m| m.is_file());
            Ok(TakeHead {
                name: name.clone(),
                frame_rate_hz,
                world_from_cpf,
                cpf_from_headset,
                goals: target.map(|g| g.1.clone()).unwrap_or_default(),
                looks: target.map(|g| g.2.clone()).unwrap_or_default(),
                motion,
            })
        })
        .collect::<Result<Vec<TakeHead>>>()?;
    let wearers = names
        .iter()
        .filter_map(|n| everyone.iter().position(|h| &h.name == n))
        .collect();
    Ok((wearers, everyone))
}

/// A dataset's wearers with their headset offsets, in the order first seen among its cameras;
/// empty for a take that is not a dataset.
fn read_dataset_wear(take: &Path) -> Result<Vec<(String, Affine3)>> {
    let mut wear: Vec<(String, Affine3)> = Vec::new();
    for cam in read_rendered_cameras(take)? {
        if !wear.iter().any(|w| w.0 == cam.wearer) {
            wear.push((cam.wearer, cam.cpf_from_headset));
        }
    }
    Ok(wear)
}

/// Every camera a dataset rendered (`cameras/*/annotations.json`), in name order; empty for
/// a take that is not a dataset.
pub(crate) fn read_rendered_cameras(take: &Path) -> Result<Vec<RenderedCamera>> {
    let Ok(dir) = std::fs::read_dir(take.join("cameras")) else {
        return Ok(Vec::new());
    };
    let mut files: Vec<PathBuf> = dir
        .filter_map(|e| e.ok().map(|e| e.path().join("annotations.json")))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files.iter().map(|p| read_rendered_camera(p)).collect()
}

/// One camera's annotations file as a [`RenderedCamera`].
fn read_rendered_camera(path: &Path) -> Result<RenderedCamera> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let doc: CameraAnnotations = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not an egogen annotations file (docs/ANNOTATIONS.md)",
            path.display()
        )
    })?;
    // The camera is written as a rig file's camera entry: read it back as a one-camera rig.
    let rig_json = serde_json::json!({
        "egogen_rig": crate::rig::FORMAT_VERSION,
        "name": "annotations",
        "cameras": [doc.camera],
    });
    let camera = Rig::from_json_str(path, &rig_json.to_string(), AriaRgbResolution::default())
        .with_context(|| format!("{}: key `camera`", path.display()))?
        .cameras
        .remove(0);
    let cpf_from_headset = match &doc.headset_wear {
        None => Affine3::IDENTITY,
        Some(w) => affine_from_row_major(&w.t_cpf_headset).with_context(|| {
            format!(
                "{}: key `headset_wear.t_cpf_headset`: expected a row-major 4×4 rigid transform",
                path.display()
            )
        })?,
    };
    let frames = doc
        .frames
        .iter()
        .map(|f| {
            let pose = affine_from_row_major(&f.t_world_cam).with_context(|| {
                format!(
                    "{}: frame {}: key `T_world_cam`: expected a row-major 4×4 transform of finite numbers",
                    path.display(),
                    f.frame
                )
            })?;
            Ok((f.frame, pose))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(RenderedCamera {
        camera,
        wearer: doc.wearer,
        frame_rate_hz: doc.frame_rate_hz,
        cpf_from_headset,
        frames,
        source: path.to_path_buf(),
    })
}
