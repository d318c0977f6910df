//! PPO training of the locomotion policy: gradients are clipped on their global norm (not per
//! tensor); a training run killed twice (SIGKILL, once in each stage) resumes to the same
//! weights and log as an uninterrupted one; bad configs are refused with file and key; a new
//! network's first actions are ≈ N(0, I).

mod common;

use std::path::Path;

use burn::module::AutodiffModule;
use burn::optim::GradientsParams;
use burn::prelude::*;
use egogen::motion::cvae::train::TrainBackend;
use egogen::policy::net::{kl_to_standard, PolicyArch};
use egogen::policy::ppo::clip_global_norm;
use egogen::walker::ObsLayout;

const OBS_DIM: usize = ObsLayout::PAPER.dim();

fn tiny_arch() -> PolicyArch {
    PolicyArch {
        hidden: 16,
        pe_frequencies: 4,
        residual_blocks: 1,
        latent_dim: 8,
        sensing: Default::default(),
    }
}

fn global_norm(
    net: &egogen::policy::net::ActorCritic<TrainBackend>,
    obs: Tensor<TrainBackend, 2>,
    clip: Option<f64>,
) -> (f64, Vec<f64>) {
    let out = net.forward(obs);
    let loss = out.mean.square().sum() + out.value.square().sum().mul_scalar(100.0);
    let mut grads = GradientsParams::from_grads(loss.backward(), net);
    let before = match clip {
        Some(c) => clip_global_norm::<TrainBackend, _>(net, &mut grads, c),
        None => 0.0,
    };
    // Norm per parameter after clipping, from the same visitor order.
    struct Norms<'a> {
        grads: &'a GradientsParams,
        norms: Vec<f64>,
    }
    impl burn::module::ModuleVisitor<TrainBackend> for Norms<'_> {
        fn visit_float<const D: usize>(
            &mut self,
            p: &burn::module::Param<Tensor<TrainBackend, D>>,
        ) {
            if let Some(g) = self
                .grads
                .get::<<TrainBackend as burn::tensor::backend::AutodiffBackend>::InnerBackend, D>(
                p.id,
            ) {
                self.norms
                    .push(g.square().sum().into_scalar().elem::<f64>().sqrt());
            }
        }
    }
    let mut n = Norms {
        grads: &grads,
        norms: Vec::new(),
    };
    net.visit(&mut n);
    (before, n.norms)
}

#[test]
fn gradients_are_clipped_on_their_global_norm() {
    let device = Default::default();
    TrainBackend::seed(&device, 1);
    let net = tiny_arch().init::<TrainBackend>(&device);
    let obs = Tensor::<TrainBackend, 2>::random(
        [5, OBS_DIM],
        burn::tensor::Distribution::Normal(0.0, 1.0),
        &device,
    );
    let (_, raw) = global_norm(&net, obs.clone(), None);
    let (before, clipped) = global_norm(&net, obs, Some(0.1));
    let total = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(
        (before - total(&raw)).abs() < 1e-3 * before,
        "{before} vs {}",
        total(&raw)
    );
    assert!(
        before > 0.1,
        "the test needs gradients larger than the limit"
    );
    assert!(
        (total(&clipped) - 0.1).abs() < 1e-5,
        "global norm after clipping {}",
        total(&clipped)
    );
    // One common factor: every tensor keeps its share (per-tensor clipping would not).
    let scale = 0.1 / before;
    for (a, b) in raw.iter().zip(&clipped) {
        assert!(
            (a * scale - b).abs() <= 1e-5 * a.max(1e-6) + 1e-9,
            "{a} × {scale} vs {b}"
        );
    }
}

#[test]
fn every_parameter_of_a_new_network_is_trained() {
    let device = Default::default();
    TrainBackend::seed(&device, 4);
    let net = tiny_arch().init::<TrainBackend>(&device);
    let obs = Tensor::<TrainBackend, 2>::random(
        [3, OBS_DIM],
        burn::tensor::Distribution::Normal(0.0, 1.0),
        &device,
    );
    let out = net.forward(obs);
    let loss = out.mean.sum() + out.logvar.sum() + out.value.sum();
    let grads = GradientsParams::from_grads(loss.backward(), &net);
    // Every float parameter has a gradient (the scaled last actor layer included).
    struct Count(usize);
    impl burn::module::ModuleVisitor<TrainBackend> for Count {
        fn visit_float<const D: usize>(
            &mut self,
            _: &burn::module::Param<Tensor<TrainBackend, D>>,
        ) {
            self.0 += 1;
        }
    }
    let mut count = Count(0);
    net.visit(&mut count);
    assert!(count.0 > 10);
    assert_eq!(grads.len(), count.0, "parameters without gradients");
}

