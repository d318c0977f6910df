//! Joins that do not show: where one motion primitive hands over to the next (or a walk to an
//! activity clip, or a body to its held pose), the decoded motion keeps its position but its
//! velocity jumps, a jolt every 0.45 s in the head's acceleration (docs/MOTION.md, "Head
//! motion"). [`smooth_joins`] removes each jump and nothing else.
//!
//! Per join and per pose channel (the pelvis translation; each joint's rotation, as the
//! rotation vectors of its left increments), the steps (frame-to-frame increments) around the
//! join are read as a kink: the step before the join (`v_b`, frame `j−2 → j−1`), the step
//! after the decoder has settled (`v_a`, [`JOIN_TRANSIENT_STEPS`] steps later) and, between,
//! a velocity that turns from one to the other at the middle of the transient (τ = 0), plus
//! a step in position `e` (what the transient moved beyond that) and the transient frames'
//! own residuals. The kink `Δv·max(τ, 0)` is replaced by its integral of a smoothstep over
//! τ ∈ [−h, h], the step `e·H(τ)` by the smoothstep, and the transient frames take the
//! model's values: the velocity turns from the old to the new over `2h` frames, `h` 8 frames
//! or, where the pelvis's velocity changes more than that turns at 2.5 m/s², up to 16
//! ([`JoinWindow`]). (A linear turn has two thirds of the smoothstep's peak acceleration but
//! moves planted feet more: foot contact of mean-action walks fell 0.01–0.02;
//! docs/records/2026-12-06-head-motion-joins-and-steady-head.md.) Outside the window the
//! motion is exactly as decoded (the replacements equal what they replace there),
//! so where the body ends up, and when, is unchanged; a foot planted across the join has no
//! jump of its own, so the corrections of the joints that carry it cancel to first order and
//! it stays planted. Corrections of nearby joins add (each is zero outside its own window).

use crate::body::{BodyParams, NUM_JOINTS};
use crate::math::{axis_angle_to_matrix, matrix_to_axis_angle, Mat3, Real, Vec3};

/// Half the window over which a join's velocity change is spread (frames; 0.2 s at 40 Hz), at
/// least.
pub(crate) const JOIN_HALF_WINDOW_FRAMES: usize = 8;

/// How wide each join's window is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct JoinWindow {
    /// Half the window, at least (frames).
    pub min_half_frames: usize,
    /// Half the window, at most (frames).
    pub max_half_frames: usize,
    /// The pelvis's acceleration a join's turn of velocity may reach, in metres per frame²:
    /// a join whose velocity changes more gets a wider window, up to the most.
    pub max_acceleration_m_per_frame2: Real,
}

impl JoinWindow {
    /// ±0.2 s, widened up to ±0.4 s so that the pelvis turns its velocity at no more than
    /// 2.5 m/s² (a reversal at a goal: 2 m/s within the window), at `rate_hz`.
    pub(crate) fn at_rate(rate_hz: Real) -> JoinWindow {
        JoinWindow {
            min_half_frames: JOIN_HALF_WINDOW_FRAMES,
            max_half_frames: 2 * JOIN_HALF_WINDOW_FRAMES,
            max_acceleration_m_per_frame2: 2.5 / (rate_hz * rate_hz),
        }
    }

    /// Half the window (frames) for a join whose pelvis velocity changes by `dv` m per frame:
    /// a smoothstep turn over ±h peaks at `0.75 |dv| / h`.
    pub(crate) fn half_frames(&self, dv: Real) -> usize {
        let needed = (0.75 * dv.abs() / self.max_acceleration_m_per_frame2).ceil();
        let needed = if needed.is_finite() {
            needed as usize
        } else {
            0
        };
        needed
            .clamp(
                self.min_half_frames,
                self.max_half_frames.max(self.min_half_frames),
            )
            .max(JOIN_TRANSIENT_STEPS / 2 + 1)
    }
}

/// Steps the decoder takes to settle after a join: the steps from `j−1 → j` on whose
/// frame-to-frame change stands above the motion inside primitives (the default take's head,
/// median acceleration by frame from the join: 25, 15, 4.9, 3.3 m/s², then 1.9 against 1.2
/// inside; docs/MOTION.md "Head motion").
pub(crate) const JOIN_TRANSIENT_STEPS: usize = 4;

