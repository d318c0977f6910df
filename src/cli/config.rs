//! The run configuration file (TOML) as written by users: parsed strictly, unknown keys refused.

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// A config file that could not be used, with the file named.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("config {path}: cannot read ({source})")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("config {path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("config {path}: key `{key}`: {message}")]
    Value {
        path: PathBuf,
        key: String,
        message: String,
    },
}

/// `[body]`: which body model and shape.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawBody {
    /// SMPL-X `.npz` model file; relative paths resolve against the config's folder.
    /// Default: the shipped CC0 model `assets/body/SMPLX_NEUTRAL.npz`.
    pub model: Option<PathBuf>,
    /// Shape coefficients (betas), each in standard deviations.
    #[serde(default)]
    pub betas: Vec<f64>,
}

/// Where motion comes from.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MotionSource {
    /// The scripted walk cycle (`duration_s`, `frame_rate_hz`, `speed_m_per_s`).
    ScriptedWalk,
    /// An AMASS- or SAMP-style `.npz` motion file (`path`).
    File,
}

/// `[motion]`: one flat table so that type errors name their key; `resolve` checks which
/// keys the chosen `source` needs.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawMotion {
    pub source: MotionSource,
    /// Length of the scripted walk (s).
    pub duration_s: Option<f64>,
    /// Frame rate of the scripted walk (Hz).
    pub frame_rate_hz: Option<f64>,
    /// Walking speed of the scripted walk (m/s, default 1.2).
    pub speed_m_per_s: Option<f64>,
    /// Motion file, relative to the config's folder.
    pub path: Option<PathBuf>,
}

/// `[output]`: where the run writes.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawOutput {
    /// Output folder; must not exist yet (or be empty).
    pub dir: PathBuf,
    /// Write a posed mesh (OBJ) every this many frames; 0 writes none.
    #[serde(default = "default_mesh_every")]
    pub mesh_every_n_frames: usize,
}

fn default_mesh_every() -> usize {
    10
}

/// The whole run config, as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawRun {
    pub body: RawBody,
    pub motion: RawMotion,
    pub output: RawOutput,
}

impl RawRun {
    /// Reads and parses a config file; errors name the file, key and what was expected.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        load_toml(path)
    }
}

/// Reads and strictly parses a TOML config file; errors name the file, key and what was
/// expected.
pub fn load_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, ConfigError> {
    let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
        path: path.into(),
        source,
    })?;
    toml::from_str(&text).map_err(|e| ConfigError::Parse {
        path: path.into(),
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_key_is_refused_and_named() {
        let text = "[body]\nbetas=[]\ncolour='red'\n[motion]\nsource='file'\npath='x.npz'\n[output]\ndir='o'\n";
        let err = toml::from_str::<RawRun>(text).unwrap_err().to_string();
        assert!(err.contains("colour"), "{err}");
    }

    #[test]
    fn wrong_type_names_the_key() {
        let text =
            "[body]\nbetas='tall'\n[motion]\nsource='file'\npath='x.npz'\n[output]\ndir='o'\n";
        let err = toml::from_str::<RawRun>(text).unwrap_err().to_string();
        assert!(err.contains("betas") && err.contains("sequence"), "{err}");
    }
}
