//! SMPL-X motion files: AMASS-style `.npz` (write and read) and SAMP-style `.npz` (read).
//!
//! AMASS (SMPL-X flavour) keys: `poses` (N, 165) axis-angle in the `smplx` joint order,
//! `trans` (N, 3) metres, `betas` (B,), `gender` (string), `mocap_frame_rate` (scalar, Hz),
//! `surface_model_type` (string, `"smplx"`). The SMPL-X AMASS split keys (`root_orient`,
//! `pose_body`, `pose_jaw`, `pose_eye`, `pose_hand`) are written too, so tools that read either
//! form work; on reading, `poses` wins. SAMP-style files use `pose_est_fullposes` (N, 165),
//! `pose_est_trans` (N, 3), `shape_est_betas` (B,) and `mocap_framerate`; SAMP's own `.pkl`
//! files are converted to that `.npz` form by `tools/samp_pkl_to_npz.py`.
//! Values are written as float64, so write → read round-trips bit for bit.

use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use npyz::npz::{NpzArchive, NpzWriter};
use npyz::WriterBuilder;

use crate::body::{BodyParams, POSE_DIM};
use crate::math::Vec3;
use crate::npz::{fortran_to_c, read_as_f64, ReadError};

/// A sequence of SMPL-X bodies sampled at a fixed rate.
/// Highest frame rate a motion file may declare (Hz): mocap runs at 30–480 Hz; a rate far
/// beyond it is a damaged file, and resampling it would allocate without bound.
pub(crate) const MAX_FRAME_RATE_HZ: f64 = 10_000.0;

#[derive(Debug, Clone, PartialEq)]
pub struct MotionSequence {
    /// Frames per second.
    pub frame_rate_hz: f64,
    /// Shape coefficients, constant over the sequence.
    pub betas: Vec<f64>,
    /// `"neutral"`, `"male"` or `"female"`.
    pub gender: String,
    /// Full pose per frame (55 × axis-angle).
    pub poses: Vec<[f64; POSE_DIM]>,
    /// Pelvis translation per frame (metres).
    pub trans: Vec<Vec3>,
}

/// What can go wrong reading or writing a motion file.
#[derive(Debug, thiserror::Error)]
pub enum MotionFileError {
    #[error("motion file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("motion file {path}: missing key `{key}` (expected {expected})")]
    MissingKey {
        path: PathBuf,
        key: String,
        expected: String,
    },
    #[error("motion file {path}: key `{key}` has shape {found:?}, expected {expected}")]
    Shape {
        path: PathBuf,
        key: String,
        found: Vec<u64>,
        expected: String,
    },
    #[error("motion file {path}: key `{key}`: {message}")]
    Invalid {
        path: PathBuf,
        key: String,
        message: String,
    },
}

