//! Shared math vocabulary: scalar and vector aliases, frame conventions, quantiles of a sample,
//! zero-phase Gaussian smoothing of a series and angles wrapped to (−π, π] here; `rotation`
//! (maps between axis-angle, 6D and matrix forms), `random` (seeded draws on ChaCha8), `colour`
//! (colour conversions), `least_squares` (small least-squares solves by normal equations, for
//! the lens fits) and `pose_spline` (a C²-continuous rigid-body trajectory through poses
//! sampled at a fixed rate: cubic B-splines on R³ × SO(3)).
//!
//! Conventions used across egogen:
//! - Lengths are metres, angles radians, time seconds unless a name says otherwise.
//! - A transform is named `a_from_b`: it maps points expressed in frame `b` into frame `a`
//!   (`point_in_world = world_from_head * point_in_head`).
//! - The SMPL-X body frame is y up, z forward (the body faces +z), x towards the body's left.
//! - The world of a generated scene is z up (see `scene`); camera annotations use the OpenCV
//!   camera frame (x right, y down, z forward).
//! - Rotations are right-handed; axis-angle vectors have angle = norm, in radians.

pub(crate) mod colour;
pub(crate) mod least_squares;
pub mod pose_spline;
pub(crate) mod random;
pub(crate) mod rotation;

/// Scalar used for geometry. Body maths runs in `f64` so that long kinematic chains and
/// large betas stay well inside the 1e-5 m tolerance of the `smplx` oracle.
pub type Real = f64;
/// 3-vector of [`Real`].
pub type Vec3 = glam::DVec3;
/// 3×3 matrix of [`Real`] (column-major, as glam stores it).
pub type Mat3 = glam::DMat3;
/// Rigid or affine 3D transform of [`Real`]: a [`Mat3`] plus a translation.
pub type Affine3 = glam::DAffine3;

pub(crate) use rotation::matrix_to_rot6d;
pub use rotation::{axis_angle_to_matrix, matrix_to_axis_angle};

/// The `p` quantile (0–1, nearest rank) of `sorted` (ascending, finite); NaN for none.
pub(crate) fn quantile(sorted: &[Real], p: Real) -> Real {
    if sorted.is_empty() {
        Real::NAN
    } else {
        sorted[((sorted.len() - 1) as Real * p.clamp(0.0, 1.0)).round() as usize]
    }
}

/// Zero-phase Gaussian smoothing with σ `sigma` samples; the kernel renormalised at the ends.
pub(crate) fn gaussian_smooth(v: &[Real], sigma: Real) -> Vec<Real> {
    if sigma <= 0.0 {
        return v.to_vec();
    }
    let half = (3.0 * sigma).ceil() as usize;
    let kernel: Vec<Real> = (0..=2 * half)
        .map(|i| {
            let d = i as Real - half as Real;
            (-0.5 * d * d / (sigma * sigma)).exp()
        })
        .collect();
    (0..v.len())
        .map(|f| {
            let (mut sum, mut w) = (0.0, 0.0);
            for (i, k) in kernel.iter().enumerate() {
                let Some(g) = (f + i).checked_sub(half) else {
                    continue;
                };
                if let Some(x) = v.get(g) {
                    sum += k * x;
                    w += k;
                }
            }
            sum / w
        })
        .collect()
}

/// Quantiles of a sample, with its mean and size.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Quantiles {
    pub count: usize,
    pub mean: f64,
    pub p05: f64,
    pub p10: f64,
    pub p25: f64,
    pub p50: f64,
    pub p75: f64,
    pub p95: f64,
    pub p99: f64,
    pub max: f64,
}

impl Quantiles {
    /// Quantiles (nearest rank) of the finite values of `values`; all NaN when there are none.
    pub(crate) fn of(values: impl IntoIterator<Item = f64>) -> Quantiles {
        let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        let q = |p: f64| quantile(&v, p);
        Quantiles {
            count: v.len(),
            mean: if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            },
            p05: q(0.05),
            p10: q(0.1),
            p25: q(0.25),
            p50: q(0.5),
            p75: q(0.75),
            p95: q(0.95),
            p99: q(0.99),
            max: q(1.0),
        }
    }
}

/// Wraps an angle to (−π, π].
pub(crate) fn wrap_rad(a: f64) -> f64 {
    let w = (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    if w <= -std::f64::consts::PI {
        w + std::f64::consts::TAU
    } else {
        w
    }
}

/// Axis-aligned bounds (min, max) of `points`; `None` for none.
pub(crate) fn point_bounds<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Option<(Vec3, Vec3)> {
    let mut points = points.into_iter();
    let first = *points.next()?;
    Some(points.fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
}

/// A 3×3 matrix from its rows (the form egogen's and Aria's JSON files write matrices in).
pub(crate) fn mat3_from_rows(rows: &[[f64; 3]; 3]) -> Mat3 {
    Mat3::from_cols_array_2d(rows).transpose()
}

/// The rows of a 3×3 matrix.
pub(crate) fn mat3_rows(m: Mat3) -> [[f64; 3]; 3] {
    m.transpose().to_cols_array_2d()
}

/// Row-major 4×4 of an affine transform (the form egogen's JSON files write transforms in).
pub(crate) fn row_major(m: Affine3) -> [[f64; 4]; 4] {
    glam::DMat4::from(m).transpose().to_cols_array_2d()
}

/// The affine transform of a row-major 4×4 (its last row is not read), or `None` if it holds
/// a non-finite number.
pub(crate) fn affine_from_row_major(rows: &[[f64; 4]; 4]) -> Option<Affine3> {
    let a = Affine3::from_mat4(glam::DMat4::from_cols_array_2d(rows).transpose());
    a.is_finite().then_some(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_stays_in_range_at_the_extremes() {
        use std::f64::consts::PI;
        for a in [PI, -PI, 3.0 * PI, -3.0 * PI, 1e-12, -1e-12, 1e6, -1e6] {
            let w = wrap_rad(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            assert!(((w - a) / std::f64::consts::TAU).fract().abs() < 1e-6 || (w - a).abs() < 1e-9);
        }
    }

    #[test]
    fn quantiles_of_a_known_sample() {
        let q = Quantiles::of((0..=100).map(f64::from).chain([f64::NAN]));
        assert_eq!(
            (q.count, q.p05, q.p10, q.p50, q.p95, q.p99, q.max),
            (101, 5.0, 10.0, 50.0, 95.0, 99.0, 100.0)
        );
        assert!((q.mean - 50.0).abs() < 1e-12);
        assert!(Quantiles::of(std::iter::empty()).p50.is_nan());
    }

    #[test]
    fn gaussian_smoothing_keeps_a_line_and_damps_a_fast_sine() {
        use std::f64::consts::PI;
        let line: Vec<Real> = (0..100).map(|i| 0.1 * i as Real).collect();
        let s = gaussian_smooth(&line, 5.0);
        for i in 20..80 {
            assert!((s[i] - line[i]).abs() < 1e-9);
        }
        let sine: Vec<Real> = (0..400)
            .map(|i| (2.0 * PI * i as Real / 44.0).sin())
            .collect();
        let s = gaussian_smooth(&sine, 18.0);
        assert!(s[100..300].iter().all(|x| x.abs() < 0.1));
    }
}
