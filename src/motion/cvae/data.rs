//! Training and evaluation data: clips cut into canonical primitives (and chains of primitives
//! for rollout training), as flat `f32` feature arrays.

use crate::body::BodyModel;
use crate::motion::primitive::{canonicalize, PrimitiveError, PRIMITIVE_FRAMES, SEED_FRAMES};
use crate::motion::resample::mirror;
use crate::motion::MotionSequence;

use super::features::{primitive_features, FRAME_DIM};

/// Values of one primitive.
pub const PRIMITIVE_VALUES: usize = PRIMITIVE_FRAMES * FRAME_DIM;
/// Frames by which consecutive primitives of a chain advance (the seed overlaps).
pub const CHAIN_STRIDE: usize = PRIMITIVE_FRAMES - SEED_FRAMES;

/// Primitives (or chains of `chain_len` primitives) as flat features, plus the floor height of
/// each primitive in its canonical frame (the clips' floor is world z = 0).
#[derive(Debug, Clone, Default)]
pub struct PrimitiveSet {
    /// Primitives per item (1 for single primitives).
    pub chain_len: usize,
    /// `[items, chain_len, PRIMITIVE_FRAMES, FRAME_DIM]`.
    pub features: Vec<f32>,
    /// `[items, chain_len]`.
    pub floor_z: Vec<f32>,
}

impl PrimitiveSet {
    pub fn new(chain_len: usize) -> Self {
        Self {
            chain_len,
            ..Self::default()
        }
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.floor_z.len() / self.chain_len.max(1)
    }

    pub fn is_empty(&self) -> bool {
        self.floor_z.is_empty()
    }

    /// Adds every chain of `frames` (a range of `seq`) starting each `stride` frames.
    pub fn add_clip(
        &mut self,
        seq: &MotionSequence,
        frames: std::ops::Range<usize>,
        stride: usize,
        model: &BodyModel,
    ) -> Result<(), PrimitiveError> {
        let span = CHAIN_STRIDE * (self.chain_len - 1) + PRIMITIVE_FRAMES;
        let end = frames.end.min(seq.len());
        let mut start = frames.start;
        while start + span <= end {
            for k in 0..self.chain_len {
                let p = canonicalize(seq, start + k * CHAIN_STRIDE, model)?;
                self.features.extend(primitive_features(&p));
                self.floor_z.push(-p.world_from_canon.translation.z as f32);
            }
            start += stride.max(1);
        }
        Ok(())
    }

    /// Features of item `i`.
    pub fn item(&self, i: usize) -> &[f32] {
        let n = self.chain_len * PRIMITIVE_VALUES;
        &self.features[i * n..(i + 1) * n]
    }

    /// Floor heights of item `i`.
    pub fn floors(&self, i: usize) -> &[f32] {
        &self.floor_z[i * self.chain_len..(i + 1) * self.chain_len]
    }

    /// Per-value mean and standard deviation over all frames (spread floored at `min_std`).
    pub fn feature_stats(&self, min_std: f32) -> ([f32; FRAME_DIM], [f32; FRAME_DIM]) {
        let frames = self.features.len() / FRAME_DIM;
        let mut mean = [0f64; FRAME_DIM];
        let mut sq = [0f64; FRAME_DIM];
        for f in self.features.chunks_exact(FRAME_DIM) {
            for c in 0..FRAME_DIM {
                mean[c] += f[c] as f64;
                sq[c] += (f[c] as f64).powi(2);
            }
        }
        let n = frames.max(1) as f64;
        let m = mean.map(|x| x / n);
        let std: [f32; FRAME_DIM] = std::array::from_fn(|c| {
            ((sq[c] / n - m[c] * m[c]).max(0.0).sqrt() as f32).max(min_std)
        });
        (m.map(|x| x as f32), std)
    }
}

/// A clip and the frames of it that a set uses.
#[derive(Debug, Clone)]
pub struct ClipPart {
    pub name: String,
    pub seq: MotionSequence,
    pub frames: std::ops::Range<usize>,
}

/// Builds a set from clip parts, each also mirrored when `with_mirror`.
pub fn build_set(
    parts: &[ClipPart],
    chain_len: usize,
    stride: usize,
    with_mirror: bool,
    model: &BodyModel,
) -> Result<PrimitiveSet, PrimitiveError> {
    let mut set = PrimitiveSet::new(chain_len);
    for part in parts {
        set.add_clip(&part.seq, part.frames.clone(), stride, model)?;
        if with_mirror {
            let m = mirror(&part.seq, model)?;
            set.add_clip(&m, part.frames.clone(), stride, model)?;
        }
    }
    Ok(set)
}
