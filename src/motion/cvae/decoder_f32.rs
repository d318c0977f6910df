//! The decoder of [`PrimitiveVae`](super::net::PrimitiveVae) for inference on the CPU in f32,
//! without burn: the same GRU-cell recursion as `PrimitiveVae::decode` over plain arrays, each
//! layer one `gemm` call on a block of primitives, no tensor allocated per operation.
//!
//! Inference decodes few primitives at a time (one per agent in a crowd, 256 in policy
//! training), where a tensor library's per-operation overhead costs more than the arithmetic:
//! see `cargo bench --bench primitive` (docs/MOTION.md) for the two side by side. Two things are
//! computed once per primitive instead of once per frame: the latent's and the floor's share of
//! the GRU's input gates (they do not change over the 18 frames). The results equal burn's to
//! float rounding (another summation order; `tests/primitive_model.rs` checks them).
//!
//! Blocks of [`BLOCK`] primitives run on all cores (rayon); a batch of one stays on one. A
//! primitive decodes the same alone or in a batch to float rounding, not bit for bit: the
//! matrix-product kernel, and so the summation order, depends on the block's size.

use gemm::Parallelism;
use rayon::prelude::*;
use wide::f32x8;

use super::features::FRAME_DIM;
use super::half_matvec::HalfMatrix;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};

/// Frames written per primitive (the network's `DECODED_FRAMES`).
const DECODED_FRAMES: usize = PRIMITIVE_FRAMES - SEED_FRAMES;

/// Primitives decoded together by one thread.
pub(crate) const BLOCK: usize = 32;

/// A dense layer `y = x · weight + bias`, `weight` `[inputs × outputs]` row-major (burn's
/// `Linear` layout).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct DenseLayer {
    pub inputs: usize,
    pub outputs: usize,
    pub weight: Vec<f32>,
    pub bias: Vec<f32>,
}

impl DenseLayer {
    fn check(&self, name: &str, inputs: usize, outputs: usize) -> Result<(), String> {
        if self.inputs != inputs
            || self.outputs != outputs
            || self.weight.len() != inputs * outputs
            || self.bias.len() != outputs
        {
            return Err(format!(
                "decoder layer {name}: {} × {} ({} weights, {} biases), expected {inputs} × \
                 {outputs}",
                self.inputs,
                self.outputs,
                self.weight.len(),
                self.bias.len()
            ));
        }
        Ok(())
    }

    /// `weight` rows `rows` (one block of the layer's inputs).
    fn rows(&self, rows: std::ops::Range<usize>) -> &[f32] {
        &self.weight[rows.start * self.outputs..rows.end * self.outputs]
    }
}

/// The decoder's parameters, as [`PrimitiveVae`](super::net::PrimitiveVae) holds them.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct DecoderF32 {
    latent: usize,
    hidden: usize,
    feature_mean: Vec<f32>,
    feature_std: Vec<f32>,
    floor_mean_std: [f32; 2],
    /// `[z, seed frames, floor] → h₀`.
    init: DenseLayer,
    /// `[z, previous frame, velocity, floor] → input gates (r, u, n)`.
    gru_input: DenseLayer,
    /// `h → hidden gates (r, u, n)`.
    gru_hidden: DenseLayer,
    /// `h → velocity` (the residual added to the previous frame).
    out: DenseLayer,
    /// The per-frame products in f16 for a primitive decoded alone, where this processor has
    /// the instructions ([`HalfMatrix::supported`]).
    half: Option<HalfLayers>,
}

/// The decoder's weights in f16: the initial state's layer and the latent's rows of the input
/// gates (read once per primitive), and those every GRU step reads: the frame and velocity
/// rows of the input gates, the hidden gates, the output layer.
#[derive(Debug, Clone, PartialEq)]
struct HalfLayers {
    init: HalfMatrix,
    latent_rows: HalfMatrix,
    frame_rows: HalfMatrix,
    gru_hidden: HalfMatrix,
    out: HalfMatrix,
}

