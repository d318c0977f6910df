//! The motion-primitive C-VAE: a tiny real training run lowers its loss and writes loadable
//! weights; weights files with the wrong shapes or no architecture are refused by name; bad
//! training configs are refused naming file and key.

mod common;

use std::path::{Path, PathBuf};

use egogen::cli::train::load_train_plan;
use egogen::motion::cvae::loss::LossWeights;
use egogen::motion::cvae::train::{ClipSpec, PhasePlan, TrainPlan};
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
        weights_out: dir.join("tiny.safetensors"),
        log_out: dir.join("tiny.log.jsonl"),
    }
}

#[test]
fn tiny_training_run_lowers_the_loss_and_writes_loadable_weights() {
    let dir = tempfile::tempdir().unwrap();
    let plan = tiny_plan(dir.path());
    let report = train(&plan, false).unwrap();
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
    let mm = report.held_out_mpjpe_mm.unwrap();
    assert!(mm.is_finite() && mm > 0.0, "held-out error {mm} mm");

    let model = MotionModel::load(&plan.weights_out).unwrap();
    assert_eq!(model.arch, plan.arch);
}

#[test]
fn weights_of_another_architecture_are_refused_naming_the_tensor() {
    let dir = tempfile::tempdir().unwrap();
    let plan = tiny_plan(dir.path());
    let arch = plan.arch;
    let small: egogen::motion::cvae::PrimitiveVae<burn::backend::Flex> =
        arch.init(&[0.0; 135], &[1.0; 135], &Default::default());
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
    ];
    for (name, (from, to), key) in cases {
        assert!(shipped.contains(from), "{from}");
        let path = write(name, &shipped.replace(from, to));
        let err = load_train_plan(&path).unwrap_err().to_string();
        assert!(err.contains(name) && err.contains(key), "{name}: {err}");
    }
}
