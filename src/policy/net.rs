//! The actor-critic network (EgoGen's `GAMMAPolicyBase`, actor and critic), in burn.
//!
//! Two GRUs read the two seed frames: one the marker state (67 × 6 per frame), one the sensing
//! (the paper's ray scan: 32 per frame; the architecture's [`SensingSpec`]; a depth image is
//! first encoded by a small CNN, `DepthCnn`); their last hidden states (`H` each) join sinusoidal positional encodings of
//! `1/(1 + d)` and `1 − t/T` (`2F` values each: sin and cos at frequencies `2^k·π`,
//! k < F). The actor, a residual MLP (two blocks `W → W → W` with LeakyReLU, `W = 2H + 4F`,
//! then a linear layer), writes the mean and log-variance of the latent (log-variance clamped
//! to [−2.5, 2.5]); the critic, the same shape, writes the value. The actor's last layer is
//! scaled by 0.01 at initialisation so that the first actions are ≈ N(0, I).
//!
//! EgoGen's sizes: H = 512, F = 32 (W = 1152; its frequencies reach 2³¹, beyond f32's
//! resolution of these inputs), about 13 M parameters. `hidden` is the width knob.

use burn::nn::{Linear, LinearConfig};
use burn::prelude::*;
use burn::tensor::activation::{leaky_relu, sigmoid};
use serde::{Deserialize, Serialize};

use crate::motion::primitive::SEED_FRAMES;
use crate::sensing::SensingSpec;
use crate::walker::{ObsLayout, STATE_FRAME_DIM};

/// The depth image's CNN (paper Tab. 3, "Egocentric depth"): convolutions whose stride equals
/// their kernel, `(kernel, channels)` in order, each followed by LeakyReLU: 4 × 4 patches of
/// the image into 16 channels, then 2 × 2 of those into 32. A 16 × 32 image becomes 2 × 4 × 32
/// = 256 features per frame for the sensing GRU.
pub(crate) const DEPTH_CNN: [(usize, usize); 2] = [(4, 16), (2, 32)];

/// How much a depth image's side shrinks through [`DEPTH_CNN`] (its strides' product).
const DEPTH_CNN_STRIDE: usize = DEPTH_CNN[0].0 * DEPTH_CNN[1].0;

/// Bounds of the actor's log-variance.
pub(crate) const LOGVAR_RANGE: (f32, f32) = (-2.5, 2.5);
/// LeakyReLU slope (PyTorch's default).
pub(super) const LEAKY_SLOPE: f64 = 0.01;

/// Architecture of the policy (saved inside its weights file).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolicyArch {
    /// GRU width `H` (EgoGen: 512).
    pub hidden: usize,
    /// Positional-encoding frequencies `F` per scalar.
    pub pe_frequencies: usize,
    /// Residual blocks of the actor and critic MLPs (EgoGen: 2).
    pub residual_blocks: usize,
    /// Latent size of the motion model (the action size).
    pub latent_dim: usize,
    /// What the policy observes of its surroundings (files written before this field: the
    /// paper's 32 rays).
    #[serde(default)]
    pub sensing: SensingSpec,
}

impl Default for PolicyArch {
    fn default() -> Self {
        Self {
            hidden: 128,
            pe_frequencies: 8,
            residual_blocks: 2,
            latent_dim: 128,
            sensing: SensingSpec::default(),
        }
    }
}

/// Largest sizes a policy may have (a GRU of width 4 096 already holds about 0.4 G weights):
/// a config or a weights file's header asking for more is refused before anything is
/// allocated.
pub(crate) const MAX_HIDDEN: usize = 4096;
pub(crate) const MAX_PE_FREQUENCIES: usize = 64;
pub(crate) const MAX_RESIDUAL_BLOCKS: usize = 64;
pub(crate) const MAX_LATENT_DIM: usize = 4096;
pub(crate) const MAX_SENSING_DIM: usize = 65_536;

