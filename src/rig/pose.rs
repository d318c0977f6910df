//! Camera poses relative to the CPF: rotation checks, the nearest rotation of a nearly
//! orthonormal matrix, and the yaw/pitch/roll read-out that `rig check` prints.

use crate::math::{matrix_to_axis_angle, Mat3, Real, Vec3};

/// Largest deviation of `RᵀR` from the identity (per entry) accepted as a rotation.
pub(crate) const ORTHONORMAL_TOLERANCE: Real = 1e-6;

/// Why a matrix is not a rotation.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum NotRotation {
    /// `max |RᵀR − I|` over the entries.
    NotOrthonormal(Real),
    /// Orthonormal but a reflection.
    Reflection,
}

/// Checks `m` is a rotation within [`ORTHONORMAL_TOLERANCE`] and returns the rotation nearest
/// to it (`m` itself when it is orthonormal to within 1e-14).
pub(crate) fn checked_rotation(m: Mat3) -> Result<Mat3, NotRotation> {
    let gram = m.transpose() * m - Mat3::IDENTITY;
    let dev = gram
        .to_cols_array()
        .iter()
        .fold(0.0, |a: Real, v| a.max(v.abs()));
    if !(dev <= ORTHONORMAL_TOLERANCE) {
        return Err(NotRotation::NotOrthonormal(dev));
    }
    if m.determinant() < 0.0 {
        return Err(NotRotation::Reflection);
    }
    // Already orthonormal to rounding: keep it bit for bit, so a written rig reads back
    // identically.
    if dev <= 1e-14 {
        return Ok(m);
    }
    Ok(nearest_rotation(m))
}

pub(crate) use crate::math::rotation::nearest_rotation;

/// Orientation of a camera relative to the CPF as yaw, pitch and roll (radians), measured
/// from an upright camera looking along the CPF's forward axis (camera x = wearer's right,
/// y = down, z = forward):
/// `cpf_from_cam = R_y(yaw) · R_x(−pitch) · R_z(roll) · diag(−1, −1, 1)` in CPF axes
/// (x left, y up, z forward).
/// - yaw: optical axis turned towards the wearer's left (+) or right (−);
/// - pitch: optical axis raised (+) or lowered (−);
/// - roll: camera turned about its optical axis, + = clockwise as the wearer sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct YawPitchRoll {
    pub yaw_rad: Real,
    pub pitch_rad: Real,
    pub roll_rad: Real,
}

impl YawPitchRoll {
    /// The `cpf_from_cam` rotation these angles describe (the tests' oracle).
    #[cfg(test)]
    pub(crate) fn to_matrix(self) -> Mat3 {
        Mat3::from_rotation_y(self.yaw_rad)
            * Mat3::from_rotation_x(-self.pitch_rad)
            * Mat3::from_rotation_z(self.roll_rad)
            * Mat3::from_diagonal(Vec3::new(-1.0, -1.0, 1.0))
    }

    /// Decomposes a `cpf_from_cam` rotation.
    pub(crate) fn of(cpf_from_cam: Mat3) -> Self {
        let m = cpf_from_cam * Mat3::from_diagonal(Vec3::new(-1.0, -1.0, 1.0));
        let z = m.z_axis;
        Self {
            yaw_rad: z.x.atan2(z.z),
            pitch_rad: z.y.clamp(-1.0, 1.0).asin(),
            roll_rad: m.x_axis.y.atan2(m.y_axis.y),
        }
    }
}

/// Axis-angle vector of a rotation (angle = norm, radians).
pub(crate) fn axis_angle(m: Mat3) -> Vec3 {
    matrix_to_axis_angle(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_pitch_roll_round_trip() {
        for (y, p, r) in [(0.3, -0.2, 1.5), (-1.2, 0.7, -2.9), (0.0, 0.0, 0.0)] {
            let a = YawPitchRoll {
                yaw_rad: y,
                pitch_rad: p,
                roll_rad: r,
            };
            let b = YawPitchRoll::of(a.to_matrix());
            assert!((a.yaw_rad - b.yaw_rad).abs() < 1e-12);
            assert!((a.pitch_rad - b.pitch_rad).abs() < 1e-12);
            assert!((a.roll_rad - b.roll_rad).abs() < 1e-12);
        }
    }

    #[test]
    fn signs_follow_the_wearer() {
        // Camera looking to the wearer's left (+x of the CPF): yaw +90°.
        let left = YawPitchRoll::of(
            YawPitchRoll {
                yaw_rad: 0.5,
                pitch_rad: 0.0,
                roll_rad: 0.0,
            }
            .to_matrix(),
        );
        assert!(left.yaw_rad > 0.0);
        let m = YawPitchRoll {
            yaw_rad: 0.5,
            pitch_rad: 0.0,
            roll_rad: 0.0,
        }
        .to_matrix();
        assert!(m.z_axis.x > 0.0, "optical axis should point to +x (left)");
        let down = YawPitchRoll {
            yaw_rad: 0.0,
            pitch_rad: -0.2,
            roll_rad: 0.0,
        }
        .to_matrix();
        assert!(down.z_axis.y < 0.0);
    }

    #[test]
    fn nearest_rotation_cleans_rounding_and_refuses_shear() {
        let r = Mat3::from_rotation_y(0.4) * Mat3::from_rotation_x(0.1);
        let noisy = r + Mat3::from_cols_array(&[1e-8, 0.0, 2e-8, 0.0, -1e-8, 0.0, 3e-9, 0.0, 0.0]);
        let clean = checked_rotation(noisy).unwrap();
        let gram = clean.transpose() * clean - Mat3::IDENTITY;
        assert!(gram.to_cols_array().iter().all(|v| v.abs() < 1e-15));
        let shear = Mat3::from_cols(Vec3::X, Vec3::new(0.1, 1.0, 0.0), Vec3::Z);
        assert!(matches!(
            checked_rotation(shear),
            Err(NotRotation::NotOrthonormal(_))
        ));
        let flip = Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0));
        assert_eq!(checked_rotation(flip), Err(NotRotation::Reflection));
    }
}
