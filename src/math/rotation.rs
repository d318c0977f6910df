//! Rotation maps between axis-angle, 6D and matrix forms, stable at the extremes.
//!
//! - Axis-angle → matrix is Rodrigues' formula with a Taylor series near 0, so tiny angles do
//!   not divide by zero; angles at and beyond π are valid (the map is periodic).
//! - Matrix → axis-angle returns the angle in [0, π]; near π it recovers the axis from the
//!   symmetric part of the matrix, where the usual `(R - Rᵀ)/2 sin θ` form is ill-conditioned.
//! - 6D is the first two **columns** of the matrix (Zhou et al., CVPR 2019), ordered
//!   `[r00, r10, r20, r01, r11, r21]`; Gram-Schmidt turns any input into a rotation, and
//!   near-degenerate inputs (parallel or vanishing columns) fall back to a valid completion.

use super::{Mat3, Real, Vec3};

/// Rodrigues' formula: rotation matrix of the axis-angle vector `aa` (angle = `|aa|` radians).
pub fn axis_angle_to_matrix(aa: Vec3) -> Mat3 {
    let theta2 = aa.length_squared();
    // sin θ / θ and (1 − cos θ) / θ² as series below θ ≈ 1e-4 (error < 1e-17).
    let (a, b) = if theta2 < 1e-8 {
        (1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0)
    } else {
        let theta = theta2.sqrt();
        (theta.sin() / theta, (1.0 - theta.cos()) / theta2)
    };
    let k = skew(aa);
    Mat3::IDENTITY + k * a + (k * k) * b
}

/// Axis-angle vector of a rotation matrix, angle in [0, π].
///
/// `m` must be a rotation (orthonormal, det +1) up to rounding.
pub fn matrix_to_axis_angle(m: Mat3) -> Vec3 {
    let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    let cos_theta = ((trace - 1.0) * 0.5).clamp(-1.0, 1.0);
    // Vector part: (R - Rᵀ)/2 = sin θ · [axis]×
    let v = Vec3::new(
        m.y_axis.z - m.z_axis.y,
        m.z_axis.x - m.x_axis.z,
        m.x_axis.y - m.y_axis.x,
    ) * 0.5;
    let sin_theta = v.length();
    let theta = sin_theta.atan2(cos_theta);
    if cos_theta > -0.9 {
        // Well conditioned: θ/ sin θ with a series near 0.
        let scale = if sin_theta < 1e-8 {
            1.0 + theta * theta / 6.0
        } else {
            theta / sin_theta
        };
        return v * scale;
    }
    // Near π: R + Rᵀ = 2 cos θ I + 2 (1 − cos θ) a aᵀ; take the best-conditioned column.
    let s = m + m.transpose();
    let one_minus_cos = 1.0 - cos_theta;
    let diag = [s.x_axis.x, s.y_axis.y, s.z_axis.z];
    let i = (0..3)
        .max_by(|&a, &b| diag[a].total_cmp(&diag[b]))
        .unwrap_or(0);
    let col = s.col(i) - Vec3::AXES[i] * (2.0 * cos_theta);
    let mut axis = col / (2.0 * one_minus_cos);
    axis = axis.normalize();
    // The sign of the axis is fixed by the vector part (sin θ > 0 for θ < π).
    if axis.dot(v) < 0.0 {
        axis = -axis;
    }
    axis * theta
}

/// Rotation from a 6D vector (first two matrix columns), by Gram-Schmidt.
///
/// Total on all finite inputs: a vanishing first column becomes the x axis, and a second
/// column parallel to the first is replaced by the most orthogonal coordinate axis.
pub(crate) fn rot6d_to_matrix(d6: [Real; 6]) -> Mat3 {
    let a1 = Vec3::new(d6[0], d6[1], d6[2]);
    let a2 = Vec3::new(d6[3], d6[4], d6[5]);
    let b1 = a1.try_normalize().unwrap_or(Vec3::X);
    let mut u2 = a2 - b1 * b1.dot(a2);
    // Relative test: a2 (nearly) parallel to b1 leaves only rounding noise in u2.
    if u2.length_squared() <= 1e-20 * a2.length_squared().max(1e-300)
        || u2.length_squared() < 1e-300
    {
        u2 = b1.any_orthonormal_vector();
    }
    // Classical Gram-Schmidt leaves b2·b1 ≈ ε·|a2|/|u2| when a2 is nearly parallel to b1;
    // a second pass brings it back to rounding ("twice is enough").
    let b2 = u2.normalize();
    let b2 = (b2 - b1 * b1.dot(b2)).normalize();
    let b3 = b1.cross(b2);
    Mat3::from_cols(b1, b2, b3)
}

