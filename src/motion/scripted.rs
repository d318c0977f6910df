//! A scripted walk cycle: a hand-written periodic gait for demos and tests, used until the
//! learned motion model drives bodies. World frame is z up; the body walks along +x.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::MotionSequence;
use crate::body::{joint, BodyParams, POSE_DIM};
use crate::math::{axis_angle_to_matrix, matrix_to_axis_angle, Mat3, Vec3};

/// Settings of the scripted walk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WalkCycle {
    /// Walking speed (m/s).
    pub speed_m_s: f64,
    /// Steps per second (two steps per gait cycle).
    pub cadence_steps_per_s: f64,
    /// Peak hip flexion (radians).
    pub hip_swing_rad: f64,
}

impl Default for WalkCycle {
    fn default() -> Self {
        Self {
            speed_m_s: 1.2,
            cadence_steps_per_s: 1.8,
            hip_swing_rad: 0.45,
        }
    }
}

impl WalkCycle {
    /// Pose of the walk at time `t_s`, for a body whose rest pelvis is `rest_pelvis` and whose
    /// soles are at height `rest_sole_y` (both in the model's y-up frame).
    pub(crate) fn params_at(
        &self,
        t_s: f64,
        betas: &[f64],
        rest_pelvis: Vec3,
        rest_sole_y: f64,
    ) -> BodyParams {
        let phase = TAU * 0.5 * self.cadence_steps_per_s * t_s;
        let (s, c) = phase.sin_cos();
        let mut p = BodyParams {
            betas: betas.to_vec(),
            ..Default::default()
        };
        let rot = |axis: Vec3, angle: f64| axis_angle_to_matrix(axis * angle);
        // Model y-up/z-forward → world z-up, facing +x: rotate +90° about x, then +90° about z.
        let world_from_body = rot(Vec3::Z, FRAC_PI_2) * rot(Vec3::X, FRAC_PI_2);
        let sway = rot(Vec3::Y, 0.08 * s);
        set(&mut p, joint::PELVIS, world_from_body * sway);
        // Legs: hip flexion is a negative rotation about x; knees flex during swing.
        let hip = self.hip_swing_rad;
        set(&mut p, joint::LEFT_HIP, rot(Vec3::X, -hip * s));
        set(&mut p, joint::RIGHT_HIP, rot(Vec3::X, hip * s));
        let knee = |ph: f64| 0.15 + 0.55 * (ph.sin().max(0.0)).powi(2);
        set(
            &mut p,
            joint::LEFT_KNEE,
            rot(Vec3::X, knee(phase + 0.5 * PI)),
        );
        set(
            &mut p,
            joint::RIGHT_KNEE,
            rot(Vec3::X, knee(phase + 1.5 * PI)),
        );
        set(&mut p, joint::LEFT_ANKLE, rot(Vec3::X, 0.1 * c));
        set(&mut p, joint::RIGHT_ANKLE, rot(Vec3::X, -0.1 * c));
        // Arms down from the T-pose, swinging against the legs, elbows a little bent.
        set(
            &mut p,
            joint::LEFT_SHOULDER,
            rot(Vec3::X, 0.35 * s) * rot(Vec3::Z, -1.25),
        );
        set(
            &mut p,
            joint::RIGHT_SHOULDER,
            rot(Vec3::X, -0.35 * s) * rot(Vec3::Z, 1.25),
        );
        set(&mut p, joint::LEFT_ELBOW, rot(Vec3::Y, -0.35));
        set(&mut p, joint::RIGHT_ELBOW, rot(Vec3::Y, 0.35));
        // Feet on z = 0: the pelvis height above the soles, with a small bob.
        let height = rest_pelvis.y - rest_sole_y - 0.02 * (1.0 - (2.0 * phase).cos());
        let pelvis_world = Vec3::new(self.speed_m_s * t_s, 0.0, height);
        // LBS rotates about the rest pelvis: transl = pelvis_world − rest_pelvis.
        p.transl = pelvis_world - rest_pelvis;
        p
    }

    /// A sequence of `duration_s` seconds at `frame_rate_hz`.
    pub(crate) fn sequence(
        &self,
        duration_s: f64,
        frame_rate_hz: f64,
        betas: &[f64],
        rest_pelvis: Vec3,
        rest_sole_y: f64,
    ) -> MotionSequence {
        let n = (duration_s * frame_rate_hz).round().max(1.0) as usize;
        let frames: Vec<BodyParams> = (0..n)
            .map(|i| self.params_at(i as f64 / frame_rate_hz, betas, rest_pelvis, rest_sole_y))
            .collect();
        MotionSequence {
            frame_rate_hz,
            betas: betas.to_vec(),
            gender: "neutral".into(),
            poses: frames
                .iter()
                .map(|f| f.pose)
                .collect::<Vec<[f64; POSE_DIM]>>(),
            trans: frames.iter().map(|f| f.transl).collect(),
        }
    }
}

fn set(p: &mut BodyParams, j: usize, r: Mat3) {
    p.set_joint_axis_angle(j, matrix_to_axis_angle(r));
}
