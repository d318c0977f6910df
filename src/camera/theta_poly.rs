//! The odd radial polynomial of the fisheye models, `θ_d = θ (1 + c₀θ² + c₁θ⁴ + …)`: its value
//! and slope, the range where it increases, and its inverse by safeguarded Newton iteration.

use crate::math::Real;

/// Newton iterations stop when the last step is below this (radians).
pub(crate) const THETA_STEP_TOLERANCE: Real = 1e-12;
/// Iteration cap for the Newton solvers; a solve that needs more is reported as failed.
pub(crate) const MAX_NEWTON_ITERATIONS: usize = 50;

/// `θ_d(θ) = θ (1 + Σᵢ cᵢ θ^(2i+2))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ThetaPolynomial<const N: usize> {
    pub coeffs: [Real; N],
}

impl<const N: usize> ThetaPolynomial<N> {
    /// `θ_d(θ)`.
    pub(crate) fn eval(&self, theta: Real) -> Real {
        self.eval_with_slope(theta).0
    }

    /// `(θ_d(θ), dθ_d/dθ)`, Horner in θ².
    pub(crate) fn eval_with_slope(&self, theta: Real) -> (Real, Real) {
        let t2 = theta * theta;
        let mut poly = 0.0;
        let mut slope = 0.0;
        for (i, c) in self.coeffs.iter().enumerate().rev() {
            poly = poly * t2 + c;
            slope = slope * t2 + (2 * i + 3) as Real * c;
        }
        (theta * (1.0 + poly * t2), 1.0 + slope * t2)
    }

    /// The first angle in `(0, upper]` at which the slope stops being positive, or `upper` if
    /// it stays positive there. Scans `upper` in 4096 steps, then bisects the crossing.
    pub(crate) fn increasing_limit(&self, upper: Real) -> Real {
        const STEPS: usize = 4096;
        let mut prev = 0.0;
        for i in 1..=STEPS {
            let t = upper * i as Real / STEPS as Real;
            if self.eval_with_slope(t).1 <= 0.0 {
                let (mut lo, mut hi) = (prev, t);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if self.eval_with_slope(mid).1 > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return lo;
            }
            prev = t;
        }
        upper
    }

    /// The θ in `[0, theta_max]` with `θ_d(θ) = theta_d`, or `None` if `theta_d` lies beyond
    /// `θ_d(theta_max)` or the iteration does not converge. The polynomial must increase on
    /// `[0, theta_max]`. Newton from `θ = θ_d`, falling back to bisection whenever a step would
    /// leave the bracket, until a step is below [`THETA_STEP_TOLERANCE`].
    pub(crate) fn invert(&self, theta_d: Real, theta_max: Real) -> Option<Real> {
        if !(theta_d >= 0.0) {
            return None;
        }
        if theta_d == 0.0 {
            return Some(0.0);
        }
        let top = self.eval(theta_max);
        if theta_d > top {
            // Allow rounding at the very edge.
            return (theta_d - top <= 4.0 * Real::EPSILON * top).then_some(theta_max);
        }
        invert_increasing(
            |t| self.eval_with_slope(t),
            theta_d,
            theta_max,
            theta_d.min(theta_max),
            THETA_STEP_TOLERANCE,
        )
    }
}

/// The `x` in `[0, x_max]` with `f(x) = target` for an increasing `f` given with its slope
/// (`f_with_slope(x) = (f(x), f′(x))`): Newton from `start`, falling back to bisection whenever a
/// step would leave the bracket, until a step is at most `tolerance`; `None` if that takes more
/// than [`MAX_NEWTON_ITERATIONS`].
pub(crate) fn invert_increasing(
    f_with_slope: impl Fn(Real) -> (Real, Real),
    target: Real,
    x_max: Real,
    start: Real,
    tolerance: Real,
) -> Option<Real> {
    let (mut lo, mut hi) = (0.0, x_max);
    let mut x = start.clamp(0.0, x_max);
    for _ in 0..MAX_NEWTON_ITERATIONS {
        let (value, slope) = f_with_slope(x);
        let residual = value - target;
        if residual > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let newton = x - residual / slope;
        let next = if slope > 0.0 && newton >= lo && newton <= hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let step = (next - x).abs();
        x = next;
        if step <= tolerance || residual == 0.0 {
            return Some(x.clamp(0.0, x_max));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_matches_finite_difference() {
        let p = ThetaPolynomial {
            coeffs: [0.1, -0.05, 0.02],
        };
        for t in [0.0, 0.3, 0.9, 1.4] {
            let h = 1e-6;
            let fd = (p.eval(t + h) - p.eval(t - h)) / (2.0 * h);
            assert!((fd - p.eval_with_slope(t).1).abs() < 1e-8);
        }
    }

    #[test]
    fn inverse_round_trips_and_rejects_beyond_max() {
        let p = ThetaPolynomial {
            coeffs: [-0.03, 0.1, -0.07, 0.012],
        };
        let max = p.increasing_limit(1.5);
        for i in 0..=100 {
            let t = max * i as Real / 100.0;
            let back = p.invert(p.eval(t), max).unwrap();
            assert!((back - t).abs() < 1e-13, "{t} {back}");
        }
        assert!(p.invert(p.eval(max) * 1.01, max).is_none());
        assert_eq!(p.invert(1e-300, max), Some(1e-300));
    }

    #[test]
    fn increasing_limit_finds_the_turning_point() {
        // θ(1 − θ²/3): slope 1 − θ², turning at θ = 1.
        let p = ThetaPolynomial {
            coeffs: [-1.0 / 3.0],
        };
        assert!((p.increasing_limit(2.0) - 1.0).abs() < 1e-12);
        assert_eq!(p.increasing_limit(0.5), 0.5);
    }
}
