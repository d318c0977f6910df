//! Turns a [`RawRun`] into a [`RunPlan`]: paths resolved, values range-checked.

use std::path::Path;

use super::config::{
    Backend, Bad, ConfigError, MotionSource, RawDepthNoise, RawMotion, RawRender, RawRun, RawSlurm,
    RawSupervisor,
};
use crate::render::depth_noise::DepthNoise;
use crate::render::lighting::{LightingPlan, WorldChoice, SHIPPED_HDRIS};
use crate::render::passes::{Pass, Passes};
use crate::render::render_camera::RenderCamera;
use crate::render::skin_tone::SkinPlan;
use crate::rig::{Rig, RigCamera};

pub use super::config_file::{crate_root, resolve_body_model, DEFAULT_BODY_MODEL};
/// Default scene, relative to the crate root.
pub(crate) const DEFAULT_SCENE: &str = "assets/scenes/apartment.glb";
/// Default rig, relative to the crate root.
pub(crate) const DEFAULT_RIG: &str = "camera_rigs/aria_gen1.json";

pub use crate::plan::{MotionPlan, RenderPlan, RunPlan, SlurmPlan, SupervisorPlan};

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

/// `motion.source = "agents"`: the synth config inside the run config, checked as
/// `egogen synth` checks its own, and who wears the rig.
fn agents_motion(
    raw: &RawRun,
    scene: &Path,
    config_path: &Path,
    bad: Bad,
) -> Result<MotionPlan, ConfigError> {
    let m = &raw.motion;
    for (key, present) in [
        ("motion.path", m.path.is_some()),
        ("motion.frame_rate_hz", m.frame_rate_hz.is_some()),
        ("motion.speed_m_per_s", m.speed_m_per_s.is_some()),
        ("scene.seed", raw.scene.seed.is_some()),
    ] {
        unused(key, present, "agents", bad)?;
    }
    if !raw.body.betas.is_empty() {
        return Err(bad(
            "body.betas",
            "not used when motion.source = \"agents\": give each agent its betas in [[agents]] (or let [crowd] draw them)".into(),
        ));
    }
    use super::synth_config::{RawSynth, RawSynthMotion, RawSynthOutput, RawSynthScene};
    let synth = RawSynth {
        body_model: raw.body.model.clone(),
        scene: RawSynthScene {
            path: Some(std::path::absolute(scene).unwrap_or_else(|_| scene.to_path_buf())),
            floor_m: None,
            indoors: raw.scene.indoors,
            floor_z_m: raw.scene.floor_z_m,
            floor_steps_m: raw.scene.floor_steps_m,
            up_axis: raw.scene.up_axis,
            unit_m: raw.scene.unit_m,
        },
        motion: RawSynthMotion {
            weights: m.weights.clone(),
            policy: m.policy.clone(),
            pose_prior: m.pose_prior.clone(),
            train_config: m.train_config.clone(),
            duration_s: m.duration_s,
            stop_when_done: Some(m.stop_when_done.unwrap_or(false)),
            wander_distance_m: m.wander_distance_m,
            clearance_m: m.clearance_m,
            seed: m.seed,
        },
        walker: raw.walker,
        activities: raw.activities,
        crowd: raw.crowd.clone(),
        agents: raw.agents.clone(),
        obstacles: raw.obstacles.clone(),
        output: RawSynthOutput {
            dir: raw.output.dir.clone(),
        },
    };
    let synth = super::synth_config::resolve_synth(synth, config_path, "")?;
    let wearers = wearer_indices(&synth, raw.render.as_ref(), bad)?;
    Ok(MotionPlan::Agents {
        synth: Box::new(synth),
        wearers,
    })
}

/// `render.wearers` as indices into the take's agents (default: the first), each named once.
fn wearer_indices(
    synth: &crate::plan::SynthPlan,
    render: Option<&RawRender>,
    bad: Bad,
) -> Result<Vec<usize>, ConfigError> {
    let names: Vec<&str> = synth.agents.iter().map(|a| a.name.as_str()).collect();
    let wearers = match render.and_then(|r| r.wearers.clone()) {
        None => vec![0],
        Some(w) if w.is_empty() => {
            return Err(bad(
                "render.wearers",
                "expected at least one agent's name".into(),
            ))
        }
        Some(w) => w
            .iter()
            .map(|n| {
                names.iter().position(|a| a == n).ok_or_else(|| {
                    bad(
                        "render.wearers",
                        format!("no agent is called \"{n}\" (agents: {})", names.join(", ")),
                    )
                })
            })
            .collect::<Result<_, _>>()?,
    };
    let mut seen = std::collections::BTreeSet::new();
    if let Some(&w) = wearers.iter().find(|&&w| !seen.insert(w)) {
        return Err(bad(
            "render.wearers",
            format!("\"{}\" is named twice", names[w]),
        ));
    }
    Ok(wearers)
}