/// Smoothstep rising from 0 at `τ = −h` to 1 at `τ = h`.
fn smooth_step(tau: Real, h: Real) -> Real {
    let x = ((tau + h) / (2.0 * h)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// `∫_{−∞}^{τ}` [`smooth_step`]: equals `max(τ, 0)` outside `[−h, h]`.
fn smooth_ramp(tau: Real, h: Real) -> Real {
    if tau >= h {
        tau
    } else if tau <= -h {
        0.0
    } else {
        let x = (tau + h) / (2.0 * h);
        2.0 * h * (x * x * x - 0.5 * x * x * x * x)
    }
}

/// 0, ½ or 1 before, at or after τ = 0.
fn heaviside(tau: Real) -> Real {
    if tau > 0.0 {
        1.0
    } else if tau < 0.0 {
        0.0
    } else {
        0.5
    }
}

/// How much of a join's velocity change (`kink`) and position step (`step`) to add at `τ`.
fn weights(tau: Real, h: Real) -> (Real, Real) {
    (
        smooth_ramp(tau, h) - tau.max(0.0),
        smooth_step(tau, h) - heaviside(tau),
    )
}

/// One channel's kink around a join: the velocity change, the position step and the
/// transient frames' residuals against the kink, from the channel's steps `steps[k]` (frame
/// `j−2+k → j−1+k`, `k` = 0 …, [`JOIN_TRANSIENT_STEPS`] + 1), τ measured from `centre`
/// frames after frame `j − 1`.
struct Kink {
    velocity_change: Vec3,
    step: Vec3,
    /// Residual of frames `j … j − 2 + JOIN_TRANSIENT_STEPS`.
    residuals: [Vec3; JOIN_TRANSIENT_STEPS - 1],
}

impl Kink {
    fn of(steps: &[Vec3; JOIN_TRANSIENT_STEPS + 2]) -> Kink {
        let t = JOIN_TRANSIENT_STEPS;
        let (vb, va) = (steps[0], steps[t + 1]);
        let dv = va - vb;
        let centre = 0.5 * t as Real;
        // The kink's position after `m` steps from frame j − 1 (without the step).
        let kinked = |m: Real| vb * m + dv * (m - centre).max(0.0);
        let moved: Vec3 = steps[1..=t].iter().copied().sum();
        let step = moved - kinked(t as Real);
        let mut residuals = [Vec3::ZERO; JOIN_TRANSIENT_STEPS - 1];
        let mut sum = Vec3::ZERO;
        for (m, r) in residuals.iter_mut().enumerate() {
            sum += steps[m + 1];
            let after = (m + 1) as Real;
            *r = sum - kinked(after) - step * heaviside(after - centre);
        }
        Kink {
            velocity_change: dv,
            step,
            residuals,
        }
    }
}

/// Removes the velocity jump at every join in `joins` (the first frame of what joins) from
/// `frames` in place, over a window about the middle of the decoder's transient as wide as
/// `window` gives for the pelvis's change of velocity (always holding the transient); joins
/// without two frames before them and the transient after are left alone. The corrections
/// are measured on the frames as given (before any is applied), so the result does not
/// depend on the order of `joins`.
pub(crate) fn smooth_joins(frames: &mut [BodyParams], joins: &[usize], window: &JoinWindow) {
    let n = frames.len();
    let t = JOIN_TRANSIENT_STEPS;
    let rot: Vec<[Mat3; NUM_JOINTS]> = frames
        .iter()
        .map(|f| std::array::from_fn(|j| axis_angle_to_matrix(f.joint_axis_angle(j))))
        .collect();
    let mut transl_offset = vec![Vec3::ZERO; n];
    let mut rot_offset = vec![[Vec3::ZERO; NUM_JOINTS]; n];
    for &j in joins {
        if j < 2 || j + t >= n {
            continue;
        }
        let first_step = j - 2;
        let transl = Kink::of(&std::array::from_fn(|k| {
            frames[first_step + k + 1].transl - frames[first_step + k].transl
        }));
        // Rotation increments on the left: R(f+1) = exp(ω) R(f).
        let rots: [Kink; NUM_JOINTS] = std::array::from_fn(|q| {
            Kink::of(&std::array::from_fn(|k| {
                let f = first_step + k;
                matrix_to_axis_angle(rot[f + 1][q] * rot[f][q].transpose())
            }))
        });
        let h = window.half_frames(transl.velocity_change.length()) as Real;
        let centre = (j - 1) as Real + 0.5 * t as Real;
        let first = (centre - h).floor().max(0.0) as usize;
        let last = ((centre + h).ceil() as usize).min(n - 1);
        for f in first..=last {
            let tau = f as Real - centre;
            let (wk, ws) = weights(tau, h);
            let transient = (j..j + t - 1).contains(&f).then(|| f - j);
            let offset = |k: &Kink| {
                k.velocity_change * wk + k.step * ws
                    - transient.map_or(Vec3::ZERO, |m| k.residuals[m])
            };
            transl_offset[f] += offset(&transl);
            for (o, k) in rot_offset[f].iter_mut().zip(&rots) {
                *o += offset(k);
            }
        }
    }
    for (f, frame) in frames.iter_mut().enumerate() {
        frame.transl += transl_offset[f];
        for (k, o) in rot_offset[f].iter().enumerate() {
            if *o != Vec3::ZERO {
                let r = axis_angle_to_matrix(*o) * rot[f][k];
                frame.set_joint_axis_angle(k, matrix_to_axis_angle(r));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn accel(x: &[Real], f: usize) -> Real {
        x[f + 1] - 2.0 * x[f] + x[f - 1]
    }

    /// A walk at 3 cm a frame whose velocity turns to 4 cm a frame at frame 20, and a knee
    /// turning at 0.01 rad a frame, then 0.03.
    fn kinked() -> Vec<BodyParams> {
        (0..40)
            .map(|f| {
                let mut b = BodyParams::default();
                let fx = f as Real;
                let x = if f < 20 {
                    0.03 * fx
                } else {
                    0.6 + 0.04 * (fx - 20.0) - 0.005
                };
                b.transl = Vec3::new(x, 0.0, 0.9);
                let a = if f < 20 {
                    0.01 * fx
                } else {
                    0.2 + 0.03 * (fx - 20.0)
                };
                b.set_joint_axis_angle(4, Vec3::new(a, 0.0, 0.0));
                b
            })
            .collect()
    }

    #[test]
    fn the_ramp_is_the_integral_of_the_step_and_meets_the_kink_outside_the_window() {
        let h = 6.0;
        for i in -100..=100 {
            let tau = i as Real * 0.1;
            let d = 1e-5;
            let slope = (smooth_ramp(tau + d, h) - smooth_ramp(tau - d, h)) / (2.0 * d);
            assert!((slope - smooth_step(tau, h)).abs() < 1e-6, "τ {tau}");
        }
        assert_eq!(smooth_ramp(6.0, h), 6.0);
        assert_eq!(weights(-6.0, h), (0.0, 0.0));
        assert_eq!(weights(7.5, h), (0.0, 0.0));
    }

    #[test]
    fn a_velocity_jump_is_spread_over_the_window_and_the_motion_rejoins() {
        let raw = kinked();
        let mut smooth = raw.clone();
        smooth_joins(&mut smooth, &[20], &JoinWindow::at_rate(40.0));
        let x: Vec<Real> = smooth.iter().map(|b| b.transl.x).collect();
        let x0: Vec<Real> = raw.iter().map(|b| b.transl.x).collect();
        let raw_peak = (1..39).map(|f| accel(&x0, f).abs()).fold(0.0, Real::max);
        let peak = (1..39).map(|f| accel(&x, f).abs()).fold(0.0, Real::max);
        // 1 cm a frame of velocity change (and a 5 mm step) over the window instead of one frame.
        assert!(raw_peak > 0.009, "{raw_peak}");
        assert!(peak < 0.25 * raw_peak, "{peak} against {raw_peak}");
        // Outside the window the motion is as decoded.
        let centre = 19.0 + 0.5 * JOIN_TRANSIENT_STEPS as Real;
        let h = JOIN_HALF_WINDOW_FRAMES as Real;
        for f in (0..40).filter(|&f| (f as Real - centre).abs() >= h) {
            assert!((x[f] - x0[f]).abs() < 1e-12, "frame {f}");
            assert!(
                (smooth[f].pose[12] - raw[f].pose[12]).abs() < 1e-12,
                "frame {f}"
            );
        }
        let knee: Vec<Real> = smooth.iter().map(|b| b.pose[12]).collect();
        let knee_peak = (1..39).map(|f| accel(&knee, f).abs()).fold(0.0, Real::max);
        assert!(knee_peak < 0.01, "{knee_peak}");
    }

    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Far from the origin, with a joint turned near π and another near 0, a walk whose
        /// velocity jumps at every join: the result is finite, exactly as decoded outside the
        /// windows, and its largest frame-to-frame change of velocity is at most a third of
        /// the jumps'.
        #[test]
        fn joins_are_smoothed_at_the_extremes(
            origin_km in -1000.0f64..1000.0,
            speed in 0.0f64..0.05,
            jumps in proptest::collection::vec(-0.02f64..0.02, 4),
            near_pi in 0.0f64..1e-3,
            turn in -0.02f64..0.02,
        ) {
            let joins: Vec<usize> = (0..4).map(|k| 2 + 18 * (k + 1)).collect();
            let velocity = |f: usize| {
                speed + joins.iter().zip(&jumps).filter(|(j, _)| f >= **j).map(|(_, d)| d).sum::<Real>()
            };
            let mut x = origin_km * 1e3;
            let mut a = std::f64::consts::PI - near_pi - 0.3;
            let raw: Vec<BodyParams> = (0..100)
                .map(|f| {
                    let mut b = BodyParams {
                        transl: Vec3::new(x, -origin_km * 1e3, 0.9),
                        ..Default::default()
                    };
                    b.set_joint_axis_angle(1, Vec3::new(0.0, 0.0, a));
                    b.set_joint_axis_angle(2, Vec3::new(near_pi, 0.0, 0.0));
                    x += velocity(f + 1);
                    a += turn * velocity(f + 1) / (speed + 0.05);
                    b
                })
                .collect();
            let mut smooth = raw.clone();
            let window = JoinWindow::at_rate(40.0);
            smooth_joins(&mut smooth, &joins, &window);
            // The widest window any join may get.
            let h = window.max_half_frames as Real;
            let centre = |j: usize| (j - 1) as Real + 0.5 * JOIN_TRANSIENT_STEPS as Real;
            for (f, (s, r)) in smooth.iter().zip(&raw).enumerate() {
                prop_assert!(s.transl.is_finite() && s.pose.iter().all(|v| v.is_finite()));
                if joins.iter().all(|&j| (f as Real - centre(j)).abs() >= h) {
                    prop_assert_eq!(s.transl, r.transl);
                    prop_assert_eq!(s.pose, r.pose);
                }
            }
            let peak = |b: &[BodyParams]| {
                (1..b.len() - 1)
                    .map(|f| (b[f + 1].transl.x - 2.0 * b[f].transl.x + b[f - 1].transl.x).abs())
                    .fold(0.0, Real::max)
            };
            let largest_jump = jumps.iter().map(|d| d.abs()).fold(0.0, Real::max);
            prop_assert!(peak(&smooth) <= largest_jump / 3.0 + 1e-6, "{} against {}", peak(&smooth), largest_jump);
        }
    }

    #[test]
    fn a_larger_change_of_velocity_gets_a_wider_window_up_to_the_most() {
        let w = JoinWindow::at_rate(40.0);
        assert_eq!(w.half_frames(0.0), JOIN_HALF_WINDOW_FRAMES);
        // 0.6 m/s: inside ±0.2 s at 2.5 m/s².
        assert_eq!(w.half_frames(0.6 / 40.0), JOIN_HALF_WINDOW_FRAMES);
        // 1.2 m/s needs ±0.36 s; 2 m/s is held at ±0.4 s.
        assert_eq!(w.half_frames(1.2 / 40.0), 15);
        assert_eq!(w.half_frames(2.0 / 40.0), 2 * JOIN_HALF_WINDOW_FRAMES);
        assert_eq!(w.half_frames(Real::NAN), JOIN_HALF_WINDOW_FRAMES);
    }

    #[test]
    fn a_smooth_motion_is_left_as_it_is() {
        let raw: Vec<BodyParams> = (0..40)
            .map(|f| {
                let mut b = BodyParams {
                    transl: Vec3::new(0.03 * f as Real, 0.0, 0.9),
                    ..Default::default()
                };
                b.set_joint_axis_angle(4, Vec3::new(0.01 * f as Real, 0.0, 0.0));
                b
            })
            .collect();
        let mut smooth = raw.clone();
        smooth_joins(&mut smooth, &[2, 20, 38], &JoinWindow::at_rate(40.0));
        for (a, b) in smooth.iter().zip(&raw) {
            assert!((a.transl - b.transl).length() < 1e-12);
            assert!((a.pose[12] - b.pose[12]).abs() < 1e-12);
        }
    }
}
