//! The seed bank: the mocap seeds every walker starts from — the first two frames of the motion
//! model's training primitives, canonical, with the floor height in that frame — or seeds
//! given in the world. Training's episodes, `egogen policy eval` and a take's people draw
//! from the same bank.

use crate::body::BodyParams;
use crate::motion::cvae::data::PrimitiveSet;
use crate::motion::cvae::features::{frame_params, FRAME_DIM};
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::{BodyContext, CanonicalSeed, PrimitiveSeed};
use crate::motion::primitive::SEED_FRAMES;

/// Mocap seeds episodes start from: the first two frames of training primitives, canonical,
/// with the floor height in that frame.
#[derive(Debug, Clone)]
pub struct SeedBank {
    pub seeds: Vec<([BodyParams; SEED_FRAMES], f64)>,
}

impl SeedBank {
    /// The seeds of every primitive of a set.
    pub(crate) fn from_set(set: &PrimitiveSet) -> Self {
        let seeds = (0..set.len())
            .map(|i| {
                let v = set.item(i);
                (
                    std::array::from_fn(|k| {
                        frame_params(&v[k * FRAME_DIM..(k + 1) * FRAME_DIM], &[])
                    }),
                    set.floors(i)[0] as f64,
                )
            })
            .collect();
        Self { seeds }
    }

    /// Seeds given in the world (any floor height), canonicalised.
    pub fn from_world_seeds(
        body: &BodyContext,
        seeds: &[PrimitiveSeed],
    ) -> Result<Self, DecodeError> {
        let seeds = seeds
            .iter()
            .map(|s| {
                let c = CanonicalSeed::new(body, s)?;
                let frames: [BodyParams; SEED_FRAMES] =
                    std::array::from_fn(|k| c.frames[k].clone());
                Ok((frames, c.floor as f64))
            })
            .collect::<Result<_, DecodeError>>()?;
        Ok(Self { seeds })
    }
}
