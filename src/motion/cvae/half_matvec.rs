//! One primitive's matrix–vector products with the weights stored in half precision (IEEE
//! f16), computed in f32: the decoder's path for a single primitive, where reading the weights
//! costs more than the arithmetic (docs/MOTION.md, "Half-precision weights at batch 1").
//!
//! At batch 1 each of the decoder's 18 GRU steps reads every weight of the step once: 1.75 MB
//! in f32, more than a core's 1 MB L2 cache, so the f32 product streams them from L3 every
//! step. In f16 the step's weights take 0.88 MB. The products themselves stay f32: weights are
//! widened to f32 in registers (x86-64 F16C) and accumulated with fused multiply-adds.
//!
//! Only on x86-64 processors with AVX2, FMA and F16C ([`HalfMatrix::supported`]); elsewhere the
//! decoder keeps its f32 path. Where the processor has AVX-512F the same products run sixteen
//! lanes at a time, each output's multiply-adds in the same order: the same bits, fewer
//! instructions (`cargo bench --bench primitive -- half_matvec`).

/// Output columns per tile: eight registers of eight f32 accumulators.
const TILE: usize = 64;

/// A `[inputs × outputs]` weight matrix (burn's `Linear` layout) in f16, packed tile by tile:
/// for each tile of 64 output columns, the inputs' rows of that tile one after another,
/// so that a product reads the matrix front to back. Columns past `outputs` are zero.
#[derive(Debug, Clone, PartialEq)]
pub struct HalfMatrix {
    inputs: usize,
    outputs: usize,
    /// f16 bit patterns, `[tiles × inputs × TILE]`.
    packed: Vec<u16>,
}

impl HalfMatrix {
    /// Whether this processor runs the f16 product (x86-64 with AVX2, FMA and F16C).
    pub fn supported() -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("f16c")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// Rounds a row-major `[inputs × outputs]` f32 matrix to f16 (to nearest, ties to even).
    ///
    /// # Panics
    /// When `weight` does not hold `inputs × outputs` values (a caller's bug).
    pub fn new(inputs: usize, outputs: usize, weight: &[f32]) -> Self {
        assert_eq!(weight.len(), inputs * outputs, "weights of the matrix");
        let tiles = outputs.div_ceil(TILE);
        let mut packed = vec![0u16; tiles * inputs * TILE];
        for t in 0..tiles {
            for k in 0..inputs {
                for c in 0..TILE.min(outputs - t * TILE) {
                    packed[(t * inputs + k) * TILE + c] =
                        half::f16::from_f32(weight[k * outputs + t * TILE + c]).to_bits();
                }
            }
        }
        Self {
            inputs,
            outputs,
            packed,
        }
    }

    /// The weight at `(input, output)`, widened to f32.
    #[cfg(test)]
    pub(crate) fn get(&self, input: usize, output: usize) -> f32 {
        let (t, c) = (output / TILE, output % TILE);
        half::f16::from_bits(self.packed[(t * self.inputs + input) * TILE + c]).to_f32()
    }

    /// `y += x · W` for one row `x` `[inputs]`, `y` `[outputs]`.
    ///
    /// # Panics
    /// When the lengths disagree with the matrix, or on a processor without the instructions
    /// ([`Self::supported`] says; a caller's bug).
    pub fn mul_add(&self, x: &[f32], y: &mut [f32]) {
        self.check(x, y);
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the processor has the instructions (checked above and here); both kernels
        // read `packed` within its `tiles × inputs × TILE` values and write `y` within its
        // length.
        unsafe {
            if std::arch::is_x86_feature_detected!("avx512f") {
                self.mul_add_avx512(x, y)
            } else {
                self.mul_add_x86(x, y)
            }
        }
    }

    /// [`Self::mul_add`] eight lanes at a time (AVX2), whatever the processor has beyond:
    /// the reference the 16-lane kernel equals bit for bit.
    ///
    /// # Panics
    /// As [`Self::mul_add`].
    pub fn mul_add_eight_lanes(&self, x: &[f32], y: &mut [f32]) {
        self.check(x, y);
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as in `mul_add`.
        unsafe {
            self.mul_add_x86(x, y)
        }
    }

    /// Panics unless `x` and `y` fit the matrix and the processor has the instructions.
    fn check(&self, x: &[f32], y: &[f32]) {
        assert!(
            x.len() == self.inputs && y.len() == self.outputs,
            "{} inputs and {} outputs for a {} × {} matrix",
            x.len(),
            y.len(),
            self.inputs,
            self.outputs
        );
        assert!(Self::supported(), "f16 products need AVX2, FMA and F16C");
    }

