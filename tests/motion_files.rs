//! AMASS-style files round-trip exactly; SAMP-style files read; bad files are named.

mod common;

use common::*;
use egogen::body::POSE_DIM;
use egogen::math::Vec3;
use egogen::motion::MotionSequence;

fn sequence(n: usize) -> MotionSequence {
    MotionSequence {
        frame_rate_hz: 120.0,
        betas: (0..16).map(|i| uniform(21, i) * 4.0 - 2.0).collect(),
        gender: "female".into(),
        poses: (0..n)
            .map(|f| std::array::from_fn(|k| (uniform(22, (f * POSE_DIM + k) as u64) - 0.5) * 6.0))
            .collect(),
        trans: (0..n)
            .map(|f| Vec3::new(f as f64 * 0.01, 1e3 + uniform(23, f as u64), -1e-300))
            .collect(),
    }
}

#[test]
fn amass_round_trips_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("walk.npz");
    let seq = sequence(37);
    seq.write_amass(&path).unwrap();
    assert!(!dir.path().join("walk.npz.partial").exists());
    let back = MotionSequence::read(&path).unwrap();
    assert_eq!(back, seq);
}

#[test]
fn samp_style_file_reads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("samp.npz");
    let seq = sequence(5);
    let poses: Vec<f64> = seq.poses.iter().flatten().copied().collect();
    let trans: Vec<f64> = seq.trans.iter().flat_map(|t| t.to_array()).collect();
    let betas: Vec<f64> = (0..5).flat_map(|_| seq.betas[..10].to_vec()).collect();
    write_npz(
        &path,
        &[
            ("pose_est_fullposes", Arr::F64(vec![5, 165], poses)),
            ("pose_est_trans", Arr::F64(vec![5, 3], trans)),
            ("shape_est_betas", Arr::F64(vec![5, 10], betas)),
            ("mocap_framerate", Arr::F64(vec![], vec![30.0])),
        ],
    );
    let back = MotionSequence::read(&path).unwrap();
    assert_eq!(back.poses, seq.poses);
    assert_eq!(back.trans, seq.trans);
    assert_eq!(back.betas, seq.betas[..10]);
    assert_eq!(back.frame_rate_hz, 30.0);
    assert_eq!(back.gender, "neutral");
}

#[test]
fn bad_motion_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.npz");
    write_npz(
        &path,
        &[
            ("poses", Arr::F64(vec![2, 72], vec![0.0; 144])),
            ("trans", Arr::F64(vec![2, 3], vec![0.0; 6])),
        ],
    );
    let msg = MotionSequence::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("bad.npz") && msg.contains("`poses`") && msg.contains("[N, 165]"),
        "{msg}"
    );

    write_npz(&path, &[("trans", Arr::F64(vec![2, 3], vec![0.0; 6]))]);
    let msg = MotionSequence::read(&path).unwrap_err().to_string();
    assert!(msg.contains("missing key `poses`"), "{msg}");

    // A file with no frames is refused by name (it used to reach placement and panic there).
    write_npz(
        &path,
        &[
            ("poses", Arr::F64(vec![0, 165], vec![])),
            ("trans", Arr::F64(vec![0, 3], vec![])),
            ("mocap_frame_rate", Arr::F64(vec![], vec![60.0])),
        ],
    );
    let msg = MotionSequence::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("bad.npz") && msg.contains("`poses`") && msg.contains("at least one frame"),
        "{msg}"
    );

    let mut poses = vec![0.0; 165 * 2];
    poses[200] = f64::INFINITY;
    write_npz(
        &path,
        &[
            ("poses", Arr::F64(vec![2, 165], poses)),
            ("trans", Arr::F64(vec![2, 3], vec![0.0; 6])),
            ("mocap_frame_rate", Arr::F64(vec![], vec![60.0])),
        ],
    );
    let msg = MotionSequence::read(&path).unwrap_err().to_string();
    assert!(msg.contains("non-finite"), "{msg}");

    write_npz(
        &path,
        &[
            ("poses", Arr::F64(vec![2, 165], vec![0.0; 330])),
            ("trans", Arr::F64(vec![2, 3], vec![0.0; 6])),
            ("mocap_frame_rate", Arr::F64(vec![], vec![-1.0])),
        ],
    );
    let msg = MotionSequence::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("`mocap_frame_rate`") && msg.contains("positive"),
        "{msg}"
    );
    // A rate no capture has (a damaged file) is refused, not resampled without bound.
    write_npz(
        &path,
        &[
            ("poses", Arr::F64(vec![2, 165], vec![0.0; 330])),
            ("trans", Arr::F64(vec![2, 3], vec![0.0; 6])),
            ("mocap_frame_rate", Arr::F64(vec![], vec![1e9])),
        ],
    );
    let msg = MotionSequence::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("`mocap_frame_rate`") && msg.contains("at most"),
        "{msg}"
    );
}
