//! The network: an MLP encoder over the whole primitive and an autoregressive GRU-cell decoder
//! that adds a residual to the previous frame, conditioned on the seed and the latent.
//!
//! The decoder also reads the floor height in the canonical frame (the pelvis height above the
//! floor, negated), so feet that drift off the floor along a chain can be brought back.
//!
//! Shapes: `B` primitives, `T = 20` frames, `S = 2` seed frames, `F = FRAME_DIM = 135`
//! values per frame, `L` latent dimensions (128).

use burn::module::{ModuleMapper, Param};
use burn::nn::{Linear, LinearConfig};
use burn::prelude::*;
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::FloatDType;
use serde::{Deserialize, Serialize};

use super::decoder_f32::{DecoderF32, DenseLayer};
use super::features::FRAME_DIM;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};

/// Frames the decoder writes per primitive.
pub(crate) const DECODED_FRAMES: usize = PRIMITIVE_FRAMES - SEED_FRAMES;

/// Architecture of the C-VAE (saved inside the weights file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArchConfig {
    /// Latent dimensions (paper: 128).
    pub latent_dim: usize,
    /// Width of the encoder's hidden layers.
    pub encoder_width: usize,
    /// GRU hidden size of the decoder.
    pub decoder_width: usize,
}

impl Default for ArchConfig {
    fn default() -> Self {
        Self {
            latent_dim: 128,
            encoder_width: 256,
            decoder_width: 256,
        }
    }
}

impl ArchConfig {
    /// Builds a freshly initialised network; `stats` normalise its inputs.
    pub fn init<B: Backend>(&self, stats: &InputStats, device: &B::Device) -> PrimitiveVae<B> {
        let (l, e, h) = (self.latent_dim, self.encoder_width, self.decoder_width);
        let constant = |v: &[f32]| {
            Param::from_tensor(Tensor::from_data(
                TensorData::new(v.to_vec(), [v.len()]),
                device,
            ))
            .set_require_grad(false)
        };
        let linear = |i, o| LinearConfig::new(i, o).init(device);
        PrimitiveVae {
            feature_mean: constant(&stats.feature_mean),
            feature_std: constant(&stats.feature_std),
            floor_mean_std: constant(&stats.floor_mean_std),
            enc_in: linear(PRIMITIVE_FRAMES * FRAME_DIM, e),
            enc_hidden: linear(e, e),
            enc_mu: linear(e, l),
            enc_logvar: linear(e, l),
            dec_init: linear(l + SEED_FRAMES * FRAME_DIM + 1, h),
            gru_input: linear(l + 2 * FRAME_DIM + 1, 3 * h),
            gru_hidden: linear(h, 3 * h),
            dec_out: linear(h, FRAME_DIM),
        }
    }

    /// Multiply-adds of one primitive decoded (linear layers only; activations and the
    /// Gram-Schmidt step are a few hundred more per frame).
    pub fn decoder_macs(&self) -> usize {
        let (l, h) = (self.latent_dim, self.decoder_width);
        let init = (l + SEED_FRAMES * FRAME_DIM + 1) * h;
        let step = (l + 2 * FRAME_DIM + 1) * 3 * h + h * 3 * h + h * FRAME_DIM;
        init + DECODED_FRAMES * step
    }
}

/// Normalisation of the network's inputs, fixed by the training data.
#[derive(Debug, Clone, PartialEq)]
pub struct InputStats {
    pub feature_mean: [f32; FRAME_DIM],
    pub feature_std: [f32; FRAME_DIM],
    /// Mean and spread of the canonical floor height (m).
    pub floor_mean_std: [f32; 2],
}

impl Default for InputStats {
    fn default() -> Self {
        Self {
            feature_mean: [0.0; FRAME_DIM],
            feature_std: [1.0; FRAME_DIM],
            floor_mean_std: [0.0, 1.0],
        }
    }
}

/// The motion-primitive C-VAE.
#[derive(Module, Debug)]
pub struct PrimitiveVae<B: Backend> {
    /// Per-value mean and spread of frame features (fixed by the training data, not trained).
    pub feature_mean: Param<Tensor<B, 1>>,
    pub feature_std: Param<Tensor<B, 1>>,
    /// Mean and spread of the canonical floor height `[2]` (not trained).
    pub floor_mean_std: Param<Tensor<B, 1>>,
    enc_in: Linear<B>,
    enc_hidden: Linear<B>,
    enc_mu: Linear<B>,
    enc_logvar: Linear<B>,
    dec_init: Linear<B>,
    gru_input: Linear<B>,
    gru_hidden: Linear<B>,
    dec_out: Linear<B>,
}

/// Casts every float parameter to one precision.
struct CastParams(FloatDType);

impl<B: Backend> ModuleMapper<B> for CastParams {
    fn map_float<const D: usize>(&mut self, param: Param<Tensor<B, D>>) -> Param<Tensor<B, D>> {
        let (id, tensor, mapper) = param.consume();
        Param::from_mapped_value(id, tensor.cast(self.0), mapper)
    }
}

impl<B: Backend> PrimitiveVae<B> {
    /// The network with its weights in another float precision (e.g. `F16` or `BF16` for
    /// faster, less exact inference); [`decode_raw`] follows it.
    pub(crate) fn with_precision(self, dtype: FloatDType) -> Self {
        self.map(&mut CastParams(dtype))
    }

    /// Float type of the weights.
    pub(crate) fn dtype(&self) -> burn::tensor::DType {
        self.feature_mean.val().dtype()
    }

    /// Latent size.
    pub(crate) fn latent_dim(&self) -> usize {
        self.enc_mu.weight.dims()[1]
    }

