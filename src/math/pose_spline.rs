//! A C²-continuous rigid-body trajectory through poses sampled at a fixed rate: uniform cubic
//! B-splines on R³ × SO(3) (the *split* form of Sommer et al., "Efficient Derivative
//! Computation for Cumulative B-Splines on Lie Groups", CVPR 2020): a cubic B-spline for the
//! position in the world, and a cumulative cubic B-spline for the rotation
//! (`R(t) = Q₋₁ · Π Exp(B̃ⱼ(u) · Log(Qⱼ₋₁⁻¹ Qⱼ))`). The split form gives the world
//! acceleration an accelerometer needs directly as the position's second derivative.
//!
//! The control points are solved so that the spline passes through every given pose at its
//! time (interpolation, not approximation): a tridiagonal solve for the positions, and for the
//! rotations the same solve on the tangent-space residuals, repeated until they vanish. Both
//! ends are natural (no second derivative at the first and last pose), so one primitive or a
//! standing body gives a still trajectory, not an overshoot.
//!
//! Derivatives are analytic: velocity and acceleration in the world, angular velocity and
//! angular acceleration in the body frame (`Ṙ = R [ω]×`).

use super::rotation::{axis_angle_to_matrix, matrix_to_axis_angle, nearest_rotation};
use super::{Affine3, Mat3, Real, Vec3};

/// The trajectory's state at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseSample {
    /// The body's pose: maps body-frame points into the world.
    pub world_from_body: Affine3,
    /// Velocity of the body's origin in the world (m/s).
    pub velocity_world: Vec3,
    /// Acceleration of the body's origin in the world (m/s²), gravity not included.
    pub acceleration_world: Vec3,
    /// Angular velocity in the body frame (rad/s): `Ṙ = R [ω]×`.
    pub angular_velocity_body: Vec3,
    /// Its time derivative, in the body frame (rad/s²).
    pub angular_acceleration_body: Vec3,
}

impl PoseSample {
    /// The state of a frame rigidly attached to the body at `body_from_frame`.
    pub(crate) fn attached(&self, body_from_frame: Affine3) -> PoseSample {
        let r = self.world_from_body.matrix3;
        let t = body_from_frame.translation;
        let w = self.angular_velocity_body;
        let a = self.angular_acceleration_body;
        let frame_from_body = body_from_frame.matrix3.transpose();
        PoseSample {
            world_from_body: self.world_from_body * body_from_frame,
            velocity_world: self.velocity_world + r * w.cross(t),
            acceleration_world: self.acceleration_world + r * (a.cross(t) + w.cross(w.cross(t))),
            angular_velocity_body: frame_from_body * w,
            angular_acceleration_body: frame_from_body * a,
        }
    }
}

/// Why poses cannot be splined.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PoseSplineError {
    #[error("no poses to spline")]
    Empty,
    #[error("the pose rate must be a positive finite number of Hz, got {0}")]
    Rate(Real),
    #[error("pose {index} is not finite")]
    NonFinite { index: usize },
    #[error(
        "poses {index} and {} turn by {angle_rad:.3} rad between two samples; a spline needs \
         less than π (sample the motion faster)",
        index + 1
    )]
    TurnTooFast { index: usize, angle_rad: Real },
    #[error(
        "the rotations turn too fast between samples for an interpolating spline: it misses a \
         pose by {residual_rad:.1e} rad (sample the motion faster)"
    )]
    NotInterpolated { residual_rad: Real },
}

/// Largest miss of a given rotation the solve accepts (rad).
pub(crate) const MAX_ROTATION_RESIDUAL_RAD: Real = 1e-9;

/// An interpolating C² trajectory through poses at `frame_rate_hz`, from time 0.
#[derive(Debug, Clone)]
pub struct PoseSpline {
    dt: Real,
    /// Positions of the control points `c₋₁ … c_N` (N + 2 for N poses).
    positions: Vec<Vec3>,
    /// Rotations of the control points `Q₋₁ … Q_N`.
    rotations: Vec<Mat3>,
    /// `Log(Qₖ⁻¹ Qₖ₊₁)` for consecutive control rotations.
    increments: Vec<Vec3>,
    /// Largest angle between a given rotation and the spline's at its time, after the solve.
    residual_rad: Real,
}

/// Tangent-space residuals below this are solved (rad); the iteration stops there.
const ROTATION_TOLERANCE_RAD: Real = 1e-13;
/// Rotation refinements at most; each about squares the residual, a handful suffice.
const MAX_ITERATIONS: usize = 50;