#[test]
fn first_actions_are_close_to_the_standard_normal() {
    let device = Default::default();
    TrainBackend::seed(&device, 2);
    let arch = PolicyArch::default();
    let net = arch.init::<TrainBackend>(&device).valid();
    let obs = Tensor::random(
        [32, OBS_DIM],
        burn::tensor::Distribution::Uniform(-1.0, 1.0),
        &device,
    );
    let out = net.forward(obs);
    let kl: Vec<f32> = kl_to_standard(out.mean.clone(), out.logvar)
        .into_data()
        .to_vec()
        .unwrap();
    // KL over 128 dimensions of the untrained policy: tiny against N(0, I) itself (0).
    assert!(kl.iter().all(|&k| k < 0.5), "{kl:?}");
}

/// Controller draws the same actions as training's `act`, without the critic.
#[test]
fn steering_actions_are_the_actions_act_draws() {
    use egogen::policy::ppo::{act, actions};
    use egogen::policy::weights::load_policy;
    use rand_core::SeedableRng;
    let device = Default::default();
    let shipped = common::repo_root().join(egogen::policy::weights::SHIPPED_POLICY);
    let (_, net) = load_policy::<TrainBackend>(&shipped, &device).unwrap();
    let obs: Vec<f32> = (0..3 * OBS_DIM)
        .map(|k| ((k as f32) * 0.618).fract() * 2.0 - 1.0)
        .collect();
    for sampled in [false, true] {
        let mut r1 = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let mut r2 = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let (a, ..) = act(&net, obs.clone(), sampled.then_some(&mut r1), &device);
        let b = actions(&net, obs.clone(), sampled.then_some(&mut r2), &device);
        assert_eq!(a.len(), 3 * net.latent_dim());
        assert_eq!(a, b, "sampled: {sampled}");
    }
}

fn tiny_config(dir: &Path) -> String {
    let root = common::repo_root();
    format!(
        r#"seed = 3
motion_weights = "{w}"
motion_config = "{c}"
pose_prior = "{p}"
[policy]
hidden = 16
pe_frequencies = 4
residual_blocks = 1
[ppo]
envs = 4
steps_per_env = 2
minibatch = 4
[[stages]]
name = "pretrain"
env_steps = 48
[[stages]]
name = "finetune"
env_steps = 48
[stages.env]
terminate_on_penetration = true
[stages.env.weights]
penetration = 0.1
[validation]
every_updates = 2
episodes = 3
[output]
weights = "{d}/w.safetensors"
log = "{d}/w.log.jsonl"
checkpoint_every_s = 0
"#,
        w = root
            .join("assets/motion/primitive_cvae.safetensors")
            .display(),
        c = root.join("configs/train_primitive.toml").display(),
        p = root.join("assets/policy/pose_prior.json").display(),
        d = dir.display(),
    )
}

