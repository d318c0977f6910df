//! The motion-primitive C-VAE: a tiny real training run lowers its loss and writes loadable
//! weights; weights files with the wrong shapes or no architecture are refused by name; bad
//! training configs are refused naming file and key.

mod common;

use std::path::{Path, PathBuf};

use egogen::cli::train_primitive::load_train_plan;
use egogen::motion::cvae::loss::{LossWeights, PriorWeights};
use egogen::motion::cvae::train::{ClipSpec, PhasePlan, PriorPlan, TrainPlan};
use egogen::motion::cvae::{train, ArchConfig, MotionModel};

fn clip(name: &str) -> PathBuf {
    common::repo_root().join("assets/motion").join(name)
}

fn tiny_plan(dir: &Path) -> TrainPlan {
    TrainPlan {
        seed: 3,
        body_model: common::default_model_path(),
        clips: vec![
            ClipSpec {
                path: clip("deepmimic_walk.npz"),
                held_out: false,
                held_out_from_s: None,
            },
            ClipSpec {
                path: clip("deepmimic_walker_turn_left0.npz"),
                held_out: true,
                held_out_from_s: None,
            },
        ],
        stride_frames: 2,
        mirror: true,
        min_contact_score: Some(0.5),
        contact_context_frames: 0,
        arch: ArchConfig {
            latent_dim: 8,
            encoder_width: 32,
            decoder_width: 32,
        },
        loss: LossWeights {
            pose: 1.0,
            transl: 1.0,
            markers: 2.0,
            velocity: 4.0,
            skate: 0.1,
            floor: 1.0,
            kl: 0.001,
        },
        kl_warmup_steps: 0,
        seed_noise: 0.1,
        primitive: PhasePlan {
            steps: 41,
            batch_size: 16,
            learning_rate: 3e-3,
        },
        rollout: PhasePlan {
            steps: 2,
            batch_size: 4,
            learning_rate: 1e-3,
        },
        rollout_primitives: 2,
        prior: Some(PriorPlan {
            phase: PhasePlan {
                steps: 2,
                batch_size: 4,
                learning_rate: 1e-3,
            },
            primitives: 2,
            pool_fraction: 0.5,
            pool_slots: None,
            range_quantile: 0.01,
            trunk_tilt_max_deg: Some(30.0),
            min_pelvis_speed_m_s: 0.5,
            weights: PriorWeights {
                contact: 1.0,
                skate: 1.0,
                penetration: 1.0,
                pelvis: 1.0,
                upright: 1.0,
                speed: 1.0,
                recovery: 1.0,
                // Needs init_weights; the fine-tuning below turns it on.
                anchor: 0.0,
            },
        }),
        init_weights: None,
        weights_out: dir.join("tiny.safetensors"),
        log_out: dir.join("tiny.log.jsonl"),
        checkpoint_every_s: 300.0,
    }
}

