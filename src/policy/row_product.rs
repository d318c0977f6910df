//! The acting actor's dense products for one observation, `y = x · W` with `W` `[inputs ×
//! outputs]` row-major (burn's `Linear` layout), bit for bit as `gemm` computes them for a
//! single row: each output is `x₀·w₀` followed by one fused multiply-add per input, inputs in
//! order (`gemm`'s matrix–vector path for `m = 1`).
//!
//! `gemm` runs that path a column of eight outputs at a time and loads and stores every output
//! once per input; here the weights are packed 64 outputs at a time, each tile's outputs
//! stay in registers over all the inputs, and two rows that share the weights (a GRU's input
//! gates for both seed frames) read them once. The same operations in the same order per
//! output, so the same bits with fewer instructions and fewer bytes read
//! (`cargo bench --bench synth -- synth_step_parts`).
//!
//! Only on x86-64 with AVX2 and FMA ([`RowMatrix::supported`]); elsewhere the actor keeps
//! calling `gemm`.

/// Output columns per tile.
const TILE: usize = 64;

/// A `[inputs × outputs]` f32 weight matrix packed tile by tile: for each tile of 64
/// output columns, the inputs' rows of that tile one after another. Columns past `outputs` are
/// zero.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RowMatrix {
    inputs: usize,
    outputs: usize,
    /// `[tiles × inputs × TILE]`.
    packed: Vec<f32>,
}

impl RowMatrix {
    /// Whether this processor runs the packed products (x86-64 with AVX2 and FMA).
    pub(crate) fn supported() -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// Packs a row-major `[inputs × outputs]` matrix.
    ///
    /// # Panics
    /// When `weight` does not hold `inputs × outputs` values, or `inputs` is 0 (a caller's bug).
    pub(crate) fn new(inputs: usize, outputs: usize, weight: &[f32]) -> Self {
        assert_eq!(weight.len(), inputs * outputs, "weights of the matrix");
        assert!(inputs > 0, "a product over no inputs");
        let tiles = outputs.div_ceil(TILE);
        let mut packed = vec![0f32; tiles * inputs * TILE];
        for t in 0..tiles {
            let width = TILE.min(outputs - t * TILE);
            for k in 0..inputs {
                let from = k * outputs + t * TILE;
                let to = (t * inputs + k) * TILE;
                packed[to..to + width].copy_from_slice(&weight[from..from + width]);
            }
        }
        Self {
            inputs,
            outputs,
            packed,
        }
    }

    /// `ys[r] = xs[r] · W` for `R` rows (1 or 2) read with the weights once.
    ///
    /// # Panics
    /// When a row's length disagrees with the matrix, or on a processor without the
    /// instructions ([`Self::supported`] says; a caller's bug).
    pub(crate) fn products<const R: usize>(&self, xs: [&[f32]; R], ys: [&mut [f32]; R]) {
        assert!((1..=2).contains(&R), "one or two rows");
        for (x, y) in xs.iter().zip(&ys) {
            assert!(
                x.len() == self.inputs && y.len() == self.outputs,
                "{} inputs and {} outputs for a {} × {} matrix",
                x.len(),
                y.len(),
                self.inputs,
                self.outputs
            );
        }
        assert!(Self::supported(), "packed products need AVX2 and FMA");
        let mut ys = ys;
        let mut out = [[0f32; TILE]; R];
        #[cfg(target_arch = "x86_64")]
        let sixteen_lanes = std::arch::is_x86_feature_detected!("avx512f");
        for (t, tile) in self.packed.chunks_exact(self.inputs * TILE).enumerate() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the processor has the instructions (checked above); the kernels read
            // `inputs × TILE` weights of the tile and `inputs` values of each row, and write
            // `TILE` outputs per row.
            unsafe {
                if sixteen_lanes {
                    tile_sixteen_lanes(tile, &xs, &mut out)
                } else {
                    tile_eight_lanes(tile, &xs, &mut out)
                }
            }
            let start = t * TILE;
            let width = TILE.min(self.outputs - start);
            for (y, o) in ys.iter_mut().zip(&out) {
                y[start..start + width].copy_from_slice(&o[..width]);
            }
        }
    }
}

/// One tile for `R` rows, sixteen lanes at a time (AVX-512F): per output `x₀·w₀`, then a fused
/// multiply-add per input.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn tile_sixteen_lanes<const R: usize>(
    tile: &[f32],
    xs: &[&[f32]; R],
    out: &mut [[f32; TILE]; R],
) {
    use std::arch::x86_64::*;
    const V: usize = TILE / 16;
    let inputs = xs[0].len();
    debug_assert_eq!(tile.len(), inputs * TILE);
    let w = tile.as_ptr();
    let mut acc = [[_mm512_setzero_ps(); V]; R];
    for (r, a) in acc.iter_mut().enumerate() {
        let xb = _mm512_set1_ps(xs[r][0]);
        for (c, a) in a.iter_mut().enumerate() {
            *a = _mm512_mul_ps(_mm512_loadu_ps(w.add(16 * c)), xb);
        }
    }
    for k in 1..inputs {
        let row = w.add(k * TILE);
        let wv: [__m512; V] = std::array::from_fn(|c| _mm512_loadu_ps(row.add(16 * c)));
        for (r, a) in acc.iter_mut().enumerate() {
            let xb = _mm512_set1_ps(*xs[r].get_unchecked(k));
            for (c, a) in a.iter_mut().enumerate() {
                *a = _mm512_fmadd_ps(wv[c], xb, *a);
            }
        }
    }
    for (o, a) in out.iter_mut().zip(&acc) {
        for (c, a) in a.iter().enumerate() {
            _mm512_storeu_ps(o.as_mut_ptr().add(16 * c), *a);
        }
    }
}