#[test]
fn a_killed_policy_run_resumes_exactly_where_it_stopped() {
    use std::process::{Command, Stdio};
    let bin = env!("CARGO_BIN_EXE_egogen");
    let run = |config: &Path, resume: bool| {
        let mut cmd = Command::new(bin);
        cmd.args(["train", "policy", "--quiet", "--config"])
            .arg(config)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        if resume {
            cmd.arg("--resume");
        }
        cmd
    };
    let whole = tempfile::tempdir().unwrap();
    let whole_config = whole.path().join("c.toml");
    std::fs::write(&whole_config, tiny_config(whole.path())).unwrap();
    common::succeeds(&mut run(&whole_config, false));
    assert!(!whole.path().join("w.safetensors.checkpoint").exists());
    for stage in ["pretrain", "finetune"] {
        assert!(whole
            .path()
            .join(format!("w.{stage}.last.safetensors"))
            .is_file());
    }

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
    // 6 updates per stage: killed in the first stage and in the second.
    for (resume, kill_from) in [(false, 3), (true, 8)] {
        let mut child = run(&config, resume).spawn().unwrap();
        let started = std::time::Instant::now();
        while global_step() < kill_from {
            assert!(
                child.try_wait().unwrap().is_none(),
                "the run ended before update {kill_from}"
            );
            assert!(
                started.elapsed().as_secs() < 300,
                "no checkpoint of update {kill_from}"
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
    }
    let out = run(&config, false).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--resume"), "{err}");
    common::succeeds(&mut run(&config, true));
    assert!(!state.exists(), "the finished run removes its checkpoint");
    for name in [
        "w.safetensors",
        "w.pretrain.last.safetensors",
        "w.finetune.last.safetensors",
    ] {
        let a = common::safetensors_tensors(&whole.path().join(name));
        let b = common::safetensors_tensors(&cut.path().join(name));
        assert!(!a.is_empty());
        assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
        for (t, bytes) in &a {
            assert!(*bytes == b[t], "{name}: tensor {t}: resumed weights differ");
        }
    }
    let la = common::log_without_times(&whole.path().join("w.log.jsonl"));
    assert_eq!(la.len(), 12);
    assert_eq!(
        la,
        common::log_without_times(&cut.path().join("w.log.jsonl"))
    );
}

/// A stage that walks generated dwellings trains: `[dwellings]` makes the dwellings of its seeds
/// (into the cache on first use) and draws their pairs.
#[test]
fn a_policy_trains_in_generated_dwellings() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("c.toml");
    let text = tiny_config(dir.path())
        .replacen(
            "[policy]",
            "[dwellings]\nseeds = [0, 2]\npairs = 8\npair_distance_m = [1, 6]\nseed = 1\n[policy]",
            1,
        )
        .replacen(
            "[stages.env]\n",
            "[stages.env]\ndwellings = { share = 1.0 }\n",
            1,
        );
    std::fs::write(&config, text).unwrap();
    let plan = egogen::cli::train_policy::load_policy_plan(&config).unwrap();
    assert_eq!(plan.dwellings.len(), 2);
    assert!(plan.dwellings.iter().all(|d| d.indoors && d.pairs == 8));
    common::succeeds(
        std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
            .args(["train", "policy", "--quiet", "--config"])
            .arg(&config),
    );
    assert!(dir.path().join("w.safetensors").is_file());
}

#[test]
fn bad_policy_configs_name_the_file_and_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    for (from, to, key) in [
        ("envs = 4", "envs = 0", "ppo.envs"),
        ("[ppo]", "[ppo]\nclip = 1.5", "ppo.clip"),
        (
            "env_steps = 48\n[[stages]]",
            "env_steps = 0\n[[stages]]",
            "stages[0].env_steps",
        ),
        ("hidden = 16", "hidden = 16\nwidth = 3", "width"),
        (
            "[stages.env]",
            "[stages.env]\ncrossing = { share = 1.5 }",
            "stages[1].env.crossing",
        ),
        (
            "[stages.env]",
            "[stages.env]\ncrossing = { people = [3, 2] }",
            "stages[1].env.crossing",
        ),
        (
            "[policy]",
            "init_weights = \"missing.safetensors\"\n[policy]",
            "init_weights",
        ),
        (
            "[stages.env]",
            "[stages.env]\nfixed_share = 0.5",
            "stages[1].env.fixed_share",
        ),
        (
            "[stages.env.weights]",
            "[stages.env.walker]\nguide_lookahead_m = -1.0\n[stages.env.weights]",
            "stages[1].env.walker.guide_lookahead_m",
        ),
        (
            "[stages.env.weights]",
            "[stages.env.walker]\nguide_memory = true\n[stages.env.weights]",
            "stages[1].env.walker.guide_memory",
        ),
        (
            "[stages.env.weights]",
            "[stages.env.walker]\nguide_lookahead_m = 1.0\nguide_centre_weight = nan\n[stages.env.weights]",
            "stages[1].env.walker.guide_centre_weight",
        ),
        (
            "[stages.env.weights]",
            "[stages.env.walker]\nguide_lookahead_m = 1.0\nguide_unknown_cost = 1.0\n[stages.env.weights]",
            "stages[1].env.walker.guide_unknown_cost",
        ),
        (
            "[stages.env.weights]",
            "[stages.env.walker]\npenetration_redraws = 4\n[stages.env.weights]",
            "stages[1].env.walker.penetration_redraws",
        ),
        (
            "[stages.env.weights]",
            "[stages.env.walker]\nsuccess_m = 0\n[stages.env.weights]",
            "stages[1].env.walker.success_m",
        ),
        (
            "[policy]",
            "[scene]\npath = \"missing.glb\"\npairs = 4\npair_distance_m = [1, 2]\nseed = 1\n[policy]",
            "scene.path",
        ),
        (
            "[policy]",
            "[scene]\npath = \"dwelling:1000000\"\npairs = 4\npair_distance_m = [1, 2]\nseed = 1\n[policy]",
            "the dwelling of seed 1000000 is held out",
        ),
        (
            "[stages.env]",
            "[stages.env]\ndwellings = { share = 0.5 }",
            "stages[1].env.dwellings.share",
        ),
        (
            "[stages.env]",
            "[stages.env]\ndwellings = { share = 1.5 }",
            "stages[1].env.dwellings",
        ),
        (
            "[policy]",
            "[dwellings]\nseeds = [0, 2]\npairs = 4\npair_distance_m = [1, 2]\nseed = 1\n[policy]",
            "no stage walks the dwellings",
        ),
        (
            "terminate_on_penetration = true\n",
            "terminate_on_penetration = true\ndwellings = { share = 0.5 }\n[dwellings]\nseeds = [999990, 1000001]\npairs = 4\npair_distance_m = [1, 2]\nseed = 1\n",
            "seeds 1000000 and up are held out",
        ),
        (
            "terminate_on_penetration = true\n",
            "terminate_on_penetration = true\ndwellings = { share = 0.5 }\n[dwellings]\nseeds = [3, 3]\npairs = 4\npair_distance_m = [1, 2]\nseed = 1\n",
            "dwellings.seeds",
        ),
        (
            "residual_blocks = 1",
            "residual_blocks = 1\n[policy.sensing]\nkind = \"rays\"\nnum_rays = 0",
            "policy.sensing",
        ),
        (
            "residual_blocks = 1",
            "residual_blocks = 1\n[policy.sensing]\nkind = \"local_map\"\ncell_m = -0.1",
            "policy.sensing",
        ),
        (
            "residual_blocks = 1",
            "residual_blocks = 1\n[policy.sensing]\nkind = \"sonar\"",
            "sonar",
        ),
        (
            "residual_blocks = 1",
            "residual_blocks = 1\n[policy.sensing]\nkind = \"depth_image\"\nhalf_fov_v_rad = 2.0",
            "policy.sensing",
        ),
        (
            "residual_blocks = 1",
            "residual_blocks = 1\n[policy.sensing]\nkind = \"depth_image\"\nrows = 12",
            "rows and cols must be multiples of 8",
        ),
        (
            "[stages.env]",
            "[stages.env]\nscene_test_vertices = 1024",
            "stages[1].env.scene_test_vertices",
        ),
        (
            "episodes = 3",
            "episodes = 3\nmax_prior_kl = -1.0",
            "validation.max_prior_kl",
        ),
        (
            "[stages.env]",
            "[stages.env]\nscene_test_keeps_cells = true",
            "stages[1].env.scene_test_keeps_cells",
        ),
    ] {
        let text = tiny_config(dir.path()).replacen(from, to, 1);
        assert_ne!(text, tiny_config(dir.path()), "{from}");
        std::fs::write(&path, text).unwrap();
        let err = egogen::cli::train_policy::load_policy_plan(&path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains(key),
            "{key}: {err}"
        );
    }
}

