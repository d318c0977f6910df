//! Inference: a batch of (seed, latent) → primitives in the world, with the 67 markers and the
//! CPF of every frame from the f64 body code. This is what the locomotion policy calls.

use std::path::{Path, PathBuf};

use burn::backend::Flex;
use burn::prelude::*;
use rayon::prelude::*;

use super::decoder_f32::DecoderF32;
use super::features::{frame_features, frame_params, FRAME_DIM};
use super::net::decode_raw;
use super::net::{ArchConfig, PrimitiveVae};
use super::tensor_body::BODY_JOINTS;
use super::weights::{self, WeightsError};
use crate::body::{
    joint, BodyModel, BodyParams, CpfCalibration, PoseError, PosedSkeleton, ShapedBody,
};
use crate::math::{Affine3, Vec3};
use crate::motion::primitive::{
    canonical_frame, Primitive, PrimitiveError, PRIMITIVE_FRAMES, SEED_FRAMES,
};

/// Backend of inference (CPU).
pub type InferBackend = Flex;

/// The two seed frames of a primitive, in world coordinates (z up), and the height of the
/// floor under the body (world z, m).
#[derive(Debug, Clone)]
pub struct PrimitiveSeed {
    pub frames: [BodyParams; SEED_FRAMES],
    pub floor_z: f64,
}

/// One decoded primitive: all 20 frames (the seed first), canonical and in the world.
#[derive(Debug, Clone)]
pub struct DecodedPrimitive {
    /// Frames in the canonical frame of the seed, and `world_from_canon`.
    pub primitive: Primitive,
    /// Floor height (world z, m) the primitive was decoded over.
    pub floor_z: f64,
    /// The same frames in the world.
    pub world: Vec<BodyParams>,
    /// The 67 markers of each frame, in the world.
    pub markers: Vec<Vec<Vec3>>,
    /// Joints of each frame, in the world.
    pub joints: Vec<Vec<Vec3>>,
    /// `world_from_cpf` of each frame.
    pub world_from_cpf: Vec<Affine3>,
}

impl DecodedPrimitive {
    /// The seed of the primitive that follows: this one's last two frames.
    pub(crate) fn next_seed(&self) -> PrimitiveSeed {
        let n = self.world.len();
        PrimitiveSeed {
            frames: std::array::from_fn(|k| self.world[n - SEED_FRAMES + k].clone()),
            floor_z: self.floor_z,
        }
    }
}

/// The body the decoded motion drives: shape, marker ids and CPF calibration.
pub struct BodyContext<'m> {
    pub model: &'m BodyModel,
    pub shaped: ShapedBody<'m>,
    pub betas: Vec<f64>,
    pub marker_ids: Vec<u32>,
    pub cpf: CpfCalibration,
}

impl<'m> BodyContext<'m> {
    pub fn new(model: &'m BodyModel, betas: &[f64]) -> Result<Self, PoseError> {
        let shaped = model.shape(betas, &[])?;
        let cpf = CpfCalibration::from_rest_joints(&shaped.rest_joints);
        Ok(Self {
            model,
            shaped,
            betas: betas.to_vec(),
            marker_ids: model.marker_ids().to_vec(),
            cpf,
        })
    }

    fn rest_pelvis(&self) -> Vec3 {
        self.shaped.rest_joints[joint::PELVIS]
    }
}

/// A seed in its canonical frame, as the network reads it.
#[derive(Debug, Clone)]
pub struct CanonicalSeed {
    pub world_from_canon: Affine3,
    /// The seed frames in the canonical frame.
    pub frames: Vec<BodyParams>,
    /// Their features `[S × F]`.
    pub features: Vec<f32>,
    /// The floor height in the canonical frame (m).
    pub floor: f32,
}

impl CanonicalSeed {
    /// Canonicalises a world seed (origin at the pelvis of its first frame, x along the hips
    /// made horizontal, z up).
    pub fn new(body: &BodyContext, seed: &PrimitiveSeed) -> Result<Self, DecodeError> {
        let first = body
            .shaped
            .skeleton(&seed.frames[0].pose, seed.frames[0].transl)?;
        let world_from_canon = canonical_frame(&first.joints)?;
        let canon_from_world = world_from_canon.inverse();
        let frames: Vec<BodyParams> = seed
            .frames
            .iter()
            .map(|f| f.moved_rigidly(canon_from_world, body.rest_pelvis()))
            .collect();
        Ok(Self {
            world_from_canon,
            features: frames.iter().flat_map(frame_features).collect(),
            floor: (seed.floor_z - world_from_canon.translation.z) as f32,
            frames,
        })
    }
}