impl PolicyArch {
    /// What is wrong with the sizes, naming the field and its limit (`None`: usable).
    pub(crate) fn problem(&self) -> Option<String> {
        let sizes = [
            ("hidden", self.hidden, 1, MAX_HIDDEN),
            ("pe_frequencies", self.pe_frequencies, 0, MAX_PE_FREQUENCIES),
            (
                "residual_blocks",
                self.residual_blocks,
                0,
                MAX_RESIDUAL_BLOCKS,
            ),
            ("latent_dim", self.latent_dim, 1, MAX_LATENT_DIM),
            (
                "sensing values per frame",
                self.sensing.dim(),
                1,
                MAX_SENSING_DIM,
            ),
        ];
        sizes
            .iter()
            .find(|(_, v, lo, hi)| !(lo..=hi).contains(&v))
            .map(|(name, v, lo, hi)| format!("{name} = {v}: expected {lo}–{hi}"))
            .or_else(|| self.sensing.problem())
            .or_else(|| match self.sensing {
                SensingSpec::DepthImage(d)
                    if d.rows % DEPTH_CNN_STRIDE != 0 || d.cols % DEPTH_CNN_STRIDE != 0 =>
                {
                    Some(format!(
                        "the depth image's rows and cols must be multiples of \
                         {DEPTH_CNN_STRIDE} (its CNN's strides), got {} × {}",
                        d.rows, d.cols
                    ))
                }
                _ => None,
            })
    }

    /// Values per frame that the sensing GRU reads: the sensing itself, or the depth CNN's
    /// features.
    pub(crate) fn sensing_features(&self) -> usize {
        match self.sensing {
            SensingSpec::DepthImage(d) => {
                (d.rows / DEPTH_CNN_STRIDE) * (d.cols / DEPTH_CNN_STRIDE) * DEPTH_CNN[1].1
            }
            _ => self.sensing.dim(),
        }
    }

    /// The depth CNN's layers as `(inputs, outputs)` (none for other sensing).
    fn depth_cnn_layers(&self) -> Vec<(usize, usize)> {
        match self.sensing {
            SensingSpec::DepthImage(_) => {
                let mut channels = 1;
                DEPTH_CNN
                    .iter()
                    .map(|&(k, out)| {
                        let inputs = k * k * channels;
                        channels = out;
                        (inputs, out)
                    })
                    .collect()
            }
            _ => Vec::new(),
        }
    }

    /// Weights and biases of the network [`Self::init`] builds (two GRUs, the actor's and the
    /// critic's residual MLPs, a depth image's CNN).
    pub(crate) fn parameter_count(&self) -> f64 {
        let (h, w) = (self.hidden as f64, self.mlp_width() as f64);
        let gru = |inputs: f64| inputs * 3.0 * h + 3.0 * h + h * 3.0 * h + 3.0 * h;
        let mlp = |out: f64| self.residual_blocks as f64 * 2.0 * (w * w + w) + w * out + out;
        let cnn: f64 = self
            .depth_cnn_layers()
            .iter()
            .map(|&(i, o)| (i * o + o) as f64)
            .sum();
        gru(STATE_FRAME_DIM as f64)
            + gru(self.sensing_features() as f64)
            + mlp(2.0 * self.latent_dim as f64)
            + mlp(1.0)
            + cnn
    }

    /// Width `W` of the actor's and critic's MLPs.
    pub(crate) fn mlp_width(&self) -> usize {
        2 * self.hidden + 4 * self.pe_frequencies
    }