#[test]
fn a_policy_keeps_its_sensing_in_its_weights_file() {
    use egogen::policy::weights::{load_policy, save_policy};
    use egogen::sensing::SensingSpec;
    let device = Default::default();
    let dir = tempfile::tempdir().unwrap();
    // Written before policies had a sensing field: the paper's 32 rays.
    let shipped = common::repo_root().join("assets/policy/policy.safetensors");
    let (arch, net) = load_policy::<TrainBackend>(&shipped, &device).unwrap();
    assert_eq!(arch.sensing, SensingSpec::default());
    assert_eq!(net.obs_layout(), ObsLayout::PAPER);
    for (sensing, per_frame) in [
        (SensingSpec::centred_map(0.8, 16), 256),
        (
            SensingSpec::Rays(egogen::sensing::RayScanSettings {
                num_rays: 8,
                ..Default::default()
            }),
            8,
        ),
        (SensingSpec::DepthImage(Default::default()), 16 * 32),
    ] {
        let arch = PolicyArch {
            sensing,
            ..tiny_arch()
        };
        let path = dir.path().join("p.safetensors");
        save_policy(&arch.init::<TrainBackend>(&device), &arch, &path).unwrap();
        let (loaded, net) = load_policy::<TrainBackend>(&path, &device).unwrap();
        assert_eq!(loaded, arch);
        assert_eq!(net.sensing(), sensing);
        let layout = net.obs_layout();
        assert_eq!(layout.sensing_per_frame, per_frame);
        let b = 3;
        let out = net.forward(Tensor::zeros([b, layout.dim()], &device));
        assert_eq!(out.mean.dims(), [b, arch.latent_dim]);
        // Every weight comes back (the depth image's CNN too): the same actions.
        let obs: Vec<f32> = (0..b * layout.dim())
            .map(|k| ((k as f32) * 0.618_034).fract() * 2.0 - 1.0)
            .collect();
        let before = arch.init::<TrainBackend>(&device);
        save_policy(&before, &arch, &path).unwrap();
        let (_, after) = load_policy::<TrainBackend>(&path, &device).unwrap();
        let act = |net: &egogen::policy::net::ActorCritic<TrainBackend>| {
            let t = Tensor::<TrainBackend, 1>::from_floats(obs.as_slice(), &device)
                .reshape([b, layout.dim()]);
            net.forward(t).mean.into_data().to_vec::<f32>().unwrap()
        };
        assert_eq!(act(&before), act(&after), "{sensing:?}");
    }
}