    /// Runs `kernel(tile, out)` on every tile of [`TILE`] outputs from tile `first` on: `tile`
    /// its packed weights (`inputs × TILE`), `out` its [`TILE`] outputs — for the last, partial
    /// tile a zero-padded copy written back after.
    fn for_each_tile(
        &self,
        first: usize,
        y: &mut [f32],
        mut kernel: impl FnMut(&[u16], &mut [f32; TILE]),
    ) {
        let mut tail = [0f32; TILE];
        let tiles = self.packed.chunks_exact(self.inputs * TILE).enumerate();
        for (t, tile) in tiles.skip(first) {
            let start = t * TILE;
            let width = TILE.min(self.outputs - start);
            if width == TILE {
                let out = (&mut y[start..start + TILE])
                    .try_into()
                    .expect("a full tile");
                kernel(tile, out);
            } else {
                tail[..width].copy_from_slice(&y[start..start + width]);
                tail[width..].fill(0.0);
                kernel(tile, &mut tail);
                y[start..start + width].copy_from_slice(&tail[..width]);
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,f16c")]
    unsafe fn mul_add_x86(&self, x: &[f32], y: &mut [f32]) {
        // SAFETY: the caller checked the instructions; the kernel reads `inputs × TILE`
        // weights of the tile and writes its `TILE` outputs.
        self.for_each_tile(0, y, |tile, out| unsafe { tile_eight_lanes(tile, x, out) });
    }

    /// The tiles with 16-lane registers (AVX-512F): per output, the same fused multiply-adds
    /// in the same order as [`Self::mul_add_x86`], so the same bits, with half the
    /// conversions and multiply-add instructions. Full tiles go four at a time (sixteen
    /// accumulators, each input's broadcast shared), the rest one at a time.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn mul_add_avx512(&self, x: &[f32], y: &mut [f32]) {
        let per_tile = self.inputs * TILE;
        let groups = self.outputs / TILE / 4;
        for (tiles, out) in self
            .packed
            .chunks_exact(4 * per_tile)
            .zip(y.chunks_exact_mut(4 * TILE))
            .take(groups)
        {
            // SAFETY: as in `mul_add_x86`; `tiles` holds four tiles' `4 × inputs × TILE`
            // weights and `out` their `4 × TILE` outputs.
            unsafe { four_tiles_sixteen_lanes(tiles, x, out) };
        }
        // SAFETY: as in `mul_add_x86`.
        self.for_each_tile(4 * groups, y, |tile, out| unsafe {
            tile_sixteen_lanes(tile, x, out)
        });
    }
}

/// `out += x · tile` for one tile, eight accumulators of eight lanes, the inputs in order.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,f16c")]
unsafe fn tile_eight_lanes(tile: &[u16], x: &[f32], out: &mut [f32; TILE]) {
    use std::arch::x86_64::*;
    debug_assert_eq!(tile.len(), x.len() * TILE);
    let (o, w) = (out.as_mut_ptr(), tile.as_ptr());
    let mut acc = [_mm256_setzero_ps(); 8];
    for (r, a) in acc.iter_mut().enumerate() {
        *a = _mm256_loadu_ps(o.add(8 * r));
    }
    for (k, &xk) in x.iter().enumerate() {
        let xb = _mm256_set1_ps(xk);
        let row = w.add(k * TILE);
        for (r, a) in acc.iter_mut().enumerate() {
            let h = _mm_loadu_si128(row.add(8 * r) as *const __m128i);
            *a = _mm256_fmadd_ps(xb, _mm256_cvtph_ps(h), *a);
        }
    }
    for (r, a) in acc.iter().enumerate() {
        _mm256_storeu_ps(o.add(8 * r), *a);
    }
}

/// `out += x · tile` for one tile, four accumulators of sixteen lanes, the inputs in order.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn tile_sixteen_lanes(tile: &[u16], x: &[f32], out: &mut [f32; TILE]) {
    use std::arch::x86_64::*;
    debug_assert_eq!(tile.len(), x.len() * TILE);
    let (o, w) = (out.as_mut_ptr(), tile.as_ptr());
    let mut acc = [_mm512_setzero_ps(); 4];
    for (r, a) in acc.iter_mut().enumerate() {
        *a = _mm512_loadu_ps(o.add(16 * r));
    }
    for (k, &xk) in x.iter().enumerate() {
        let xb = _mm512_set1_ps(xk);
        let row = w.add(k * TILE);
        for (r, a) in acc.iter_mut().enumerate() {
            let h = _mm256_loadu_si256(row.add(16 * r) as *const __m256i);
            *a = _mm512_fmadd_ps(xb, _mm512_cvtph_ps(h), *a);
        }
    }
    for (r, a) in acc.iter().enumerate() {
        _mm512_storeu_ps(o.add(16 * r), *a);
    }
}

/// `out += x · tiles` for four tiles side by side (`tiles` `[4 × inputs × TILE]`, `out`
/// `[4 × TILE]`), sixteen accumulators of sixteen lanes, the inputs in order: per output the
/// fused multiply-adds of [`tile_sixteen_lanes`], while four tiles' worth of them are in flight.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn four_tiles_sixteen_lanes(tiles: &[u16], x: &[f32], out: &mut [f32]) {
    use std::arch::x86_64::*;
    let inputs = x.len();
    debug_assert_eq!(tiles.len(), 4 * inputs * TILE);
    debug_assert_eq!(out.len(), 4 * TILE);
    let (o, w) = (out.as_mut_ptr(), tiles.as_ptr());
    let mut acc = [[_mm512_setzero_ps(); 4]; 4];
    for (t, a) in acc.iter_mut().enumerate() {
        for (r, a) in a.iter_mut().enumerate() {
            *a = _mm512_loadu_ps(o.add(t * TILE + 16 * r));
        }
    }
    for (k, &xk) in x.iter().enumerate() {
        let xb = _mm512_set1_ps(xk);
        for (t, a) in acc.iter_mut().enumerate() {
            let row = w.add((t * inputs + k) * TILE);
            for (r, a) in a.iter_mut().enumerate() {
                let h = _mm256_loadu_si256(row.add(16 * r) as *const __m256i);
                *a = _mm512_fmadd_ps(xb, _mm512_cvtph_ps(h), *a);
            }
        }
    }
    for (t, a) in acc.iter().enumerate() {
        for (r, a) in a.iter().enumerate() {
            _mm512_storeu_ps(o.add(t * TILE + 16 * r), *a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_product_is_the_rounded_matrix_times_the_vector() {
        if !HalfMatrix::supported() {
            eprintln!("no AVX2/FMA/F16C here: nothing to check");
            return;
        }
        // 70 outputs: one full tile and a partial one; 5 inputs.
        let (k, n) = (5, 70);
        let w: Vec<f32> = (0..k * n)
            .map(|i| ((i as f32) * 0.173).sin() * 2.0)
            .collect();
        let x: Vec<f32> = (0..k).map(|i| 1.0 - 0.37 * i as f32).collect();
        let m = HalfMatrix::new(k, n, &w);
        let mut y: Vec<f32> = (0..n).map(|j| j as f32 * 0.01).collect();
        let before = y.clone();
        m.mul_add(&x, &mut y);
        // Whatever the lanes, the same bits.
        let mut eight = before.clone();
        m.mul_add_eight_lanes(&x, &mut eight);
        assert_eq!(
            y.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            eight.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        for j in 0..n {
            let want: f64 = before[j] as f64
                + (0..k)
                    .map(|i| x[i] as f64 * m.get(i, j) as f64)
                    .sum::<f64>();
            assert!(
                (y[j] as f64 - want).abs() < 1e-5,
                "{j}: {} against {want}",
                y[j]
            );
            // Rounding to f16 keeps 11 significant bits.
            for i in 0..k {
                let (a, b) = (w[i * n + j], m.get(i, j));
                assert!((a - b).abs() <= a.abs() * 4.9e-4 + 6e-8, "{a} → {b}");
            }
        }
    }

    #[test]
    fn sixteen_lanes_give_the_bits_of_eight_on_the_decoders_shapes() {
        if !HalfMatrix::supported() {
            eprintln!("no AVX2/FMA/F16C here: nothing to check");
            return;
        }
        // The GRU's frame rows and hidden gates, and the output layer (a partial tile); five
        // full tiles and a partial one (four side by side, then one at a time).
        for (k, n) in [(270, 768), (256, 768), (256, 135), (33, 350)] {
            let w: Vec<f32> = (0..k * n).map(|i| ((i as f32) * 0.0137).cos()).collect();
            let x: Vec<f32> = (0..k).map(|i| ((i as f32) * 0.71).sin() * 3.0).collect();
            let m = HalfMatrix::new(k, n, &w);
            let y0: Vec<f32> = (0..n).map(|j| (j as f32 * 0.3).sin()).collect();
            let (mut a, mut b) = (y0.clone(), y0);
            m.mul_add(&x, &mut a);
            m.mul_add_eight_lanes(&x, &mut b);
            assert!(
                a.iter().zip(&b).all(|(p, q)| p.to_bits() == q.to_bits()),
                "{k} × {n}"
            );
        }
    }
}
