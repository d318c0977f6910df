//! The `[render]` section resolved: the rig and its cameras, the headset's wear, skin, outfits, passes,
//! COLMAP export, lighting and depth noise.

use std::path::Path;

use super::DEFAULT_RIG;
use crate::cli::config::{Bad, ConfigError, RawDepthNoise, RawRender};
use crate::cli::config_file::crate_root;
use crate::plan::RenderPlan;
use crate::render::depth_noise::DepthNoise;
use crate::render::lighting::{LightingPlan, WorldChoice, SHIPPED_HDRIS};
use crate::render::outfit::{OutfitPlan, Shares};
use crate::render::passes::{Pass, Passes};
use crate::render::render_camera::RenderCamera;
use crate::render::skin_tone::SkinPlan;
use crate::rig::{Rig, RigCamera};

pub(super) fn resolve_render(
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
    let outfits = match &r.outfits {
        None => OutfitPlan::default(),
        Some(raw) => outfit_plan(raw, &bad)?,
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
        outfits,
        passes,
        colmap,
        device: r.device.unwrap_or_default(),
        aria,
    })
}

/// `[render.aria]`: the streams asked (none: `None`), checked against the rig.
fn aria_settings(
    raw: &crate::cli::config::RawAria,
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
    w: &crate::cli::config::RawHeadsetWear,
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
fn skin_plan(raw: &crate::cli::config::RawSkin, bad: Bad) -> Result<SkinPlan, ConfigError> {
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

/// `[render.outfits]`: the shares of each style, the colours' ranges and the seed; an error
/// names the key.
fn outfit_plan(raw: &crate::cli::config::RawOutfits, bad: Bad) -> Result<OutfitPlan, ConfigError> {
    let d = OutfitPlan::default();
    fn shares<S: crate::render::outfit::Style>(
        table: &Option<std::collections::BTreeMap<String, f64>>,
        default: Shares<S>,
        key: &str,
        bad: Bad,
    ) -> Result<Shares<S>, ConfigError> {
        match table {
            None => Ok(default),
            Some(t) => Shares::from_table(t).map_err(|m| bad(key, m)),
        }
    }
    let range = |v: Option<[f64; 2]>, default: [f64; 2], key: &str| match v.unwrap_or(default) {
        [lo, hi] if (0.0..=1.0).contains(&lo) && (lo..=1.0).contains(&hi) => Ok([lo, hi]),
        r => Err(bad(
            key,
            format!("expected [MIN, MAX] with 0 ≤ MIN ≤ MAX ≤ 1, found {r:?}"),
        )),
    };
    let shoes = raw.shoes.unwrap_or(d.shoes);
    if !(0.0..=1.0).contains(&shoes) {
        return Err(bad(
            "render.outfits.shoes",
            format!("expected a share in [0, 1], found {shoes}"),
        ));
    }
    Ok(OutfitPlan {
        mode: raw.mode.unwrap_or(d.mode),
        seed: raw.seed.unwrap_or(d.seed),
        tops: shares(&raw.tops, d.tops, "render.outfits.tops", bad)?,
        bottoms: shares(&raw.bottoms, d.bottoms, "render.outfits.bottoms", bad)?,
        hair: shares(&raw.hair, d.hair, "render.outfits.hair", bad)?,
        shoes,
        saturation: range(raw.saturation, d.saturation, "render.outfits.saturation")?,
        value: range(raw.value, d.value, "render.outfits.value")?,
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
    raw: crate::cli::config::RawLighting,
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
