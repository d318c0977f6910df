//! The motion model's decoder and training read through their internals: the f32 decoder
//! equals burn's network, half-precision weights decode the same motion, the shipped weights
//! decode finite rigid bodies (one primitive, fifty chained), goal costs and best-of-k, the
//! prior losses on mocap and off it, the contact filter's context, and training chains seeded
//! as inference seeds them. (Training runs and configs read as the command reads them:
//! `tests/primitive_model.rs`.)

use std::path::PathBuf;

use crate::motion::cvae::MotionModel;

fn model_path() -> PathBuf {
    crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz")
}

fn clip(name: &str) -> PathBuf {
    crate::paths::crate_root().join("assets/motion").join(name)
}

/// Seeds from the shipped walking clip (world frames, floor at z = 0).
fn walking_seeds(count: usize) -> Vec<crate::motion::cvae::PrimitiveSeed> {
    let clip = crate::motion::MotionSequence::read(&clip("cmu_01_03.npz")).unwrap();
    (0..count)
        .map(|i| crate::motion::cvae::PrimitiveSeed {
            frames: [clip.frame(40 * i), clip.frame(40 * i + 1)],
            floor_z: 0.0,
        })
        .collect()
}

#[test]
fn the_f32_decoder_equals_burns_network_to_float_rounding() {
    use crate::body::BodyModel;
    use crate::motion::cvae::train::{normal_samples, shipped_weights_path};
    use crate::motion::cvae::{BodyContext, CanonicalSeed};
    use rand_core::SeedableRng;
    // Every batch size in f32 (a primitive alone reads f16 weights by default: the test
    // below).
    let model = MotionModel::load(shipped_weights_path())
        .unwrap()
        .without_half_precision();
    let body = BodyModel::load(model_path()).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let seeds = walking_seeds(8);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    // 1 primitive, and 40 (more than one block of 32, run on both cores); the last 8 latents
    // far out in the prior's tail (5 σ).
    for b in [1usize, 40] {
        let (mut features, mut floors) = (Vec::new(), Vec::new());
        for i in 0..b {
            let c = CanonicalSeed::new(&ctx, &seeds[i % seeds.len()]).unwrap();
            features.extend_from_slice(&c.features);
            floors.push(c.floor);
        }
        let latents: Vec<f32> = (0..b)
            .flat_map(|i| {
                let scale = if i >= 32 { 5.0 } else { 1.0 };
                normal_samples(&mut rng, 128)
                    .into_iter()
                    .map(move |v| v * scale)
            })
            .collect();
        let fast = model.decode_features(&features, &floors, &latents);
        let reference = model.decode_features_burn(&features, &floors, &latents);
        assert_eq!(fast.len(), reference.len());
        let worst = fast
            .iter()
            .zip(&reference)
            .map(|(a, r)| (a - r).abs() / (1.0 + r.abs()))
            .fold(0.0f32, f32::max);
        assert!(fast.iter().all(|v| v.is_finite()));
        assert!(worst < 1e-4, "batch {b}: largest difference {worst}");
        // The seed frames come back as they went in.
        assert_eq!(&fast[..2 * 135], &features[..2 * 135]);
    }
    // In another precision decoding runs burn's network.
    let half = MotionModel::load(shipped_weights_path())
        .unwrap()
        .with_precision(burn::tensor::FloatDType::BF16);
    let c = CanonicalSeed::new(&ctx, &seeds[0]).unwrap();
    let z = normal_samples(&mut rng, 128);
    assert_eq!(
        half.decode_features(&c.features, &[c.floor], &z),
        half.decode_features_burn(&c.features, &[c.floor], &z)
    );
}