#[test]
fn tiny_training_run_lowers_the_loss_and_writes_loadable_weights() {
    let dir = tempfile::tempdir().unwrap();
    let plan = tiny_plan(dir.path());
    let report = train(&plan, false, false).unwrap();
    assert!(report.train_primitives > 0 && report.held_out_primitives > 0);
    let log = std::fs::read_to_string(&plan.log_out).unwrap();
    let losses: Vec<(String, f64)> = log
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter_map(|v| Some((v["phase"].as_str()?.to_owned(), v["loss"].as_f64()?)))
        .collect();
    let primitive: Vec<f64> = losses
        .iter()
        .filter(|(p, _)| p == "primitive")
        .map(|(_, l)| *l)
        .collect();
    assert!(primitive.len() >= 5, "{log}");
    let (first, last) = (primitive[0], *primitive.last().unwrap());
    assert!(
        last < 0.7 * first,
        "loss went from {first} to {last}, expected a clear drop"
    );
    assert!(losses.iter().any(|(p, l)| p == "rollout" && l.is_finite()));
    assert!(losses.iter().any(|(p, l)| p == "prior" && l.is_finite()));
    assert!(
        log.contains("prior_contact") && log.contains("prior_range"),
        "{log}"
    );
    // The second prior step has a pool of chain ends to recover from.
    assert!(log.contains("\"recovery\""), "{log}");
    let mm = report.held_out_mpjpe_mm.unwrap();
    assert!(mm.is_finite() && mm > 0.0, "held-out error {mm} mm");

    let model = MotionModel::load(&plan.weights_out).unwrap();
    assert_eq!(model.arch, plan.arch);

    // Random latents spread the decoded primitives; one latent for every draw does not.
    {
        use egogen::body::BodyModel;
        use egogen::motion::cvae::measure::latent_spread_mm;
        use egogen::motion::cvae::tensor_body::{RigGeometry, TensorRig};
        use egogen::motion::cvae::train::{evaluation_sets, normal_samples};
        use rand_core::SeedableRng;
        let body = BodyModel::load(common::default_model_path()).unwrap();
        let (train_set, _) = evaluation_sets(&plan, &body, true).unwrap();
        let rig = TensorRig::new(&RigGeometry::new(&body, &[]).unwrap(), &Default::default());
        let l = model.latent_dim();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let z = normal_samples(&mut rng, 4 * 4 * l);
        let spread = latent_spread_mm(&model.net, &rig, &train_set, 4, &z);
        assert!(spread.is_finite() && spread > 0.01, "{spread} mm");
        let same = z[..l].repeat(16);
        let none = latent_spread_mm(&model.net, &rig, &train_set, 4, &same);
        assert!(none < 1e-3, "{none} mm");
    }

    // Fine-tuning starts from those weights; another architecture is refused.
    let mut tune = plan.clone();
    tune.init_weights = Some(plan.weights_out.clone());
    tune.primitive.steps = 0;
    tune.rollout.steps = 0;
    tune.weights_out = dir.path().join("tuned.safetensors");
    tune.prior.as_mut().unwrap().weights.anchor = 1.0;
    tune.log_out = dir.path().join("tuned.log.jsonl");
    let tuned = train(&tune, false, false).unwrap();
    let tuned_mm = tuned.held_out_mpjpe_mm.unwrap();
    assert!(tuned_mm.is_finite(), "{tuned_mm}");
    // The anchor starts at 0 (the frozen copy decodes the same seeds and latents) and grows
    // once the weights move.
    let anchor: Vec<f64> = std::fs::read_to_string(&tune.log_out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter_map(|v| v["prior_anchor"].as_f64())
        .collect();
    assert_eq!(anchor.len(), 2, "{anchor:?}");
    assert!(anchor[0] < 1e-6 && anchor[1] > anchor[0], "{anchor:?}");
    tune.arch.decoder_width = 16;
    let err = train(&tune, false, false).unwrap_err().to_string();
    assert!(
        err.contains("tiny.safetensors") && err.contains("architecture"),
        "{err}"
    );
}

#[test]
fn weights_of_another_architecture_are_refused_naming_the_tensor() {
    let dir = tempfile::tempdir().unwrap();
    let plan = tiny_plan(dir.path());
    let arch = plan.arch;
    let small: egogen::motion::cvae::PrimitiveVae<burn::backend::Flex> =
        arch.init(&Default::default(), &Default::default());
    let path = dir.path().join("w.safetensors");
    // A file whose header claims a wider decoder than its tensors have.
    let wider = ArchConfig {
        decoder_width: 48,
        ..arch
    };
    egogen::motion::cvae::weights::save(&small, &wider, &path).unwrap();
    let err = MotionModel::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("w.safetensors") && err.contains("tensor `"),
        "{err}"
    );
    assert!(err.contains("shape"), "{err}");

    let missing = MotionModel::load(dir.path().join("none.safetensors"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("none.safetensors"), "{missing}");

    std::fs::write(
        dir.path().join("junk.safetensors"),
        b"\x10\0\0\0\0\0\0\0{\"a\":1}         ",
    )
    .unwrap();
    let junk = MotionModel::load(dir.path().join("junk.safetensors"))
        .unwrap_err()
        .to_string();
    assert!(junk.contains("egogen.arch"), "{junk}");
}

#[test]
fn bad_training_configs_are_refused_naming_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let shipped = std::fs::read_to_string(common::repo_root().join("configs/train_primitive.toml"))
        .unwrap()
        .replace(
            "../assets",
            &common::repo_root().join("assets").display().to_string(),
        );
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // The shipped config resolves.
    let ok = write("ok.toml", &shipped);
    let plan = load_train_plan(&ok).unwrap();
    assert_eq!(plan.arch.latent_dim, 128);
    assert!(plan.clips.iter().any(|c| c.held_out));

    // (file, edit of the shipped config, words the error must contain)
    let cases = [
        (
            "unknown.toml",
            ("[model]", "[model]\ndropout = 0.1"),
            "dropout",
        ),
        (
            "zero.toml",
            ("batch_size = 64", "batch_size = 0"),
            "primitive.batch_size",
        ),
        (
            "clip.toml",
            ("cmu_01_01.npz", "cmu_99_99.npz"),
            "clips[0].path",
        ),
        (
            "chain.toml",
            ("primitives = 3", "primitives = 1"),
            "rollout.primitives",
        ),
        (
            "rate.toml",
            ("learning_rate = 0.001", "learning_rate = 2.0"),
            "primitive.learning_rate",
        ),
        (
            "context.toml",
            (
                "min_contact_score = 0.8",
                "min_contact_score = 0.8\ncontact_context_s = -1.0",
            ),
            "data.contact_context_s",
        ),
        (
            "context_alone.toml",
            ("min_contact_score = 0.8", "contact_context_s = 1.0"),
            "data.contact_context_s",
        ),
    ];
    for (name, (from, to), key) in cases {
        assert!(shipped.contains(from), "{from}");
        let path = write(name, &shipped.replace(from, to));
        let err = load_train_plan(&path).unwrap_err().to_string();
        assert!(err.contains(name) && err.contains(key), "{name}: {err}");
    }
}

