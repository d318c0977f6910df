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
