//! How a motion's fingers move, read from its hand pose as written (any AMASS-style SMPL-X
//! file, egogen's or not): each joint's flexion against its anatomical range, how fast the
//! fingers turn and how smoothly, and how closed the hands are ([`HandStats`]; `egogen motion
//! hand-stats`, docs/HANDS.md).

use serde::Serialize;

use super::{joint_flexion, HandAxes, JOINT_RANGES_DEG};
use crate::body::BodyParams;
use crate::math::{Quantiles, Real};

/// Finger statistics of one motion.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HandStats {
    pub frames: usize,
    /// Frames whose hand pose is not all zeros.
    pub frames_with_hand_pose: usize,
    /// Frames with a finger joint outside its range ([`JOINT_RANGES_DEG`], 1e-6° slack).
    pub frames_outside_range: usize,
    /// How far the farthest joint is outside its range over the motion (°; 0: inside).
    pub most_outside_range_deg: Real,
    /// Flexion summed over the 15 joints of a hand, less the rest hand's, per hand and frame
    /// (°): how closed the hands are.
    pub added_flexion_deg: Quantiles,
    /// Each joint's flexion speed per frame (rad/s).
    pub flexion_speed_rad_s: Quantiles,
    /// Each joint's flexion acceleration per frame (rad/s²): a jump in the hand pose shows
    /// here.
    pub flexion_acceleration_rad_s2: Quantiles,
}

impl HandStats {
    /// The statistics of `frames` at `rate_hz`, measured about `axes` (the body's rest hand).
    pub fn of(frames: &[BodyParams], axes: &HandAxes, rate_hz: Real) -> HandStats {
        let flex: Vec<[Real; 30]> = frames
            .iter()
            .map(|f| {
                let j = joint_flexion(f, axes);
                std::array::from_fn(|i| j[i / 15][(i % 15) / 3][i % 3])
            })
            .collect();
        let mut outside = 0;
        let mut most: Real = 0.0;
        for row in &flex {
            let mut here: Real = 0.0;
            for (i, x) in row.iter().enumerate() {
                let (lo, hi) = JOINT_RANGES_DEG[(i % 15) / 3][i % 3];
                let d = x.to_degrees();
                here = here.max(lo - d).max(d - hi);
            }
            if here > 1e-6 {
                outside += 1;
            }
            most = most.max(here);
        }
        let rest: [Real; 2] = std::array::from_fn(|h| axes.rest_flex[h].iter().flatten().sum());
        let added = flex.iter().flat_map(|row| {
            (0..2).map(move |h| {
                (row[15 * h..15 * h + 15].iter().sum::<Real>() - rest[h]).to_degrees()
            })
        });
        let speed = flex
            .windows(2)
            .flat_map(|w| (0..30).map(move |i| (w[1][i] - w[0][i]).abs() * rate_hz));
        let acceleration = flex.windows(3).flat_map(|w| {
            (0..30).map(move |i| (w[2][i] - 2.0 * w[1][i] + w[0][i]).abs() * rate_hz * rate_hz)
        });
        HandStats {
            frames: frames.len(),
            frames_with_hand_pose: frames
                .iter()
                .filter(|f| f.pose[75..].iter().any(|&x| x != 0.0))
                .count(),
            frames_outside_range: outside,
            most_outside_range_deg: most,
            added_flexion_deg: Quantiles::of(added),
            flexion_speed_rad_s: Quantiles::of(speed),
            flexion_acceleration_rad_s2: Quantiles::of(acceleration),
        }
    }
}
