//! The `[motion]` section resolved: the agents' synth config and who wears the rig, a scripted
//! walk, or a motion file.

use std::path::Path;

use super::{unused, MAX_SCRIPTED_FRAMES};
use crate::cli::config::{Bad, ConfigError, RawMotion, RawRender, RawRun};
use crate::plan::MotionPlan;

/// `motion.source = "agents"`: the synth config inside the run config, checked as
/// `egogen synth` checks its own, and who wears the rig.
pub(super) fn agents_motion(
    raw: &RawRun,
    scene: &Path,
    config_path: &Path,
    bad: Bad,
) -> Result<MotionPlan, ConfigError> {
    let m = &raw.motion;
    for (key, present) in [
        ("motion.path", m.path.is_some()),
        ("motion.frame_rate_hz", m.frame_rate_hz.is_some()),
        ("motion.speed_m_s", m.speed_m_s.is_some()),
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
    use crate::cli::synth_config::{RawSynth, RawSynthMotion, RawSynthOutput, RawSynthScene};
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
    let synth = crate::cli::synth_config::resolve_synth(synth, config_path, "")?;
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
pub(super) fn scripted_motion(m: &RawMotion, bad: Bad) -> Result<MotionPlan, ConfigError> {
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
    let speed_m_s = m.speed_m_s.unwrap_or(1.2);
    if !(speed_m_s.is_finite() && (0.0..=10.0).contains(&speed_m_s)) {
        return Err(bad(
            "motion.speed_m_s",
            format!("expected 0..=10 m/s, found {speed_m_s}"),
        ));
    }
    Ok(MotionPlan::ScriptedWalk {
        duration_s,
        frame_rate_hz,
        speed_m_s,
    })
}

/// `motion.source = "file"`: the motion file, relative to `base`.
pub(super) fn file_motion(m: &RawMotion, base: &Path, bad: Bad) -> Result<MotionPlan, ConfigError> {
    for (key, present) in [
        ("motion.duration_s", m.duration_s.is_some()),
        ("motion.frame_rate_hz", m.frame_rate_hz.is_some()),
        ("motion.speed_m_s", m.speed_m_s.is_some()),
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
