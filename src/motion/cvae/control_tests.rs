//! Pace, foot contact and latent control of the motion model: the contact score counts a foot's
//! vertical speed (3-D, EgoGen/DIMOS) where GAMMA's horizontal variant does not; the CEM
//! controller moves the body faster when asked and keeps its best sample; decoded chains
//! export as AMASS-style npz that read back frame for frame (the shipped training config's
//! pace is `tests/motion_control.rs`: it reads the config as the command does).

use std::path::PathBuf;

use crate::body::BodyModel;
use crate::motion::cvae::control::{chain_sequence, CemSettings, LatentController, PaceTarget};
use crate::motion::cvae::measure::{contact_score, contact_score_horizontal};
use crate::motion::cvae::pace::Pace;
use crate::motion::cvae::train::{normal_samples, shipped_weights_path};
use crate::motion::cvae::{BodyContext, MotionModel, PrimitiveSeed};
use rand_core::SeedableRng;

fn walking_seed() -> PrimitiveSeed {
    let path = crate::paths::crate_root().join("assets/motion/cmu_01_03.npz");
    let clip = crate::motion::MotionSequence::read(&path).unwrap();
    PrimitiveSeed {
        frames: [clip.frame(80), clip.frame(81)],
        floor_z: 0.0,
    }
}

#[test]
fn contact_counts_vertical_foot_speed_only_in_3d() {
    // Two feet, 20 frames: one planted 2 cm above the floor; the other rises 1 cm per frame.
    let feet: Vec<Vec<[f64; 3]>> = (0..20)
        .map(|t| vec![[0.0, 0.0, 0.02], [0.3, 0.0, 0.02 + 0.01 * t as f64]])
        .collect();
    // The planted foot is the slowest: perfect in both.
    assert!((contact_score(&feet, 0.0) - 1.0).abs() < 1e-12);
    assert!((contact_score_horizontal(&feet, 0.0) - 1.0).abs() < 1e-12);
    // Both feet rising at 0.4 m/s: 3-D speed counts it as skating, horizontal speed does not.
    let rising: Vec<Vec<[f64; 3]>> = (0..20)
        .map(|t| {
            let z = 0.02 + 0.01 * t as f64;
            vec![[0.0, 0.0, z], [0.3, 0.0, z]]
        })
        .collect();
    let three_d = contact_score(&rising, 0.0);
    let flat = contact_score_horizontal(&rising, 0.0);
    // Central difference: 2 cm over 2 frames at 40 Hz = 0.4 m/s, 0.325 above the free speed.
    assert!(
        (flat - (-mean_height_error(&rising)).exp()).abs() < 1e-12,
        "{flat}"
    );
    assert!(
        (three_d - flat * (-0.325f64).exp()).abs() < 1e-9,
        "{three_d} vs {flat}"
    );
}

fn mean_height_error(feet: &[Vec<[f64; 3]>]) -> f64 {
    feet.iter()
        .map(|f| (f.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min) - 0.02).abs())
        .sum::<f64>()
        / feet.len() as f64
}

#[test]
fn the_controller_walks_faster_when_asked_and_keeps_its_best_sample() {
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body =
        BodyModel::load(crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let seed = walking_seed();
    let settings = CemSettings {
        samples: 24,
        iterations: 2,
        ..CemSettings::default()
    };
    let controller = LatentController::new(&ctx, settings).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let heading = {
        let last = &seed.frames[1];
        let joints = ctx.shaped.skeleton(&last.pose, last.transl).unwrap().joints;
        crate::motion::cvae::pace::heading_rad(&joints)
    };
    let mut speed_for = |v: f64| {
        controller
            .next(
                &model,
                &ctx,
                &seed,
                &PaceTarget {
                    speed_m_s: v,
                    heading_rad: heading,
                },
                &mut rng,
            )
            .unwrap()
    };
    let slow = speed_for(0.0);
    let fast = speed_for(2.0);
    assert!(
        fast.pace.speed_m_s > slow.pace.speed_m_s + 0.1,
        "asked 0 → {:?}, asked 2 → {:?}",
        slow.pace,
        fast.pace
    );
    // The kept primitive is at least as good as plain random latents from the same seed.
    let target = PaceTarget {
        speed_m_s: 1.0,
        heading_rad: heading,
    };
    let chosen = controller
        .next(&model, &ctx, &seed, &target, &mut rng)
        .unwrap();
    let latents: Vec<Vec<f32>> = (0..8).map(|_| normal_samples(&mut rng, 128)).collect();
    let plain = model
        .decode(&ctx, &vec![seed.clone(); 8], &latents)
        .unwrap();
    let plain_err: Vec<f64> = plain
        .iter()
        .map(|p| (Pace::of_frames(&p.joints).speed_m_s - 1.0).abs())
        .collect();
    let best_plain = plain_err.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        (chosen.pace.speed_m_s - 1.0).abs() <= best_plain + 0.05,
        "CEM {:?} vs random {plain_err:?}",
        chosen.pace
    );
    assert!(chosen.cost.is_finite());
    // The pace it reports is the primitive's.
    assert_eq!(chosen.pace, Pace::of_frames(&chosen.primitive.joints));
}

#[test]
fn decoded_chains_export_as_amass_npz_that_reads_back() {
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body =
        BodyModel::load(crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut seed = walking_seed();
    let mut prims = Vec::new();
    for _ in 0..3 {
        let p = model
            .decode(
                &ctx,
                std::slice::from_ref(&seed),
                &[normal_samples(&mut rng, 128)],
            )
            .unwrap()
            .remove(0);
        seed = p.next_seed();
        prims.push(p);
    }
    let refs: Vec<_> = prims.iter().collect();
    let seq = chain_sequence(&refs, &[]);
    assert_eq!(seq.len(), 2 + 3 * 18);
    assert_eq!(seq.frame_rate_hz, 40.0);
    assert_eq!(
        seq.betas,
        vec![0.0; 10],
        "the mean shape as AMASS writes it"
    );
    // Frame 20 is the second primitive's first decoded frame (it continues the first's).
    assert_eq!(seq.poses[20], prims[1].world[2].pose);
    assert_eq!(seq.poses[19], prims[0].world[19].pose);
    let dir = tempfile::tempdir().unwrap();
    let path: PathBuf = dir.path().join("chain.npz");
    seq.write_amass(&path).unwrap();
    let back = crate::motion::MotionSequence::read(&path).unwrap();
    assert_eq!(back.len(), seq.len());
    for (a, b) in back.poses.iter().zip(&seq.poses) {
        assert_eq!(a, b);
    }
    for (a, b) in back.trans.iter().zip(&seq.trans) {
        assert!((*a - *b).length() < 1e-12);
    }
}