/// [`rot6d_to_matrix`] of many 6D vectors into `out`, bit for bit: the same steps for
/// [`INTERLEAVED`] vectors at a time, each step over all of them before the next, so their square
/// roots and divisions overlap instead of each waiting on the one before (a decoded frame's 22
/// joints). Near-degenerate inputs take [`rot6d_to_matrix`] itself.
///
/// # Panics
/// When `out` is not as long as `d6` (a caller's bug).
pub(crate) fn rot6d_to_matrices(d6: &[[Real; 6]], out: &mut [Mat3]) {
    assert_eq!(d6.len(), out.len(), "one matrix per 6D vector");
    for (d6, out) in d6.chunks(INTERLEAVED).zip(out.chunks_mut(INTERLEAVED)) {
        let n = d6.len();
        let mut b1 = [Vec3::ZERO; INTERLEAVED];
        let mut b2 = [Vec3::ZERO; INTERLEAVED];
        let mut regular = [true; INTERLEAVED];
        // The steps of `rot6d_to_matrix`, with `normalize` spelled out as glam computes it
        // (`v · (1 / |v|)`, `|v| = √(v·v)`).
        for j in 0..n {
            let a1 = Vec3::new(d6[j][0], d6[j][1], d6[j][2]);
            let rcp = 1.0 / a1.dot(a1).sqrt();
            regular[j] = rcp.is_finite() && rcp > 0.0;
            b1[j] = a1 * rcp;
        }
        for j in 0..n {
            let a2 = Vec3::new(d6[j][3], d6[j][4], d6[j][5]);
            let u2 = a2 - b1[j] * b1[j].dot(a2);
            let l2 = u2.dot(u2);
            regular[j] &= !(l2 <= 1e-20 * a2.dot(a2).max(1e-300) || l2 < 1e-300);
            b2[j] = u2 * (1.0 / l2.sqrt());
        }
        for (b2, b1) in b2.iter_mut().zip(&b1).take(n) {
            let v = *b2 - *b1 * b1.dot(*b2);
            *b2 = v * (1.0 / v.dot(v).sqrt());
        }
        for j in 0..n {
            out[j] = if regular[j] {
                Mat3::from_cols(b1[j], b2[j], b1[j].cross(b2[j]))
            } else {
                rot6d_to_matrix(d6[j])
            };
        }
    }
}

/// Rotations converted side by side in [`rot6d_to_matrices`], [`axis_angles_to_matrices`] and
/// [`matrices_to_axis_angles`].
pub(crate) const INTERLEAVED: usize = 8;

/// [`axis_angle_to_matrix`] of many axis-angle vectors into `out`, bit for bit: each step over
/// [`INTERLEAVED`] of them before the next, so that their square roots, sines and divisions
/// overlap (a pose's 55 joints).
///
/// # Panics
/// When `out` is not as long as `aa` (a caller's bug).
pub(crate) fn axis_angles_to_matrices(aa: &[Vec3], out: &mut [Mat3]) {
    assert_eq!(aa.len(), out.len(), "one matrix per axis-angle vector");
    for (aa, out) in aa.chunks(INTERLEAVED).zip(out.chunks_mut(INTERLEAVED)) {
        let mut ab = [(0.0, 0.0); INTERLEAVED];
        for (ab, aa) in ab.iter_mut().zip(aa) {
            let theta2 = aa.length_squared();
            *ab = if theta2 < 1e-8 {
                (1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0)
            } else {
                let theta = theta2.sqrt();
                (theta.sin() / theta, (1.0 - theta.cos()) / theta2)
            };
        }
        for ((out, aa), (a, b)) in out.iter_mut().zip(aa).zip(ab) {
            let k = skew(*aa);
            *out = Mat3::IDENTITY + k * a + (k * k) * b;
        }
    }
}

