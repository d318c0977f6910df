//! Finger motion: the SMPL-X hand pose (30 finger joints, axis-angle, read by `smplx` with
//! `use_pca=False`) of a person over a take, made procedurally — no finger mocap is openly
//! licensed. The model is a coupled curl (the idea of Infinigen's `objects/human.py`, BSD-3,
//! reimplemented): each finger has one curl, split over its three joints in fixed shares and
//! added to the body model's relaxed rest hand, plus a spread of the fingers in the palm's
//! plane. What a hand does on a frame ([`HandDoing`]: walking, standing, seated, reaching,
//! holding) sets its target curls; each person draws its own hand ([`HandStyle`]: curls, spread,
//! the split and a slow drift); the targets are smoothed over time (a zero-phase Gaussian, so
//! the hand preshapes a little before it reaches) and every joint is kept inside its
//! anatomical range ([`JOINT_RANGES_DEG`], measured with the rest hand's own flexion).
//!
//! The joints' axes come from the person's rest skeleton ([`HandAxes`]): a finger flexes about
//! the axis across its bone and the palm's normal (the model's rest hand has its palm facing
//! −y, docs/BODY_MODEL.md), the thumb towards the palm and the little finger.

use rand_chacha::ChaCha8Rng;

use crate::body::{BodyParams, NUM_JOINTS};
use crate::math::random::{standard_normal, uniform_in};
use crate::math::{axis_angle_to_matrix, gaussian_smooth, matrix_to_axis_angle, Real, Vec3};

/// First SMPL-X joint of each hand's 15 finger joints (left, right).
pub(crate) const HAND_FIRST_JOINT: [usize; 2] = [25, 40];

/// Offset of each finger's first joint among its hand's 15 (SMPL-X order: index, middle,
/// pinky, ring, thumb), indexed thumb to little finger.
const FINGER_OFFSET: [usize; 5] = [12, 0, 3, 9, 6];

/// The wrists (left, right).
const WRIST: [usize; 2] = [20, 21];

/// Anatomical flexion range of each finger joint (degrees, rest flexion included; negative:
/// extension), indexed `[finger][joint]` thumb to little finger, joints from the palm out (for the
/// thumb: CMC, MCP, IP). Active ranges of motion of the hand (American Academy of Orthopaedic
/// Surgeons' norms, rounded).
pub(crate) const JOINT_RANGES_DEG: [[(Real, Real); 3]; 5] = [
    [(-15.0, 50.0), (-10.0, 60.0), (-15.0, 80.0)],
    [(-20.0, 90.0), (0.0, 110.0), (-5.0, 85.0)],
    [(-20.0, 90.0), (0.0, 110.0), (-5.0, 85.0)],
    [(-20.0, 90.0), (0.0, 110.0), (-5.0, 85.0)],
    [(-20.0, 90.0), (0.0, 110.0), (-5.0, 85.0)],
];

/// Degrees of flexion a curl of 1 adds at each joint (a fist), `[finger][joint]`: the
/// coupled curl's split over the three joints.
const CURL_DEG: [[Real; 3]; 5] = [
    [35.0, 45.0, 60.0],
    [80.0, 95.0, 65.0],
    [80.0, 95.0, 65.0],
    [80.0, 95.0, 65.0],
    [80.0, 95.0, 65.0],
];

/// Degrees of spread a spread of 1 turns each finger's first joint in the palm's plane, away
/// from the middle finger (the thumb: away from the index).
const SPREAD_DEG: [Real; 5] = [12.0, 8.0, 0.0, 6.0, 12.0];

/// What a hand does on a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HandDoing {
    /// Hanging relaxed, swinging with the walk.
    Walking,
    /// At rest by the body.
    Standing,
    /// Resting on the thighs or the seat: nearly flat.
    Seated,
    /// Opening to take hold of something.
    Reaching,
    /// Closed round something held, `grip_mm` wide where the fingers wrap it.
    Holding { grip_mm: u16 },
}

impl HandDoing {
    /// Holding something as wide as a cup.
    pub const HOLDING_A_CUP: HandDoing = HandDoing::Holding { grip_mm: 80 };
}

