//! Training and evaluation data: clips cut into canonical primitives (and chains of primitives
//! for rollout training), as flat `f32` feature arrays.

use crate::body::{BodyModel, PoseError, ShapedBody};
use crate::motion::primitive::{canonicalize, PrimitiveError, PRIMITIVE_FRAMES, SEED_FRAMES};
use crate::motion::resample::mirror;
use crate::motion::MotionSequence;

use super::contact::contact_score;
use super::features::{primitive_features, FRAME_DIM};
use super::net::InputStats;
use super::tensor_body::RigGeometry;

/// Values of one primitive.
pub(crate) const PRIMITIVE_VALUES: usize = PRIMITIVE_FRAMES * FRAME_DIM;
/// Frames by which consecutive primitives of a chain advance (the seed overlaps).
pub(crate) const CHAIN_STRIDE: usize = PRIMITIVE_FRAMES - SEED_FRAMES;

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
    pub(crate) fn new(chain_len: usize) -> Self {
        Self {
            chain_len,
            ..Self::default()
        }
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.floor_z.len() / self.chain_len.max(1)
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.floor_z.is_empty()
    }

    /// Adds every chain of `frames` (a range of `seq`) starting each `stride` frames whose
    /// primitives all pass `filter`.
    pub(crate) fn add_clip(
        &mut self,
        seq: &MotionSequence,
        frames: std::ops::Range<usize>,
        stride: usize,
        model: &BodyModel,
        filter: Option<&ContactFilter>,
    ) -> Result<(), PrimitiveError> {
        let span = CHAIN_STRIDE * (self.chain_len - 1) + PRIMITIVE_FRAMES;
        let end = frames.end.min(seq.len());
        // Contact verdicts of primitives by start frame, computed once each.
        let mut passes: Vec<Option<bool>> = vec![None; end];
        let mut start = frames.start;
        while start + span <= end {
            let chain = (0..self.chain_len)
                .map(|k| canonicalize(seq, start + k * CHAIN_STRIDE, model))
                .collect::<Result<Vec<_>, _>>()?;
            let keep = match filter {
                None => true,
                Some(f) if f.context_frames == 0 => {
                    let mut keep = true;
                    for p in &chain {
                        keep &= f.score(p)? >= f.min_score;
                    }
                    keep
                }
                Some(f) => {
                    // Every primitive starting within the context of the chain must pass.
                    let first = start.saturating_sub(f.context_frames).max(frames.start);
                    let last = (start + span - PRIMITIVE_FRAMES + f.context_frames)
                        .min(end - PRIMITIVE_FRAMES);
                    let mut keep = true;
                    for (s, verdict) in passes.iter_mut().enumerate().take(last + 1).skip(first) {
                        let pass = match *verdict {
                            Some(v) => v,
                            None => f.score(&canonicalize(seq, s, model)?)? >= f.min_score,
                        };
                        *verdict = Some(pass);
                        if !pass {
                            keep = false;
                            break;
                        }
                    }
                    keep
                }
            };
            if keep {
                for p in &chain {
                    self.features.extend(primitive_features(p));
                    self.floor_z.push(-p.world_from_canon.translation.z as f32);
                }
            }
            start += stride.max(1);
        }
        Ok(())
    }

    /// Features of item `i`.
    pub(crate) fn item(&self, i: usize) -> &[f32] {
        let n = self.chain_len * PRIMITIVE_VALUES;
        &self.features[i * n..(i + 1) * n]
    }

    /// Floor heights of item `i`.
    pub(crate) fn floors(&self, i: usize) -> &[f32] {
        &self.floor_z[i * self.chain_len..(i + 1) * self.chain_len]
    }

    /// Mean and spread of features and floors (spreads floored at `min_std`).
    pub(crate) fn input_stats(&self, min_std: f32) -> InputStats {
        let (feature_mean, feature_std) = self.feature_stats(min_std);
        let n = self.floor_z.len().max(1) as f64;
        let mean = self.floor_z.iter().map(|&f| f as f64).sum::<f64>() / n;
        let var = self
            .floor_z
            .iter()
            .map(|&f| (f as f64 - mean).powi(2))
            .sum::<f64>()
            / n;
        InputStats {
            feature_mean,
            feature_std,
            floor_mean_std: [mean as f32, (var.sqrt() as f32).max(min_std)],
        }
    }

    /// Per-value mean and standard deviation over all frames (spread floored at `min_std`).
    pub(crate) fn feature_stats(&self, min_std: f32) -> ([f32; FRAME_DIM], [f32; FRAME_DIM]) {
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
pub(crate) struct ClipPart {
    pub seq: MotionSequence,
    pub frames: std::ops::Range<usize>,
}

/// Keeps primitives whose mocap foot-contact score (see `eval`) reaches `min_score`: feet on
/// the floor (z = 0) and not sliding. Drops climbing on objects and jumps. With
/// `context_frames` > 0 a primitive is kept only when every primitive starting within that
/// many frames of it passes too, so the run-up to a dropped motion (standing still before a
/// jump, stepping up onto an object) goes with it: a model should not learn the start of a
/// motion whose rest it never sees.
pub(crate) struct ContactFilter<'m> {
    shaped: ShapedBody<'m>,
    foot_vertices: Vec<u32>,
    pub min_score: f64,
    pub context_frames: usize,
}

impl<'m> ContactFilter<'m> {
    pub(crate) fn new(
        model: &'m BodyModel,
        min_score: f64,
        context_frames: usize,
    ) -> Result<Self, PoseError> {
        let geo = RigGeometry::new(model, &[])?;
        Ok(Self {
            shaped: model.shape(&[], &[])?,
            foot_vertices: geo
                .foot_markers
                .iter()
                .map(|&k| geo.marker_ids[k])
                .collect(),
            min_score,
            context_frames,
        })
    }

    /// Foot-contact score of a canonical primitive over the world floor z = 0.
    pub(crate) fn score(&self, p: &crate::motion::primitive::Primitive) -> Result<f64, PoseError> {
        let feet = p
            .frames
            .iter()
            .map(|f| {
                let m = self
                    .shaped
                    .marker_frame(&f.pose, f.transl, &self.foot_vertices)?;
                Ok(m.markers.iter().map(|v| v.to_array()).collect())
            })
            .collect::<Result<Vec<Vec<[f64; 3]>>, PoseError>>()?;
        Ok(contact_score(&feet, -p.world_from_canon.translation.z))
    }
}

/// Builds a set from clip parts, each also mirrored when `with_mirror`, keeping the chains
/// that pass `filter`.
pub(crate) fn build_set(
    parts: &[ClipPart],
    chain_len: usize,
    stride: usize,
    with_mirror: bool,
    model: &BodyModel,
    filter: Option<&ContactFilter>,
) -> Result<PrimitiveSet, PrimitiveError> {
    let mut set = PrimitiveSet::new(chain_len);
    for part in parts {
        set.add_clip(&part.seq, part.frames.clone(), stride, model, filter)?;
        if with_mirror {
            let m = mirror(&part.seq, model)?;
            set.add_clip(&m, part.frames.clone(), stride, model, filter)?;
        }
    }
    Ok(set)
}