    pub fn init<B: Backend>(&self, device: &B::Device) -> ActorCritic<B> {
        let (h, w) = (self.hidden, self.mlp_width());
        let linear = |i, o| LinearConfig::new(i, o).init(device);
        let mlp = |out: usize, scale: f32| {
            let mut last: Linear<B> = linear(w, out);
            // New leaves that require gradients: a mapped tensor would be a node of the graph
            // that the optimiser never updates.
            last.weight = last
                .weight
                .map(|t| t.mul_scalar(scale).detach().require_grad());
            if let Some(b) = last.bias.take() {
                last.bias = Some(b.map(|t| t.zeros_like().detach().require_grad()));
            }
            ResidualMlp {
                blocks: (0..self.residual_blocks)
                    .map(|_| [linear(w, w), linear(w, w)])
                    .collect(),
                out: last,
            }
        };
        ActorCritic {
            state_gru: Gru::new(STATE_FRAME_DIM, h, device),
            ray_gru: Gru::new(self.sensing_features(), h, device),
            depth_cnn: match self.sensing {
                SensingSpec::DepthImage(d) => Some(DepthCnn {
                    layers: self
                        .depth_cnn_layers()
                        .into_iter()
                        .map(|(i, o)| linear(i, o))
                        .collect(),
                    rows: d.rows,
                    cols: d.cols,
                }),
                _ => None,
            },
            actor: mlp(2 * self.latent_dim, 0.01),
            critic: mlp(1, 1.0),
            pe_frequencies: self.pe_frequencies,
            latent_dim: self.latent_dim,
            sensing: self.sensing,
        }
    }
}

/// A single-layer GRU (PyTorch's equations) run over a short sequence.
#[derive(Module, Debug)]
pub(crate) struct Gru<B: Backend> {
    pub(super) input: Linear<B>,
    pub(super) hidden: Linear<B>,
}

impl<B: Backend> Gru<B> {
    fn new(inputs: usize, width: usize, device: &B::Device) -> Self {
        Self {
            input: LinearConfig::new(inputs, 3 * width).init(device),
            hidden: LinearConfig::new(width, 3 * width).init(device),
        }
    }

    /// Last hidden state `[B, H]` after the frames `[B, T, I]` (initial state zero).
    fn forward(&self, x: Tensor<B, 3>) -> Tensor<B, 2> {
        let [b, t, _] = x.dims();
        let w = self.hidden.weight.dims()[0];
        let mut h = Tensor::zeros([b, w], &x.device());
        for k in 0..t {
            let gx = self.input.forward(x.clone().narrow(1, k, 1).squeeze_dim(1));
            let gh = self.hidden.forward(h.clone());
            let r = sigmoid(gx.clone().narrow(1, 0, w) + gh.clone().narrow(1, 0, w));
            let z = sigmoid(gx.clone().narrow(1, w, w) + gh.clone().narrow(1, w, w));
            let n = (gx.narrow(1, 2 * w, w) + r * gh.narrow(1, 2 * w, w)).tanh();
            h = n.clone() + z * (h - n);
        }
        h
    }
}

/// The depth image's CNN ([`DEPTH_CNN`]): each convolution, its stride equal to its kernel, is
/// one linear layer applied to every patch (the patch's values row by row, channels innermost).
#[derive(Module, Debug)]
pub(crate) struct DepthCnn<B: Backend> {
    pub(super) layers: Vec<Linear<B>>,
    pub(super) rows: usize,
    pub(super) cols: usize,
}

impl<B: Backend> DepthCnn<B> {
    /// Features `[N, F]` of images `[N, rows·cols]` (row-major): the last layer's grid row by
    /// row, channels innermost.
    fn forward(&self, images: Tensor<B, 2>) -> Tensor<B, 2> {
        let n = images.dims()[0];
        let (mut rows, mut cols, mut channels) = (self.rows, self.cols, 1);
        let mut x = images.reshape([n, rows, cols, channels]);
        for (layer, &(k, out)) in self.layers.iter().zip(&DEPTH_CNN) {
            let y = leaky_relu(layer.forward(patches(x, k)), LEAKY_SLOPE);
            (rows, cols, channels) = (rows / k, cols / k, out);
            x = y.reshape([n, rows, cols, channels]);
        }
        x.reshape([n, rows * cols * channels])
    }
}