#[test]
fn damaged_policy_weights_are_refused_with_their_path() {
    use egogen::policy::weights::{load_policy, save_policy};
    let device = Default::default();
    let arch = tiny_arch();
    let net = arch.init::<TrainBackend>(&device).valid();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.safetensors");
    save_policy(&net, &arch, &path).unwrap();
    let (back_arch, _) =
        load_policy::<egogen::motion::cvae::infer::InferBackend>(&path, &device).unwrap();
    assert_eq!(back_arch, arch);
    let bytes = std::fs::read(&path).unwrap();
    for cut in [4, 100, bytes.len() / 2, bytes.len() - 1] {
        let bad = dir.path().join(format!("cut{cut}.safetensors"));
        std::fs::write(&bad, &bytes[..cut]).unwrap();
        let err = load_policy::<egogen::motion::cvae::infer::InferBackend>(&bad, &device)
            .err()
            .unwrap_or_else(|| panic!("{cut} bytes accepted"))
            .to_string();
        assert!(err.contains(&format!("cut{cut}.safetensors")), "{err}");
    }
    // Motion-model weights are not policy weights.
    let err = load_policy::<egogen::motion::cvae::infer::InferBackend>(
        &egogen::motion::cvae::train::shipped_weights_path(),
        &device,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(err.contains("egogen.policy_arch"), "{err}");
}

#[test]
fn the_prior_kl_penalty_holds_the_policy_near_the_standard_normal() {
    // An entropy bonus large enough to spread the policy fast; the KL penalty pulls it back.
    let final_kl = |coef: f64| -> f64 {
        let dir = tempfile::tempdir().unwrap();
        let config = dir.path().join("c.toml");
        let text = tiny_config(dir.path()).replace(
            "[ppo]\n",
            &format!(
                "[ppo]\nlearning_rate = 0.01\nentropy_coef = 1.0\nmax_grad_norm = 10.0\nprior_kl_coef = {coef}\n"
            ),
        );
        std::fs::write(&config, text).unwrap();
        common::succeeds(
            std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
                .args(["train", "policy", "--quiet", "--config"])
                .arg(&config),
        );
        let log = std::fs::read_to_string(dir.path().join("w.log.jsonl")).unwrap();
        let last: serde_json::Value = serde_json::from_str(log.lines().last().unwrap()).unwrap();
        last["kl_prior"].as_f64().unwrap()
    };
    let (free, held) = (final_kl(0.0), final_kl(10.0));
    assert!(
        free > 1.0,
        "the entropy bonus spreads the policy: KL {free}"
    );
    assert!(
        held < 0.5 * free,
        "KL with the penalty {held}, without {free}"
    );
}

/// The f32 actor that acting uses (`policy::Actor`) gives burn's actions bit for bit: mean and
/// sampled, one observation and batches (the batch sizes cross burn's threshold for threaded
/// products), for policies of three widths and all three kinds of sensing (the depth image's
/// CNN on a freshly initialised network).
#[test]
fn plain_f32_actor_equals_burn_bit_for_bit() {
    use egogen::motion::cvae::infer::InferBackend;
    use egogen::policy::ppo::{action_distribution, actions};
    use egogen::policy::weights::load_policy;
    use egogen::policy::Actor;
    use rand_core::SeedableRng;
    let device = Default::default();
    let root = common::repo_root();
    let depth = PolicyArch {
        sensing: egogen::sensing::SensingSpec::DepthImage(Default::default()),
        ..Default::default()
    };
    let mut nets: Vec<(String, egogen::policy::net::ActorCritic<InferBackend>)> = [
        egogen::policy::weights::SHIPPED_POLICY,
        "assets/policy/knobs/width_64.safetensors",
        "assets/policy/knobs/width_256.safetensors",
        "assets/policy/table2/local_map_0.8m.safetensors",
    ]
    .into_iter()
    .map(|file| {
        let (_, net) = load_policy::<InferBackend>(&root.join(file), &device).unwrap();
        (file.to_string(), net)
    })
    .collect();
    nets.push(("a depth image's CNN".into(), depth.init(&device)));
    for (file, net) in nets {
        let actor = Actor::of(&net);
        let d = actor.obs_layout().dim();
        assert_eq!(actor.latent_dim(), net.latent_dim());
        for batch in [1usize, 3, 64, 300] {
            // Observations over the range the environment writes (markers, unit directions,
            // scans in [-1, 1], encodings' inputs in [0, 1]), a few large values too.
            let obs: Vec<f32> = (0..batch * d)
                .map(|k| {
                    let u = ((k as f32) * 0.618_034).fract();
                    if k % 97 == 0 {
                        40.0 * (u - 0.5)
                    } else {
                        2.0 * u - 1.0
                    }
                })
                .collect();
            for sampled in [false, true] {
                let mut r1 = rand_chacha::ChaCha8Rng::seed_from_u64(9);
                let mut r2 = rand_chacha::ChaCha8Rng::seed_from_u64(9);
                let burn = actions(&net, obs.clone(), sampled.then_some(&mut r1), &device);
                let plain = actor.actions(&obs, sampled.then_some(&mut r2));
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&burn),
                    bits(&plain),
                    "{file}, batch {batch}, sampled {sampled}"
                );
            }
        }
        let one = vec![0.25f32; d];
        let (m1, s1) = action_distribution(&net, one.clone(), &device);
        let (m2, s2) = actor.distribution(&one);
        assert_eq!((m1, s1), (m2, s2), "{file}: distribution");
    }
}

