//! A wearer's hands as MPS hand tracking writes them (`hand_tracking/hand_tracking_results.csv`,
//! the v2 layout with normals; `mps.hand_tracking.read_hand_tracking_results`): each hand's 21
//! landmarks from the body (`body::hand_landmarks`) in the device frame at the trajectory's
//! pose of the same microsecond.

use std::fmt::Write as _;

use crate::body::hand_landmarks::HandLandmarks;
use crate::math::pose_spline::PoseSpline;
use crate::math::{Affine3, Real};

/// The header of MPS hand tracking (projectaria-tools' `HandTrackingReader.cpp`, the v2
/// layout with normals): per hand its confidence and 21 landmarks in the device frame, then
/// both wrists' poses, then the palms' and wrists' normals.
fn hand_tracking_header() -> String {
    let mut h = vec!["tracking_timestamp_us".to_string()];
    for side in ["left", "right"] {
        h.push(format!("{side}_tracking_confidence"));
        for k in 0..21 {
            for a in ["x", "y", "z"] {
                h.push(format!("t{a}_{side}_landmark_{k}_device"));
            }
        }
    }
    for side in ["left", "right"] {
        for a in ["tx", "ty", "tz", "qx", "qy", "qz", "qw"] {
            h.push(format!("{a}_{side}_device_wrist"));
        }
    }
    for side in ["left", "right"] {
        for what in ["palm", "wrist"] {
            for a in ["nx", "ny", "nz"] {
                h.push(format!("{a}_{side}_{what}_device"));
            }
        }
    }
    h.join(",")
}

/// Both hands of every frame (`hands`, in the world, at `frame_rate_hz`) as MPS hand tracking
/// writes them: one row per frame at its whole microsecond, every point in the device's frame
/// there (the device trajectory's pose at the same microsecond), confidence 1.
pub(crate) fn hand_tracking_csv(
    spline: &PoseSpline,
    head_from_device: Affine3,
    frame_rate_hz: Real,
    hands: &[[HandLandmarks; 2]],
) -> String {
    let mut text = hand_tracking_header();
    text.push('\n');
    let mut last_q: [Option<glam::DQuat>; 2] = [None, None];
    for (i, both) in hands.iter().enumerate() {
        let us = (i as Real / frame_rate_hz * 1e6).round() as i64;
        let world_from_device = spline
            .sample(us as Real * 1e-6)
            .attached(head_from_device)
            .world_from_body;
        let device_from_world = world_from_device.inverse();
        let local = both.map(|h| h.moved(device_from_world));
        let _ = write!(text, "{us}");
        for h in &local {
            let _ = write!(text, ",1");
            for p in &h.points {
                let _ = write!(text, ",{},{},{}", p.x, p.y, p.z);
            }
        }
        for (k, h) in local.iter().enumerate() {
            let t = h.wrist.translation;
            let mut q = glam::DQuat::from_mat3(&h.wrist.matrix3).normalize();
            if last_q[k].is_some_and(|p| p.dot(q) < 0.0) {
                q = -q;
            }
            last_q[k] = Some(q);
            let _ = write!(
                text,
                ",{},{},{},{},{},{},{}",
                t.x, t.y, t.z, q.x, q.y, q.z, q.w
            );
        }
        for h in &local {
            for n in [h.palm_normal, h.wrist_normal] {
                let _ = write!(text, ",{},{},{}", n.x, n.y, n.z);
            }
        }
        text.push('\n');
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::hand_landmarks::hand_track;
    use crate::body::{BodyModel, POSE_DIM};
    use crate::math::Vec3;

    /// Every landmark of the hand-tracking file, taken back to the world by the device's pose
    /// at its microsecond, is the body's own to 1e-9 m, far from the origin and with a head
    /// that turns.
    #[test]
    fn hand_tracking_rows_are_the_bodies_hands_in_the_device_frame() {
        let model = BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap();
        let n = 12;
        let poses: Vec<[Real; POSE_DIM]> = (0..n)
            .map(|i| {
                let mut p = [0.0; POSE_DIM];
                for (k, v) in p.iter_mut().enumerate().skip(60) {
                    *v = 0.3 * ((k * 7 + i * 3) as Real * 0.37).sin();
                }
                p
            })
            .collect();
        let trans: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(5000.0 + 0.03 * i as Real, -3000.0, 1.0))
            .collect();
        let hands = hand_track(&model, &[], &poses, &trans).unwrap();
        let heads: Vec<Affine3> = (0..n)
            .map(|i| {
                Affine3::from_rotation_translation(
                    glam::DQuat::from_rotation_z(0.4 * i as Real),
                    trans[i] + Vec3::new(0.0, 0.0, 1.5),
                )
            })
            .collect();
        let spline = PoseSpline::interpolate(40.0, &heads).unwrap();
        let head_from_device = Affine3::from_translation(Vec3::new(0.01, 0.07, -0.02));
        let text = hand_tracking_csv(&spline, head_from_device, 40.0, &hands);
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(header.len(), 1 + 2 * 64 + 14 + 12);
        for (i, line) in lines.enumerate() {
            let v: Vec<Real> = line.split(',').map(|x| x.parse().unwrap()).collect();
            assert_eq!(v.len(), header.len());
            let us = v[0];
            assert_eq!(us, (i as Real * 25_000.0).round());
            let world_from_device = spline
                .sample(us * 1e-6)
                .attached(head_from_device)
                .world_from_body;
            for hand in 0..2 {
                let at = 1 + 64 * hand;
                assert_eq!(v[at], 1.0);
                for k in 0..21 {
                    let p = Vec3::new(v[at + 1 + 3 * k], v[at + 2 + 3 * k], v[at + 3 + 3 * k]);
                    let world = world_from_device.transform_point3(p);
                    let err = world.distance(hands[i][hand].points[k]);
                    assert!(err < 1e-9, "frame {i} hand {hand} landmark {k}: {err} m");
                }
            }
        }
    }
}