/// Seeds from the shipped walking clip (world frames, floor at z = 0).
fn walking_seeds(count: usize) -> Vec<egogen::motion::cvae::PrimitiveSeed> {
    let clip = egogen::motion::MotionSequence::read(&clip("cmu_01_03.npz")).unwrap();
    (0..count)
        .map(|i| egogen::motion::cvae::PrimitiveSeed {
            frames: [clip.frame(40 * i), clip.frame(40 * i + 1)],
            floor_z: 0.0,
        })
        .collect()
}

#[test]
fn the_f32_decoder_equals_burns_network_to_float_rounding() {
    use egogen::body::BodyModel;
    use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
    use egogen::motion::cvae::{BodyContext, CanonicalSeed};
    use rand_core::SeedableRng;
    // Every batch size in f32 (a primitive alone reads f16 weights by default: the test
    // below).
    let model = MotionModel::load(shipped_weights_path())
        .unwrap()
        .without_half_precision();
    let body = BodyModel::load(common::default_model_path()).unwrap();
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
    use egogen::body::BodyModel;
    use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
    use egogen::motion::cvae::BodyContext;
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
    let body = BodyModel::load(common::default_model_path()).unwrap();
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
    use egogen::body::{BodyModel, NUM_MARKERS, PARENTS};
    use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
    use egogen::motion::cvae::BodyContext;
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    assert_eq!(model.latent_dim(), 128);
    let body = BodyModel::load(common::default_model_path()).unwrap();
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
    use egogen::body::BodyModel;
    use egogen::motion::cvae::measure::long_rollout;
    use egogen::motion::cvae::train::shipped_weights_path;
    use egogen::motion::cvae::{BestOfK, BodyContext, PlausibilityRules};
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body = BodyModel::load(common::default_model_path()).unwrap();
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
    use egogen::body::BodyModel;
    use egogen::motion::cvae::sampler::plausibility;
    use egogen::motion::cvae::tensor_body::RigGeometry;
    use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
    use egogen::motion::cvae::{goal_ahead, goal_toward, BodyContext, PlausibilityRules};
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body = BodyModel::load(common::default_model_path()).unwrap();
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
    let hip_left = (joints[egogen::body::joint::LEFT_HIP] - joints[0]).truncate();
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
    use egogen::body::BodyModel;
    use egogen::motion::cvae::sampler::plausibility;
    use egogen::motion::cvae::tensor_body::RigGeometry;
    use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
    use egogen::motion::cvae::{BestOfK, BodyContext, PlausibilityRules};
    use rand_core::SeedableRng;
    // In f32 at every batch size, so that one draw decodes alone as in the batch.
    let model = MotionModel::load(shipped_weights_path())
        .unwrap()
        .without_half_precision();
    let body = BodyModel::load(common::default_model_path()).unwrap();
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
    use burn::backend::Flex;
    use burn::prelude::*;
    use egogen::body::BodyModel;
    use egogen::motion::cvae::data::{build_set, ClipPart};
    use egogen::motion::cvae::features::{FRAME_DIM, TRANSL_OFFSET};
    use egogen::motion::cvae::loss::{plausible_range, prior_loss, PriorWeights};
    use egogen::motion::cvae::measure::set_batch;
    use egogen::motion::cvae::tensor_body::{RigGeometry, TensorRig};

    let body = BodyModel::load(common::default_model_path()).unwrap();
    let seq =
        egogen::motion::MotionSequence::read(&clip("deepmimic_walker_0walk_forward.npz")).unwrap();
    let part = ClipPart {
        name: "walk".into(),
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
fn prior_fine_tuning_configs_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let root = common::repo_root();
    let stage1 = root.join("configs/train_primitive.toml");
    let shipped = std::fs::read_to_string(root.join("configs/train_primitive_prior.toml"))
        .unwrap()
        .replace("../assets", &root.join("assets").display().to_string())
        .replace(
            "clips_from = \"train_primitive.toml\"",
            &format!("clips_from = \"{}\"", stage1.display()),
        );
    let init = init_weights_line(&shipped);
    // The first stage's weights are a build output; the shipped weights stand in for them.
    let resolved = shipped.replace(
        &init,
        &format!(
            "init_weights = \"{}\"",
            root.join("assets/motion/primitive_cvae.safetensors")
                .display()
        ),
    );
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let plan = load_train_plan(&write("ok.toml", &resolved)).unwrap();
    // Stage 2 trains on stage 1's clips and holds out the same ones (`clips_from`).
    assert_eq!(plan.clips, load_train_plan(&stage1).unwrap().clips);
    let prior = plan.prior.expect("a prior phase");
    assert!(prior.phase.steps > 0 && prior.primitives >= 2);
    assert!(plan.init_weights.is_some());
    for (name, text, key) in [
        (
            "pool.toml",
            resolved.replace("pool_fraction = 0.5", "pool_fraction = 1.5"),
            "prior.pool_fraction",
        ),
        (
            "weight.toml",
            resolved.replace("upright = ", "upright = -"),
            "prior.loss.upright",
        ),
        (
            "slots.toml",
            resolved.replace("range_quantile = ", "pool_slots = 3\nrange_quantile = "),
            "prior.pool_slots",
        ),
        (
            "tilt.toml",
            resolved.replace(
                "range_quantile = ",
                "trunk_tilt_max_deg = 95.0\nrange_quantile = ",
            ),
            "prior.trunk_tilt_max_deg",
        ),
        (
            "speed.toml",
            resolved.replace(
                "range_quantile = ",
                "min_pelvis_speed_m_s = -1.0\nrange_quantile = ",
            ),
            "prior.min_pelvis_speed_m_s",
        ),
        (
            "init.toml",
            shipped.replace(&init, "init_weights = \"none.safetensors\""),
            "init_weights",
        ),
        (
            "anchor.toml",
            resolved.replace(&init_weights_line(&resolved), ""),
            "prior.loss.anchor",
        ),
        (
            "both.toml",
            format!(
                "{resolved}\n[[clips]]\npath = \"{}\"\n",
                root.join("assets/motion/deepmimic_walk.npz").display()
            ),
            "clips_from",
        ),
    ] {
        assert_ne!(text, resolved, "{name}: the edit must apply");
        let err = load_train_plan(&write(name, &text))
            .unwrap_err()
            .to_string();
        assert!(err.contains(name) && err.contains(key), "{name}: {err}");
    }
}

/// The `init_weights = ...` line of a config.
fn init_weights_line(config: &str) -> String {
    config
        .lines()
        .find(|l| l.starts_with("init_weights"))
        .expect("init_weights line")
        .to_owned()
}

#[test]
fn contact_context_drops_the_run_up_to_a_failing_primitive() {
    use egogen::body::BodyModel;
    use egogen::motion::cvae::data::ContactFilter;
    use egogen::motion::cvae::data::PrimitiveSet;
    use egogen::motion::MotionSequence;
    let body = BodyModel::load(common::default_model_path()).unwrap();
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
    use burn::backend::Flex;
    use burn::prelude::*;
    use egogen::body::BodyModel;
    use egogen::motion::cvae::rollout::next_seed;
    use egogen::motion::cvae::tensor_body::{RigGeometry, TensorRig};
    use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
    use egogen::motion::cvae::{BodyContext, CanonicalSeed};
    use rand_core::SeedableRng;
    let model = MotionModel::load(shipped_weights_path()).unwrap();
    let body = BodyModel::load(common::default_model_path()).unwrap();
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

/// A tiny config with all three phases (and the seed pool), checkpointing after every step,
/// writing into `dir`.
fn tiny_config(dir: &Path) -> String {
    let assets = common::repo_root().join("assets/motion");
    format!(
        r#"seed = 9
kl_warmup_steps = 5
seed_noise = 0.1
[data]
stride_frames = 2
mirror = true
min_contact_score = 0.5
[[clips]]
path = "{walk}"
[[clips]]
path = "{turn}"
held_out = true
[model]
latent_dim = 8
encoder_width = 32
decoder_width = 32
[loss]
pose = 1.0
transl = 1.0
markers = 2.0
velocity = 4.0
skate = 0.1
floor = 1.0
kl = 0.001
[primitive]
steps = 24
batch_size = 16
learning_rate = 0.003
[rollout]
steps = 6
batch_size = 4
learning_rate = 0.001
primitives = 2
[prior]
steps = 8
batch_size = 4
learning_rate = 0.001
primitives = 2
pool_fraction = 0.5
range_quantile = 0.0
[prior.loss]
contact = 1.0
skate = 1.0
penetration = 1.0
pelvis = 1.0
upright = 1.0
[output]
weights = "{out}/w.safetensors"
log = "{out}/w.log.jsonl"
checkpoint_every_s = 0
"#,
        walk = assets.join("deepmimic_walk.npz").display(),
        turn = assets.join("deepmimic_walker_turn_left0.npz").display(),
        out = dir.display(),
    )
}

/// The loss log without wall times, for comparing runs.
#[test]
fn a_killed_training_run_resumes_exactly_where_it_stopped() {
    use std::process::{Command, Stdio};
    let bin = env!("CARGO_BIN_EXE_egogen");
    let run = |config: &Path, resume: bool| {
        let mut cmd = Command::new(bin);
        cmd.args(["train", "primitive", "--quiet", "--config"])
            .arg(config)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        if resume {
            cmd.arg("--resume");
        }
        cmd
    };
    // The whole run, uninterrupted.
    let whole = tempfile::tempdir().unwrap();
    let whole_config = whole.path().join("c.toml");
    std::fs::write(&whole_config, tiny_config(whole.path())).unwrap();
    common::succeeds(&mut run(&whole_config, false));
    assert!(!whole.path().join("w.safetensors.checkpoint").exists());

    // The same run killed (SIGKILL) twice: in the first phase and in the prior phase.
    let cut = tempfile::tempdir().unwrap();
    let config = cut.path().join("c.toml");
    std::fs::write(&config, tiny_config(cut.path())).unwrap();
    let state = cut.path().join("w.safetensors.checkpoint/state.json");
    let global_step = || -> usize {
        std::fs::read_to_string(&state)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|v| v["global_step"].as_u64())
            .unwrap_or(0) as usize
    };
    for (resume, kill_from) in [(false, 10), (true, 33)] {
        let mut child = run(&config, resume).spawn().unwrap();
        let started = std::time::Instant::now();
        while global_step() < kill_from {
            assert!(
                child.try_wait().unwrap().is_none(),
                "the run ended before step {kill_from}"
            );
            assert!(
                started.elapsed().as_secs() < 300,
                "no checkpoint of step {kill_from}"
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
    }
    // A fresh start over the checkpoint is refused; nothing is deleted.
    let out = run(&config, false).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--resume"), "{err}");
    assert!(state.is_file());
    // A damaged file of the newest checkpoint (one byte flipped: it still parses, its
    // checksum does not match): resuming says so and continues from the one before it, which
    // replays to the same result.
    let current: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&state).unwrap()).unwrap();
    let net_file = state.with_file_name(current["net_file"].as_str().unwrap());
    let mut bytes = std::fs::read(&net_file).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x01;
    std::fs::write(&net_file, &bytes).unwrap();
    let out = run(&config, true).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&*net_file.file_name().unwrap().to_string_lossy())
            && err.contains("damaged")
            && err.contains("checkpoint before it"),
        "{err}"
    );
    assert!(!state.exists(), "the finished run removes its checkpoint");
    // Bit for bit the weights of the uninterrupted run, and the same loss log.
    let a = common::safetensors_tensors(&whole.path().join("w.safetensors"));
    let b = common::safetensors_tensors(&cut.path().join("w.safetensors"));
    assert!(!a.is_empty());
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, bytes) in &a {
        assert!(*bytes == b[name], "tensor {name}: resumed weights differ");
    }
    assert_eq!(
        common::log_without_times(&whole.path().join("w.log.jsonl")),
        common::log_without_times(&cut.path().join("w.log.jsonl"))
    );
    // Resuming with nothing to resume is refused.
    let out = run(&config, true).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no checkpoint"));
}
