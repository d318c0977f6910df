//! Small linear least-squares problems, solved by their normal equations: the lens fits
//! (`camera::kannala_brandt::fit_kb4`, COLMAP's thin-prism fisheye in `export::colmap`) add one
//! row per pixel coordinate and solve for a handful of coefficients.

use super::Real;

/// The normal equations `AᵀA x = Aᵀb` of an overdetermined system with `N` unknowns, built one
/// row of `A` (and its entry of `b`) at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NormalEquations<const N: usize> {
    ata: [[Real; N]; N],
    atb: [Real; N],
    rows: usize,
}

impl<const N: usize> Default for NormalEquations<N> {
    fn default() -> Self {
        Self {
            ata: [[0.0; N]; N],
            atb: [0.0; N],
            rows: 0,
        }
    }
}

impl<const N: usize> NormalEquations<N> {
    /// Adds the equation `row · x = target`.
    pub(crate) fn add(&mut self, row: &[Real; N], target: Real) {
        for i in 0..N {
            self.atb[i] += row[i] * target;
            for j in 0..N {
                self.ata[i][j] += row[i] * row[j];
            }
        }
        self.rows += 1;
    }

    /// Equations added so far.
    #[cfg(test)]
    pub(crate) fn rows(&self) -> usize {
        self.rows
    }

    /// The least-squares `x`, by Gaussian elimination with partial pivoting; a direction no
    /// equation constrains (a pivot below 1e-14 of the largest diagonal entry) gets 0.
    pub(crate) fn solve(&self) -> [Real; N] {
        let (mut a, mut b) = (self.ata, self.atb);
        let scale = (0..N).map(|i| a[i][i].abs()).fold(0.0, Real::max);
        for col in 0..N {
            let pivot = (col..N)
                .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
                .unwrap_or(col);
            a.swap(col, pivot);
            b.swap(col, pivot);
            if a[col][col].abs() <= 1e-14 * scale {
                a[col] = [0.0; N];
                a[col][col] = 1.0;
                b[col] = 0.0;
                continue;
            }
            for row in col + 1..N {
                let m = a[row][col] / a[col][col];
                for k in col..N {
                    a[row][k] -= m * a[col][k];
                }
                b[row] -= m * b[col];
            }
        }
        let mut x = [0.0; N];
        for row in (0..N).rev() {
            let s: Real = (row + 1..N).map(|k| a[row][k] * x[k]).sum();
            x[row] = (b[row] - s) / a[row][row];
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_an_exact_line_and_zeroes_an_unconstrained_unknown() {
        let mut eq = NormalEquations::<3>::default();
        for k in 0..10 {
            let t = k as Real * 0.3;
            // y = 2 − 0.5 t; the third unknown multiplies 0 in every row.
            eq.add(&[1.0, t, 0.0], 2.0 - 0.5 * t);
        }
        let x = eq.solve();
        assert_eq!(eq.rows(), 10);
        assert!(
            (x[0] - 2.0).abs() < 1e-12 && (x[1] + 0.5).abs() < 1e-12,
            "{x:?}"
        );
        assert_eq!(x[2], 0.0);
    }
}
