//! Numeric arrays in NumPy `.npy`/`.npz` files, read as `f64` whatever their stored type.
//!
//! Shared by the body model reader and the motion file reader; each adds its own typed errors.

use std::io::{Cursor, Read, Seek};

use npyz::npz::NpzArchive;
use npyz::NpyFile;

/// Why an array could not be read.
pub(crate) enum ReadError {
    /// The archive or array could not be read.
    Io(std::io::Error),
    /// The dtype is not a plain number type (the descriptor found).
    Dtype(String),
}

/// The array `name` of an `.npz`, its bytes inflated at once into memory, or `None` when the
/// archive has no such array. (Read through the archive, an array is inflated a value at a
/// time: loading a body model took several times longer.)
pub(crate) fn array_in_memory<R: Read + Seek>(
    npz: &mut NpzArchive<R>,
    name: &str,
) -> std::io::Result<Option<NpyFile<Cursor<Vec<u8>>>>> {
    use npyz::zip::result::ZipError;
    let invalid = |s: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, s.to_owned());
    let file_name = npyz::npz::file_name_from_array_name(name);
    let mut entry = match npz.zip_archive().by_name(&file_name) {
        Ok(entry) => entry,
        Err(ZipError::FileNotFound) => return Ok(None),
        Err(ZipError::Io(e)) => return Err(e),
        Err(ZipError::InvalidArchive(s)) | Err(ZipError::UnsupportedArchive(s)) => {
            return Err(invalid(s))
        }
    };
    // The size the archive declares, as a hint only: a damaged archive may declare anything.
    let hint = entry.size().min(1 << 28);
    let mut bytes = Vec::with_capacity(usize::try_from(hint).unwrap_or(0));
    entry.read_to_end(&mut bytes)?;
    NpyFile::new(Cursor::new(bytes)).map(Some)
}

/// Reads any plain numeric npy array as `f64` in file order; returns whether it was floating point.
pub(crate) fn read_as_f64<R: Read>(file: NpyFile<R>) -> Result<(Vec<f64>, bool), ReadError> {
    let descr = match file.dtype() {
        npyz::DType::Plain(ts) => ts.to_string(),
        other => return Err(ReadError::Dtype(other.descr())),
    };
    let kind = descr
        .trim_matches('\'')
        .trim_start_matches(['<', '>', '|', '=']);
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

/// Reorders a Fortran-order (column-major) array of `shape` into C (row-major) order.
pub(crate) fn fortran_to_c(data: &[f64], shape: &[u64]) -> Vec<f64> {
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
