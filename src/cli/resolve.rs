//! Turns a [`RawRun`] into a [`RunPlan`]: paths resolved, values range-checked.

use std::path::{Path, PathBuf};

use super::config::{ConfigError, RawMotion, RawRun};

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
    let body_model = match raw.body.model {
        Some(p) => base.join(p),
        None => crate_root().join(DEFAULT_BODY_MODEL),
    };
    if !body_model.is_file() {
        return Err(bad(
            "body.model",
            format!("file {} not found", body_model.display()),
        ));
    }
    if let Some(i) = raw.body.betas.iter().position(|b| !b.is_finite()) {
        return Err(bad(
            "body.betas",
            format!("value {i} is not a finite number"),
        ));
    }
    let motion = match raw.motion {
        RawMotion::ScriptedWalk {
            duration_s,
            frame_rate_hz,
            speed_m_per_s,
        } => {
            for (key, v) in [
                ("motion.duration_s", duration_s),
                ("motion.frame_rate_hz", frame_rate_hz),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(bad(key, format!("expected a positive number, found {v}")));
                }
            }
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
        RawMotion::File { path } => {
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

/// The folder shipped data is found in: `EGOGEN_HOME` if set, else the crate's source root.
pub fn crate_root() -> PathBuf {
    std::env::var_os("EGOGEN_HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}