impl DecoderF32 {
    /// Builds the decoder from the network's arrays; the error names the first layer whose
    /// shape does not fit the others.
    pub(crate) fn new(
        feature_mean: Vec<f32>,
        feature_std: Vec<f32>,
        floor_mean_std: [f32; 2],
        [init, gru_input, gru_hidden, out]: [DenseLayer; 4],
    ) -> Result<Self, String> {
        let hidden = gru_hidden.inputs;
        let latent = init.inputs.saturating_sub(SEED_FRAMES * FRAME_DIM + 1);
        if feature_mean.len() != FRAME_DIM || feature_std.len() != FRAME_DIM {
            return Err(format!(
                "feature statistics: {} means and {} spreads, expected {FRAME_DIM}",
                feature_mean.len(),
                feature_std.len()
            ));
        }
        init.check("dec_init", latent + SEED_FRAMES * FRAME_DIM + 1, hidden)?;
        gru_input.check("gru_input", latent + 2 * FRAME_DIM + 1, 3 * hidden)?;
        gru_hidden.check("gru_hidden", hidden, 3 * hidden)?;
        out.check("dec_out", hidden, FRAME_DIM)?;
        let half = HalfMatrix::supported().then(|| {
            let (l, f) = (latent, FRAME_DIM);
            HalfLayers {
                init: HalfMatrix::new(init.inputs, hidden, &init.weight),
                latent_rows: HalfMatrix::new(l, 3 * hidden, gru_input.rows(0..l)),
                frame_rows: HalfMatrix::new(2 * f, 3 * hidden, gru_input.rows(l..l + 2 * f)),
                gru_hidden: HalfMatrix::new(hidden, 3 * hidden, &gru_hidden.weight),
                out: HalfMatrix::new(hidden, f, &out.weight),
            }
        });
        Ok(Self {
            latent,
            hidden,
            feature_mean,
            feature_std,
            floor_mean_std,
            init,
            gru_input,
            gru_hidden,
            out,
            half,
        })
    }

    /// The decoder without its f16 path: every batch size decodes in f32 (the reference the
    /// f16 path is measured against).
    pub(crate) fn without_half_precision(mut self) -> Self {
        self.half = None;
        self
    }

    /// Whether a primitive decoded alone reads its weights in f16.
    #[cfg(test)]
    pub(crate) fn half_precision_weights(&self) -> bool {
        self.half.is_some()
    }

    /// Raw canonical seed features `[B × 2 × F]`, canonical floor heights `[B]` (m) and latents
    /// `[B × L]` → raw canonical features of all 20 frames `[B × 20 × F]` (the seed first), as
    /// `net::decode_raw` computes them.
    ///
    /// # Panics
    /// When the slices' lengths disagree with `B = floors.len()` (a caller's bug).
    pub(crate) fn decode(&self, seeds: &[f32], floors: &[f32], latents: &[f32]) -> Vec<f32> {
        let b = floors.len();
        let (l, f) = (self.latent, FRAME_DIM);
        assert_eq!(
            seeds.len(),
            b * SEED_FRAMES * f,
            "seed features of {b} primitives"
        );
        assert_eq!(latents.len(), b * l, "latents of {b} primitives");
        let per = PRIMITIVE_FRAMES * f;
        let mut out = vec![0.0f32; b * per];
        // A primitive decoded alone reads the weights in f16 (half the bytes; see
        // `half_matvec`), a batch in f32 through `gemm`.
        let half = self.half.as_ref().filter(|_| b == 1);
        out.par_chunks_mut(BLOCK * per)
            .enumerate()
            .for_each(|(k, block)| {
                let start = k * BLOCK;
                let n = block.len() / per;
                self.decode_block(
                    &seeds[start * SEED_FRAMES * f..(start + n) * SEED_FRAMES * f],
                    &floors[start..start + n],
                    &latents[start * l..(start + n) * l],
                    block,
                    half,
                );
            });
        out
    }

