//! The files bodies reach Blender in: topology once (`faces.npy`, int32 F×3) and a PC2 point
//! cache of posed vertices with sub-frame samples, which Blender's Mesh Cache modifier plays
//! back so Cycles' deformation blur sees the real motion inside the shutter interval
//! (`synth::body_cache` fills one from a motion).
//!
//! PC2 layout (little endian): `"POINTCACHE2\0"`, i32 version 1, i32 points, f32 start frame,
//! f32 sample rate, i32 samples, then `samples × points × 3` f32. Blender ignores the header's
//! start and rate; playback keys (`render::ShardBody::cache_keys`) place the samples in time.

use std::io::Read;
use std::path::{Path, PathBuf};

use npyz::WriterBuilder;

use crate::atomic_file::write_atomically;

const PC2_MAGIC: &[u8; 12] = b"POINTCACHE2\0";

/// A cache file that could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a PC2 point cache: {reason}")]
    Format { path: PathBuf, reason: String },
}

/// A point cache in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCache {
    pub start_frame: f32,
    pub sample_rate: f32,
    /// `samples[k][v]`.
    pub samples: Vec<Vec<[f32; 3]>>,
}

impl PointCache {
    pub(crate) fn num_points(&self) -> usize {
        self.samples.first().map_or(0, Vec::len)
    }

    /// Writes the cache atomically (temporary name, then rename).
    pub fn write(&self, path: &Path) -> Result<(), CacheError> {
        let io = |source| CacheError::Io {
            path: path.into(),
            source,
        };
        let n = self.num_points();
        let mut bytes = Vec::with_capacity(32 + self.samples.len() * n * 12);
        bytes.extend_from_slice(PC2_MAGIC);
        bytes.extend_from_slice(&1i32.to_le_bytes());
        bytes.extend_from_slice(&(n as i32).to_le_bytes());
        bytes.extend_from_slice(&self.start_frame.to_le_bytes());
        bytes.extend_from_slice(&self.sample_rate.to_le_bytes());
        bytes.extend_from_slice(&(self.samples.len() as i32).to_le_bytes());
        for sample in &self.samples {
            assert_eq!(sample.len(), n, "every sample has the same points");
            for p in sample {
                for c in p {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        write_atomically(path, &bytes).map_err(io)
    }

    /// Reads a PC2 file, checking its header against its size.
    pub fn read(path: &Path) -> Result<Self, CacheError> {
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|mut f| f.read_to_end(&mut bytes))
            .map_err(|source| CacheError::Io {
                path: path.into(),
                source,
            })?;
        let bad = |reason: String| CacheError::Format {
            path: path.into(),
            reason,
        };
        if bytes.len() < 32 || &bytes[..12] != PC2_MAGIC {
            return Err(bad("missing the POINTCACHE2 signature".into()));
        }
        let i32_at = |o: usize| i32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let (points, samples) = (i32_at(16), i32_at(28));
        if points < 0 || samples < 0 {
            return Err(bad(format!("{points} points, {samples} samples")));
        }
        let (points, samples) = (points as usize, samples as usize);
        let expected = points
            .checked_mul(samples)
            .and_then(|n| n.checked_mul(12))
            .and_then(|n| n.checked_add(32));
        if expected != Some(bytes.len()) {
            return Err(bad(format!(
                "header says {samples} samples of {points} points ({} bytes) but the file has {} bytes",
                expected.map_or("more than 2^64".into(), |n| n.to_string()),
                bytes.len()
            )));
        }
        let samples = (0..samples)
            .map(|k| {
                (0..points)
                    .map(|v| {
                        let o = 32 + (k * points + v) * 12;
                        [f32_at(o), f32_at(o + 4), f32_at(o + 8)]
                    })
                    .collect()
            })
            .collect();
        Ok(Self {
            start_frame: f32_at(20),
            sample_rate: f32_at(24),
            samples,
        })
    }
}

/// Writes the triangle list as an int32 `.npy` of shape F×3 (atomically).
pub(crate) fn write_faces_npy(path: &Path, faces: &[[u32; 3]]) -> Result<(), CacheError> {
    write_npy_rows(path, faces.iter().map(|f| f.map(|i| i as i32)))
}

/// Writes the cache's first sample as a float32 `.npy` of shape N×3 (atomically): the mesh's
/// vertices before the cache plays, so that Blender never parses the PC2 file itself.
pub(crate) fn write_rest_vertices_npy(path: &Path, cache: &PointCache) -> Result<(), CacheError> {
    let first = cache.samples.first().map(Vec::as_slice).unwrap_or(&[]);
    write_npy_rows(path, first.iter().copied())
}

/// Writes per-corner texture coordinates as a float32 `.npy` of shape (F·3)×2 (atomically),
/// corner for corner with [`write_faces_npy`]'s triangles.
pub(crate) fn write_corner_uvs_npy(path: &Path, uvs: &[[f32; 2]]) -> Result<(), CacheError> {
    write_npy_rows(path, uvs.iter().copied())
}

/// Writes per-vertex rows of `C` values as a float32 `.npy` of shape N×C (atomically): a
/// person's garment regions and rest positions (`render::outfit::regions`).
pub(crate) fn write_vertex_rows_npy<const C: usize>(
    path: &Path,
    rows: &[[f32; C]],
) -> Result<(), CacheError> {
    write_npy_rows(path, rows.iter().copied())
}

/// Writes an object index per face of a scene file as an int32 `.npy` of shape F×1
/// (atomically; `u32::MAX`, a face that made no triangle, as −1): how Blender splits a scan it
/// imports as one mesh into the scene's objects.
pub(crate) fn write_face_objects_npy(path: &Path, objects: &[u32]) -> Result<(), CacheError> {
    write_npy_rows(
        path,
        objects.iter().map(|&o| [i32::try_from(o).unwrap_or(-1)]),
    )
}

/// Rows of `C` values as an `.npy` of shape N×C, written atomically.
fn write_npy_rows<T: npyz::Serialize + npyz::AutoSerialize + Copy, const C: usize>(
    path: &Path,
    rows: impl ExactSizeIterator<Item = [T; C]>,
) -> Result<(), CacheError> {
    let io = |source| CacheError::Io {
        path: path.into(),
        source,
    };
    let mut bytes = Vec::new();
    {
        let mut w = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[rows.len() as u64, C as u64])
            .writer(&mut bytes)
            .begin_nd()
            .map_err(io)?;
        for row in rows {
            for v in row {
                w.push(&v).map_err(io)?;
            }
        }
        w.finish().map_err(io)?;
    }
    write_atomically(path, &bytes).map_err(io)
}