/// `motion.source = "scripted_walk"`: its length, rate and pace.
fn scripted_motion(m: &RawMotion, bad: Bad) -> Result<MotionPlan, ConfigError> {
    unused("motion.path", m.path.is_some(), "scripted_walk", bad)?;
    let positive = |key: &str, v: Option<f64>| match v {
        Some(v) if v.is_finite() && v > 0.0 => Ok(v),
        Some(v) => Err(bad(key, format!("expected a positive number, found {v}"))),
        None => Err(bad(
            key,
            "required when motion.source = \"scripted_walk\"".into(),
        )),
    };
    let duration_s = positive("motion.duration_s", m.duration_s)?;
    let frame_rate_hz = positive("motion.frame_rate_hz", m.frame_rate_hz)?;
    let frames = duration_s * frame_rate_hz;
    if frames > MAX_SCRIPTED_FRAMES {
        return Err(bad(
            "motion.duration_s",
            format!(
                "{duration_s} s at {frame_rate_hz} Hz is {frames:.3e} frames ({:.1} GB of \
                 poses alone); at most {MAX_SCRIPTED_FRAMES:.0} frames",
                frames * (165.0 + 3.0) * 8.0 / 1e9
            ),
        ));
    }
    // The walk's poses and the track made from them (joints and eye frame per frame).
    let per_frame = std::mem::size_of::<crate::body::BodyParams>()
        + std::mem::size_of::<crate::synth::TrackFrame>();
    crate::memory::check_fits(
        &format!("a scripted walk of {frames:.0} frames ({duration_s} s at {frame_rate_hz} Hz)"),
        frames * per_frame as f64,
    )
    .map_err(|m| bad("motion.duration_s", m))?;
    let speed_m_per_s = m.speed_m_per_s.unwrap_or(1.2);
    if !(speed_m_per_s.is_finite() && (0.0..=10.0).contains(&speed_m_per_s)) {
        return Err(bad(
            "motion.speed_m_per_s",
            format!("expected 0..=10 m/s, found {speed_m_per_s}"),
        ));
    }
    Ok(MotionPlan::ScriptedWalk {
        duration_s,
        frame_rate_hz,
        speed_m_per_s,
    })
}

/// `motion.source = "file"`: the motion file, relative to `base`.
fn file_motion(m: &RawMotion, base: &Path, bad: Bad) -> Result<MotionPlan, ConfigError> {
    for (key, present) in [
        ("motion.duration_s", m.duration_s.is_some()),
        ("motion.frame_rate_hz", m.frame_rate_hz.is_some()),
        ("motion.speed_m_per_s", m.speed_m_per_s.is_some()),
    ] {
        unused(key, present, "file", bad)?;
    }
    let path = m.path.as_ref().ok_or_else(|| {
        bad(
            "motion.path",
            "required when motion.source = \"file\"".into(),
        )
    })?;
    let path = base.join(path);
    if !path.is_file() {
        return Err(bad(
            "motion.path",
            format!("file {} not found", path.display()),
        ));
    }
    Ok(MotionPlan::File { path })
}