/// The `k × k` patches of a grid `[N, R, C, Ch]` as rows `[N·(R/k)·(C/k), k·k·Ch]`, in the
/// order of `(n, patch row, patch column)`, each patch's values row by row, channels
/// innermost.
fn patches<B: Backend>(x: Tensor<B, 4>, k: usize) -> Tensor<B, 2> {
    let [n, r, c, ch] = x.dims();
    x.reshape([n * r / k, k, c / k, k * ch])
        .swap_dims(1, 2)
        .reshape([n * (r / k) * (c / k), k * k * ch])
}

/// Residual blocks then a linear output layer.
#[derive(Module, Debug)]
pub(crate) struct ResidualMlp<B: Backend> {
    pub(super) blocks: Vec<[Linear<B>; 2]>,
    pub(super) out: Linear<B>,
}

impl<B: Backend> ResidualMlp<B> {
    fn forward(&self, mut h: Tensor<B, 2>) -> Tensor<B, 2> {
        for [a, b] in &self.blocks {
            let y = leaky_relu(a.forward(h.clone()), LEAKY_SLOPE);
            let y = leaky_relu(b.forward(y), LEAKY_SLOPE);
            h = h + y;
        }
        self.out.forward(h)
    }
}

/// The actor-critic.
#[derive(Module, Debug)]
pub struct ActorCritic<B: Backend> {
    pub(super) state_gru: Gru<B>,
    /// The sensing GRU, of whatever [`SensingSpec`] (its name is its weights' key).
    pub(super) ray_gru: Gru<B>,
    /// A depth image's encoder (only for [`SensingSpec::DepthImage`]).
    pub(super) depth_cnn: Option<DepthCnn<B>>,
    pub(super) actor: ResidualMlp<B>,
    critic: ResidualMlp<B>,
    pub(super) pe_frequencies: usize,
    latent_dim: usize,
    #[module(skip)]
    sensing: SensingSpec,
}

/// What the network says about a batch of observations.
#[derive(Debug, Clone)]
pub struct PolicyOutput<B: Backend> {
    /// `[B, L]`.
    pub mean: Tensor<B, 2>,
    /// `[B, L]`, clamped to [`LOGVAR_RANGE`].
    pub logvar: Tensor<B, 2>,
    /// `[B]`.
    pub value: Tensor<B, 1>,
}

impl<B: Backend> ActorCritic<B> {
    /// Sinusoidal encoding `[B, 2F]` of a column `[B, 1]`.
    fn encode(&self, x: Tensor<B, 2>) -> Tensor<B, 2> {
        let f = self.pe_frequencies;
        let freqs: Vec<f32> = (0..f)
            .map(|k| (2f32).powi(k as i32) * std::f32::consts::PI)
            .collect();
        let freqs =
            Tensor::<B, 1>::from_data(TensorData::new(freqs, [f]), &x.device()).unsqueeze_dim(0);
        let a = x * freqs;
        Tensor::cat(vec![a.clone().sin(), a.cos()], 1)
    }

    /// The joint features `[B, W]` of observations `[B, D]` ([`Self::obs_layout`]).
    fn features(&self, obs: Tensor<B, 2>) -> Tensor<B, 2> {
        let [b, d] = obs.dims();
        let layout = self.obs_layout();
        debug_assert_eq!(d, layout.dim());
        let s = layout.sensing_per_frame;
        let state = obs
            .clone()
            .narrow(1, 0, SEED_FRAMES * STATE_FRAME_DIM)
            .reshape([b, SEED_FRAMES, STATE_FRAME_DIM]);
        let sensing = obs
            .clone()
            .narrow(1, layout.sensing_offset(), SEED_FRAMES * s);
        let sensing = match &self.depth_cnn {
            Some(cnn) => {
                let features = cnn.forward(sensing.reshape([b * SEED_FRAMES, s]));
                let f = features.dims()[1];
                features.reshape([b, SEED_FRAMES, f])
            }
            None => sensing.reshape([b, SEED_FRAMES, s]),
        };
        let dist = obs.clone().narrow(1, layout.dist_offset(), 1);
        let time = obs.narrow(1, layout.dist_offset() + 1, 1);
        Tensor::cat(
            vec![
                self.state_gru.forward(state),
                self.ray_gru.forward(sensing),
                self.encode(dist),
                self.encode(time),
            ],
            1,
        )
    }