/// A scaled action spread draws `mean + S · (sample − mean)` from the same noise: 1 is the
/// sample as trained, bit for bit, 0 the mean action.
#[test]
fn action_spread_scales_the_sampled_actions_about_the_mean() {
    use egogen::motion::cvae::infer::InferBackend;
    use egogen::policy::weights::load_policy;
    use egogen::policy::Actor;
    use rand_core::SeedableRng;
    let root = common::repo_root();
    let (_, net) = load_policy::<InferBackend>(
        &root.join(egogen::policy::weights::SHIPPED_POLICY),
        &Default::default(),
    )
    .unwrap();
    let actor = Actor::of(&net);
    let d = actor.obs_layout().dim();
    let obs: Vec<f32> = (0..4 * d)
        .map(|k| ((k as f32) * 0.618_034).fract() * 2.0 - 1.0)
        .collect();
    let draw = |spread: f32| {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        actor.actions_with_spread(&obs, Some(&mut rng), spread)
    };
    let mean = actor.actions(&obs, None);
    let sample = actor.actions(&obs, Some(&mut rand_chacha::ChaCha8Rng::seed_from_u64(5)));
    assert_eq!(draw(1.0), sample);
    assert_eq!(draw(0.0), mean);
    let half = draw(0.5);
    for ((h, m), s) in half.iter().zip(&mean).zip(&sample) {
        assert!((h - (m + 0.5 * (s - m))).abs() < 1e-5, "{h} {m} {s}");
    }
    assert_ne!(half, mean);
}

