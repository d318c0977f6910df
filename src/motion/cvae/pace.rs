//! Pace and turn of primitives: the horizontal pelvis speed and the change of the body's heading
//! over a primitive's decoded frames, measured the same way on mocap primitives, decoded ones
//! and chains, and summarised as quantiles.
//!
//! Heading is the yaw of the way the body faces: the horizontal normal of the left hip → right
//! hip line (the canonical frame's y axis), in radians counter-clockwise from world +x, seen from
//! above (z up). A primitive's pace is measured from the last seed frame to its last frame
//! (18 frames, 0.45 s at 40 Hz), as [`super::measure::ChainReport`] measures it.

use burn::prelude::*;
use serde::Serialize;

use crate::math::{wrap_rad, Quantiles};

use super::data::PrimitiveSet;
use super::loss::pose_frames;
use super::measure::set_batch;
use super::tensor_body::TensorRig;
use crate::body::joint;
use crate::math::Vec3;
use crate::motion::primitive::{PRIMITIVE_FRAMES, PRIMITIVE_RATE_HZ, SEED_FRAMES};

/// Seconds between the last seed frame and the last frame of a primitive.
pub(crate) const PACE_SPAN_S: f64 = (PRIMITIVE_FRAMES - SEED_FRAMES) as f64 / PRIMITIVE_RATE_HZ;

/// Heading (rad, counter-clockwise from world +x) of a body from its posed joints (z up).
pub(crate) fn heading_rad(joints: &[Vec3]) -> f64 {
    let right = joints[joint::RIGHT_HIP] - joints[joint::LEFT_HIP];
    // Forward = z × right, horizontal.
    (right.x).atan2(-right.y)
}

/// How fast a primitive moves and how far it turns.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pace {
    /// Horizontal pelvis displacement over the primitive divided by its time (m/s).
    pub speed_m_s: f64,
    /// Change of heading over the primitive (degrees, positive = to the body's left).
    pub turn_deg: f64,
}

impl Pace {
    /// The pace between the joints of the last seed frame and those of the last frame.
    pub(crate) fn between(first: &[Vec3], last: &[Vec3]) -> Pace {
        let d = last[joint::PELVIS].truncate() - first[joint::PELVIS].truncate();
        Pace {
            speed_m_s: d.length() / PACE_SPAN_S,
            turn_deg: wrap_rad(heading_rad(last) - heading_rad(first)).to_degrees(),
        }
    }

    /// The pace of a primitive from its posed joints of all `PRIMITIVE_FRAMES` frames.
    pub(crate) fn of_frames(joints: &[Vec<Vec3>]) -> Pace {
        Pace::between(&joints[SEED_FRAMES - 1], &joints[joints.len() - 1])
    }
}

/// Paces of every item of a single-primitive set, posed in batches of `batch`.
pub fn set_paces<B: Backend>(rig: &TensorRig<B>, set: &PrimitiveSet, batch: usize) -> Vec<Pace> {
    let device = rig.foot_markers.device();
    let mut out = Vec::with_capacity(set.len());
    for start in (0..set.len()).step_by(batch.max(1)) {
        let end = (start + batch).min(set.len());
        let (x, _) = set_batch::<B>(set, start..end, &device);
        out.extend(raw_paces(rig, x));
    }
    out
}

/// Paces of raw primitives `[B, T, F]` (canonical features).
pub(crate) fn raw_paces<B: Backend>(rig: &TensorRig<B>, x: Tensor<B, 3>) -> Vec<Pace> {
    let [b, t, _] = x.dims();
    // Only the last seed frame and the last frame are posed.
    let ends = Tensor::cat(
        vec![
            x.clone().narrow(1, SEED_FRAMES - 1, 1),
            x.narrow(1, t - 1, 1),
        ],
        1,
    );
    let joints = pose_frames(rig, ends).joints; // [B, 2, 22, 3]
    let j = joints.dims()[2];
    let pick = |frame: usize| -> Vec<f32> {
        joints
            .clone()
            .narrow(1, frame, 1)
            .into_data()
            .to_vec()
            .expect("f32 joints")
    };
    let (first, last) = (pick(0), pick(1));
    let as_joints = |v: &[f32], i: usize| -> Vec<Vec3> {
        (0..j)
            .map(|k| {
                let o = (i * j + k) * 3;
                Vec3::new(v[o] as f64, v[o + 1] as f64, v[o + 2] as f64)
            })
            .collect()
    };
    (0..b)
        .map(|i| Pace::between(&as_joints(&first, i), &as_joints(&last, i)))
        .collect()
}

/// Speed and turn distributions of a set of paces (turns as absolute degrees).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaceSummary {
    pub speed_m_s: Quantiles,
    pub abs_turn_deg: Quantiles,
    /// Share of primitives slower than 0.2 m/s (standing), 0.2–0.8 (slow), 0.8–1.8 (walking at
    /// a human pace), faster (running).
    pub share_standing: f64,
    pub share_slow: f64,
    pub share_walking: f64,
    pub share_running: f64,
}

