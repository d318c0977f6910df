//! The policy's actor for acting on the CPU in f32, without burn: the same layers as
//! [`ActorCritic::actor_forward`] over plain arrays, and bit for bit its results.
//!
//! Acting asks for one agent's action at a time (`egogen synth` steps its people in turn, paper
//! Alg. 1), where a tensor library's cost per operation — a tensor allocated, copied and freed
//! for each of some fifty operations — outweighs the arithmetic. Each dense layer of a batch is
//! the very `gemm` call burn's Flex backend makes for it (the same sizes, strides and threading),
//! and every element-wise step the same f32 operation in the same order (its sigmoid, tanh,
//! LeakyReLU, clamp, sin and cos), so the actions equal burn's exactly (`tests/policy_training.rs`
//! compares them); `cargo bench --bench synth` shows the two side by side. Training keeps burn.
//!
//! One observation at a time (what acting asks for) takes two shortcuts with the same bits:
//! its products run on weights packed for a single row ([`super::row_product`], `gemm`'s own
//! order for one row), the GRUs' input gates of both seed frames in one pass over the weights;
//! and a GRU's first hidden gates, the product of a zero state, are its bias.

use burn::nn::Linear;
use burn::prelude::*;
use rand_chacha::ChaCha8Rng;

use super::net::{ActorCritic, Gru, DEPTH_CNN, LEAKY_SLOPE, LOGVAR_RANGE};
use super::row_product::RowMatrix;
use crate::math::random::normal_samples;
use crate::motion::primitive::SEED_FRAMES;
use crate::sensing::SensingSpec;
use crate::walker::{ObsLayout, STATE_FRAME_DIM};

/// burn Flex's threshold (`m · n · k`) above which a product runs on all cores.
const PARALLEL_OPS: usize = 192 * 192 * 192;

/// A dense layer `y = x · weight + bias`, `weight` `[inputs × outputs]` row-major (burn's
/// `Linear` layout).
#[derive(Debug, Clone)]
struct Dense {
    inputs: usize,
    outputs: usize,
    weight: Vec<f32>,
    bias: Vec<f32>,
    /// The weights packed for one observation's products, where this processor has the
    /// instructions ([`RowMatrix::supported`]).
    rows: Option<RowMatrix>,
}

impl Dense {
    fn of<B: Backend>(l: &Linear<B>) -> Self {
        let [inputs, outputs] = l.weight.dims();
        let weight = l.weight.val().into_data().to_vec().expect("f32 weights");
        let bias = match &l.bias {
            Some(b) => b.val().into_data().to_vec().expect("f32 bias"),
            None => vec![0.0; outputs],
        };
        let rows = (RowMatrix::supported() && inputs > 0)
            .then(|| RowMatrix::new(inputs, outputs, &weight));
        Self {
            inputs,
            outputs,
            weight,
            bias,
            rows,
        }
    }

    /// `[m × outputs]` from `m` input rows `row_stride` apart in `x`.
    fn forward(&self, m: usize, x: &[f32], row_stride: usize) -> Vec<f32> {
        let (n, k) = (self.outputs, self.inputs);
        assert!(
            m == 0 || x.len() >= (m - 1) * row_stride + k,
            "{m} input rows of {k}"
        );
        if let (1, Some(rows)) = (m, &self.rows) {
            let mut y = vec![0.0f32; n];
            rows.products([&x[..k]], [&mut y[..]]);
            self.add_bias(&mut y);
            return y;
        }
        let mut y = vec![0.0f32; m * n];
        if m == 0 {
            return y;
        }
        let parallelism = if m * n * k >= PARALLEL_OPS {
            gemm::Parallelism::Rayon(0)
        } else {
            gemm::Parallelism::None
        };
        // SAFETY: `y` holds `m × n` values written with row stride `n`; `x` holds `m` rows of
        // `k` (checked above) with row stride `row_stride`; the weight is `k × n` row-major.
        // `read_dst` is false, so `y` is only written.
        unsafe {
            gemm::gemm(
                m,
                n,
                k,
                y.as_mut_ptr(),
                1,
                n as isize,
                false,
                x.as_ptr(),
                1,
                row_stride as isize,
                self.weight.as_ptr(),
                1,
                n as isize,
                0.0,
                1.0,
                false,
                false,
                false,
                parallelism,
            );
        }
        self.add_bias(&mut y);
        y
    }