/// Each finger's curl and the hand's spread for one [`HandDoing`], before a person's own
/// offsets (curl 0: the rest hand; 1: a fist).
fn target(doing: HandDoing) -> ([Real; 5], Real) {
    match doing {
        HandDoing::Walking => ([0.15, 0.20, 0.26, 0.32, 0.38], -0.4),
        HandDoing::Standing => ([0.12, 0.16, 0.22, 0.28, 0.34], -0.3),
        HandDoing::Seated => ([0.05, 0.06, 0.08, 0.10, 0.12], -0.5),
        HandDoing::Reaching => ([-0.10, -0.08, -0.08, -0.05, -0.02], 0.6),
        HandDoing::Holding { grip_mm } => {
            let k = grip_curl(grip_mm);
            ([0.55 * k, 0.60 * k, 0.64 * k, 0.68 * k, 0.72 * k], -0.6)
        }
    }
}

/// How much a grip closes the hand, against one round a 60 mm object (the targets' curls are
/// scaled by it): wider things open it, narrower ones close it further.
fn grip_curl(grip_mm: u16) -> Real {
    ((160.0 - grip_mm as Real) / 100.0).clamp(0.35, 1.25)
}

/// How much a person's relaxed hand may differ from the targets, and its drift.
const STYLE_CURL_SD: Real = 0.06;
const STYLE_SPREAD_SD: Real = 0.25;
/// Drift of each finger's curl: the sum of [`DRIFT_WAVES`] sines of these periods and a
/// total amplitude (curl units) — slow enough to be smooth at 40 Hz.
const DRIFT_PERIOD_S: (Real, Real) = (2.0, 9.0);
const DRIFT_AMPLITUDE: Real = 0.05;
const DRIFT_WAVES: usize = 3;
/// σ of the Gaussian the targets are smoothed with (s): a change of what a hand does takes
/// about 4σ.
pub(crate) const SMOOTHING_S: Real = 0.09;

/// One person's hands: its relaxed curls, spread, the split of a curl over the joints and the
/// drift of each finger, both hands alike but for the drift's phases.
#[derive(Debug, Clone, PartialEq)]
pub struct HandStyle {
    /// Added to every target curl, per finger.
    pub curl: [Real; 5],
    /// Added to every target spread.
    pub spread: Real,
    /// Scales each joint's share of a curl (`[finger][joint]`, about 1).
    pub split: [[Real; 3]; 5],
    /// Per hand and finger: `(period s, phase rad, amplitude)` of each drift wave.
    pub drift: [[[(Real, Real, Real); DRIFT_WAVES]; 5]; 2],
}

impl HandStyle {
    /// A person's hands drawn from `rng`.
    pub fn draw(rng: &mut ChaCha8Rng) -> HandStyle {
        let curl = std::array::from_fn(|_| STYLE_CURL_SD * standard_normal(rng));
        let spread = STYLE_SPREAD_SD * standard_normal(rng);
        let split = std::array::from_fn(|_| {
            std::array::from_fn(|_| (1.0 + 0.08 * standard_normal(rng)).clamp(0.8, 1.2))
        });
        let drift = std::array::from_fn(|_| {
            std::array::from_fn(|_| {
                std::array::from_fn(|_| {
                    let period = uniform_in(rng, DRIFT_PERIOD_S.0, DRIFT_PERIOD_S.1);
                    let phase = uniform_in(rng, 0.0, std::f64::consts::TAU);
                    let amplitude =
                        DRIFT_AMPLITUDE / DRIFT_WAVES as Real * uniform_in(rng, 0.5, 1.5);
                    (period, phase, amplitude)
                })
            })
        });
        HandStyle {
            curl,
            spread,
            split,
            drift,
        }
    }

    /// The drift of `hand`'s `finger` at time `t` (s).
    fn drift_at(&self, hand: usize, finger: usize, t: Real) -> Real {
        self.drift[hand][finger]
            .iter()
            .map(|&(period, phase, amplitude)| {
                amplitude * (std::f64::consts::TAU * t / period + phase).sin()
            })
            .sum()
    }
}