/// Training never writes a non-finite policy and never replaces an earlier run's weights
/// unasked: a learning rate of 1e10 is refused by key; a run that diverges stops with the
/// update and the term that went non-finite (exit non-zero); the same run twice writes the
/// same bytes; a second run into the same outputs is refused until `--force`.
#[test]
fn non_finite_training_stops_and_earlier_weights_are_not_replaced_unasked() {
    use std::process::Command;
    let train = |config: &Path, extra: &[&str]| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_egogen"));
        cmd.args(["train", "policy", "--quiet", "--config"])
            .arg(config)
            .args(extra);
        cmd.output().unwrap()
    };
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("c.toml");
    // A learning rate from 1 up is refused before any training, naming the key.
    let text = tiny_config(dir.path()).replace("[ppo]\n", "[ppo]\nlearning_rate = 1e10\n");
    std::fs::write(&config, text).unwrap();
    let out = train(&config, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success()
            && err.contains("ppo.learning_rate")
            && err.contains("expected a learning rate in (0, 1), got 10000000000"),
        "{err}"
    );
    assert!(!dir.path().join("w.safetensors").exists() && !dir.path().join("w.log.jsonl").exists());
    // A run that diverges all the same (a value loss weighted by 1e38) stops at the update that
    // did, naming the term, and writes nothing after it.
    let text = tiny_config(dir.path()).replace("[ppo]\n", "[ppo]\nvalue_coef = 1e38\n");
    std::fs::write(&config, text).unwrap();
    let out = train(&config, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a diverged run exited 0: {err}");
    assert!(
        err.contains("update")
            && (err.contains("not finite") || err.contains("NaN") || err.contains("inf")),
        "{err}"
    );
    assert!(err.contains("learning_rate"), "{err}");
    // Whatever was written before the divergence is finite.
    for f in std::fs::read_dir(dir.path()).unwrap().flatten() {
        let path = f.path();
        if path.extension().is_some_and(|e| e == "safetensors") {
            for (name, bytes) in common::safetensors_tensors(&path) {
                assert!(
                    bytes
                        .chunks_exact(4)
                        .all(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]).is_finite()),
                    "{}: {name} is not finite",
                    path.display()
                );
            }
        }
    }

    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("c.toml");
    std::fs::write(&config, tiny_config(dir.path())).unwrap();
    assert!(train(&config, &[]).status.success());
    let weights = dir.path().join("w.safetensors");
    let first = std::fs::read(&weights).unwrap();
    // The same config and seed give the same bytes (the header's keys in one order).
    let twin = tempfile::tempdir().unwrap();
    let twin_config = twin.path().join("c.toml");
    std::fs::write(&twin_config, tiny_config(twin.path())).unwrap();
    assert!(train(&twin_config, &[]).status.success());
    assert!(
        std::fs::read(twin.path().join("w.safetensors")).unwrap() == first,
        "the same run wrote other bytes"
    );
    std::fs::write(
        &config,
        tiny_config(dir.path()).replace("seed = 3", "seed = 4"),
    )
    .unwrap();
    let again = train(&config, &[]);
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(!again.status.success() && err.contains("--force"), "{err}");
    assert_eq!(
        std::fs::read(&weights).unwrap(),
        first,
        "weights replaced unasked"
    );
    assert!(train(&config, &["--force"]).status.success());
    assert_ne!(
        std::fs::read(&weights).unwrap(),
        first,
        "--force trains anew"
    );
}
