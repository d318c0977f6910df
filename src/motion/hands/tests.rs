use rand_core::SeedableRng;

use super::*;

/// The fingers, thumb first.
const FINGERS: [&str; 5] = ["thumb", "index", "middle", "ring", "pinky"];
use crate::body::{BodyModel, ShapedBody};

fn model() -> BodyModel {
    BodyModel::load(crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap()
}

fn joints(shaped: &ShapedBody, frame: &BodyParams) -> [Vec3; NUM_JOINTS] {
    shaped.skeleton(&frame.pose, frame.transl).unwrap().joints
}

fn no_drift(mut style: HandStyle) -> HandStyle {
    for hand in &mut style.drift {
        for finger in hand {
            for wave in finger {
                wave.2 = 0.0;
            }
        }
    }
    style
}

#[test]
fn a_curl_moves_every_fingertip_towards_the_palm() {
    let model = model();
    let shaped = model.shape(&[], &[]).unwrap();
    let axes = HandAxes::from_rest(&shaped.rest_joints);
    let rest = BodyParams::default();
    let mut curled = rest.clone();
    let split = [[1.0; 3]; 5];
    for hand in 0..2 {
        let pose = axes.hand_pose(hand, &axes.flexion(hand, &[0.7; 5], &split), 0.0);
        let at = 3 * HAND_FIRST_JOINT[hand];
        curled.pose[at..at + 45].copy_from_slice(&pose);
    }
    let (a, b) = (joints(&shaped, &rest), joints(&shaped, &curled));
    for hand in 0..2 {
        let wrist = a[WRIST[hand]];
        for finger in 0..5 {
            let tip = HAND_FIRST_JOINT[hand] + FINGER_OFFSET[finger] + 2;
            assert!(
                b[tip].y < a[tip].y - 0.005,
                "hand {hand} {}: {} -> {}",
                FINGERS[finger],
                a[tip].y,
                b[tip].y
            );
            assert!((b[tip] - wrist).length() < (a[tip] - wrist).length());
        }
        // The thumb curls across the palm, towards the little finger.
        let thumb = HAND_FIRST_JOINT[hand] + FINGER_OFFSET[0] + 2;
        let pinky = HAND_FIRST_JOINT[hand] + FINGER_OFFSET[4];
        assert!((b[thumb] - a[pinky]).length() < (a[thumb] - a[pinky]).length());
    }
    // The rest of the body does not move.
    for j in 0..25 {
        assert!((a[j] - b[j]).length() < 1e-12, "joint {j}");
    }
}

#[test]
fn flexion_reads_back_and_stays_in_range_at_the_extremes() {
    let model = model();
    let shaped = model.shape(&[], &[]).unwrap();
    let axes = HandAxes::from_rest(&shaped.rest_joints);
    let split = [[1.0; 3]; 5];
    for curl in [-3.0, -0.1, 0.0, 0.3, 0.9, 1.0, 5.0] {
        let mut frame = BodyParams::default();
        for hand in 0..2 {
            let pose = axes.hand_pose(hand, &axes.flexion(hand, &[curl; 5], &split), 0.0);
            let at = 3 * HAND_FIRST_JOINT[hand];
            frame.pose[at..at + 45].copy_from_slice(&pose);
        }
        let flex = joint_flexion(&frame, &axes);
        for hand in 0..2 {
            for finger in 0..5 {
                for k in 0..3 {
                    let (lo, hi) = JOINT_RANGES_DEG[finger][k];
                    let f = flex[hand][finger][k].to_degrees();
                    let rest = axes.rest_flex[hand][finger][k].to_degrees();
                    let want = (rest + curl * CURL_DEG[finger][k]).clamp(lo, hi);
                    assert!(
                        (f - want).abs() < 1e-6,
                        "curl {curl} hand {hand} {} joint {k}: {f} against {want}",
                        FINGERS[finger]
                    );
                }
            }
        }
    }
}

#[test]
fn the_rest_hand_lies_inside_the_ranges() {
    let model = model();
    for betas in [vec![], vec![3.0, -3.0], vec![-3.0, 3.0]] {
        let shaped = model.shape(&betas, &[]).unwrap();
        let axes = HandAxes::from_rest(&shaped.rest_joints);
        for hand in 0..2 {
            for finger in 0..5 {
                for k in 0..3 {
                    let (lo, hi) = JOINT_RANGES_DEG[finger][k];
                    let r = axes.rest_flex[hand][finger][k].to_degrees();
                    assert!((lo..=hi).contains(&r), "{betas:?} {hand} {finger} {k}: {r}");
                }
            }
        }
    }
}

#[test]
fn fingers_move_smoothly_between_what_the_hands_do() {
    let model = model();
    let shaped = model.shape(&[], &[]).unwrap();
    let axes = HandAxes::from_rest(&shaped.rest_joints);
    let style = HandStyle::draw(&mut ChaCha8Rng::seed_from_u64(3));
    let order = [
        HandDoing::Walking,
        HandDoing::Reaching,
        HandDoing::HOLDING_A_CUP,
        HandDoing::Standing,
        HandDoing::Seated,
        HandDoing::Walking,
    ];
    let doing: Vec<[HandDoing; 2]> = (0..480)
        .map(|f| [order[f / 80], order[(f / 80 + 2) % order.len()]])
        .collect();
    let mut frames = vec![BodyParams::default(); doing.len()];
    move_fingers(&mut frames, &doing, &axes, &style, 40.0);
    let mut worst: Real = 0.0;
    for f in 1..frames.len() - 1 {
        let flex = [-1, 0, 1].map(|d| joint_flexion(&frames[(f as isize + d) as usize], &axes));
        for hand in 0..2 {
            for finger in 0..5 {
                for k in 0..3 {
                    let [a, b, c] = flex.map(|x| x[hand][finger][k]);
                    worst = worst.max((a - 2.0 * b + c).abs() * 1600.0);
                    let (lo, hi) = JOINT_RANGES_DEG[finger][k];
                    assert!((lo - 1e-9..=hi + 1e-9).contains(&b.to_degrees()));
                }
            }
        }
    }
    // A hand closing from open to a grasp over about 0.35 s: up to 70 rad/s² (7 rad/s at
    // most); a step would be 1.6 rad in one frame, 2 500 rad/s².
    assert!(worst < 100.0, "largest angular acceleration {worst} rad/s²");
    // Holding closes the hand further than reaching.
    let curl_sum = |f: usize, hand: usize| -> Real {
        joint_flexion(&frames[f], &axes)[hand]
            .iter()
            .flatten()
            .sum()
    };
    assert!(curl_sum(200, 0) > curl_sum(120, 0) + 1.0);
    // Without drift, a hand that keeps doing one thing keeps still.
    let still = no_drift(style);
    let mut frames = vec![BodyParams::default(); 100];
    move_fingers(
        &mut frames,
        &[[HandDoing::Walking; 2]; 100],
        &axes,
        &still,
        40.0,
    );
    for w in frames.windows(2) {
        let most = (0..165)
            .map(|i| (w[0].pose[i] - w[1].pose[i]).abs())
            .fold(0.0, Real::max);
        assert!(most < 1e-12, "{most}");
    }
}

#[test]
fn each_person_draws_its_own_hands() {
    let a = HandStyle::draw(&mut ChaCha8Rng::seed_from_u64(1));
    let b = HandStyle::draw(&mut ChaCha8Rng::seed_from_u64(2));
    assert_ne!(a, b);
    assert_eq!(a, HandStyle::draw(&mut ChaCha8Rng::seed_from_u64(1)));
}