    /// One block of `n` primitives on this thread.
    fn decode_block(
        &self,
        seeds: &[f32],
        floors: &[f32],
        latents: &[f32],
        out: &mut [f32],
        half: Option<&HalfLayers>,
    ) {
        let n = floors.len();
        let (l, f, h) = (self.latent, FRAME_DIM, self.hidden);
        let sf = SEED_FRAMES * f;
        let normal_floor: Vec<f32> = floors
            .iter()
            .map(|v| (v - self.floor_mean_std[0]) / self.floor_mean_std[1])
            .collect();
        // h₀ = tanh([z, normalised seed, floor] · W + b).
        let mut x = vec![0.0f32; n * self.init.inputs];
        for i in 0..n {
            let row = &mut x[i * self.init.inputs..(i + 1) * self.init.inputs];
            row[..l].copy_from_slice(&latents[i * l..(i + 1) * l]);
            for (j, v) in row[l..l + sf].iter_mut().enumerate() {
                let k = j % f;
                *v = (seeds[i * sf + j] - self.feature_mean[k]) / self.feature_std[k];
            }
            row[l + sf] = normal_floor[i];
        }
        let mut state = with_bias(n, &self.init.bias);
        // The latent's and the floor's share of the input gates, fixed over the frames.
        let mut fixed_gates = with_bias(n, &self.gru_input.bias);
        match half {
            Some(w) => {
                w.init.mul_add(&x, &mut state);
                w.latent_rows.mul_add(latents, &mut fixed_gates);
            }
            None => {
                matmul_add(n, self.init.inputs, h, &x, &self.init.weight, &mut state);
                matmul_add(
                    n,
                    l,
                    3 * h,
                    latents,
                    self.gru_input.rows(0..l),
                    &mut fixed_gates,
                );
            }
        }
        tanh_in_place(&mut state);
        let floor_row = self.gru_input.rows(l + 2 * f..l + 2 * f + 1);
        for i in 0..n {
            let row = &mut fixed_gates[i * 3 * h..(i + 1) * 3 * h];
            for (v, w) in row.iter_mut().zip(floor_row) {
                *v += normal_floor[i] * w;
            }
        }
        // [previous frame, velocity], normalised: the seed's last frame and its last step.
        let mut frame_velocity = vec![0.0f32; n * 2 * f];
        for i in 0..n {
            let seed = &x[i * self.init.inputs + l..i * self.init.inputs + l + sf];
            let row = &mut frame_velocity[i * 2 * f..(i + 1) * 2 * f];
            for k in 0..f {
                row[k] = seed[f + k];
                row[f + k] = seed[f + k] - seed[k];
            }
        }
        let frame_rows = self.gru_input.rows(l..l + 2 * f);
        let per = PRIMITIVE_FRAMES * f;
        for i in 0..n {
            out[i * per..i * per + sf].copy_from_slice(&seeds[i * sf..(i + 1) * sf]);
        }
        let mut input_gates = vec![0.0f32; n * 3 * h];
        let mut hidden_gates = vec![0.0f32; n * 3 * h];
        let mut velocity = vec![0.0f32; n * f];
        for t in 0..DECODED_FRAMES {
            input_gates.copy_from_slice(&fixed_gates);
            fill_bias(&mut hidden_gates, &self.gru_hidden.bias);
            if let Some(w) = half {
                w.frame_rows.mul_add(&frame_velocity, &mut input_gates);
                w.gru_hidden.mul_add(&state, &mut hidden_gates);
            } else {
                matmul_add(
                    n,
                    2 * f,
                    3 * h,
                    &frame_velocity,
                    frame_rows,
                    &mut input_gates,
                );
                matmul_add(
                    n,
                    h,
                    3 * h,
                    &state,
                    &self.gru_hidden.weight,
                    &mut hidden_gates,
                );
            }
            for i in 0..n {
                gru_cell(
                    &input_gates[i * 3 * h..(i + 1) * 3 * h],
                    &hidden_gates[i * 3 * h..(i + 1) * 3 * h],
                    &mut state[i * h..(i + 1) * h],
                );
            }
            fill_bias(&mut velocity, &self.out.bias);
            match half {
                Some(w) => w.out.mul_add(&state, &mut velocity),
                None => matmul_add(n, h, f, &state, &self.out.weight, &mut velocity),
            }
            for i in 0..n {
                let row = &mut frame_velocity[i * 2 * f..(i + 1) * 2 * f];
                let v = &velocity[i * f..(i + 1) * f];
                let frame = &mut out[i * per + sf + t * f..i * per + sf + (t + 1) * f];
                for k in 0..f {
                    row[k] += v[k];
                    row[f + k] = v[k];
                    frame[k] = row[k] * self.feature_std[k] + self.feature_mean[k];
                }
            }
        }
    }
}

/// One GRU cell update of a hidden state `s` `[H]` from its input and hidden gates `[3H]`
/// (reset, update, new; the hidden gates with their bias): `r = σ(x_r + h_r)`,
/// `u = σ(x_u + h_u)`, `c = tanh(x_n + r·h_n)`, `s ← c + u·(s − c)`. Eight values at a time.
fn gru_cell(gx: &[f32], gh: &[f32], s: &mut [f32]) {
    let h = s.len();
    let lanes = |v: &[f32], at: usize| f32x8::from(<[f32; 8]>::try_from(&v[at..at + 8]).unwrap());
    let sigmoid = |x: f32x8| f32x8::ONE / (f32x8::ONE + (-x).exp());
    let mut j = 0;
    while j + 8 <= h {
        let r = sigmoid(lanes(gx, j) + lanes(gh, j));
        let u = sigmoid(lanes(gx, h + j) + lanes(gh, h + j));
        let c = (lanes(gx, 2 * h + j) + r * lanes(gh, 2 * h + j)).tanh();
        let new = c + u * (lanes(s, j) - c);
        s[j..j + 8].copy_from_slice(&new.to_array());
        j += 8;
    }
    for j in j..h {
        let sigmoid = |x: f32| 1.0 / (1.0 + (-x).exp());
        let r = sigmoid(gx[j] + gh[j]);
        let u = sigmoid(gx[h + j] + gh[h + j]);
        let c = (gx[2 * h + j] + r * gh[2 * h + j]).tanh();
        s[j] = c + u * (s[j] - c);
    }
}