impl PaceSummary {
    pub fn of(paces: &[Pace]) -> PaceSummary {
        let n = paces.len().max(1) as f64;
        let share = |lo: f64, hi: f64| {
            paces
                .iter()
                .filter(|p| p.speed_m_s >= lo && p.speed_m_s < hi)
                .count() as f64
                / n
        };
        PaceSummary {
            speed_m_s: Quantiles::of(paces.iter().map(|p| p.speed_m_s)),
            abs_turn_deg: Quantiles::of(paces.iter().map(|p| p.turn_deg.abs())),
            share_standing: share(0.0, 0.2),
            share_slow: share(0.2, 0.8),
            share_walking: share(0.8, 1.8),
            share_running: share(1.8, f64::INFINITY),
        }
    }
}

/// Upper edges (degrees of |turn| per primitive) of [`speed_by_turn`]'s bins; the last bin is
/// open above.
pub(crate) const TURN_BIN_EDGES_DEG: [f64; 4] = [10.0, 20.0, 30.0, 45.0];

/// A brisk walk (m/s): what [`SpeedAtTurn::share_at_1_2_m_s`] counts.
pub(crate) const BRISK_WALK_M_S: f64 = 1.2;

/// Speeds of the primitives that turn within one range of angles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct SpeedAtTurn {
    /// |turn| per primitive from this many degrees (inclusive) …
    pub from_deg: f64,
    /// … to this many (exclusive; `None`: no upper edge).
    pub to_deg: Option<f64>,
    pub speed_m_s: Quantiles,
    /// Share of these primitives at a brisk walk or faster (≥ [`BRISK_WALK_M_S`]).
    pub share_at_1_2_m_s: f64,
}

/// How fast the primitives move by how far they turn: whether a set turns at pace (bins of
/// [`TURN_BIN_EDGES_DEG`]; bins with no primitive are left out).
pub(crate) fn speed_by_turn(paces: &[Pace]) -> Vec<SpeedAtTurn> {
    let mut edges = vec![0.0];
    edges.extend(TURN_BIN_EDGES_DEG);
    edges
        .iter()
        .enumerate()
        .filter_map(|(k, &from)| {
            let to = edges.get(k + 1).copied();
            let within: Vec<f64> = paces
                .iter()
                .filter(|p| p.turn_deg.abs() >= from && to.is_none_or(|t| p.turn_deg.abs() < t))
                .map(|p| p.speed_m_s)
                .collect();
            (!within.is_empty()).then(|| SpeedAtTurn {
                from_deg: from,
                to_deg: to,
                share_at_1_2_m_s: within.iter().filter(|&&v| v >= BRISK_WALK_M_S).count() as f64
                    / within.len() as f64,
                speed_m_s: Quantiles::of(within),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hips_facing(heading: f64, pelvis: Vec3) -> Vec<Vec3> {
        // Right hip = pelvis + 0.1 · (the body's right), right = forward rotated by −90°.
        let forward = Vec3::new(heading.cos(), heading.sin(), 0.0);
        let right = Vec3::new(forward.y, -forward.x, 0.0);
        let mut j = vec![pelvis; 22];
        j[joint::RIGHT_HIP] = pelvis + right * 0.1;
        j[joint::LEFT_HIP] = pelvis - right * 0.1;
        j
    }

    #[test]
    fn heading_and_turn_follow_the_hips() {
        for h in [-3.0, -1.0, 0.0, 0.5, 3.1] {
            assert!((wrap_rad(heading_rad(&hips_facing(h, Vec3::ZERO)) - h)).abs() < 1e-12);
        }
        // Walking 0.45 m forward while turning 170° → −170° is a 20° turn to the left.
        let a = hips_facing(170f64.to_radians(), Vec3::ZERO);
        let b = hips_facing(-170f64.to_radians(), Vec3::new(-0.45, 0.0, 0.0));
        let p = Pace::between(&a, &b);
        assert!((p.speed_m_s - 1.0).abs() < 1e-12);
        assert!((p.turn_deg - 20.0).abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn speed_by_turn_bins_each_primitive_once_by_its_absolute_turn() {
        let p = |speed_m_s, turn_deg| Pace {
            speed_m_s,
            turn_deg,
        };
        let paces = [
            p(1.4, 2.0),
            p(1.0, -9.99),
            p(1.3, 10.0),
            p(0.6, -35.0),
            p(0.5, 90.0),
            p(1.25, -180.0),
        ];
        let bins = speed_by_turn(&paces);
        let got: Vec<(f64, Option<f64>, usize, f64)> = bins
            .iter()
            .map(|b| (b.from_deg, b.to_deg, b.speed_m_s.count, b.share_at_1_2_m_s))
            .collect();
        // 20–30° holds no primitive: left out.
        assert_eq!(
            got,
            vec![
                (0.0, Some(10.0), 2, 0.5),
                (10.0, Some(20.0), 1, 1.0),
                (30.0, Some(45.0), 1, 0.0),
                (45.0, None, 2, 0.5),
            ]
        );
        assert_eq!(bins[0].speed_m_s.max, 1.4);
        assert!(speed_by_turn(&[]).is_empty());
    }
}