/// Each finger joint's axes and rest flexion, from a person's rest skeleton.
#[derive(Debug, Clone, PartialEq)]
pub struct HandAxes {
    /// Flexion axis of each finger joint, `[hand][finger][joint]` (a positive angle curls the
    /// finger towards the palm).
    pub flex: [[[Vec3; 3]; 5]; 2],
    /// Axis of each finger's spread at its first joint, square to its flexion axis (a positive
    /// angle turns it away from the middle finger; the thumb away from the index).
    pub spread: [[Vec3; 5]; 2],
    /// Flexion of each joint in the rest hand (rad): the angle its bone makes with the bone
    /// before it, about its flexion axis.
    pub rest_flex: [[[Real; 3]; 5]; 2],
}

/// Where the rest hand's palm faces (docs/BODY_MODEL.md: the back of the hand +y).
const PALM_NORMAL: Vec3 = Vec3::new(0.0, -1.0, 0.0);

impl HandAxes {
    /// The axes of the hands of the rest skeleton `rest` (the model's y-up frame).
    pub fn from_rest(rest: &[Vec3; NUM_JOINTS]) -> HandAxes {
        let mut axes = HandAxes {
            flex: [[[Vec3::ZERO; 3]; 5]; 2],
            spread: [[Vec3::ZERO; 5]; 2],
            rest_flex: [[[0.0; 3]; 5]; 2],
        };
        for hand in 0..2 {
            let j = |finger: usize, k: usize| HAND_FIRST_JOINT[hand] + FINGER_OFFSET[finger] + k;
            let wrist = rest[WRIST[hand]];
            // Across the palm, from the index side to the little finger's.
            let across = (rest[j(4, 0)] - rest[j(1, 0)]).normalize();
            for finger in 0..5 {
                let p = [rest[j(finger, 0)], rest[j(finger, 1)], rest[j(finger, 2)]];
                // Each joint's bone: to the next joint; the last joint's continues the one before.
                let bones = [p[1] - p[0], p[2] - p[1], p[2] - p[1]];
                let towards = if finger == 0 {
                    (PALM_NORMAL + across).normalize()
                } else {
                    PALM_NORMAL
                };
                let before = [p[0] - wrist, bones[0], bones[1]];
                for k in 0..3 {
                    let d = bones[k].normalize();
                    let a = d.cross(towards).normalize();
                    axes.flex[hand][finger][k] = a;
                    let b = before[k].normalize();
                    axes.rest_flex[hand][finger][k] = b.cross(d).dot(a).atan2(b.dot(d));
                }
                let away = match finger {
                    0 | 1 => -across,
                    2 => Vec3::ZERO,
                    _ => across,
                };
                // About the palm's normal, made square to the bone and so to the flexion
                // axis: flexion and spread read back apart ([`joint_flexion`]).
                let d = bones[0].normalize();
                let normal = (towards - d * towards.dot(d)).normalize();
                let sign = normal.cross(d).dot(away).signum();
                axes.spread[hand][finger] = if finger == 2 {
                    Vec3::ZERO
                } else {
                    normal * sign
                };
            }
        }
        axes
    }

    /// Each joint's flexion (rad, rest flexion included) for each finger's `curl` split over
    /// its joints, clamped into [`JOINT_RANGES_DEG`].
    pub(crate) fn flexion(
        &self,
        hand: usize,
        curl: &[Real; 5],
        split: &[[Real; 3]; 5],
    ) -> [[Real; 3]; 5] {
        std::array::from_fn(|finger| {
            std::array::from_fn(|k| {
                let added = curl[finger] * CURL_DEG[finger][k] * split[finger][k];
                clamp_flexion(
                    finger,
                    k,
                    self.rest_flex[hand][finger][k] + added.to_radians(),
                )
            })
        })
    }

    /// The 45 hand-pose values of `hand` with each joint's `flex`ion (rad, rest flexion
    /// included) and the hand's `spread`.
    pub(crate) fn hand_pose(&self, hand: usize, flex: &[[Real; 3]; 5], spread: Real) -> [Real; 45] {
        let mut out = [0.0; 45];
        for finger in 0..5 {
            for k in 0..3 {
                let added = flex[finger][k] - self.rest_flex[hand][finger][k];
                let mut r = axis_angle_to_matrix(self.flex[hand][finger][k] * added);
                if k == 0 {
                    let turn = (spread * SPREAD_DEG[finger]).to_radians();
                    r = axis_angle_to_matrix(self.spread[hand][finger] * turn) * r;
                }
                let aa = matrix_to_axis_angle(r);
                let at = 3 * (FINGER_OFFSET[finger] + k);
                out[at..at + 3].copy_from_slice(&aa.to_array());
            }
        }
        out
    }
}