/// A primitive decoded alone on f16 weights (the default where the processor has
/// F16C) moves its joints as the f32 decoder does, to a fraction of a millimetre.
#[test]
fn half_precision_weights_decode_the_same_motion_as_f32() {
    use crate::body::BodyModel;
    use crate::motion::cvae::train::{normal_samples, shipped_weights_path};
    use crate::motion::cvae::BodyContext;
    use rand_core::SeedableRng;
    let half = MotionModel::load(shipped_weights_path()).unwrap();
    if !half.half_precision_weights() {
        eprintln!("no AVX2/FMA/F16C here: every primitive decodes in f32");
        return;
    }
    let full = MotionModel::load(shipped_weights_path())
        .unwrap()
        .without_half_precision();
    assert!(!full.half_precision_weights());
    let body = BodyModel::load(model_path()).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let seeds = walking_seeds(8);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let (mut worst_m, mut sum_m, mut count) = (0.0f64, 0.0f64, 0usize);
    // 32 primitives, the last 8 with latents at 3 σ.
    for i in 0..32 {
        let scale = if i >= 24 { 3.0 } else { 1.0 };
        let z: Vec<f32> = normal_samples(&mut rng, 128)
            .into_iter()
            .map(|v| v * scale)
            .collect();
        let seed = std::slice::from_ref(&seeds[i % seeds.len()]);
        let a = half.decode(&ctx, seed, std::slice::from_ref(&z)).unwrap();
        let b = full.decode(&ctx, seed, std::slice::from_ref(&z)).unwrap();
        for (fa, fb) in a[0].joints.iter().zip(&b[0].joints) {
            for (ja, jb) in fa.iter().zip(fb) {
                let d = (*ja - *jb).length();
                worst_m = worst_m.max(d);
                sum_m += d;
                count += 1;
            }
        }
    }
    let mean_m = sum_m / count as f64;
    eprintln!(
        "f16 weights against f32: joints {:.3} mm mean, {:.3} mm worst",
        mean_m * 1e3,
        worst_m * 1e3
    );
    // Measured: 0.060 mm mean, 0.52 mm worst (2026-11-25).
    assert!(
        mean_m < 0.2e-3 && worst_m < 2e-3,
        "mean {mean_m} m, worst {worst_m} m"
    );
}

#[test]
fn shipped_weights_decode_a_batch_of_finite_rigid_bodies() {
    use crate::body::{BodyModel, NUM_MARKERS, PARENTS};
    use crate::motion::cvae::train::{normal_samples, shipped_weights_path};
    use crate::motion::cvae::BodyContext;
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    assert_eq!(model.latent_dim(), 128);
    let body = BodyModel::load(model_path()).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let seeds = walking_seeds(8);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let latents: Vec<Vec<f32>> = (0..8).map(|_| normal_samples(&mut rng, 128)).collect();
    let out = model.decode(&ctx, &seeds, &latents).unwrap();
    assert_eq!(out.len(), 8);
    let rest = body.rest_joints(&[], &[]).unwrap();
    for (p, seed) in out.iter().zip(&seeds) {
        assert_eq!(p.world.len(), 20);
        assert_eq!(p.markers.len(), 20);
        assert_eq!(p.world_from_cpf.len(), 20);
        // The seed comes back unchanged.
        for k in 0..2 {
            assert!((p.world[k].transl - seed.frames[k].transl).length() < 1e-9);
        }
        for (f, joints) in p.joints.iter().enumerate() {
            assert_eq!(p.markers[f].len(), NUM_MARKERS);
            assert!(p.markers[f].iter().all(|m| m.is_finite()));
            assert!(p.world_from_cpf[f].is_finite());
            for j in 1..22 {
                let parent = PARENTS[j].unwrap();
                let d = joints[j].distance(joints[parent]) - rest[j].distance(rest[parent]);
                assert!(d.abs() < 1e-9, "frame {f} bone {j}: {d} m");
            }
        }
    }
    // Wrong latent size is refused with the sizes named.
    let err = model
        .decode(&ctx, &seeds[..1], &[vec![0.0; 3]])
        .unwrap_err()
        .to_string();
    assert!(err.contains('3') && err.contains("128"), "{err}");
}

#[test]
fn fifty_chained_primitives_stay_finite_and_rigid() {
    use crate::body::BodyModel;
    use crate::motion::cvae::measure::long_rollout;
    use crate::motion::cvae::train::shipped_weights_path;
    use crate::motion::cvae::{BestOfK, BodyContext, PlausibilityRules};
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body = BodyModel::load(model_path()).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let plain = BestOfK::new(&ctx, 1, PlausibilityRules::default()).unwrap();
    // `decode` refuses non-finite output, so reaching the end means no NaN anywhere.
    let (report, prims) = long_rollout(
        &model,
        &ctx,
        walking_seeds(1).remove(0),
        50,
        &plain,
        &mut rng,
    )
    .unwrap();
    assert_eq!(prims.len(), 50);
    assert_eq!(report.frames, 50 * 18);
    assert!(report.canonical_orthonormality_max_err < 1e-9);
    assert!(report.bone_length_max_dev_m < 1e-9);
    // Random-latent chains of the shipped weights stay upright with their feet on the floor
    // for 1 000 primitives (docs/MOTION.md); all 25 s of this one must, and the body must keep
    // moving.
    assert_eq!(report.upright_primitives, 50, "{report:?}");
    assert!(report.feet_on_floor_share > 0.95, "{report:?}");
    assert!(report.moving_share > 0.2, "{report:?}");
    assert!(report.displacement_m > 0.5, "{report:?}");
}