/// Why decoding failed.
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    #[error("{seeds} seeds but {latents} latents")]
    BatchMismatch { seeds: usize, latents: usize },
    #[error("latent {index} has {found} values, the model takes {expected}")]
    LatentSize {
        index: usize,
        found: usize,
        expected: usize,
    },
    #[error("decoded primitive {index} is not finite")]
    NonFinite { index: usize },
    #[error(transparent)]
    Primitive(#[from] PrimitiveError),
    #[error(transparent)]
    Pose(#[from] PoseError),
}

/// A trained primitive model, ready to decode.
#[derive(Debug)]
pub struct MotionModel {
    pub path: PathBuf,
    pub arch: ArchConfig,
    pub net: PrimitiveVae<InferBackend>,
    /// The network's decoder as plain f32 arrays, what decoding runs (`None` in another
    /// precision, which runs burn's).
    decoder: Option<DecoderF32>,
}

impl MotionModel {
    /// Loads a weights file (e.g. the shipped `assets/motion/primitive_cvae.safetensors`).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, WeightsError> {
        let path = path.as_ref();
        let (arch, net) = weights::load(path, &Default::default())?;
        Ok(Self {
            path: path.into(),
            arch,
            decoder: net.decoder_f32(),
            net,
        })
    }

    /// The model with its network in another float precision (`F16`, `BF16`; `F32` as
    /// trained). Decoding still takes and returns `f32`.
    pub fn with_precision(self, dtype: burn::tensor::FloatDType) -> Self {
        let net = self.net.with_precision(dtype);
        Self {
            decoder: net.decoder_f32(),
            net,
            ..self
        }
    }

    /// The model decoding a primitive alone in f32 too, not on f16 weights (the
    /// reference of that path: `DecoderF32::without_half_precision`).
    pub fn without_half_precision(self) -> Self {
        Self {
            decoder: self.decoder.map(DecoderF32::without_half_precision),
            ..self
        }
    }

    /// Whether a primitive decoded alone reads f16 weights (on x86-64 with AVX2, FMA
    /// and F16C, in f32 precision).
    #[cfg(test)]
    pub(crate) fn half_precision_weights(&self) -> bool {
        self.decoder
            .as_ref()
            .is_some_and(DecoderF32::half_precision_weights)
    }

    /// Latent size.
    pub fn latent_dim(&self) -> usize {
        self.arch.latent_dim
    }

    /// The network alone: canonical seed features `[B × 2 × F]`, canonical floor heights
    /// `[B]` (m) and latents `[B × L]` → canonical features of all 20 frames `[B × 20 × F]`.
    /// f32 weights run the plain f32 decoder, other precisions burn's.
    pub fn decode_features(&self, seeds: &[f32], floors: &[f32], latents: &[f32]) -> Vec<f32> {
        match &self.decoder {
            Some(d) => d.decode(seeds, floors, latents),
            None => self.decode_features_burn(seeds, floors, latents),
        }
    }

    /// [`Self::decode_features`] through burn's network, whatever the precision (the
    /// reference the f32 decoder is checked against).
    pub fn decode_features_burn(&self, seeds: &[f32], floors: &[f32], latents: &[f32]) -> Vec<f32> {
        let b = floors.len();
        let device = Default::default();
        let seed = Tensor::<InferBackend, 3>::from_data(
            TensorData::new(seeds.to_vec(), [b, SEED_FRAMES, FRAME_DIM]),
            &device,
        );
        let floor = Tensor::from_data(TensorData::new(floors.to_vec(), [b]), &device);
        let z = Tensor::from_data(
            TensorData::new(latents.to_vec(), [b, self.latent_dim()]),
            &device,
        );
        decode_raw(&self.net, seed, floor, z)
            .into_data()
            .to_vec()
            .expect("f32 features")
    }

    /// Decodes a batch of seeds (world) with one latent each; fails on the first primitive
    /// that is not finite.
    pub fn decode(
        &self,
        body: &BodyContext,
        seeds: &[PrimitiveSeed],
        latents: &[Vec<f32>],
    ) -> Result<Vec<DecodedPrimitive>, DecodeError> {
        self.decode_each(body, seeds, latents)?
            .into_iter()
            .collect()
    }

    /// Decodes a batch of seeds (world) with one latent each, with a result per item (a
    /// non-finite primitive fails alone).
    pub fn decode_each(
        &self,
        body: &BodyContext,
        seeds: &[PrimitiveSeed],
        latents: &[Vec<f32>],
    ) -> Result<Vec<Result<DecodedPrimitive, DecodeError>>, DecodeError> {
        if seeds.len() != latents.len() {
            return Err(DecodeError::BatchMismatch {
                seeds: seeds.len(),
                latents: latents.len(),
            });
        }
        let l = self.latent_dim();
        if let Some((index, z)) = latents.iter().enumerate().find(|(_, z)| z.len() != l) {
            return Err(DecodeError::LatentSize {
                index,
                found: z.len(),
                expected: l,
            });
        }
        let mut canon_seeds = Vec::with_capacity(seeds.len());
        let mut seed_features = Vec::with_capacity(seeds.len() * SEED_FRAMES * FRAME_DIM);
        let mut floors = Vec::with_capacity(seeds.len());
        for seed in seeds {
            let c = CanonicalSeed::new(body, seed)?;
            seed_features.extend_from_slice(&c.features);
            floors.push(c.floor);
            canon_seeds.push((c.world_from_canon, c.frames));
        }
        let flat: Vec<f32> = latents.iter().flatten().copied().collect();
        let decoded = self.decode_features(&seed_features, &floors, &flat);
        let per = PRIMITIVE_FRAMES * FRAME_DIM;
        // Posing (f64 skinning of markers, joints and CPF) runs on all cores.
        Ok(canon_seeds
            .into_par_iter()
            .zip(seeds)
            .enumerate()
            .map(|(i, ((world_from_canon, seed_frames), seed))| {
                let values = &decoded[i * per..(i + 1) * per];
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(DecodeError::NonFinite { index: i });
                }
                let last_seed = seed_frames[SEED_FRAMES - 1].clone();
                let mut frames = seed_frames;
                frames.reserve_exact(PRIMITIVE_FRAMES - SEED_FRAMES);
                for f in SEED_FRAMES..PRIMITIVE_FRAMES {
                    let mut p =
                        frame_params(&values[f * FRAME_DIM..(f + 1) * FRAME_DIM], &body.betas);
                    // Joints the model does not drive (jaw, eyes, hands) keep the seed's pose.
                    p.pose[3 * BODY_JOINTS..].copy_from_slice(&last_seed.pose[3 * BODY_JOINTS..]);
                    p.expression = last_seed.expression.clone();
                    frames.push(p);
                }
                let primitive = Primitive {
                    world_from_canon,
                    frames,
                };
                posed(body, primitive, seed.floor_z)
            })
            .collect())
    }
}

/// World frames, markers, joints and CPF of a canonical primitive.
fn posed(
    body: &BodyContext,
    primitive: Primitive,
    floor_z: f64,
) -> Result<DecodedPrimitive, DecodeError> {
    let world = primitive.to_world(body.model)?;
    let mut markers = Vec::with_capacity(world.len());
    let mut joints = Vec::with_capacity(world.len());
    let mut world_from_cpf = Vec::with_capacity(world.len());
    // One skeleton buffer for all frames (what `marker_frame` computes, without moving it).
    let mut skeleton = PosedSkeleton::default();
    for f in &world {
        body.shaped
            .skeleton_into(&f.pose, f.transl, &mut skeleton)?;
        markers.push(
            body.shaped
                .pose_vertices(&skeleton, &f.pose, &body.marker_ids),
        );
        world_from_cpf.push(body.cpf.world_from_cpf(&skeleton));
        joints.push(skeleton.joints.to_vec());
    }
    Ok(DecodedPrimitive {
        primitive,
        floor_z,
        world,
        markers,
        joints,
        world_from_cpf,
    })
}
