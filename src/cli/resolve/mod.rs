//! Turns a [`RawRun`] into a [`RunPlan`]: paths resolved, values range-checked.
//!
//! This file holds the run and the checks of keys a motion source does not read; the sections
//! are `motion`, `render` and `supervisor`.

mod motion;
mod render;
mod supervisor;

use std::path::Path;

use super::config::{Bad, ConfigError, MotionSource, RawRun};
pub(crate) use super::config_file::resolve_body_model;
pub(crate) use super::config_file::{crate_root, DEFAULT_BODY_MODEL};
use motion::{agents_motion, file_motion, scripted_motion};
use render::resolve_render;
use supervisor::resolve_supervisor;

/// Default scene, relative to the crate root.
pub(crate) const DEFAULT_SCENE: &str = "assets/scenes/apartment.glb";
/// Default rig, relative to the crate root.
pub(crate) const DEFAULT_RIG: &str = "camera_rigs/aria_gen1.json";

pub(crate) use crate::plan::MotionPlan;
pub(crate) use crate::plan::RunPlan;

/// Most frames a scripted walk may have (about 7 h at 40 Hz).
pub(crate) const MAX_SCRIPTED_FRAMES: f64 = 1e6;

/// Largest shape coefficient a config may ask for (standard deviations).
pub(crate) const MAX_ABS_BETA: f64 = 10.0;

/// Resolves paths against the config's folder and checks value ranges.
pub fn resolve_run(raw: RawRun, config_path: &Path) -> Result<RunPlan, ConfigError> {
    let base = config_path.parent().unwrap_or(Path::new("."));
    let bad = |key: &str, message: String| ConfigError::Value {
        path: config_path.into(),
        key: key.into(),
        message,
    };
    let body_model =
        resolve_body_model(raw.body.model.clone(), base).map_err(|m| bad("body.model", m))?;
    check_betas(&raw.body.betas, &bad)?;
    let scene = match &raw.scene.path {
        Some(p) => crate::scene::dwelling::scene_source(&p.to_string_lossy(), base)
            .map_err(|m| bad("scene.path", m))?,
        None => crate_root().join(DEFAULT_SCENE),
    };
    check_unused_for_source(&raw, &bad)?;
    let motion = match raw.motion.source {
        MotionSource::Agents => agents_motion(&raw, &scene, config_path, &bad)?,
        MotionSource::ScriptedWalk => scripted_motion(&raw.motion, &bad)?,
        MotionSource::File => file_motion(&raw.motion, base, &bad)?,
    };
    if !scene.is_file() {
        return Err(bad(
            "scene.path",
            format!("file {} not found", scene.display()),
        ));
    }
    let render = raw
        .render
        .map(|r| resolve_render(r, base, config_path))
        .transpose()?;
    let renderable = scene
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["glb", "gltf", "obj", "ply"].contains(&e.to_lowercase().as_str()));
    if render.is_some() && !renderable {
        return Err(bad(
            "scene.path",
            format!(
                "{}: rendering reads glTF (.glb, .gltf), OBJ (.obj) and PLY (.ply) scenes; convert the scene to one of them, or leave out [render] for a motion-only run",
                scene.display()
            ),
        ));
    }
    Ok(RunPlan {
        body_model,
        betas: raw.body.betas,
        motion,
        output_dir: base.join(raw.output.dir),
        mesh_every_n_frames: raw.output.mesh_every_n_frames,
        scene,
        scene_frame: super::synth_config::scene_frame(raw.scene.up_axis, raw.scene.unit_m, &bad)?,
        scene_seed: raw.scene.seed.unwrap_or(0),
        ceiling: raw.scene.ceiling.unwrap_or(true),
        walkable: super::synth_config::floor_settings(
            raw.scene.floor_z_m,
            raw.scene.floor_steps_m,
            &bad,
        )?,
        render,
        supervisor: resolve_supervisor(raw.supervisor, config_path)?,
    })
}

/// A key that `source` does not read.
fn unused(key: &str, present: bool, source: &str, bad: Bad) -> Result<(), ConfigError> {
    match present {
        true => Err(bad(
            key,
            format!("not used when motion.source = \"{source}\"; remove it"),
        )),
        false => Ok(()),
    }
}

/// `body.betas`: finite, within ±[`MAX_ABS_BETA`].
fn check_betas(betas: &[f64], bad: Bad) -> Result<(), ConfigError> {
    if let Some(i) = betas.iter().position(|b| !b.is_finite()) {
        return Err(bad(
            "body.betas",
            format!("value {i} is not a finite number"),
        ));
    }
    if let Some((i, b)) = betas
        .iter()
        .enumerate()
        .find(|(_, b)| b.abs() > MAX_ABS_BETA)
    {
        return Err(bad(
            "body.betas",
            format!(
                "value {i} is {b}: expected within ±{MAX_ABS_BETA} (shape coefficients are in \
                 standard deviations of the shape space; people lie within about ±3)"
            ),
        ));
    }
    Ok(())
}

/// The agents' keys are refused with a scripted walk or a motion file.
fn check_unused_for_source(raw: &RawRun, bad: Bad) -> Result<(), ConfigError> {
    let m = &raw.motion;
    if m.source == MotionSource::Agents {
        return Ok(());
    }
    let source = match m.source {
        MotionSource::ScriptedWalk => "scripted_walk",
        _ => "file",
    };
    let walker_key = raw
        .walker
        .changed_keys()
        .first()
        .map_or("walker".into(), |k| format!("walker.{k}"));
    for (key, present) in [
        ("motion.weights", m.weights.is_some()),
        ("motion.policy", m.policy.is_some()),
        ("motion.pose_prior", m.pose_prior.is_some()),
        ("motion.train_config", m.train_config.is_some()),
        ("motion.stop_when_done", m.stop_when_done.is_some()),
        ("motion.wander_distance_m", m.wander_distance_m.is_some()),
        ("motion.clearance_m", m.clearance_m.is_some()),
        ("motion.seed", m.seed.is_some()),
        (walker_key.as_str(), !raw.walker.is_default()),
        ("activities", !raw.activities.is_default()),
        ("crowd", raw.crowd.is_some()),
        ("agents", !raw.agents.is_empty()),
        ("obstacles", !raw.obstacles.is_empty()),
        ("scene.indoors", raw.scene.indoors.is_some()),
        (
            "render.wearers",
            raw.render.as_ref().is_some_and(|r| r.wearers.is_some()),
        ),
    ] {
        unused(key, present, source, bad)?;
    }
    Ok(())
}