#[test]
fn a_goal_costs_its_weight_per_metre_left_to_walk() {
    use crate::body::BodyModel;
    use crate::motion::cvae::sampler::plausibility;
    use crate::motion::cvae::tensor_body::RigGeometry;
    use crate::motion::cvae::train::{normal_samples, shipped_weights_path};
    use crate::motion::cvae::{goal_ahead, goal_toward, BodyContext, PlausibilityRules};
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body = BodyModel::load(model_path()).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let feet = RigGeometry::new(&body, &[]).unwrap().foot_markers;
    let seed = walking_seeds(1).remove(0);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let p = model
        .decode(
            &ctx,
            std::slice::from_ref(&seed),
            &[normal_samples(&mut rng, 128)],
        )
        .unwrap()
        .remove(0);
    // The goal lies in front of the body: 10 m ahead of the seed's pelvis.
    let pelvis = goal_ahead(&ctx, &seed, 0.0).unwrap();
    let goal = goal_ahead(&ctx, &seed, 10.0).unwrap();
    assert!(((goal[0] - pelvis[0]).hypot(goal[1] - pelvis[1]) - 10.0).abs() < 1e-9);
    // Goals at other bearings: 90° to the left lies on the left hip's side, square to ahead;
    // 180° is behind.
    let toward = |bearing_deg: f64| {
        let g = goal_toward(&ctx, &seed, 10.0, bearing_deg.to_radians()).unwrap();
        glam::DVec2::new(g[0] - pelvis[0], g[1] - pelvis[1])
    };
    let ahead = toward(0.0);
    assert!((ahead - glam::DVec2::new(goal[0] - pelvis[0], goal[1] - pelvis[1])).length() < 1e-9);
    let last = &seed.frames[1];
    let joints = ctx.shaped.skeleton(&last.pose, last.transl).unwrap().joints;
    let hip_left = (joints[crate::body::joint::LEFT_HIP] - joints[0]).truncate();
    let left_goal = toward(90.0);
    assert!(left_goal.dot(hip_left) > 0.0 && left_goal.dot(ahead).abs() < 1e-9);
    assert!((left_goal.length() - 10.0).abs() < 1e-9);
    assert!((toward(180.0) + ahead).length() < 1e-9);
    let free = plausibility(&p, &feet, &PlausibilityRules::default());
    let rules = PlausibilityRules {
        goal_xy: Some(goal),
        goal_weight: 3.0,
        ..PlausibilityRules::default()
    };
    let steered = plausibility(&p, &feet, &rules);
    let end = p.joints[p.joints.len() - 1][0];
    let left = (end.x - goal[0]).hypot(end.y - goal[1]);
    assert!((steered.goal_distance_m - left).abs() < 1e-12);
    assert!((free.score - steered.score - 3.0 * left).abs() < 1e-9);
    assert_eq!(free.goal_distance_m, 0.0);
    // The seed walks forward, so its primitive ends nearer the goal than it started.
    assert!(left < 10.0, "{left} m left of 10");
}

