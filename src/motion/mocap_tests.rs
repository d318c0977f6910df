//! Mocap ingestion: CMU BVH retargeting keeps every mapped bone's direction, resampling picks
//! exact frames, mirroring is an involution that swaps left and right.

use crate::body::{joint, BodyModel};
use crate::math::Vec3;
use crate::motion::bvh::BvhClip;
use crate::motion::resample::{mirror, resample};
use crate::motion::retarget::{retarget_cmu, CMU_TO_SMPLX};
use std::path::Path;

fn fixture() -> BvhClip {
    BvhClip::read(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/cmu_01_01_excerpt.bvh"),
    )
    .unwrap()
}

fn model() -> BodyModel {
    BodyModel::load(crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap()
}

#[test]
fn bvh_reads_cmu_skeleton() {
    let clip = fixture();
    assert_eq!(clip.frame_rate_hz, 120.0);
    assert_eq!(clip.frames.len(), 12);
    assert_eq!(clip.joints.len(), 31);
    assert_eq!(clip.joints[0].name, "Hips");
    assert!(clip.joint_index("LeftForeArm").is_some());
}

#[test]
fn retargeted_bones_point_where_the_source_bones_point() {
    let clip = fixture();
    let m = model();
    let seq = retarget_cmu(&clip, &m).unwrap();
    assert_eq!(seq.len(), 12);
    let shaped = m.shape(&[], &[]).unwrap();
    // Source bones in the z-up world: body (x, y, z) → world (x, −z, y).
    let to_world = |p: Vec3| Vec3::new(p.x, -p.z, p.y);
    let mut worst: f64 = 0.0;
    for f in 0..seq.len() {
        let ours = shaped.skeleton(&seq.poses[f], seq.trans[f]).unwrap();
        let g = clip.global_transforms(f);
        for (j, name, child) in CMU_TO_SMPLX {
            let Some(c) = child else { continue };
            let child_name = CMU_TO_SMPLX.iter().find(|(jj, _, _)| *jj == c).unwrap().1;
            let (a, b) = (
                clip.joint_index(name).unwrap(),
                clip.joint_index(child_name).unwrap(),
            );
            let src = to_world(g[b].translation - g[a].translation).normalize();
            let dst = (ours.joints[c] - ours.joints[j]).normalize();
            worst = worst.max(src.angle_between(dst));
        }
    }
    eprintln!("max bone direction error after retargeting: {worst:.2e} rad");
    assert!(worst < 1e-6);
    // Feet on the floor: the lowest foot joint sits at its rest height above the soles.
    let lowest = (0..seq.len())
        .flat_map(|f| {
            let s = shaped.skeleton(&seq.poses[f], seq.trans[f]).unwrap();
            [
                joint::LEFT_ANKLE,
                joint::RIGHT_ANKLE,
                joint::LEFT_FOOT,
                joint::RIGHT_FOOT,
            ]
            .map(|j| s.joints[j].z)
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        (0.0..0.15).contains(&lowest),
        "lowest foot joint at {lowest} m"
    );
}

#[test]
fn resampling_120_to_40_picks_every_third_frame() {
    let seq = retarget_cmu(&fixture(), &model()).unwrap();
    let r = resample(&seq, 40.0);
    assert_eq!(r.len(), 4);
    for k in 0..4 {
        assert_eq!(r.poses[k], seq.poses[3 * k]);
        assert_eq!(r.trans[k], seq.trans[3 * k]);
    }
    // A non-integer ratio interpolates between neighbours.
    let r = resample(&seq, 50.0);
    assert_eq!(r.len(), 5);
    assert!(r.poses[1].iter().all(|v| v.is_finite()));
}

#[test]
fn mirroring_swaps_sides_and_is_an_involution() {
    let m = model();
    let seq = retarget_cmu(&fixture(), &m).unwrap();
    let mir = mirror(&seq, &m).unwrap();
    let back = mirror(&mir, &m).unwrap();
    for (a, b) in seq.poses.iter().zip(&back.poses) {
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-9);
        }
    }
    let shaped = m.shape(&[], &[]).unwrap();
    let s = shaped.skeleton(&seq.poses[5], seq.trans[5]).unwrap();
    let t = shaped.skeleton(&mir.poses[5], mir.trans[5]).unwrap();
    let flip = |p: Vec3| Vec3::new(-p.x, p.y, p.z);
    // Left wrist of the mirror = mirrored right wrist of the original (up to the model's
    // small left-right asymmetry).
    let d = (t.joints[joint::LEFT_WRIST] - flip(s.joints[joint::RIGHT_WRIST])).length();
    assert!(d < 0.01, "{d}");
}

#[test]
fn bad_bvh_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.bvh");
    std::fs::write(&p, "HIERARCHY\nROOT Hips\n{\n").unwrap();
    let msg = BvhClip::read(&p).unwrap_err().to_string();
    assert!(msg.contains("broken.bvh"), "{msg}");
    // A non-CMU skeleton is refused with the missing joint named.
    let bvh = "HIERARCHY\nROOT Root\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n\tEnd Site\n\t{\n\t\tOFFSET 0 1 0\n\t}\n}\nMOTION\nFrames: 1\nFrame Time: 0.033333\n0 0 0 0 0 0\n";
    let p = dir.path().join("other.bvh");
    std::fs::write(&p, bvh).unwrap();
    let clip = BvhClip::read(&p).unwrap();
    let msg = retarget_cmu(&clip, &model()).unwrap_err().to_string();
    assert!(msg.contains("other.bvh") && msg.contains("`Hips`"), "{msg}");
}