    /// The outputs of one observation's `count` rows `step` apart in `x` (a GRU's frames),
    /// `[count][outputs]`: two at a time with the weights read once where they are packed.
    fn forward_frames(&self, x: &[f32], step: usize, count: usize) -> Vec<Vec<f32>> {
        let k = self.inputs;
        let Some(rows) = &self.rows else {
            return (0..count)
                .map(|t| self.forward(1, &x[t * step..], step))
                .collect();
        };
        assert!(
            count == 0 || x.len() >= (count - 1) * step + k,
            "{count} frames of {k}"
        );
        let mut out = vec![vec![0.0f32; self.outputs]; count];
        for (pair, ys) in out.chunks_mut(2).enumerate() {
            let row = |t: usize| &x[t * step..t * step + k];
            match ys {
                [a, b] => rows.products([row(2 * pair), row(2 * pair + 1)], [a, b]),
                [a] => rows.products([row(2 * pair)], [a]),
                _ => unreachable!("chunks of one or two"),
            }
        }
        for y in &mut out {
            self.add_bias(y);
        }
        out
    }

    /// `m` rows of the bias alone: what a product of zeros gives (`+0 + b`, the same bits).
    fn bias_rows(&self, m: usize) -> Vec<f32> {
        let mut y = vec![0.0f32; m * self.outputs];
        self.add_bias(&mut y);
        y
    }

    fn add_bias(&self, y: &mut [f32]) {
        for row in y.chunks_mut(self.outputs) {
            for (v, b) in row.iter_mut().zip(&self.bias) {
                *v += b;
            }
        }
    }
}

/// A single-layer GRU (PyTorch's equations).
#[derive(Debug, Clone)]
struct GruF32 {
    input: Dense,
    hidden: Dense,
}

impl GruF32 {
    fn of<B: Backend>(g: &Gru<B>) -> Self {
        Self {
            input: Dense::of(&g.input),
            hidden: Dense::of(&g.hidden),
        }
    }

    /// Last hidden state `[m × H]` after `frames` frames of `per_frame` values each, frame `t`
    /// of row `i` at `x[i·row_stride + t·per_frame ..]`.
    fn forward(
        &self,
        m: usize,
        x: &[f32],
        row_stride: usize,
        frames: usize,
        per_frame: usize,
    ) -> Vec<f32> {
        let w = self.hidden.inputs;
        let input_gates: Vec<Vec<f32>> = if m == 1 {
            self.input.forward_frames(x, per_frame, frames)
        } else {
            (0..frames)
                .map(|t| self.input.forward(m, &x[t * per_frame..], row_stride))
                .collect()
        };
        let mut h = vec![0.0f32; m * w];
        for (t, gx) in input_gates.iter().enumerate() {
            // The state starts at zero, so its first gates are the bias alone.
            let gh = if t == 0 {
                self.hidden.bias_rows(m)
            } else {
                self.hidden.forward(m, &h, w)
            };
            for i in 0..m {
                let (gx, gh) = (
                    &gx[i * 3 * w..(i + 1) * 3 * w],
                    &gh[i * 3 * w..(i + 1) * 3 * w],
                );
                for (j, h) in h[i * w..(i + 1) * w].iter_mut().enumerate() {
                    let r = sigmoid(gx[j] + gh[j]);
                    let z = sigmoid(gx[w + j] + gh[w + j]);
                    let n = (gx[2 * w + j] + r * gh[2 * w + j]).tanh();
                    *h = n + z * (*h - n);
                }
            }
        }
        h
    }
}

/// A depth image's CNN ([`super::net::DepthCnn`]) in plain f32 arrays.
#[derive(Debug, Clone)]
struct DepthCnnF32 {
    layers: Vec<Dense>,
    rows: usize,
    cols: usize,
}