    pub fn forward(&self, obs: Tensor<B, 2>) -> PolicyOutput<B> {
        let h = self.features(obs);
        let value = self.critic.forward(h.clone()).squeeze_dim(1);
        let (mean, logvar) = self.actor_head(h);
        PolicyOutput {
            mean,
            logvar,
            value,
        }
    }

    /// The actor alone, `(mean, logvar)` `[B, L]` each: what acting needs, without the
    /// critic's value (as [`Self::forward`] computes them).
    pub(crate) fn actor_forward(&self, obs: Tensor<B, 2>) -> (Tensor<B, 2>, Tensor<B, 2>) {
        self.actor_head(self.features(obs))
    }

    fn actor_head(&self, h: Tensor<B, 2>) -> (Tensor<B, 2>, Tensor<B, 2>) {
        let l = self.latent_dim;
        let a = self.actor.forward(h);
        (
            a.clone().narrow(1, 0, l),
            a.narrow(1, l, l).clamp(LOGVAR_RANGE.0, LOGVAR_RANGE.1),
        )
    }

    /// Action size.
    pub fn latent_dim(&self) -> usize {
        self.latent_dim
    }

    /// What the policy observes of its surroundings.
    pub fn sensing(&self) -> SensingSpec {
        self.sensing
    }

    /// Where the parts of the policy's observations lie.
    pub fn obs_layout(&self) -> ObsLayout {
        ObsLayout::of(&self.sensing)
    }
}

/// `ln N(a; μ, diag exp(logvar))` per row `[B]`.
pub fn log_prob<B: Backend>(
    a: Tensor<B, 2>,
    mean: Tensor<B, 2>,
    logvar: Tensor<B, 2>,
) -> Tensor<B, 1> {
    let l = a.dims()[1] as f64;
    let z2 = (a - mean).square() / logvar.clone().exp();
    (z2 + logvar).sum_dim(1).squeeze_dim(1).mul_scalar(-0.5)
        - 0.5 * l * (std::f64::consts::TAU).ln()
}

/// Entropy of the diagonal Gaussian per row `[B]`.
pub(crate) fn entropy<B: Backend>(logvar: Tensor<B, 2>) -> Tensor<B, 1> {
    let l = logvar.dims()[1] as f64;
    logvar.sum_dim(1).squeeze_dim(1).mul_scalar(0.5) + 0.5 * l * (1.0 + std::f64::consts::TAU.ln())
}

/// KL(N(μ, σ²) ‖ N(0, I)) per row `[B]`.
pub fn kl_to_standard<B: Backend>(mean: Tensor<B, 2>, logvar: Tensor<B, 2>) -> Tensor<B, 1> {
    (logvar.clone().exp() + mean.square() - logvar - 1.0)
        .sum_dim(1)
        .squeeze_dim(1)
        .mul_scalar(0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::module::Module;

    #[test]
    fn the_parameter_count_is_what_init_builds() {
        type B = burn::backend::Flex;
        for arch in [
            PolicyArch::default(),
            PolicyArch {
                hidden: 7,
                pe_frequencies: 0,
                residual_blocks: 3,
                latent_dim: 5,
                sensing: SensingSpec::default(),
            },
            PolicyArch {
                hidden: 9,
                sensing: SensingSpec::DepthImage(Default::default()),
                ..PolicyArch::default()
            },
        ] {
            let net = arch.init::<B>(&Default::default());
            assert_eq!(arch.parameter_count(), net.num_params() as f64, "{arch:?}");
        }
    }
}