impl MotionSequence {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.poses.len()
    }
    /// Whether the sequence has no frame.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }
    /// Body parameters of frame `i`.
    pub fn frame(&self, i: usize) -> BodyParams {
        BodyParams {
            betas: self.betas.clone(),
            expression: Vec::new(),
            pose: self.poses[i],
            transl: self.trans[i],
        }
    }

    /// Writes an AMASS-style `.npz` atomically (temporary file, then rename).
    pub fn write_amass(&self, path: &Path) -> Result<(), MotionFileError> {
        let io = |source| MotionFileError::Io {
            path: path.to_owned(),
            source,
        };
        let tmp = path.with_extension("npz.partial");
        let file = std::fs::File::create(&tmp).map_err(io)?;
        let result = self.write_amass_to(std::io::BufWriter::new(file));
        match result {
            Ok(()) => std::fs::rename(&tmp, path).map_err(io),
            Err(e) => {
                let _ = std::fs::remove_file(&tmp);
                Err(io(e))
            }
        }
    }

    fn write_amass_to<W: Write + Seek>(&self, w: W) -> std::io::Result<()> {
        let n = self.len() as u64;
        let mut npz = NpzWriter::new(w);
        let flat: Vec<f64> = self.poses.iter().flatten().copied().collect();
        let trans: Vec<f64> = self.trans.iter().flat_map(|t| t.to_array()).collect();
        write_f64(&mut npz, "poses", &[n, POSE_DIM as u64], &flat)?;
        write_f64(&mut npz, "trans", &[n, 3], &trans)?;
        write_f64(&mut npz, "betas", &[self.betas.len() as u64], &self.betas)?;
        write_f64(&mut npz, "mocap_frame_rate", &[], &[self.frame_rate_hz])?;
        write_str(&mut npz, "gender", &self.gender)?;
        write_str(&mut npz, "surface_model_type", "smplx")?;
        for (key, start, len) in [
            ("root_orient", 0, 3),
            ("pose_body", 3, 63),
            ("pose_jaw", 66, 3),
            ("pose_eye", 69, 6),
            ("pose_hand", 75, 90),
        ] {
            let part: Vec<f64> = self
                .poses
                .iter()
                .flat_map(|p| p[start..start + len].iter().copied())
                .collect();
            write_f64(&mut npz, key, &[n, len as u64], &part)?;
        }
        npz.zip_writer().finish()?;
        Ok(())
    }

    /// Reads an AMASS-style or SAMP-style `.npz` motion file.
    pub fn read(path: &Path) -> Result<Self, MotionFileError> {
        let io = |source| MotionFileError::Io {
            path: path.to_owned(),
            source,
        };
        let mut npz = NpzArchive::open(path).map_err(io)?;
        let names: Vec<String> = npz.array_names().map(str::to_owned).collect();
        let has = |k: &str| names.iter().any(|n| n == k);
        let (poses_key, trans_key, betas_key, rate_key) = if has("poses") {
            ("poses", "trans", "betas", "mocap_frame_rate")
        } else if has("pose_est_fullposes") {
            (
                "pose_est_fullposes",
                "pose_est_trans",
                "shape_est_betas",
                "mocap_framerate",
            )
        } else {
            return Err(MotionFileError::MissingKey {
                path: path.into(),
                key: "poses".into(),
                expected: "an AMASS file (`poses` N×165) or a SAMP-style file (`pose_est_fullposes` N×165)".into(),
            });
        };
        let mut reader = KeyReader {
            path,
            npz: &mut npz,
        };
        let (pshape, pdata) = reader.f64(poses_key)?;
        if pshape.len() != 2 || pshape[1] != POSE_DIM as u64 {
            return Err(reader.shape(
                poses_key,
                pshape,
                "[N, 165] (SMPL-X: 55 joints × axis-angle)",
            ));
        }
        let n = pshape[0];
        if n == 0 {
            return Err(reader.shape(
                poses_key,
                pshape,
                "[N, 165] with at least one frame (the file holds none)",
            ));
        }
        let (tshape, tdata) = reader.f64(trans_key)?;
        if tshape != [n, 3] {
            return Err(reader.shape(
                trans_key,
                tshape,
                &format!("[{n}, 3] (one translation per pose)"),
            ));
        }
        let betas = if has(betas_key) {
            let (bshape, b) = reader.f64(betas_key)?;
            // SAMP stores one row of betas per frame; they are constant, so keep the first.
            match bshape.as_slice() {
                [_] => b,
                [rows, cols] if *rows >= 1 => b[..*cols as usize].to_vec(),
                _ => return Err(reader.shape(betas_key, bshape, "[B] or [N, B]")),
            }
        } else {
            Vec::new()
        };
        let (_, rate) = reader.f64(rate_key)?;
        let frame_rate_hz = match rate.as_slice() {
            [r] if r.is_finite() && *r > 0.0 && *r <= MAX_FRAME_RATE_HZ => *r,
            _ => {
                return Err(reader.invalid(
                    rate_key,
                    format!(
                        "expected one positive frame rate of at most {MAX_FRAME_RATE_HZ} Hz, \
                         found {rate:?}"
                    ),
                ))
            }
        };
        let gender = if has("gender") {
            reader.string("gender")?
        } else {
            "neutral".to_string()
        };
        if let Some(i) = pdata
            .iter()
            .chain(&tdata)
            .chain(&betas)
            .position(|v| !v.is_finite())
        {
            return Err(reader.invalid(
                poses_key,
                format!("non-finite value (flat index {i} over poses, trans, betas)"),
            ));
        }
        Ok(Self {
            frame_rate_hz,
            betas,
            gender,
            poses: pdata
                .chunks_exact(POSE_DIM)
                .map(|c| c.try_into().expect("chunk of POSE_DIM"))
                .collect(),
            trans: tdata
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect(),
        })
    }
}