impl DepthCnnF32 {
    /// Features `[n × F]` of `n` images, image `j` at `x[j·stride ..]` (row-major).
    fn forward(&self, n: usize, x: &[f32], stride: usize) -> Vec<f32> {
        let (mut rows, mut cols, mut channels) = (self.rows, self.cols, 1);
        let mut grid = Vec::with_capacity(n * rows * cols);
        for j in 0..n {
            grid.extend_from_slice(&x[j * stride..j * stride + rows * cols]);
        }
        for (layer, &(k, out)) in self.layers.iter().zip(&DEPTH_CNN) {
            let p = patches(&grid, n, rows, cols, channels, k);
            grid = layer.forward(p.len() / layer.inputs, &p, layer.inputs);
            leaky(&mut grid);
            (rows, cols, channels) = (rows / k, cols / k, out);
        }
        grid
    }
}

/// The `k × k` patches of `n` grids `[R, C, Ch]` as rows of `k·k·Ch`, in the order of `(n,
/// patch row, patch column)`, each patch's values row by row, channels innermost (as
/// [`super::net`]'s `patches`).
fn patches(x: &[f32], n: usize, r: usize, c: usize, ch: usize, k: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity(x.len());
    for j in 0..n {
        for pr in 0..r / k {
            for pc in 0..c / k {
                for dy in 0..k {
                    let at = ((j * r + pr * k + dy) * c + pc * k) * ch;
                    out.extend_from_slice(&x[at..at + k * ch]);
                }
            }
        }
    }
    out
}

/// LeakyReLU in place, as burn's.
fn leaky(v: &mut [f32]) {
    let slope = LEAKY_SLOPE as f32;
    for x in v.iter_mut() {
        if *x < 0.0 {
            *x *= slope;
        }
    }
}

/// The actor of a policy network in plain f32 arrays.
#[derive(Debug, Clone)]
pub struct Actor {
    state_gru: GruF32,
    ray_gru: GruF32,
    depth_cnn: Option<DepthCnnF32>,
    blocks: Vec<[Dense; 2]>,
    out: Dense,
    pe_frequencies: usize,
    latent_dim: usize,
    sensing: SensingSpec,
}

impl Actor {
    /// The actor's weights, copied out of a network.
    pub fn of<B: Backend>(net: &ActorCritic<B>) -> Self {
        Self {
            state_gru: GruF32::of(&net.state_gru),
            ray_gru: GruF32::of(&net.ray_gru),
            depth_cnn: net.depth_cnn.as_ref().map(|cnn| DepthCnnF32 {
                layers: cnn.layers.iter().map(Dense::of).collect(),
                rows: cnn.rows,
                cols: cnn.cols,
            }),
            blocks: net
                .actor
                .blocks
                .iter()
                .map(|[a, b]| [Dense::of(a), Dense::of(b)])
                .collect(),
            out: Dense::of(&net.actor.out),
            pe_frequencies: net.pe_frequencies,
            latent_dim: net.latent_dim(),
            sensing: net.sensing(),
        }
    }

    /// Action size.
    pub fn latent_dim(&self) -> usize {
        self.latent_dim
    }

    /// What the policy observes of its surroundings.
    pub(crate) fn sensing(&self) -> SensingSpec {
        self.sensing
    }

    /// Where the parts of the policy's observations lie.
    pub fn obs_layout(&self) -> ObsLayout {
        ObsLayout::of(&self.sensing)
    }