    /// The decoder as plain f32 arrays, for inference without burn; `None` unless the
    /// weights are f32.
    pub(crate) fn decoder_f32(&self) -> Option<DecoderF32> {
        fn values<B: Backend>(t: Tensor<B, 1>) -> Option<Vec<f32>> {
            t.into_data().to_vec::<f32>().ok()
        }
        fn dense<B: Backend>(layer: &Linear<B>) -> Option<DenseLayer> {
            let [inputs, outputs] = layer.weight.dims();
            Some(DenseLayer {
                inputs,
                outputs,
                weight: values(layer.weight.val().flatten(0, 1))?,
                bias: match &layer.bias {
                    Some(b) => values(b.val())?,
                    None => vec![0.0; outputs],
                },
            })
        }
        let floor = values(self.floor_mean_std.val())?;
        DecoderF32::new(
            values(self.feature_mean.val())?,
            values(self.feature_std.val())?,
            [*floor.first()?, *floor.get(1)?],
            [
                dense(&self.dec_init)?,
                dense(&self.gru_input)?,
                dense(&self.gru_hidden)?,
                dense(&self.dec_out)?,
            ],
        )
        .ok()
    }

    /// Raw features `[.., F]` → normalised.
    pub(crate) fn normalize<const D: usize>(&self, x: Tensor<B, D>) -> Tensor<B, D> {
        let (mean, std) = self.stats::<D>();
        (x - mean) / std
    }

    /// Normalised features `[.., F]` → raw.
    pub(crate) fn denormalize<const D: usize>(&self, x: Tensor<B, D>) -> Tensor<B, D> {
        let (mean, std) = self.stats::<D>();
        x * std + mean
    }

    fn stats<const D: usize>(&self) -> (Tensor<B, D>, Tensor<B, D>) {
        let mut shape = [1usize; D];
        shape[D - 1] = FRAME_DIM;
        (
            self.feature_mean.val().detach().reshape(shape),
            self.feature_std.val().detach().reshape(shape),
        )
    }

    /// Posterior `(mu, logvar)`, each `[B, L]`, of normalised primitives `[B, T, F]`.
    pub(crate) fn encode(&self, x: Tensor<B, 3>) -> (Tensor<B, 2>, Tensor<B, 2>) {
        let h = relu(self.enc_in.forward(x.flatten(1, 2)));
        let h = relu(self.enc_hidden.forward(h));
        (self.enc_mu.forward(h.clone()), self.enc_logvar.forward(h))
    }

    /// Canonical floor heights `[B]` (m) → normalised `[B, 1]`.
    pub(crate) fn normalize_floor(&self, floor: Tensor<B, 1>) -> Tensor<B, 2> {
        let stats = self.floor_mean_std.val().detach();
        let mean = stats.clone().narrow(0, 0, 1);
        let std = stats.narrow(0, 1, 1);
        ((floor - mean) / std).unsqueeze_dim(1)
    }

    /// Decodes normalised seeds `[B, S, F]`, normalised floors `[B, 1]` and latents `[B, L]`
    /// into the normalised frames after the seed, `[B, T − S, F]`.
    pub(crate) fn decode(
        &self,
        seed: Tensor<B, 3>,
        floor: Tensor<B, 2>,
        z: Tensor<B, 2>,
    ) -> Tensor<B, 3> {
        let [b, s, f] = seed.dims();
        let hidden = self.gru_hidden.weight.dims()[0];
        let mut h = self
            .dec_init
            .forward(Tensor::cat(
                vec![z.clone(), seed.clone().reshape([b, s * f]), floor.clone()],
                1,
            ))
            .tanh();
        let mut prev = seed.clone().narrow(1, s - 1, 1).reshape([b, f]);
        let mut velocity = prev.clone() - seed.narrow(1, s - 2, 1).reshape([b, f]);
        let mut out = Vec::with_capacity(DECODED_FRAMES);
        for _ in 0..DECODED_FRAMES {
            let gx = self.gru_input.forward(Tensor::cat(
                vec![z.clone(), prev.clone(), velocity, floor.clone()],
                1,
            ));
            let gh = self.gru_hidden.forward(h.clone());
            let r = sigmoid(gx.clone().narrow(1, 0, hidden) + gh.clone().narrow(1, 0, hidden));
            let u = sigmoid(
                gx.clone().narrow(1, hidden, hidden) + gh.clone().narrow(1, hidden, hidden),
            );
            let n =
                (gx.narrow(1, 2 * hidden, hidden) + r * gh.narrow(1, 2 * hidden, hidden)).tanh();
            h = n.clone() + u * (h - n);
            velocity = self.dec_out.forward(h.clone());
            prev = prev + velocity.clone();
            out.push(prev.clone());
        }
        Tensor::stack(out, 1)
    }
}

/// Decodes raw seeds `[B, S, F]` over canonical floors `[B]` (m) with latents `[B, L]` into
/// whole raw primitives `[B, T, F]` (the seed frames first). The network runs in its weights'
/// precision; inputs and output are in the seed's.
pub(crate) fn decode_raw<B: Backend>(
    net: &PrimitiveVae<B>,
    seed: Tensor<B, 3>,
    floor: Tensor<B, 1>,
    z: Tensor<B, 2>,
) -> Tensor<B, 3> {
    let io = seed.dtype();
    let decoded = match net.dtype() {
        d if d == io => {
            let s = net.normalize(seed.clone());
            net.denormalize(net.decode(s, net.normalize_floor(floor), z))
        }
        d => {
            let dt: FloatDType = d.into();
            let s = net.normalize(seed.clone().cast(dt));
            let f = net.normalize_floor(floor.cast(dt));
            net.denormalize(net.decode(s, f, z.cast(dt)))
                .cast(FloatDType::from(io))
        }
    };
    Tensor::cat(vec![seed, decoded], 1)
}
