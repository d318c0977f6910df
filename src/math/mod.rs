//! Shared math vocabulary: scalar and vector aliases, frame conventions, rotation maps, seeded
//! random draws, colour conversions, small least-squares solves.
//!
//! Conventions used across egogen:
//! - Lengths are metres, angles radians, time seconds unless a name says otherwise.
//! - A transform is named `a_from_b`: it maps points expressed in frame `b` into frame `a`
//!   (`point_in_world = world_from_head * point_in_head`).
//! - The SMPL-X body frame is y up, z forward (the body faces +z), x towards the body's left.
//! - The world of a generated scene is z up (see `scene`); camera annotations use the OpenCV
//!   camera frame (x right, y down, z forward).
//! - Rotations are right-handed; axis-angle vectors have angle = norm, in radians.

pub mod colour;
pub mod least_squares;
pub mod pose_spline;
pub mod random;
pub mod rotation;

/// Scalar used for geometry. Body maths runs in `f64` so that long kinematic chains and
/// large betas stay well inside the 1e-5 m tolerance of the `smplx` oracle.
pub type Real = f64;
/// 3-vector of [`Real`].
pub type Vec3 = glam::DVec3;
/// 3×3 matrix of [`Real`] (column-major, as glam stores it).
pub type Mat3 = glam::DMat3;
/// Rigid or affine 3D transform of [`Real`]: a [`Mat3`] plus a translation.
pub type Affine3 = glam::DAffine3;

pub use rotation::{axis_angle_to_matrix, matrix_to_axis_angle, matrix_to_rot6d, rot6d_to_matrix};

/// The `p` quantile (0–1, nearest rank) of `sorted` (ascending, finite); NaN for none.
pub fn quantile(sorted: &[Real], p: Real) -> Real {
    if sorted.is_empty() {
        Real::NAN
    } else {
        sorted[((sorted.len() - 1) as Real * p.clamp(0.0, 1.0)).round() as usize]
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