struct KeyReader<'a, R: Read + Seek> {
    path: &'a Path,
    npz: &'a mut NpzArchive<R>,
}

impl<R: Read + Seek> KeyReader<'_, R> {
    fn file(&mut self, key: &str) -> Result<npyz::NpyFile<impl Read + '_>, MotionFileError> {
        let path = self.path.to_owned();
        crate::npz::array_in_memory(self.npz, key)
            .map_err(|source| MotionFileError::Io {
                path: path.clone(),
                source,
            })?
            .ok_or(MotionFileError::MissingKey {
                path,
                key: key.into(),
                expected: "a numeric array".into(),
            })
    }

    fn f64(&mut self, key: &str) -> Result<(Vec<u64>, Vec<f64>), MotionFileError> {
        let path = self.path.to_owned();
        let file = self.file(key)?;
        let shape = file.shape().to_vec();
        let order = file.order();
        let (data, _) = read_as_f64(file).map_err(|e| match e {
            ReadError::Io(source) => MotionFileError::Io {
                path: path.clone(),
                source,
            },
            ReadError::Dtype(found) => MotionFileError::Invalid {
                path: path.clone(),
                key: key.into(),
                message: format!("dtype {found}, expected a numeric array"),
            },
        })?;
        let data = if order == npyz::Order::Fortran {
            fortran_to_c(&data, &shape)
        } else {
            data
        };
        Ok((shape, data))
    }

    fn string(&mut self, key: &str) -> Result<String, MotionFileError> {
        let path = self.path.to_owned();
        let file = self.file(key)?;
        let v = file
            .into_vec::<String>()
            .map_err(|source| MotionFileError::Io { path, source })?;
        v.into_iter()
            .next()
            .ok_or_else(|| self.invalid(key, "empty string array"))
    }

    fn shape(&self, key: &str, found: Vec<u64>, expected: &str) -> MotionFileError {
        MotionFileError::Shape {
            path: self.path.into(),
            key: key.into(),
            found,
            expected: expected.into(),
        }
    }

    fn invalid(&self, key: &str, message: impl Into<String>) -> MotionFileError {
        MotionFileError::Invalid {
            path: self.path.into(),
            key: key.into(),
            message: message.into(),
        }
    }
}

/// Deflate, with a fixed timestamp so the same sequence always gives the same bytes.
fn zip_options() -> npyz::zip::write::FileOptions {
    npyz::zip::write::FileOptions::default()
        .compression_method(npyz::zip::CompressionMethod::Deflated)
        .last_modified_time(npyz::zip::DateTime::default())
}

/// One array of the archive: serialised in memory, then written in one piece (fed to the
/// archive's deflate stream value by value, a long take's arrays took several times longer
/// to write than to compress).
fn write_f64<W: Write + Seek>(
    npz: &mut NpzWriter<W>,
    key: &str,
    shape: &[u64],
    data: &[f64],
) -> std::io::Result<()> {
    let mut bytes = Vec::with_capacity(128 + 8 * data.len());
    {
        let mut w = npyz::WriteOptions::new()
            .default_dtype()
            .shape(shape)
            .writer(&mut bytes)
            .begin_nd()?;
        w.extend(data.iter().copied())?;
        w.finish()?;
    }
    let zip = npz.zip_writer();
    zip.start_file(npyz::npz::file_name_from_array_name(key), zip_options())?;
    zip.write_all(&bytes)?;
    // npyz's array writer flushed the archive twice (in `finish`, again when dropped): so do
    // we, and archives stay byte for byte what they were.
    zip.flush()?;
    zip.flush()
}

fn write_str<W: Write + Seek>(
    npz: &mut NpzWriter<W>,
    key: &str,
    value: &str,
) -> std::io::Result<()> {
    let options = zip_options();
    let chars = value.chars().count().max(1);
    let dtype = npyz::DType::Plain(
        format!("<U{chars}")
            .parse()
            .expect("valid unicode type string"),
    );
    let mut w = npz
        .array::<str>(key, options)?
        .dtype(dtype)
        .shape(&[])
        .begin_nd()?;
    w.push(value)?;
    w.finish()
}