#[test]
fn primitives_are_canonical_and_map_back_exactly() {
    use crate::math::rotation::orthonormality_error;
    use crate::motion::primitive::{extract_primitives, PRIMITIVE_FRAMES};
    use crate::motion::MotionSequence;
    let m = model();
    let seq = MotionSequence::read(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/motion/cmu_01_03.npz"),
    )
    .unwrap();
    let prims = extract_primitives(&seq, 200, &m).unwrap();
    assert!(prims.len() >= 7);
    let shaped = m.shape(&[], &[]).unwrap();
    let mut worst_mesh: f64 = 0.0;
    for (k, p) in prims.iter().enumerate() {
        assert_eq!(p.frames.len(), PRIMITIVE_FRAMES);
        assert!(orthonormality_error(p.world_from_canon.matrix3) < 1e-14);
        let first = shaped
            .skeleton(&p.frames[0].pose, p.frames[0].transl)
            .unwrap();
        // Origin at the first pelvis; hips along +x, level.
        assert!(first.joints[joint::PELVIS].length() < 1e-9);
        let hips = first.joints[joint::RIGHT_HIP] - first.joints[joint::LEFT_HIP];
        assert!(hips.y.abs() < 1e-9 && hips.x > 0.0, "{hips:?}");
        // Back to the world: the same mesh as the source frames.
        let back = p.to_world(&m).unwrap();
        for (i, b) in back.iter().enumerate().step_by(6) {
            let src = m.pose(&seq.frame(200 * k + i)).unwrap();
            let got = m.pose(b).unwrap();
            for (a, c) in src.vertices.iter().zip(&got.vertices).step_by(50) {
                worst_mesh = worst_mesh.max((*a - *c).length());
            }
        }
    }
    assert!(worst_mesh < 1e-9, "{worst_mesh}");
}

/// A DeepMimic frame: duration, root position, 13 joint rotations (identity quaternions
/// `w x y z` = 1 0 0 0, hinges 0), with optional knee and elbow angles.
fn deepmimic_clip(dir: &Path, right_knee: f64, left_elbow: f64) -> std::path::PathBuf {
    let mut f = vec![1.0 / 30.0, 0.0, 0.85, 0.0];
    let q = [1.0, 0.0, 0.0, 0.0];
    for part in [
        "root",
        "chest",
        "neck",
        "rhip",
        "rknee",
        "rankle",
        "rshoulder",
        "relbow",
        "lhip",
        "lknee",
        "lankle",
        "lshoulder",
        "lelbow",
    ] {
        match part {
            "rknee" => f.push(right_knee),
            "relbow" | "lknee" => f.push(0.0),
            "lelbow" => f.push(left_elbow),
            _ => f.extend(q),
        }
    }
    assert_eq!(f.len(), 44);
    let text = format!("{{\"Loop\": \"wrap\", \"Frames\": [{:?}, {:?}]}}", f, f);
    let p = dir.join("clip.txt");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn deepmimic_rest_hangs_arms_and_hinges_bend_by_their_angle() {
    use crate::motion::deepmimic::import_deepmimic;
    let m = model();
    let dir = tempfile::tempdir().unwrap();
    let seq = import_deepmimic(&deepmimic_clip(dir.path(), -1.0, 0.0), &m).unwrap();
    assert_eq!(seq.frame_rate_hz, 30.0);
    let s = m
        .shape(&[], &[])
        .unwrap()
        .skeleton(&seq.poses[0], seq.trans[0])
        .unwrap();
    // Rest: arms hang down (elbow straight below the shoulder, world z up).
    let arm = (s.joints[joint::LEFT_ELBOW] - s.joints[joint::LEFT_SHOULDER]).normalize();
    assert!(arm.z < -0.99, "{arm:?}");
    let forearm = (s.joints[joint::LEFT_WRIST] - s.joints[joint::LEFT_ELBOW]).normalize();
    assert!(forearm.z < -0.99, "{forearm:?}");
    // The right knee bends by the hinge angle (1 rad) between thigh and shin.
    let thigh = s.joints[joint::RIGHT_KNEE] - s.joints[joint::RIGHT_HIP];
    let shin = s.joints[joint::RIGHT_ANKLE] - s.joints[joint::RIGHT_KNEE];
    assert!(
        (thigh.angle_between(shin) - 1.0).abs() < 1e-6,
        "{}",
        thigh.angle_between(shin)
    );
    let straight = s.joints[joint::LEFT_ANKLE] - s.joints[joint::LEFT_KNEE];
    assert!(
        (s.joints[joint::LEFT_KNEE] - s.joints[joint::LEFT_HIP]).angle_between(straight) < 1e-6
    );
    // A malformed clip names the file.
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "{\"Frames\": [[0.03, 1, 2]]}").unwrap();
    let msg = import_deepmimic(&bad, &m).unwrap_err().to_string();
    assert!(
        msg.contains("bad.txt") && msg.contains("expected 44"),
        "{msg}"
    );
}