fn tanh_in_place(v: &mut [f32]) {
    let mut chunks = v.chunks_exact_mut(8);
    for c in &mut chunks {
        let t = f32x8::from(<[f32; 8]>::try_from(&*c).unwrap()).tanh();
        c.copy_from_slice(&t.to_array());
    }
    chunks
        .into_remainder()
        .iter_mut()
        .for_each(|x| *x = x.tanh());
}

/// `n` rows of `bias`.
fn with_bias(n: usize, bias: &[f32]) -> Vec<f32> {
    let mut v = vec![0.0; n * bias.len()];
    fill_bias(&mut v, bias);
    v
}

fn fill_bias(rows: &mut [f32], bias: &[f32]) {
    for row in rows.chunks_exact_mut(bias.len()) {
        row.copy_from_slice(bias);
    }
}

/// `y[m × n] += x[m × k] · w[k × n]`, all row-major and contiguous.
fn matmul_add(m: usize, k: usize, n: usize, x: &[f32], w: &[f32], y: &mut [f32]) {
    assert!(x.len() == m * k && w.len() == k * n && y.len() == m * n);
    if m == 0 || n == 0 || k == 0 {
        return;
    }
    // SAFETY: the three slices hold exactly the m × k, k × n and m × n row-major matrices the
    // strides describe (checked above), and `y` is borrowed mutably, so it overlaps neither.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            y.as_mut_ptr(),
            1,
            n as isize,
            true,
            x.as_ptr(),
            1,
            k as isize,
            w.as_ptr(),
            1,
            n as isize,
            1.0f32,
            1.0f32,
            false,
            false,
            false,
            Parallelism::None,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_matrix_product_adds_to_what_is_there() {
        // [1 2; 3 4] · [1 0 2; 0 1 1] added to ones.
        let mut y = vec![1.0f32; 6];
        matmul_add(
            2,
            2,
            3,
            &[1.0, 2.0, 3.0, 4.0],
            &[1.0, 0.0, 2.0, 0.0, 1.0, 1.0],
            &mut y,
        );
        assert_eq!(y, vec![2.0, 3.0, 5.0, 4.0, 5.0, 11.0]);
    }

    #[test]
    fn the_cell_matches_the_gru_formula_in_every_lane_and_the_remainder() {
        // H = 11: one block of eight lanes and three values after it.
        let h = 11;
        let gx: Vec<f32> = (0..3 * h).map(|k| (k as f32 * 0.37).sin() * 3.0).collect();
        let gh: Vec<f32> = (0..3 * h).map(|k| (k as f32 * 0.91).cos() * 4.0).collect();
        let before: Vec<f32> = (0..h).map(|k| (k as f32 * 0.5).sin()).collect();
        let mut s = before.clone();
        gru_cell(&gx, &gh, &mut s);
        let sigmoid = |x: f64| 1.0 / (1.0 + (-x).exp());
        for j in 0..h {
            let (x, g) = (|k: usize| gx[k] as f64, |k: usize| gh[k] as f64);
            let r = sigmoid(x(j) + g(j));
            let u = sigmoid(x(h + j) + g(h + j));
            let c = (x(2 * h + j) + r * g(2 * h + j)).tanh();
            let want = c + u * (before[j] as f64 - c);
            assert!(
                (s[j] as f64 - want).abs() < 1e-6,
                "{j}: {} against {want}",
                s[j]
            );
        }
        // tanh at its extremes: saturated, tiny, zero.
        let mut v = vec![-30.0, -9.5, -1e-5, 0.0, 1e-5, 0.5, 9.5, 30.0, 2.0];
        tanh_in_place(&mut v);
        for (got, x) in v
            .iter()
            .zip([-30.0f64, -9.5, -1e-5, 0.0, 1e-5, 0.5, 9.5, 30.0, 2.0])
        {
            assert!((*got as f64 - x.tanh()).abs() < 1e-6, "tanh({x}) = {got}");
        }
    }

    #[test]
    fn a_layer_of_the_wrong_shape_is_named() {
        let layer = |i: usize, o: usize| DenseLayer {
            inputs: i,
            outputs: o,
            weight: vec![0.0; i * o],
            bias: vec![0.0; o],
        };
        let (l, h, f) = (4, 8, FRAME_DIM);
        let ok = [
            layer(l + 2 * f + 1, h),
            layer(l + 2 * f + 1, 3 * h),
            layer(h, 3 * h),
            layer(h, f),
        ];
        let stats = || (vec![0.0; f], vec![1.0; f]);
        let (m, s) = stats();
        assert!(DecoderF32::new(m, s, [0.0, 1.0], ok.clone()).is_ok());
        let mut bad = ok;
        bad[3] = layer(h, f + 1);
        let (m, s) = stats();
        let err = DecoderF32::new(m, s, [0.0, 1.0], bad).unwrap_err();
        assert!(err.contains("dec_out"), "{err}");
    }
}