fn resolve_render(
    r: RawRender,
    base: &Path,
    config_path: &Path,
) -> Result<RenderPlan, ConfigError> {
    let bad = |key: &str, message: String| ConfigError::Value {
        path: config_path.into(),
        key: key.into(),
        message,
    };
    let (rig, cameras) = rig_cameras(&r, base, &bad)?;
    let fisheye = r.fisheye.unwrap_or_default();
    let render_cameras = cameras
        .iter()
        .map(|cam| {
            RenderCamera::for_camera(&cam.model, 1.0, fisheye)
                .map_err(|e| bad("render.fisheye", format!("camera `{}`: {e}", cam.name)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let depth_noise = match r.depth_noise {
        None => vec![None; cameras.len()],
        Some(raw) => resolve_depth_noise(raw, &cameras, config_path)?,
    };
    let positive_int = |key: &str, v: Option<usize>, default: usize| match v.unwrap_or(default) {
        0 => Err(bad(key, "expected a whole number ≥ 1, found 0".into())),
        n => Ok(n),
    };
    let every_n_frames = positive_int("render.every_n_frames", r.every_n_frames, 1)?;
    let frames_per_shard = positive_int("render.frames_per_shard", r.frames_per_shard, 20)?;
    let samples = positive_int("render.samples", r.samples.map(|s| s as usize), 16)? as u32;
    let cache_samples_per_frame = positive_int(
        "render.cache_samples_per_frame",
        r.cache_samples_per_frame.map(|s| s as usize),
        4,
    )? as u32;
    let shutter_frames = r.shutter_frames.unwrap_or(0.5);
    if !(shutter_frames.is_finite() && (0.0..=1.0).contains(&shutter_frames)) {
        return Err(bad(
            "render.shutter_frames",
            format!("expected a shutter time in frames within [0, 1], found {shutter_frames}"),
        ));
    }
    let adaptive_threshold = r.adaptive_threshold.unwrap_or(0.0);
    if !(adaptive_threshold.is_finite() && adaptive_threshold >= 0.0) {
        return Err(bad(
            "render.adaptive_threshold",
            format!("expected a noise threshold ≥ 0 (0 = off), found {adaptive_threshold}"),
        ));
    }
    let denoise = r
        .denoise
        .unwrap_or(false)
        .then(|| r.denoise_prefilter.unwrap_or_default());
    if r.denoise_prefilter.is_some() && denoise.is_none() {
        return Err(bad(
            "render.denoise_prefilter",
            "guides the denoiser, which is off: set `denoise = true` or leave the key out".into(),
        ));
    }
    let near_clip_m = r.near_clip_m.unwrap_or(0.12);
    if !(near_clip_m.is_finite() && near_clip_m > 0.0 && near_clip_m < 10.0) {
        return Err(bad(
            "render.near_clip_m",
            format!("expected a distance in (0, 10) m, found {near_clip_m}"),
        ));
    }
    let headset_wear = r
        .headset_wear
        .as_ref()
        .map(|w| headset_wear(w, &bad))
        .transpose()?;
    let lighting = match r.lighting {
        None => LightingPlan::default(),
        Some(l) => resolve_lighting(l, config_path)?,
    };
    let materials = r
        .materials
        .as_ref()
        .map(|m| crate::render::materials::MaterialsPlan {
            mode: m.mode.unwrap_or_default(),
            seed: m.seed.unwrap_or(0),
        })
        .unwrap_or_default();
    let skin = match &r.skin {
        None => SkinPlan::default(),
        Some(raw) => skin_plan(raw, &bad)?,
    };
    let passes = resolve_passes(
        r.passes.as_deref(),
        depth_noise.iter().any(Option::is_some),
        config_path,
    )?;
    let colmap = resolve_colmap(r.colmap, passes, config_path)?;
    let aria = r
        .aria
        .as_ref()
        .map(|a| aria_settings(a, &rig, &bad))
        .transpose()?
        .flatten();
    Ok(RenderPlan {
        rig,
        cameras,
        every_n_frames,
        samples,
        adaptive_threshold,
        denoise,
        shutter_frames,
        cache_samples_per_frame,
        frames_per_shard,
        near_clip_m,
        render_cameras,
        depth_noise,
        headset_wear,
        lighting,
        materials,
        skin,
        passes,
        colmap,
        device: r.device.unwrap_or_default(),
        aria,
    })
}

/// `[render.aria]`: the streams asked (none: `None`), checked against the rig.
fn aria_settings(
    raw: &super::config::RawAria,
    rig: &Rig,
    bad: Bad,
) -> Result<Option<crate::export::aria::AriaSettings>, ConfigError> {
    use crate::export::aria::{AriaSettings, AriaStreams};
    let streams = AriaStreams::parse(raw.streams.as_deref().unwrap_or_default())
        .map_err(|m| bad("render.aria.streams", m))?;
    if !streams.any() {
        return Ok(None);
    }
    let d = AriaSettings::default();
    let settings = AriaSettings {
        streams,
        trajectory_rate_hz: raw.trajectory_rate_hz.unwrap_or(d.trajectory_rate_hz),
        imu_errors: raw.imu_errors.unwrap_or(d.imu_errors),
        imu_error_overrides: raw.imu.clone(),
        seed: raw.seed.unwrap_or(d.seed),
        calibration_every_s: raw.calibration_every_s.unwrap_or(d.calibration_every_s),
        gaze_rate_hz: raw.gaze_rate_hz.unwrap_or(d.gaze_rate_hz),
    };
    match settings.problem(rig) {
        Some(p) => Err(bad("render.aria", p)),
        None => Ok(Some(settings)),
    }
}

/// The rig of `[render] rig` and the cameras `[render] cameras` names from it, at
/// `resolution_scale`.
fn rig_cameras(r: &RawRender, base: &Path, bad: Bad) -> Result<(Rig, Vec<RigCamera>), ConfigError> {
    let rig_path = match &r.rig {
        Some(p) => base.join(p),
        None => crate_root().join(DEFAULT_RIG),
    };
    if !rig_path.is_file() {
        return Err(bad(
            "render.rig",
            format!("file {} not found", rig_path.display()),
        ));
    }
    let rig = Rig::load(&rig_path).map_err(|e| bad("render.rig", e.to_string()))?;
    let names: Vec<String> = match r.cameras.clone() {
        Some(names) if names.is_empty() => {
            return Err(bad(
                "render.cameras",
                "empty list: name at least one camera".into(),
            ))
        }
        Some(names) => {
            if let Some(dup) = names
                .iter()
                .enumerate()
                .find_map(|(i, n)| names[..i].contains(n).then_some(n))
            {
                return Err(bad(
                    "render.cameras",
                    format!("camera {dup:?} is listed twice; name each camera once"),
                ));
            }
            names
        }
        None => rig.camera_names().iter().map(|n| n.to_string()).collect(),
    };
    let scale = r.resolution_scale.unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0 && scale <= 4.0) {
        return Err(bad(
            "render.resolution_scale",
            format!("expected a factor in (0, 4], found {scale}"),
        ));
    }
    let mut cameras = Vec::with_capacity(names.len());
    for name in &names {
        let cam = rig
            .camera(name)
            .map_err(|e| bad("render.cameras", e.to_string()))?;
        let model = cam
            .model
            .scaled(scale)
            .map_err(|e| bad("render.resolution_scale", format!("camera `{name}`: {e}")))?;
        cameras.push(RigCamera {
            model,
            ..cam.clone()
        });
    }
    Ok((rig, cameras))
}

/// `[render.headset_wear]`: how far the rig may sit off its place on each wearer's head.
fn headset_wear(
    w: &super::config::RawHeadsetWear,
    bad: Bad,
) -> Result<crate::rig::wear::HeadsetWear, ConfigError> {
    let translation_m = w.translation_m.unwrap_or(0.01);
    if !(translation_m.is_finite() && (0.0..=0.1).contains(&translation_m)) {
        return Err(bad(
            "render.headset_wear.translation_m",
            format!("expected a distance within [0, 0.1] m, found {translation_m}"),
        ));
    }
    let rotation_deg = w.rotation_deg.unwrap_or(3.0);
    if !(rotation_deg.is_finite() && (0.0..=30.0).contains(&rotation_deg)) {
        return Err(bad(
            "render.headset_wear.rotation_deg",
            format!("expected an angle within [0, 30] degrees, found {rotation_deg}"),
        ));
    }
    Ok(crate::rig::wear::HeadsetWear {
        translation_m,
        rotation_rad: rotation_deg.to_radians(),
        seed: w.seed.unwrap_or(0),
    })
}

/// `[render.skin]`: the Monk Skin Tones drawn from, and the seed.
fn skin_plan(raw: &super::config::RawSkin, bad: Bad) -> Result<SkinPlan, ConfigError> {
    let tones = raw.tones.clone().unwrap_or_else(|| (1..=10).collect());
    if tones.is_empty() || tones.iter().any(|t| !(1..=10).contains(t)) {
        return Err(bad(
            "render.skin.tones",
            format!(
                "expected a non-empty list of Monk Skin Tones, each in 1..=10, found {tones:?}"
            ),
        ));
    }
    Ok(SkinPlan {
        tones,
        seed: raw.seed.unwrap_or(0),
    })
}

/// `[render] passes`, checked against each other and against `[render.depth_noise]`.
fn resolve_passes(
    names: Option<&[String]>,
    has_depth_noise: bool,
    config_path: &Path,
) -> Result<Passes, ConfigError> {
    let bad = |message: String| ConfigError::Value {
        path: config_path.into(),
        key: "render.passes".into(),
        message,
    };
    // COLMAP was a pass before it became an export of its own.
    if names.is_some_and(|n| n.iter().any(|n| n == "colmap")) {
        return Err(bad(
            "\"colmap\" is not a pass: the COLMAP export is `[render] colmap = true` (the default whenever \"colour\" is listed); drop it from the list".into(),
        ));
    }
    let Some(names) = names else {
        let all = Passes::default();
        return Ok(if has_depth_noise {
            all.with(Pass::DepthNoise)
        } else {
            all
        });
    };
    let known = || {
        Pass::ALL
            .iter()
            .map(|p| format!("\"{}\"", p.name()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut passes = Passes::NONE;
    for name in names {
        let pass = Pass::from_name(name)
            .ok_or_else(|| bad(format!("expected any of {}, found \"{name}\"", known())))?;
        if passes.has(pass) {
            return Err(bad(format!("\"{name}\" is listed twice")));
        }
        passes = passes.with(pass);
    }
    if passes == Passes::NONE {
        return Err(bad(format!(
            "expected at least one of {}, found an empty list",
            known()
        )));
    }
    if passes.has(Pass::DepthNoise) != has_depth_noise {
        return Err(bad(if has_depth_noise {
            "[render.depth_noise] is given but \"depth_noise\" is not listed: add it, or drop the section".into()
        } else {
            "\"depth_noise\" needs a [render.depth_noise] section naming the cameras".into()
        }));
    }
    Ok(passes)
}

/// `[render] colmap`: asked for, or by default whenever the colour pass is rendered; it
/// exports the colour images, so it needs them.
fn resolve_colmap(
    colmap: Option<bool>,
    passes: Passes,
    config_path: &Path,
) -> Result<bool, ConfigError> {
    let colour = passes.has(Pass::Colour);
    match colmap {
        None => Ok(colour),
        Some(true) if !colour => Err(ConfigError::Value {
            path: config_path.into(),
            key: "render.colmap".into(),
            message: "the COLMAP export is made of the colour images: list \"colour\" in `passes`, or set `colmap = false`".into(),
        }),
        Some(asked) => Ok(asked),
    }
}

/// `[render.lighting]`, checked.
fn resolve_lighting(
    raw: super::config::RawLighting,
    config_path: &Path,
) -> Result<LightingPlan, ConfigError> {
    let bad = |key: &str, message: String| ConfigError::Value {
        path: config_path.into(),
        key: format!("render.lighting.{key}"),
        message,
    };
    let d = LightingPlan::default();
    let world_rgb = raw.world_rgb.unwrap_or([0.25; 3]);
    if !world_rgb.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(bad(
            "world_rgb",
            format!("expected three colour values ≥ 0, found {world_rgb:?}"),
        ));
    }
    let world = match raw.hdri.as_deref().unwrap_or("none") {
        "none" => WorldChoice::Colour(world_rgb),
        "random" => WorldChoice::RandomHdri,
        name if SHIPPED_HDRIS.contains(&name) => WorldChoice::Hdri(name.into()),
        other => {
            return Err(bad(
                "hdri",
                format!(
                "expected \"none\", \"random\" or one of Blender's HDRIs ({}), found \"{other}\"",
                SHIPPED_HDRIS.join(", ")
            ),
            ))
        }
    };
    let range = |key: &str, v: Option<[f64; 2]>, default: (f64, f64), max: f64| {
        let [lo, hi] = v.unwrap_or([default.0, default.1]);
        if lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi && hi <= max {
            Ok((lo, hi))
        } else {
            Err(bad(
                key,
                format!("expected [MIN, MAX] with 0 ≤ MIN ≤ MAX ≤ {max}, found [{lo}, {hi}]"),
            ))
        }
    };
    Ok(LightingPlan {
        world,
        hdri_strength: range("hdri_strength", raw.hdri_strength, (0.5, 1.5), 100.0)?,
        lamp_watts: range("lamp_watts", raw.lamp_watts, d.lamp_watts, 1e5)?,
        seed: raw.seed.unwrap_or(0),
    })
}

/// The model and seed for each rendered camera named in `[render.depth_noise]`.
fn resolve_depth_noise(
    raw: RawDepthNoise,
    cameras: &[RigCamera],
    config_path: &Path,
) -> Result<Vec<Option<(DepthNoise, u64)>>, ConfigError> {
    let bad = |key: &str, message: String| ConfigError::Value {
        path: config_path.into(),
        key: format!("render.depth_noise.{key}"),
        message,
    };
    let d = DepthNoise::default();
    let model = DepthNoise {
        sigma_base_m: raw.sigma_base_m.unwrap_or(d.sigma_base_m),
        sigma_quadratic_per_m: raw.sigma_quadratic_per_m.unwrap_or(d.sigma_quadratic_per_m),
        sigma_offset_m: raw.sigma_offset_m.unwrap_or(d.sigma_offset_m),
        sigma_grazing: raw.sigma_grazing.unwrap_or(d.sigma_grazing),
        max_incidence_deg: raw.max_incidence_deg.unwrap_or(d.max_incidence_deg),
        min_range_m: raw.min_range_m.unwrap_or(d.min_range_m),
        max_range_m: raw.max_range_m.unwrap_or(d.max_range_m),
        quantisation_m: raw.quantisation_m.unwrap_or(d.quantisation_m),
    };
    model.check().map_err(|(key, message)| bad(key, message))?;
    let rendered: Vec<&str> = cameras.iter().map(|c| c.name.as_str()).collect();
    if let Some(name) = raw.cameras.iter().find(|n| !rendered.contains(&n.as_str())) {
        return Err(bad(
            "cameras",
            format!(
                "`{name}` is not a rendered camera (rendered: {})",
                rendered.join(", ")
            ),
        ));
    }
    let seed = raw.seed.unwrap_or(0);
    Ok(cameras
        .iter()
        .map(|c| raw.cameras.contains(&c.name).then_some((model, seed)))
        .collect())
}

fn resolve_supervisor(s: RawSupervisor, config_path: &Path) -> Result<SupervisorPlan, ConfigError> {
    let bad = |key: &str, message: String| ConfigError::Value {
        path: config_path.into(),
        key: key.into(),
        message,
    };
    let workers = s.workers.unwrap_or(1);
    if workers == 0 || workers > 256 {
        return Err(bad(
            "supervisor.workers",
            format!("expected 1..=256 workers, found {workers}"),
        ));
    }
    let shard_timeout_s = s.shard_timeout_s.unwrap_or(3600.0);
    if !(shard_timeout_s.is_finite() && shard_timeout_s > 0.0) {
        return Err(bad(
            "supervisor.shard_timeout_s",
            format!("expected a positive number of seconds, found {shard_timeout_s}"),
        ));
    }
    let backend = s.backend.unwrap_or(Backend::Local);
    if s.slurm.is_some() && backend != Backend::Slurm {
        return Err(bad(
            "supervisor.slurm",
            "given but `supervisor.backend` is not \"slurm\"".into(),
        ));
    }
    Ok(SupervisorPlan {
        backend,
        workers,
        shard_timeout_s,
        retries: s.retries.unwrap_or(2),
        keep_blender: s.keep_blender.unwrap_or(false),
        slurm: resolve_slurm(s.slurm.unwrap_or_default(), &bad)?,
    })
}

fn resolve_slurm(
    s: RawSlurm,
    bad: &dyn Fn(&str, String) -> ConfigError,
) -> Result<SlurmPlan, ConfigError> {
    let cpus_per_task = s.cpus_per_task.unwrap_or(2);
    if cpus_per_task == 0 {
        return Err(bad(
            "supervisor.slurm.cpus_per_task",
            "expected at least 1".into(),
        ));
    }
    let mem_gb = s.mem_gb.unwrap_or(4.0);
    if !(mem_gb.is_finite() && mem_gb > 0.0) {
        return Err(bad(
            "supervisor.slurm.mem_gb",
            format!("expected a positive number of GB, found {mem_gb}"),
        ));
    }
    let poll_interval_s = s.poll_interval_s.unwrap_or(10.0);
    if !(poll_interval_s.is_finite() && poll_interval_s > 0.0) {
        return Err(bad(
            "supervisor.slurm.poll_interval_s",
            format!("expected a positive number of seconds, found {poll_interval_s}"),
        ));
    }
    let sbatch_args = s.sbatch_args.unwrap_or_default();
    if let Some(a) = sbatch_args.iter().find(|a| !a.starts_with('-')) {
        return Err(bad(
            "supervisor.slurm.sbatch_args",
            format!("expected sbatch options starting with `-`, found {a:?}"),
        ));
    }
    if let Some(p) = &s.partition {
        if p.is_empty() || p.contains(char::is_whitespace) {
            return Err(bad(
                "supervisor.slurm.partition",
                format!("expected a partition name, found {p:?}"),
            ));
        }
    }
    Ok(SlurmPlan {
        partition: s.partition,
        cpus_per_task,
        mem_gb,
        poll_interval_s,
        sbatch_args,
    })
}