#[test]
fn best_of_k_keeps_the_most_plausible_of_its_draws() {
    use crate::body::BodyModel;
    use crate::motion::cvae::sampler::plausibility;
    use crate::motion::cvae::tensor_body::RigGeometry;
    use crate::motion::cvae::train::{normal_samples, shipped_weights_path};
    use crate::motion::cvae::{BestOfK, BodyContext, PlausibilityRules};
    use rand_core::SeedableRng;
    // In f32 at every batch size, so that one draw decodes alone as in the batch.
    let model = MotionModel::load(shipped_weights_path())
        .unwrap()
        .without_half_precision();
    let body = BodyModel::load(model_path()).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let rules = PlausibilityRules::default();
    let feet = RigGeometry::new(&body, &[]).unwrap().foot_markers;
    let seed = walking_seeds(3).remove(2);
    let sampler = BestOfK::new(&ctx, 6, rules).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let chosen = sampler.next(&model, &ctx, &seed, &mut rng).unwrap();
    // The same six draws, decoded one by one.
    let mut again = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let scores: Vec<f64> = (0..6)
        .map(|_| {
            let z = normal_samples(&mut again, 128);
            let p = model
                .decode(&ctx, std::slice::from_ref(&seed), &[z])
                .unwrap()
                .remove(0);
            plausibility(&p, &feet, &rules).score
        })
        .collect();
    let best = scores.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!(scores.iter().any(|&s| s < best), "draws differ: {scores:?}");
    // Decoded as a batch of six or one by one: equal to float rounding (the f32 decoder's
    // summation order depends on the batch size).
    assert!(
        (chosen.plausibility.score - best).abs() < 1e-5,
        "{scores:?} vs {:?}",
        chosen.plausibility
    );
    assert_eq!(chosen.non_finite_candidates, 0);
    // Plausibility of a mocap walk: feet on the floor, upright, moving.
    let p = chosen.plausibility;
    assert!(p.contact > 0.8 && p.pelvis_out_m == 0.0, "{p:?}");
    // Lifting the body 0.5 m costs contact and pelvis height.
    let mut lifted = chosen.primitive.clone();
    for m in lifted.markers.iter_mut().flatten() {
        m.z += 0.5;
    }
    for j in lifted.joints.iter_mut().flatten() {
        j.z += 0.5;
    }
    let l = plausibility(&lifted, &feet, &rules);
    assert!(l.score < p.score - 0.5 && l.pelvis_out_m > 0.1, "{l:?}");
}

