//! What every config file of egogen shares, below the files that read their sections: the
//! error that names the file and key, strict TOML loading, and where shipped files (the default
//! body model) are found. `config`, `synth`, `train` and `resolve` build on it.

use std::path::{Path, PathBuf};

/// Makes the error for a bad value: the key as the config names it, and what was wrong. Config
/// checks split by section take one, so that every error names the same file.
pub(crate) type Bad<'a> = &'a dyn Fn(&str, String) -> ConfigError;

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

/// Reads and strictly parses a TOML config file; errors name the file, key and what was
/// expected. A table given as an array (`lighting = [0.5, 1.5]` where `[render.lighting]` is
/// meant) is refused by its key, not read by position as serde would.
pub(crate) fn load_toml<T: serde::de::DeserializeOwned + serde::Serialize>(
    path: &Path,
) -> Result<T, ConfigError> {
    let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
        path: path.into(),
        source,
    })?;
    let parse_error = |message: String| ConfigError::Parse {
        path: path.into(),
        message: with_walker_hint(message),
    };
    let document = toml::Deserializer::parse(&text).map_err(|e| parse_error(e.to_string()))?;
    // The key a bad value was given by (`crowd.layout`, `agents[0].k`), beside TOML's line.
    let parsed: T = serde_path_to_error::deserialize(document).map_err(|e| {
        let key = e.path().to_string();
        let message = e.into_inner().to_string();
        parse_error(match key.as_str() {
            "" | "." => message,
            _ => format!("key `{key}`: {message}"),
        })
    })?;
    if let (Ok(written), Ok(read)) = (
        toml::from_str::<toml::Table>(&text),
        toml::Table::try_from(&parsed),
    ) {
        if let Some(key) = array_for_table(&written, &read, "") {
            return Err(ConfigError::Value {
                path: path.into(),
                key,
                message: "expected a table (a `[section]` or `{ key = value, … }`), got an \
                          array: a table's values are named, not read by position"
                    .into(),
            });
        }
    }
    Ok(parsed)
}

/// The first key (dotted, under `prefix`) that the file `written` gives as an array where
/// what it was `read` into holds a table.
fn array_for_table(written: &toml::Table, read: &toml::Table, prefix: &str) -> Option<String> {
    use toml::Value;
    for (key, w) in written {
        let path = match prefix {
            "" => key.clone(),
            p => format!("{p}.{key}"),
        };
        match (w, read.get(key)) {
            (Value::Array(_), Some(Value::Table(_))) => return Some(path),
            (Value::Table(w), Some(Value::Table(r))) => {
                if let Some(found) = array_for_table(w, r, &path) {
                    return Some(found);
                }
            }
            (Value::Array(ws), Some(Value::Array(rs))) => {
                for (i, (w, r)) in ws.iter().zip(rs).enumerate() {
                    let at = format!("{path}[{i}]");
                    match (w, r) {
                        (Value::Array(_), Value::Table(_)) => return Some(at),
                        (Value::Table(w), Value::Table(r)) => {
                            if let Some(found) = array_for_table(w, r, &at) {
                                return Some(found);
                            }
                        }
                        _ => {}
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// A parse error's message, with where a walker setting goes when the error is that key
/// refused in another table (such as `[motion]`, where it once was).
fn with_walker_hint(message: String) -> String {
    let refused = message
        .split("unknown field `")
        .nth(1)
        .and_then(|rest| rest.split('`').next());
    match refused {
        Some(key)
            if crate::walker::WalkerSettings::keys()
                .iter()
                .any(|k| k == key) =>
        {
            format!(
                "{message}`{key}` is a walker setting: it goes in the `[walker]` table \
             (docs/SYNTH.md, \"Walker settings\")"
            )
        }
        _ => message,
    }
}

/// The shipped body model, relative to [`crate_root`].
pub(crate) const DEFAULT_BODY_MODEL: &str = "assets/body/SMPLX_NEUTRAL.npz";

/// A body model path from a config (relative to its folder `base`), else the shipped default;
/// the error says which file is missing.
pub(crate) fn resolve_body_model(path: Option<PathBuf>, base: &Path) -> Result<PathBuf, String> {
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
pub(crate) fn crate_root() -> PathBuf {
    crate::paths::crate_root()
}
