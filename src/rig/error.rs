//! What can go wrong reading a rig; every message names the file, the field and what was
//! expected.

use std::path::PathBuf;

/// A rig that could not be used.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    #[error("rig {path}: cannot read ({source})")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("rig {path}: not valid JSON: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error(
        "rig {path}: line {line} column {column}: `{field}` is {token}; rig values must be \
         finite numbers (JSON has no NaN or infinity)"
    )]
    NonFinite {
        path: PathBuf,
        line: usize,
        column: usize,
        field: String,
        token: String,
    },
    #[error("rig {path}: {field}: {message}")]
    Field {
        path: PathBuf,
        /// Where in the file, e.g. `cameras[1] (camera-rgb).model`.
        field: String,
        message: String,
    },
    #[error(
        "rig {path}: camera name `{name}` is used by cameras[{first}] and cameras[{second}]; \
         camera names must be unique"
    )]
    DuplicateCamera {
        path: PathBuf,
        name: String,
        first: usize,
        second: usize,
    },
    #[error("rig {path}: no camera named `{name}`; available: {available}")]
    UnknownCamera {
        path: PathBuf,
        name: String,
        available: String,
    },
    #[error("rig {path}: cannot write ({source})")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl RigError {
    pub(crate) fn field(
        path: impl Into<PathBuf>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::Field {
            path: path.into(),
            field: field.into(),
            message: message.into(),
        }
    }
}