impl PoseSpline {
    /// The spline through `poses` (pose `i` at time `i / frame_rate_hz`). Their rotations are
    /// snapped to the nearest rotation first.
    pub fn interpolate(frame_rate_hz: Real, poses: &[Affine3]) -> Result<Self, PoseSplineError> {
        if !(frame_rate_hz.is_finite() && frame_rate_hz > 0.0) {
            return Err(PoseSplineError::Rate(frame_rate_hz));
        }
        if poses.is_empty() {
            return Err(PoseSplineError::Empty);
        }
        if let Some(index) = poses.iter().position(|p| !p.is_finite()) {
            return Err(PoseSplineError::NonFinite { index });
        }
        let targets: Vec<Mat3> = poses.iter().map(|p| nearest_rotation(p.matrix3)).collect();
        for (index, w) in targets.windows(2).enumerate() {
            let angle_rad = matrix_to_axis_angle(w[0].transpose() * w[1]).length();
            if angle_rad > 0.95 * std::f64::consts::PI {
                return Err(PoseSplineError::TurnTooFast { index, angle_rad });
            }
        }
        // One pose: a still body (two equal poses give the same spline).
        let (targets, positions): (Vec<Mat3>, Vec<Vec3>) = if poses.len() == 1 {
            (vec![targets[0]; 2], vec![poses[0].translation; 2])
        } else {
            (targets, poses.iter().map(|p| p.translation).collect())
        };
        let n = targets.len();
        let mut spline = PoseSpline {
            dt: 1.0 / frame_rate_hz,
            positions: solve_natural(&positions),
            rotations: Vec::new(),
            increments: Vec::new(),
            residual_rad: 0.0,
        };
        let mut control: Vec<Mat3> = targets.clone();
        for _ in 0..MAX_ITERATIONS {
            spline.set_rotations(&control);
            let residuals: Vec<Vec3> = (0..n)
                .map(|i| {
                    let r = spline.rotation_at_knot(i);
                    matrix_to_axis_angle(r.transpose() * targets[i])
                })
                .collect();
            spline.residual_rad = residuals.iter().map(|r| r.length()).fold(0.0, Real::max);
            if spline.residual_rad < ROTATION_TOLERANCE_RAD {
                break;
            }
            let deltas = solve_with_fixed_ends(&residuals);
            for (q, d) in control.iter_mut().zip(&deltas) {
                *q = nearest_rotation(*q * axis_angle_to_matrix(*d));
            }
        }
        if spline.residual_rad > MAX_ROTATION_RESIDUAL_RAD {
            return Err(PoseSplineError::NotInterpolated {
                residual_rad: spline.residual_rad,
            });
        }
        Ok(spline)
    }

    /// Time of the last pose (s); the spline is defined on `[0, duration_s]`.
    pub fn duration_s(&self) -> Real {
        (self.positions.len() - 3) as Real * self.dt
    }

    /// Largest angle (rad) between a given pose's rotation and the spline's at its time.
    pub(crate) fn rotation_residual_rad(&self) -> Real {
        self.residual_rad
    }