#[test]
fn prior_losses_are_small_on_mocap_and_grow_when_the_body_leaves_the_floor_or_leans() {
    use crate::body::BodyModel;
    use crate::motion::cvae::data::{build_set, ClipPart};
    use crate::motion::cvae::features::{FRAME_DIM, TRANSL_OFFSET};
    use crate::motion::cvae::loss::{plausible_range, prior_loss, PriorWeights};
    use crate::motion::cvae::measure::set_batch;
    use crate::motion::cvae::tensor_body::{RigGeometry, TensorRig};
    use burn::backend::Flex;
    use burn::prelude::*;

    let body = BodyModel::load(model_path()).unwrap();
    let seq =
        crate::motion::MotionSequence::read(&clip("deepmimic_walker_0walk_forward.npz")).unwrap();
    let part = ClipPart {
        frames: 0..seq.len(),
        seq,
    };
    let set = build_set(&[part], 1, 2, false, &body, None).unwrap();
    let device = Default::default();
    let rig = TensorRig::<Flex>::new(&RigGeometry::new(&body, &[]).unwrap(), &device);
    let (x, floors) = set_batch::<Flex>(&set, 0..set.len(), &device);
    let floor =
        || Tensor::<Flex, 1>::from_data(TensorData::new(floors.clone(), [floors.len()]), &device);
    let mut range = plausible_range(&rig, x.clone(), floor(), 0.0);
    range.pelvis_speed_min = 0.5;
    assert!(
        range.pelvis_m.0 > 0.6 && range.pelvis_m.1 < 1.2 && range.trunk_up_min > 0.7,
        "{range:?}"
    );
    let one = |name: &str| PriorWeights {
        contact: (name == "contact") as u8 as f64,
        skate: (name == "skate") as u8 as f64,
        penetration: (name == "penetration") as u8 as f64,
        pelvis: (name == "pelvis") as u8 as f64,
        upright: (name == "upright") as u8 as f64,
        speed: (name == "speed") as u8 as f64,
        recovery: 0.0,
        anchor: (name == "anchor") as u8 as f64,
    };
    let anchored = |x: Tensor<Flex, 3>, name: &str, anchor: Option<Tensor<Flex, 3>>| {
        prior_loss(&rig, &one(name), &range, x, floor(), anchor)
            .total
            .into_scalar()
            .elem::<f64>()
    };
    let term = |x: Tensor<Flex, 3>, name: &str| anchored(x, name, None);
    // The mocap walk itself: feet on the floor, inside its own ranges.
    assert!(term(x.clone(), "contact") < 0.05);
    assert!(term(x.clone(), "skate") < 0.1);
    assert!(term(x.clone(), "penetration") < 0.005);
    assert_eq!(term(x.clone(), "pelvis"), 0.0);
    assert_eq!(term(x.clone(), "upright"), 0.0);
    assert_eq!(term(x.clone(), "speed"), 0.0);
    // Every decoded frame frozen at the seed's last: a body standing still is 0.5 m/s short
    // of the slowest walk allowed.
    let [b, t, _] = x.dims();
    let frozen = {
        let mut v: Vec<f32> = x.clone().into_data().to_vec().unwrap();
        for i in 0..b {
            let last_seed = (i * t + 1) * FRAME_DIM;
            let seed_frame = v[last_seed..last_seed + FRAME_DIM].to_vec();
            for f in 2..t {
                let at = (i * t + f) * FRAME_DIM;
                v[at..at + FRAME_DIM].copy_from_slice(&seed_frame);
            }
        }
        Tensor::<Flex, 3>::from_data(TensorData::new(v, [b, t, FRAME_DIM]), &device)
    };
    let still = term(frozen, "speed");
    assert!(
        (0.49..0.51).contains(&still),
        "standing still scored {still}"
    );
    // Every frame after the seed lifted by 0.4 m: the contact term grows by about 0.4 m and
    // the pelvis leaves its range; sunk by 0.4 m, the feet go through the floor.
    let shift = |dz: f32| {
        let mut v = vec![0f32; b * t * FRAME_DIM];
        for i in 0..b {
            for f in 2..t {
                v[(i * t + f) * FRAME_DIM + TRANSL_OFFSET + 2] = dz;
            }
        }
        x.clone() + Tensor::from_data(TensorData::new(v, [b, t, FRAME_DIM]), &device)
    };
    let lifted = term(shift(0.4), "contact") - term(x.clone(), "contact");
    assert!((0.3..0.45).contains(&lifted), "contact grew by {lifted}");
    assert!(term(shift(0.4), "pelvis") > 0.1);
    assert!(term(shift(-0.4), "penetration") > 0.2);
    assert!(term(shift(-0.4), "pelvis") > 0.1);
    // A body pitched forward by 60° about its canonical x axis leans beyond the data's range.
    let (c, s) = (60f32.to_radians().cos(), 60f32.to_radians().sin());
    let mut pitched: Vec<f32> = x.clone().into_data().to_vec().unwrap();
    for frame in pitched.chunks_exact_mut(FRAME_DIM) {
        // Rotate both 6D columns of global orient about x.
        for col in 0..2 {
            let (y, z) = (frame[3 * col + 1], frame[3 * col + 2]);
            frame[3 * col + 1] = c * y - s * z;
            frame[3 * col + 2] = s * y + c * z;
        }
    }
    let pitched = Tensor::from_data(TensorData::new(pitched, [b, t, FRAME_DIM]), &device);
    assert!(term(pitched.clone(), "upright") > 0.1);
    // The anchor is the root's distance from the starting weights' decoding: none from
    // itself, a third of the lift (one of three `transl` values), and the pitch alone
    // (global orient only; the other 6D values are the legs').
    assert_eq!(anchored(x.clone(), "anchor", Some(x.clone())), 0.0);
    assert_eq!(term(shift(0.4), "anchor"), 0.0, "no anchor, no term");
    let lift = anchored(shift(0.4), "anchor", Some(x.clone()));
    assert!((lift - 0.4 / 3.0).abs() < 1e-6, "lift scored {lift}");
    let pitch = anchored(pitched.clone(), "anchor", Some(x.clone()));
    assert!(pitch > 0.05, "pitch scored {pitch}");
    assert_eq!(
        pitch,
        anchored(x.clone(), "anchor", Some(pitched)),
        "symmetric"
    );
}