/// [`matrix_to_axis_angle`] of many rotation matrices into `out`, bit for bit: each step over
/// [`INTERLEAVED`] of them before the next, so that their square roots, arc tangents and
/// divisions overlap (a decoded frame's 22 joints). Angles near π take
/// [`matrix_to_axis_angle`] itself.
///
/// # Panics
/// When `out` is not as long as `m` (a caller's bug).
pub(crate) fn matrices_to_axis_angles(m: &[Mat3], out: &mut [Vec3]) {
    assert_eq!(m.len(), out.len(), "one axis-angle vector per matrix");
    for (m, out) in m.chunks(INTERLEAVED).zip(out.chunks_mut(INTERLEAVED)) {
        let mut cos_theta = [0.0; INTERLEAVED];
        let mut v = [Vec3::ZERO; INTERLEAVED];
        let mut sin_theta = [0.0; INTERLEAVED];
        for j in 0..m.len() {
            let m = &m[j];
            let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
            cos_theta[j] = ((trace - 1.0) * 0.5).clamp(-1.0, 1.0);
            v[j] = Vec3::new(
                m.y_axis.z - m.z_axis.y,
                m.z_axis.x - m.x_axis.z,
                m.x_axis.y - m.y_axis.x,
            ) * 0.5;
            sin_theta[j] = v[j].length();
        }
        let mut theta = [0.0; INTERLEAVED];
        for j in 0..m.len() {
            theta[j] = sin_theta[j].atan2(cos_theta[j]);
        }
        for j in 0..m.len() {
            out[j] = if cos_theta[j] > -0.9 {
                let scale = if sin_theta[j] < 1e-8 {
                    1.0 + theta[j] * theta[j] / 6.0
                } else {
                    theta[j] / sin_theta[j]
                };
                v[j] * scale
            } else {
                matrix_to_axis_angle(m[j])
            };
        }
    }
}

/// 6D representation (first two columns) of a rotation matrix.
pub(crate) fn matrix_to_rot6d(m: Mat3) -> [Real; 6] {
    [
        m.x_axis.x, m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.y, m.y_axis.z,
    ]
}

/// Cross-product matrix: `skew(a) * b == a.cross(b)`.
pub(crate) fn skew(a: Vec3) -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.0, a.z, -a.y),
        Vec3::new(-a.z, 0.0, a.x),
        Vec3::new(a.y, -a.x, 0.0),
    )
}

/// Largest deviation of `mᵀm` from the identity: how far `m` is from orthonormal.
pub(crate) fn orthonormality_error(m: Mat3) -> Real {
    let e = m.transpose() * m - Mat3::IDENTITY;
    e.to_cols_array()
        .iter()
        .fold(0.0, |acc: Real, x| acc.max(x.abs()))
}

/// The orthogonal polar factor of `m` (the rotation nearest in Frobenius norm, the same as
/// `U·Vᵀ` of its SVD, which Sophus' `makeRotationMatrix` uses), by the Newton iteration
/// `R ← (R + R⁻ᵀ)/2`. `m` must be close to a rotation (det > 0).
pub(crate) fn nearest_rotation(m: Mat3) -> Mat3 {
    let mut r = m;
    for _ in 0..100 {
        let next = (r + r.inverse().transpose()) * 0.5;
        let change = (next - r)
            .to_cols_array()
            .iter()
            .fold(0.0, |a: Real, v| a.max(v.abs()));
        r = next;
        if change < 1e-16 {
            break;
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turn_about_z_maps_x_to_y() {
        let r = axis_angle_to_matrix(Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
        assert!((r * Vec3::X - Vec3::Y).length() < 1e-15);
    }

    #[test]
    fn axis_angle_round_trip_at_pi() {
        let aa = Vec3::new(1.0, -2.0, 0.5).normalize() * std::f64::consts::PI;
        let back = matrix_to_axis_angle(axis_angle_to_matrix(aa));
        // At exactly π, axis and −axis are the same rotation.
        let err = (back - aa).length().min((back + aa).length());
        assert!(err < 1e-7, "err {err}");
    }
}