    /// The trajectory's state at `t` seconds, clamped to `[0, duration_s]`.
    pub fn sample(&self, t: Real) -> PoseSample {
        let segments = self.positions.len() - 3;
        let s = (t / self.dt).clamp(0.0, segments as Real);
        let i = (s.floor() as usize).min(segments - 1);
        let u = s - i as Real;
        let (inv_dt, inv_dt2) = (1.0 / self.dt, 1.0 / (self.dt * self.dt));

        let c = &self.positions[i..i + 4];
        let um = 1.0 - u;
        let b = [
            um * um * um / 6.0,
            (3.0 * u * u * u - 6.0 * u * u + 4.0) / 6.0,
            (-3.0 * u * u * u + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
            u * u * u / 6.0,
        ];
        let db = [
            -um * um / 2.0,
            (3.0 * u * u - 4.0 * u) / 2.0,
            (-3.0 * u * u + 2.0 * u + 1.0) / 2.0,
            u * u / 2.0,
        ];
        let ddb = [um, 3.0 * u - 2.0, 1.0 - 3.0 * u, u];
        let combine = |w: [Real; 4]| c[0] * w[0] + c[1] * w[1] + c[2] * w[2] + c[3] * w[3];
        let position = combine(b);
        let velocity = combine(db) * inv_dt;
        let acceleration = combine(ddb) * inv_dt2;

        // Cumulative basis B̃₁..B̃₃ and their derivatives in u.
        let cb = cumulative_basis(u);
        let dcb = [
            um * um / 2.0,
            (1.0 + 2.0 * u - 2.0 * u * u) / 2.0,
            u * u / 2.0,
        ];
        let ddcb = [u - 1.0, 1.0 - 2.0 * u, u];
        let mut rotation = self.rotations[i];
        let mut omega = Vec3::ZERO;
        let mut alpha = Vec3::ZERO;
        for j in 0..3 {
            let inc = self.increments[i + j];
            let a = axis_angle_to_matrix(inc * cb[j]);
            let at = a.transpose();
            let (d1, d2) = (dcb[j] * inv_dt, ddcb[j] * inv_dt2);
            let carried = at * omega;
            alpha = at * alpha - (inc * d1).cross(carried) + inc * d2;
            omega = carried + inc * d1;
            rotation *= a;
        }
        PoseSample {
            world_from_body: Affine3 {
                matrix3: rotation,
                translation: position,
            },
            velocity_world: velocity,
            acceleration_world: acceleration,
            angular_velocity_body: omega,
            angular_acceleration_body: alpha,
        }
    }

    /// The spline's rotation at pose `i`'s time (segment `i`, u = 0; the last pose at u = 1).
    fn rotation_at_knot(&self, i: usize) -> Mat3 {
        let segments = self.rotations.len() - 3;
        let (seg, u) = if i < segments {
            (i, 0.0)
        } else {
            (segments - 1, 1.0)
        };
        let cb = cumulative_basis(u);
        let mut r = self.rotations[seg];
        for (j, w) in cb.iter().enumerate() {
            r *= axis_angle_to_matrix(self.increments[seg + j] * *w);
        }
        r
    }

    /// Sets the control rotations from `Q₀ … Q_{N−1}`, reflecting one more at each end
    /// (`Q₋₁ = Q₀ Exp(−Log(Q₀⁻¹ Q₁))`), which makes the ends natural and exact.
    fn set_rotations(&mut self, inner: &[Mat3]) {
        let n = inner.len();
        let first = matrix_to_axis_angle(inner[0].transpose() * inner[1]);
        let last = matrix_to_axis_angle(inner[n - 2].transpose() * inner[n - 1]);
        self.rotations.clear();
        self.rotations.push(inner[0] * axis_angle_to_matrix(-first));
        self.rotations.extend_from_slice(inner);
        self.rotations
            .push(inner[n - 1] * axis_angle_to_matrix(last));
        self.increments = self
            .rotations
            .windows(2)
            .map(|w| matrix_to_axis_angle(w[0].transpose() * w[1]))
            .collect();
    }
}

/// The cumulative cubic B-spline basis `B̃₁..B̃₃` at `u` in [0, 1] (B̃₀ = 1).
fn cumulative_basis(u: Real) -> [Real; 3] {
    [
        (5.0 + 3.0 * u - 3.0 * u * u + u * u * u) / 6.0,
        (1.0 + 3.0 * u + 3.0 * u * u - 2.0 * u * u * u) / 6.0,
        u * u * u / 6.0,
    ]
}

/// Control points `c₋₁ … c_N` of the natural cubic B-spline through `p₀ … p_{N−1}` (N ≥ 2):
/// `(cᵢ₋₁ + 4cᵢ + cᵢ₊₁) / 6 = pᵢ`, `c₋₁ − 2c₀ + c₁ = 0` and the same at the end.
fn solve_natural(p: &[Vec3]) -> Vec<Vec3> {
    let n = p.len();
    let inner = solve_with_fixed_ends(p);
    let mut c = Vec::with_capacity(n + 2);
    c.push(inner[0] * 2.0 - inner[1]);
    c.extend_from_slice(&inner);
    c.push(inner[n - 1] * 2.0 - inner[n - 2]);
    c
}

/// Solves `(xᵢ₋₁ + 4xᵢ + xᵢ₊₁) / 6 = rᵢ` for the interior, with `x₀ = r₀`, `x_{N−1} = r_{N−1}`
/// (what natural ends reduce to), by the Thomas algorithm.
fn solve_with_fixed_ends(r: &[Vec3]) -> Vec<Vec3> {
    let n = r.len();
    let mut x = r.to_vec();
    if n <= 2 {
        return x;
    }
    // Interior unknowns x₁ … x_{N−2}: x_{i−1} + 4 x_i + x_{i+1} = 6 r_i.
    let m = n - 2;
    let mut diag = vec![4.0; m];
    let mut rhs: Vec<Vec3> = (1..n - 1).map(|i| r[i] * 6.0).collect();
    rhs[0] -= x[0];
    rhs[m - 1] -= x[n - 1];
    for k in 1..m {
        let w = 1.0 / diag[k - 1];
        diag[k] -= w;
        let prev = rhs[k - 1];
        rhs[k] -= prev * w;
    }
    x[m] = rhs[m - 1] / diag[m - 1];
    for k in (0..m - 1).rev() {
        x[k + 1] = (rhs[k] - x[k + 2]) / diag[k];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wobble(n: usize, rate: Real) -> Vec<Affine3> {
        (0..n)
            .map(|i| {
                let t = i as Real / rate;
                let aa = Vec3::new(0.3 * (2.1 * t).sin(), 1.7 * t, 0.2 * (3.3 * t).cos());
                Affine3 {
                    matrix3: axis_angle_to_matrix(aa),
                    translation: Vec3::new(1.2 * t, 0.05 * (11.0 * t).sin(), 1.6 + 0.02 * t),
                }
            })
            .collect()
    }

    #[test]
    fn passes_through_every_pose() {
        let poses = wobble(200, 40.0);
        let s = PoseSpline::interpolate(40.0, &poses).unwrap();
        assert!(s.rotation_residual_rad() < 1e-12);
        for (i, p) in poses.iter().enumerate() {
            let q = s.sample(i as Real / 40.0).world_from_body;
            assert!((q.translation - p.translation).length() < 1e-12, "pose {i}");
            let angle = matrix_to_axis_angle(q.matrix3.transpose() * p.matrix3).length();
            assert!(angle < 1e-12, "pose {i}: {angle}");
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let poses = wobble(40, 40.0);
        let s = PoseSpline::interpolate(40.0, &poses).unwrap();
        let h = 1e-5;
        for &t in &[0.1137, 0.3337, 0.5123, 0.6617] {
            let (a, b, c) = (s.sample(t - h), s.sample(t), s.sample(t + h));
            let p = |x: &PoseSample| x.world_from_body.translation;
            let v = (p(&c) - p(&a)) / (2.0 * h);
            assert!((v - b.velocity_world).length() < 1e-6);
            let acc = (c.velocity_world - a.velocity_world) / (2.0 * h);
            assert!(
                (acc - b.acceleration_world).length() < 1e-5,
                "{t}: {acc} {}",
                b.acceleration_world
            );
            let dr = b.world_from_body.matrix3.transpose() * c.world_from_body.matrix3;
            let w = matrix_to_axis_angle(dr) / h;
            assert!(
                (w - b.angular_velocity_body).length() < 1e-3,
                "{w} {}",
                b.angular_velocity_body
            );
            let al = (c.angular_velocity_body - a.angular_velocity_body) / (2.0 * h);
            assert!((al - b.angular_acceleration_body).length() < 1e-4);
        }
    }

    #[test]
    fn c2_across_knots() {
        let poses = wobble(30, 40.0);
        let s = PoseSpline::interpolate(40.0, &poses).unwrap();
        for k in 1..28 {
            let t = k as Real / 40.0;
            let (a, b) = (s.sample(t - 1e-9), s.sample(t + 1e-9));
            assert!((a.acceleration_world - b.acceleration_world).length() < 1e-5);
            assert!((a.angular_acceleration_body - b.angular_acceleration_body).length() < 1e-5);
        }
    }

    #[test]
    fn one_pose_and_still_poses_stand_still() {
        let p = wobble(1, 40.0);
        for poses in [p.clone(), vec![p[0]; 7]] {
            let s = PoseSpline::interpolate(40.0, &poses).unwrap();
            for t in [0.0, 0.01, 0.1] {
                let x = s.sample(t);
                assert!(x.velocity_world.length() < 1e-12, "{}", x.velocity_world);
                assert!(x.angular_velocity_body.length() < 1e-12);
                assert!((x.world_from_body.translation - p[0].translation).length() < 1e-12);
            }
        }
    }

    #[test]
    fn attached_frame_matches_its_own_finite_differences() {
        let poses = wobble(40, 40.0);
        let s = PoseSpline::interpolate(40.0, &poses).unwrap();
        let off = Affine3 {
            matrix3: axis_angle_to_matrix(Vec3::new(0.1, -0.4, 1.2)),
            translation: Vec3::new(0.07, -0.02, 0.1),
        };
        let h = 1e-5;
        let t = 0.4123;
        let (a, b, c) = (
            s.sample(t - h).attached(off),
            s.sample(t).attached(off),
            s.sample(t + h).attached(off),
        );
        let v = (c.world_from_body.translation - a.world_from_body.translation) / (2.0 * h);
        assert!((v - b.velocity_world).length() < 1e-6);
        let acc = (c.velocity_world - a.velocity_world) / (2.0 * h);
        assert!((acc - b.acceleration_world).length() < 1e-5);
        let w =
            matrix_to_axis_angle(a.world_from_body.matrix3.transpose() * c.world_from_body.matrix3)
                / (2.0 * h);
        assert!((w - b.angular_velocity_body).length() < 1e-6);
    }

    #[test]
    fn refuses_what_it_cannot_spline() {
        assert_eq!(
            PoseSpline::interpolate(40.0, &[]).unwrap_err(),
            PoseSplineError::Empty
        );
        assert!(matches!(
            PoseSpline::interpolate(0.0, &wobble(3, 40.0)),
            Err(PoseSplineError::Rate(_))
        ));
        let mut p = wobble(3, 40.0);
        p[1].translation.x = Real::NAN;
        assert!(matches!(
            PoseSpline::interpolate(40.0, &p),
            Err(PoseSplineError::NonFinite { index: 1 })
        ));
    }
}