    /// `(mean, logvar)` `[B × L]` each for observations `[B × D]`, as
    /// [`ActorCritic::actor_forward`] computes them.
    ///
    /// # Panics
    /// When `obs.len()` is not a multiple of the observation size (a caller's bug).
    pub(crate) fn forward(&self, obs: &[f32]) -> (Vec<f32>, Vec<f32>) {
        let layout = self.obs_layout();
        let d = layout.dim();
        assert_eq!(obs.len() % d, 0, "observations of {d} values");
        let m = obs.len() / d;
        let (f, l) = (self.pe_frequencies, self.latent_dim);
        let s = layout.sensing_per_frame;
        let state = self
            .state_gru
            .forward(m, obs, d, SEED_FRAMES, STATE_FRAME_DIM);
        let rays = match &self.depth_cnn {
            Some(cnn) => {
                // Each seed frame's image; image `i·T + t` is row i's frame t.
                let images: Vec<f32> = (0..m)
                    .flat_map(|i| {
                        let at = i * d + layout.sensing_offset();
                        obs[at..at + SEED_FRAMES * s].iter().copied()
                    })
                    .collect();
                let features = cnn.forward(m * SEED_FRAMES, &images, s);
                let per_frame = features.len() / (m * SEED_FRAMES).max(1);
                self.ray_gru.forward(
                    m,
                    &features,
                    SEED_FRAMES * per_frame,
                    SEED_FRAMES,
                    per_frame,
                )
            }
            None => self
                .ray_gru
                .forward(m, &obs[layout.sensing_offset()..], d, SEED_FRAMES, s),
        };
        let hs = self.state_gru.hidden.inputs;
        let hr = self.ray_gru.hidden.inputs;
        let width = hs + hr + 4 * f;
        let freqs: Vec<f32> = (0..f)
            .map(|k| (2f32).powi(k as i32) * std::f32::consts::PI)
            .collect();
        let mut h = Vec::with_capacity(m * width);
        for i in 0..m {
            h.extend_from_slice(&state[i * hs..(i + 1) * hs]);
            h.extend_from_slice(&rays[i * hr..(i + 1) * hr]);
            for x in [
                obs[i * d + layout.dist_offset()],
                obs[i * d + layout.dist_offset() + 1],
            ] {
                h.extend(freqs.iter().map(|q| (x * q).sin()));
                h.extend(freqs.iter().map(|q| (x * q).cos()));
            }
        }
        for [a, b] in &self.blocks {
            let mut y = a.forward(m, &h, width);
            leaky(&mut y);
            let mut y = b.forward(m, &y, width);
            leaky(&mut y);
            for (h, y) in h.iter_mut().zip(&y) {
                *h += y;
            }
        }
        let a = self.out.forward(m, &h, width);
        let mut mean = Vec::with_capacity(m * l);
        let mut logvar = Vec::with_capacity(m * l);
        for row in a.chunks(2 * l) {
            mean.extend_from_slice(&row[..l]);
            logvar.extend(
                row[l..]
                    .iter()
                    .map(|v| v.clamp(LOGVAR_RANGE.0, LOGVAR_RANGE.1)),
            );
        }
        (mean, logvar)
    }

    /// Actions `[B × L]` for observations `[B × D]`: `mean + exp(logvar / 2) · ε` with ε drawn
    /// from `rng`, or the mean without one (as [`super::ppo::actions`]).
    pub fn actions(&self, obs: &[f32], rng: Option<&mut ChaCha8Rng>) -> Vec<f32> {
        self.actions_with_spread(obs, rng, 1.0)
    }

    /// [`Self::actions`] with the standard deviation scaled by `spread`:
    /// `mean + (exp(logvar / 2) · spread) · ε` (1 draws as trained, bit for bit; 0 gives the
    /// mean, though it still draws ε from `rng`).
    pub fn actions_with_spread(
        &self,
        obs: &[f32],
        rng: Option<&mut ChaCha8Rng>,
        spread: f32,
    ) -> Vec<f32> {
        let (mean, logvar) = self.forward(obs);
        match rng {
            Some(rng) => {
                let eps = normal_samples(rng, mean.len());
                mean.iter()
                    .zip(&logvar)
                    .zip(&eps)
                    .map(|((m, lv), e)| m + (lv * 0.5).exp() * spread * e)
                    .collect()
            }
            None => mean,
        }
    }

    /// The action distribution for one observation: `(mean, standard deviation)`, `[L]` each
    /// (as [`super::ppo::action_distribution`]).
    pub fn distribution(&self, obs: &[f32]) -> (Vec<f32>, Vec<f32>) {
        let (mean, logvar) = self.forward(obs);
        let std = logvar.iter().map(|lv| (lv * 0.5).exp()).collect();
        (mean, std)
    }
}

impl crate::walker::Policy for Actor {
    fn obs_dim(&self) -> usize {
        self.obs_layout().dim()
    }

    fn distribution(&self, obs: &[f32]) -> (Vec<f32>, Vec<f32>) {
        Actor::distribution(self, obs)
    }
}

/// burn Flex's sigmoid.
#[inline]
fn sigmoid(x: f32) -> f32 {
    if x >= 0.0 {
        1.0 / (1.0 + (-x).exp())
    } else {
        let e = x.exp();
        e / (1.0 + e)
    }
}
