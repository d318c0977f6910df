//! Turns a [`RawRun`] into a [`RunPlan`]: paths resolved, values range-checked.

use std::path::{Path, PathBuf};

use super::config::{ConfigError, MotionSource, RawRun};

/// Default body model, relative to the crate root.
pub const DEFAULT_BODY_MODEL: &str = "assets/body/SMPLX_NEUTRAL.npz";

/// Where a run's motion comes from, checked.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionPlan {
    ScriptedWalk {
        duration_s: f64,
        frame_rate_hz: f64,
        speed_m_per_s: f64,
    },
    File {
        path: PathBuf,
    },
}

/// A checked run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunPlan {
    pub body_model: PathBuf,
    pub betas: Vec<f64>,
    pub motion: MotionPlan,
    pub output_dir: PathBuf,
    pub mesh_every_n_frames: usize,
}

/// Resolves paths against the config's folder and checks value ranges.
pub fn resolve_run(raw: RawRun, config_path: &Path) -> Result<RunPlan, ConfigError> {
    let base = config_path.parent().unwrap_or(Path::new("."));
    let bad = |key: &str, message: String| ConfigError::Value {
        path: config_path.into(),
        key: key.into(),
        message,
    };
    let body_model = resolve_body_model(raw.body.model, base).map_err(|m| bad("body.model", m))?;
    if let Some(i) = raw.body.betas.iter().position(|b| !b.is_finite()) {
        return Err(bad(
            "body.betas",
            format!("value {i} is not a finite number"),
        ));
    }
    let m = raw.motion;
    let unused = |key: &str, present: bool, source: &str| match present {
        true => Err(bad(
            key,
            format!("not used when motion.source = \"{source}\"; remove it"),
        )),
        false => Ok(()),
    };
    let motion = match m.source {
        MotionSource::ScriptedWalk => {
            unused("motion.path", m.path.is_some(), "scripted_walk")?;
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
            let speed_m_per_s = m.speed_m_per_s.unwrap_or(1.2);
            if !(speed_m_per_s.is_finite() && (0.0..=10.0).contains(&speed_m_per_s)) {
                return Err(bad(
                    "motion.speed_m_per_s",
                    format!("expected 0..=10 m/s, found {speed_m_per_s}"),
                ));
            }
            MotionPlan::ScriptedWalk {
                duration_s,
                frame_rate_hz,
                speed_m_per_s,
            }
        }
        MotionSource::File => {
            for (key, present) in [
                ("motion.duration_s", m.duration_s.is_some()),
                ("motion.frame_rate_hz", m.frame_rate_hz.is_some()),
                ("motion.speed_m_per_s", m.speed_m_per_s.is_some()),
            ] {
                unused(key, present, "file")?;
            }
            let path = m.path.ok_or_else(|| {
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
            MotionPlan::File { path }
        }
    };
    Ok(RunPlan {
        body_model,
        betas: raw.body.betas,
        motion,
        output_dir: base.join(raw.output.dir),
        mesh_every_n_frames: raw.output.mesh_every_n_frames,
    })
}

/// A body model path from a config (relative to its folder `base`), else the shipped default;
/// the error says which file is missing.
pub fn resolve_body_model(path: Option<PathBuf>, base: &Path) -> Result<PathBuf, String> {
    let body_model = match path {
        Some(p) => base.join(p),
        None => crate_root().join(DEFAULT_BODY_MODEL),
    };
    match body_model.is_file() {
        true => Ok(body_model),
        false => Err(format!("file {} not found", body_model.display())),
    }
}

/// The folder shipped data is found in: `EGOGEN_HOME` if set, else the crate's source root.
pub fn crate_root() -> PathBuf {
    std::env::var_os("EGOGEN_HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}
