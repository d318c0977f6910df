//! Reading a body model in the SMPL-X `.npz` layout (as the `smplx` package loads it), with
//! errors that name the file, the key and the expected shape.

use std::io::{Read, Seek};
use std::path::{Path, PathBuf};

use npyz::npz::NpzArchive;
use npyz::Order;

use crate::npz::{array_in_memory, fortran_to_c, read_as_f64, ReadError};

/// What can go wrong reading a body model file.
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    #[error("body model {path}: cannot open ({source})")]
    Open {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("body model {path}: missing key `{key}` (an SMPL-X .npz must hold {expected})")]
    MissingKey {
        path: PathBuf,
        key: String,
        expected: String,
    },
    #[error("body model {path}: key `{key}` has shape {found:?}, expected {expected}")]
    Shape {
        path: PathBuf,
        key: String,
        found: Vec<u64>,
        expected: String,
    },
    #[error(
        "body model {path}: key `{key}` has dtype {found}, expected a numeric array ({expected})"
    )]
    Dtype {
        path: PathBuf,
        key: String,
        found: String,
        expected: String,
    },
    #[error(
        "body model {path}: key `{key}` holds a non-finite value ({value}) at flat index {index}"
    )]
    NonFinite {
        path: PathBuf,
        key: String,
        index: usize,
        value: f64,
    },
    #[error("body model {path}: key `{key}`: {message}")]
    Invalid {
        path: PathBuf,
        key: String,
        message: String,
    },
    #[error("body model {path}: cannot read key `{key}` ({source})")]
    Read {
        path: PathBuf,
        key: String,
        source: std::io::Error,
    },
}

/// One array read from the archive, converted to `f64`, in C (row-major) order.
pub(crate) struct Array {
    pub shape: Vec<u64>,
    pub data: Vec<f64>,
}

/// An open `.npz` model archive that reads arrays by key with typed errors.
pub(crate) struct ModelArchive<R: Read + Seek> {
    path: PathBuf,
    archive: NpzArchive<R>,
}

impl ModelArchive<std::io::BufReader<std::fs::File>> {
    pub(crate) fn open(path: &Path) -> Result<Self, ModelFileError> {
        let archive = NpzArchive::open(path).map_err(|source| ModelFileError::Open {
            path: path.to_owned(),
            source,
        })?;
        Ok(Self {
            path: path.to_owned(),
            archive,
        })
    }
}

impl<R: Read + Seek> ModelArchive<R> {
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Reads `key` as `f64`, checks its shape against `expected` (`None` = any extent) and,
    /// for float arrays, that every value is finite.
    pub(crate) fn read(
        &mut self,
        key: &str,
        expected: &[Option<u64>],
    ) -> Result<Array, ModelFileError> {
        let path = self.path.clone();
        let describe = || describe_shape(expected);
        let file = array_in_memory(&mut self.archive, key)
            .map_err(|source| ModelFileError::Read {
                path: path.clone(),
                key: key.into(),
                source,
            })?
            .ok_or_else(|| ModelFileError::MissingKey {
                path: path.clone(),
                key: key.into(),
                expected: format!("`{key}` with shape {}", describe()),
            })?;
        let shape = file.shape().to_vec();
        let shape_ok = shape.len() == expected.len()
            && shape
                .iter()
                .zip(expected)
                .all(|(s, e)| e.is_none_or(|e| e == *s));
        if !shape_ok {
            return Err(ModelFileError::Shape {
                path,
                key: key.into(),
                found: shape,
                expected: describe(),
            });
        }
        let order = file.order();
        let (data, is_float) = read_as_f64(file).map_err(|e| match e {
            ReadError::Io(source) => ModelFileError::Read {
                path: path.clone(),
                key: key.into(),
                source,
            },
            ReadError::Dtype(found) => ModelFileError::Dtype {
                path: path.clone(),
                key: key.into(),
                found,
                expected: "float32/float64 or an integer type".into(),
            },
        })?;
        if is_float {
            if let Some((index, value)) = data
                .iter()
                .copied()
                .enumerate()
                .find(|(_, v)| !v.is_finite())
            {
                return Err(ModelFileError::NonFinite {
                    path,
                    key: key.into(),
                    index,
                    value,
                });
            }
        }
        let data = if order == Order::Fortran {
            fortran_to_c(&data, &shape)
        } else {
            data
        };
        Ok(Array { shape, data })
    }

    /// [`Self::read`] for a key the format allows to be absent: `None` when it is.
    pub(crate) fn read_optional(
        &mut self,
        key: &str,
        expected: &[Option<u64>],
    ) -> Result<Option<Array>, ModelFileError> {
        match self.read(key, expected) {
            Ok(array) => Ok(Some(array)),
            Err(ModelFileError::MissingKey { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }

    pub(crate) fn invalid(&self, key: &str, message: impl Into<String>) -> ModelFileError {
        ModelFileError::Invalid {
            path: self.path.clone(),
            key: key.into(),
            message: message.into(),
        }
    }
}

fn describe_shape(expected: &[Option<u64>]) -> String {
    let parts: Vec<String> = expected
        .iter()
        .map(|e| e.map_or_else(|| "*".to_string(), |v| v.to_string()))
        .collect();
    format!("[{}]", parts.join(", "))
}