#[test]
fn contact_context_drops_the_run_up_to_a_failing_primitive() {
    use crate::body::BodyModel;
    use crate::motion::cvae::data::ContactFilter;
    use crate::motion::cvae::data::PrimitiveSet;
    use crate::motion::MotionSequence;
    let body = BodyModel::load(model_path()).unwrap();
    // 4 s of walking with the body lifted 0.4 m off the floor for 0.5 s in the middle (like a
    // step onto an object): the primitives overlapping the lift fail the contact filter.
    let mut seq = MotionSequence::read(&clip("cmu_01_03.npz")).unwrap();
    seq.poses.truncate(160);
    seq.trans.truncate(160);
    for t in &mut seq.trans[70..90] {
        t.z += 0.4;
    }
    let count = |frames: std::ops::Range<usize>, context: usize| {
        let filter = ContactFilter::new(&body, 0.8, context).unwrap();
        let mut set = PrimitiveSet::new(1);
        set.add_clip(&seq, frames, 1, &body, Some(&filter)).unwrap();
        set.len()
    };
    // Oracle: which single primitives pass on their own.
    let passes: Vec<bool> = (0..=140).map(|s| count(s..s + 20, 0) == 1).collect();
    let failing: Vec<usize> = (0..=140).filter(|&s| !passes[s]).collect();
    assert!(
        failing.len() >= 20 && failing.len() < 60,
        "{} failing starts",
        failing.len()
    );
    for context in [0, 10, 40] {
        let expected = (0..=140usize)
            .filter(|&s| failing.iter().all(|&f| f.abs_diff(s) > context))
            .count();
        assert_eq!(count(0..160, context), expected, "context {context}");
    }
    assert!(count(0..160, 40) < count(0..160, 0));
}

#[test]
fn training_chains_seed_the_next_primitive_as_inference_does() {
    use crate::body::BodyModel;
    use crate::motion::cvae::rollout::next_seed;
    use crate::motion::cvae::tensor_body::{RigGeometry, TensorRig};
    use crate::motion::cvae::train::{normal_samples, shipped_weights_path};
    use crate::motion::cvae::{BodyContext, CanonicalSeed};
    use burn::backend::Flex;
    use burn::prelude::*;
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body = BodyModel::load(model_path()).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let seeds = walking_seeds(4);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
    let latents: Vec<Vec<f32>> = (0..4).map(|_| normal_samples(&mut rng, 128)).collect();
    // Inference: decode, take the last two world frames, canonicalise them (f64).
    let decoded = model.decode(&ctx, &seeds, &latents).unwrap();
    // Training: the raw network output, chained on tensors.
    let canon: Vec<CanonicalSeed> = seeds
        .iter()
        .map(|s| CanonicalSeed::new(&ctx, s).unwrap())
        .collect();
    let features: Vec<f32> = canon.iter().flat_map(|c| c.features.clone()).collect();
    let floors: Vec<f32> = canon.iter().map(|c| c.floor).collect();
    let flat: Vec<f32> = latents.concat();
    let raw = model.decode_features(&features, &floors, &flat);
    let f = raw.len() / 4 / 20;
    let device = Default::default();
    let rig = TensorRig::<Flex>::new(&RigGeometry::new(&body, &[]).unwrap(), &device);
    let x = Tensor::<Flex, 3>::from_data(TensorData::new(raw.clone(), [4, 20, f]), &device);
    let (seed, height) = next_seed(&rig, x);
    let seed: Vec<f32> = seed.into_data().to_vec().unwrap();
    let height: Vec<f32> = height.into_data().to_vec().unwrap();
    // The raw output is not a set of valid rotations: the seed must not copy it.
    let d6 = &raw[19 * f + 6..19 * f + 12];
    let norm = (d6[..3].iter().map(|v| v * v).sum::<f32>()).sqrt();
    assert!((norm - 1.0).abs() > 1e-4, "raw 6D column norm {norm}");
    for i in 0..4 {
        let next = CanonicalSeed::new(&ctx, &decoded[i].next_seed()).unwrap();
        let tensor_seed = &seed[i * 2 * f..(i + 1) * 2 * f];
        let worst = next
            .features
            .iter()
            .zip(tensor_seed)
            .map(|(a, b)| (a - b).abs())
            .fold(0f32, f32::max);
        assert!(worst < 1e-4, "chain {i}: seed features differ by {worst}");
        let floor = floors[i] - height[i];
        assert!(
            (floor - next.floor).abs() < 1e-4,
            "{floor} vs {}",
            next.floor
        );
    }
}