/// One tile for `R` rows, eight lanes at a time (AVX2 and FMA), half a tile per pass so the
/// accumulators stay in registers: the same operations per output as the sixteen-lane kernel.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn tile_eight_lanes<const R: usize>(
    tile: &[f32],
    xs: &[&[f32]; R],
    out: &mut [[f32; TILE]; R],
) {
    use std::arch::x86_64::*;
    const V: usize = TILE / 16;
    let inputs = xs[0].len();
    debug_assert_eq!(tile.len(), inputs * TILE);
    for half in 0..2 {
        let w = tile.as_ptr().add(half * TILE / 2);
        let mut acc = [[_mm256_setzero_ps(); V]; R];
        for (r, a) in acc.iter_mut().enumerate() {
            let xb = _mm256_set1_ps(xs[r][0]);
            for (c, a) in a.iter_mut().enumerate() {
                *a = _mm256_mul_ps(_mm256_loadu_ps(w.add(8 * c)), xb);
            }
        }
        for k in 1..inputs {
            let row = w.add(k * TILE);
            let wv: [__m256; V] = std::array::from_fn(|c| _mm256_loadu_ps(row.add(8 * c)));
            for (r, a) in acc.iter_mut().enumerate() {
                let xb = _mm256_set1_ps(*xs[r].get_unchecked(k));
                for (c, a) in a.iter_mut().enumerate() {
                    *a = _mm256_fmadd_ps(wv[c], xb, *a);
                }
            }
        }
        for (o, a) in out.iter_mut().zip(&acc) {
            for (c, a) in a.iter().enumerate() {
                _mm256_storeu_ps(o.as_mut_ptr().add(half * TILE / 2 + 8 * c), *a);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The order `gemm` sums in for one row: `x₀·w₀`, then fused multiply-adds.
    fn reference(inputs: usize, outputs: usize, w: &[f32], x: &[f32]) -> Vec<f32> {
        (0..outputs)
            .map(|j| (1..inputs).fold(x[0] * w[j], |acc, k| w[k * outputs + j].mul_add(x[k], acc)))
            .collect()
    }

    #[test]
    fn one_and_two_rows_equal_gemms_order_bit_for_bit() {
        if !RowMatrix::supported() {
            return;
        }
        // Full and partial tiles, one input, values of mixed scale and sign.
        for (inputs, outputs) in [(1, 5), (3, 64), (37, 100), (130, 288), (7, 1)] {
            let w: Vec<f32> = (0..inputs * outputs)
                .map(|k| ((k as f32) * 0.7548).sin() * if k % 13 == 0 { 50.0 } else { 0.3 })
                .collect();
            let x1: Vec<f32> = (0..inputs).map(|k| ((k as f32) * 1.3).cos()).collect();
            let x2: Vec<f32> = (0..inputs).map(|k| (k as f32) * 0.01 - 0.2).collect();
            let m = RowMatrix::new(inputs, outputs, &w);
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let mut y1 = vec![f32::NAN; outputs];
            m.products([&x1[..]], [&mut y1[..]]);
            assert_eq!(bits(&y1), bits(&reference(inputs, outputs, &w, &x1)));
            let (mut a, mut b) = (vec![0f32; outputs], vec![0f32; outputs]);
            m.products([&x1[..], &x2[..]], [&mut a[..], &mut b[..]]);
            assert_eq!(bits(&a), bits(&y1));
            assert_eq!(bits(&b), bits(&reference(inputs, outputs, &w, &x2)));
            #[cfg(target_arch = "x86_64")]
            {
                // The eight-lane kernel, whatever the processor has beyond.
                let mut out = [[0f32; TILE]; 1];
                for (t, tile) in m.packed.chunks_exact(inputs * TILE).enumerate() {
                    // SAFETY: AVX2 and FMA are there (checked above); the tile holds
                    // `inputs × TILE` weights and the row `inputs` values.
                    unsafe { tile_eight_lanes(tile, &[&x2[..]], &mut out) };
                    let width = TILE.min(outputs - t * TILE);
                    assert_eq!(bits(&out[0][..width]), bits(&b[t * TILE..t * TILE + width]));
                }
            }
        }
    }

    #[test]
    #[should_panic(expected = "inputs and")]
    fn a_row_of_the_wrong_length_is_refused() {
        let m = RowMatrix::new(2, 3, &[0.0; 6]);
        let mut y = [0f32; 3];
        m.products([&[1.0f32; 3][..]], [&mut y[..]]);
    }
}