/// `flex` (rad) clamped into `finger`'s joint `k`'s range.
fn clamp_flexion(finger: usize, k: usize, flex: Real) -> Real {
    let (lo, hi) = JOINT_RANGES_DEG[finger][k];
    flex.clamp(lo.to_radians(), hi.to_radians())
}

/// Each column of `rows` smoothed by [`gaussian_smooth`] with σ `sigma` samples.
fn smooth_columns<const N: usize>(rows: &[[Real; N]], sigma: Real) -> Vec<[Real; N]> {
    let columns: [Vec<Real>; N] = std::array::from_fn(|c| {
        gaussian_smooth(&rows.iter().map(|r| r[c]).collect::<Vec<_>>(), sigma)
    });
    (0..rows.len())
        .map(|f| std::array::from_fn(|c| columns[c][f]))
        .collect()
}

/// Writes both hands' pose into `frames` (at `rate_hz`) from what each hand does on each frame
/// (`doing[f] = [left, right]`): the person's curls and spread for it, as joint angles inside
/// their ranges, smoothed over time; then the drift, clamped again.
pub fn move_fingers(
    frames: &mut [BodyParams],
    doing: &[[HandDoing; 2]],
    axes: &HandAxes,
    style: &HandStyle,
    rate_hz: Real,
) {
    assert_eq!(frames.len(), doing.len(), "one hand state per frame");
    for hand in 0..2 {
        // 15 joint flexions, finger by finger, then the spread.
        let targets: Vec<[Real; 16]> = doing
            .iter()
            .map(|d| {
                let (curl, spread) = target(d[hand]);
                let curl = std::array::from_fn(|i| curl[i] + style.curl[i]);
                let flex = axes.flexion(hand, &curl, &style.split);
                std::array::from_fn(|i| {
                    if i < 15 {
                        flex[i / 3][i % 3]
                    } else {
                        spread + style.spread
                    }
                })
            })
            .collect();
        let smoothed = smooth_columns(&targets, SMOOTHING_S * rate_hz);
        for (f, (frame, s)) in frames.iter_mut().zip(&smoothed).enumerate() {
            let t = f as Real / rate_hz;
            let flex: [[Real; 3]; 5] = std::array::from_fn(|finger| {
                let drift = style.drift_at(hand, finger, t);
                std::array::from_fn(|k| {
                    let added = drift * CURL_DEG[finger][k] * style.split[finger][k];
                    clamp_flexion(finger, k, s[3 * finger + k] + added.to_radians())
                })
            });
            let pose = axes.hand_pose(hand, &flex, s[15]);
            let at = 3 * HAND_FIRST_JOINT[hand];
            frame.pose[at..at + 45].copy_from_slice(&pose);
        }
    }
}

/// Each finger joint's flexion on a posed frame (rad, rest flexion included) about its axis,
/// `[hand][finger][joint]`: what [`JOINT_RANGES_DEG`] bounds. Reads the frame's hand pose as
/// written, so it checks any file's hands, not only egogen's own.
pub fn joint_flexion(frame: &BodyParams, axes: &HandAxes) -> [[[Real; 3]; 5]; 2] {
    std::array::from_fn(|hand| {
        std::array::from_fn(|finger| {
            std::array::from_fn(|k| {
                let j = HAND_FIRST_JOINT[hand] + FINGER_OFFSET[finger] + k;
                let r = axis_angle_to_matrix(frame.joint_axis_angle(j));
                let a = axes.flex[hand][finger][k];
                // The rotation's angle about the flexion axis (swing-twist: the twist part).
                let q = glam::DQuat::from_mat3(&r);
                let q = if q.w < 0.0 { -q } else { q };
                let twist = q.xyz().dot(a);
                axes.rest_flex[hand][finger][k] + 2.0 * twist.atan2(q.w)
            })
        })
    })
}

pub mod stats;
#[cfg(test)]
mod tests;
