//! Reading a body model in the SMPL-X `.npz` layout (as the `smplx` package loads it), with
//! errors that name the file, the key and the expected shape.

use std::io::{Read, Seek};
use std::path::{Path, PathBuf};

use npyz::npz::NpzArchive;
use npyz::{NpyFile, Order};

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
    pub fn open(path: &Path) -> Result<Self, ModelFileError> {
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
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads `key` as `f64`, checks its shape against `expected` (`None` = any extent) and,
    /// for float arrays, that every value is finite.
    pub fn read(&mut self, key: &str, expected: &[Option<u64>]) -> Result<Array, ModelFileError> {
        let path = self.path.clone();
        let describe = || describe_shape(expected);
        let file = self
            .archive
            .by_name(key)
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

    pub fn invalid(&self, key: &str, message: impl Into<String>) -> ModelFileError {
        ModelFileError::Invalid {
            path: self.path.clone(),
            key: key.into(),
            message: message.into(),
        }
    }
}

enum ReadError {
    Io(std::io::Error),
    Dtype(String),
}

/// Reads any plain numeric npy array as `f64`; returns whether the source was floating point.
fn read_as_f64<R: Read>(file: NpyFile<R>) -> Result<(Vec<f64>, bool), ReadError> {
    let descr = match file.dtype() {
        npyz::DType::Plain(ts) => ts.to_string(),
        other => return Err(ReadError::Dtype(other.descr())),
    };
    let kind = descr.trim_start_matches(['<', '>', '|', '=']);
    macro_rules! conv {
        ($t:ty, $float:expr) => {
            file.into_vec::<$t>()
                .map(|v| (v.into_iter().map(|x| x as f64).collect(), $float))
                .map_err(ReadError::Io)
        };
    }
    match kind {
        "f8" => file
            .into_vec::<f64>()
            .map(|v| (v, true))
            .map_err(ReadError::Io),
        "f4" => conv!(f32, true),
        "i8" => conv!(i64, false),
        "i4" => conv!(i32, false),
        "i2" => conv!(i16, false),
        "i1" => conv!(i8, false),
        "u8" => conv!(u64, false),
        "u4" => conv!(u32, false),
        "u2" => conv!(u16, false),
        "u1" => conv!(u8, false),
        "b1" => file
            .into_vec::<bool>()
            .map(|v| (v.into_iter().map(|x| x as u8 as f64).collect(), false))
            .map_err(ReadError::Io),
        _ => Err(ReadError::Dtype(descr)),
    }
}

fn fortran_to_c(data: &[f64], shape: &[u64]) -> Vec<f64> {
    let dims: Vec<usize> = shape.iter().map(|&d| d as usize).collect();
    let n = data.len();
    let mut out = vec![0.0; n];
    let mut idx = vec![0usize; dims.len()];
    for (c_flat, slot) in out.iter_mut().enumerate() {
        // Decompose the C index, then recompose as a Fortran index.
        let mut rem = c_flat;
        for k in (0..dims.len()).rev() {
            idx[k] = rem % dims[k];
            rem /= dims[k];
        }
        let mut f_flat = 0;
        for k in (0..dims.len()).rev() {
            f_flat = f_flat * dims[k] + idx[k];
        }
        *slot = data[f_flat];
    }
    out
}

fn describe_shape(expected: &[Option<u64>]) -> String {
    let parts: Vec<String> = expected
        .iter()
        .map(|e| e.map_or_else(|| "*".to_string(), |v| v.to_string()))
        .collect();
    format!("[{}]", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fortran_order_is_transposed_to_c() {
        // 2×3 matrix [[0,1,2],[3,4,5]] stored column-major.
        let f = [0.0, 3.0, 1.0, 4.0, 2.0, 5.0];
        assert_eq!(
            fortran_to_c(&f, &[2, 3]),
            vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
        );
    }
}
