//! Where an environment step of policy training goes, for a batch of 64 episodes: the decoder
//! network alone (the f32 decoder that inference runs, and burn's beside it), decoding with f64
//! posing (world frames, 67 markers, joints and CPF of 20 frames), decoding with posing and the
//! reward, a whole step (and the next episodes), the observations (markers in the canonical
//! frame, 2 × 32 rays); then the policy's forward pass at two widths (H = 128, the shipped one,
//! and EgoGen's 512) and one PPO minibatch update of 256 transitions at both widths. Throughput
//! is in environment steps (episodes stepped).

use burn::module::AutodiffModule;
use burn::optim::{AdamWConfig, GradientsParams, Optimizer};
use burn::prelude::*;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use egogen::body::BodyModel;
use egogen::motion::cvae::infer::InferBackend;
use egogen::motion::cvae::train::{normal_samples, shipped_weights_path, TrainBackend};
use egogen::motion::cvae::{BodyContext, MotionModel, PrimitiveSeed};
use egogen::motion::MotionSequence;
use egogen::policy::net::{log_prob, PolicyArch};
use egogen::policy::{EnvSettings, PolicyEnv};
use egogen::walker::pose_prior::shipped_pose_prior_path;
use egogen::walker::SeedBank;
use egogen::walker::{ObsLayout, PosePrior};

const OBS_DIM: usize = ObsLayout::PAPER.dim();
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

const B: usize = 64;

fn bench(c: &mut Criterion) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let model = MotionModel::load(shipped_weights_path()).expect("primitive weights");
    let l = model.latent_dim();
    let clip = MotionSequence::read(&root.join("assets/motion/cmu_01_03.npz")).unwrap();
    let body = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let seeds: Vec<PrimitiveSeed> = (0..16)
        .map(|i| PrimitiveSeed {
            frames: [clip.frame(30 * i + 20), clip.frame(30 * i + 21)],
            floor_z: 0.0,
        })
        .collect();
    let bank = SeedBank::from_world_seeds(&ctx, &seeds).unwrap();
    let prior = PosePrior::load(&shipped_pose_prior_path()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut env =
        PolicyEnv::new(&model, &ctx, &bank, &prior, EnvSettings::default(), B, 0).unwrap();
    let latents = normal_samples(&mut rng, B * l);

    let mut g = c.benchmark_group("policy_env");
    g.sample_size(10);
    g.throughput(Throughput::Elements(B as u64));
    // Canonical seeds of the current episodes for the network-only run.
    let world_seeds: Vec<PrimitiveSeed> = (0..B).map(|i| seeds[i % seeds.len()].clone()).collect();
    let zs: Vec<Vec<f32>> = latents.chunks(l).map(<[f32]>::to_vec).collect();
    let mut feats = Vec::new();
    let mut floors = Vec::new();
    for s in &world_seeds {
        let c = egogen::motion::cvae::CanonicalSeed::new(&ctx, s).unwrap();
        feats.extend_from_slice(&c.features);
        floors.push(c.floor);
    }
    g.bench_function("decoder_network", |b| {
        b.iter(|| model.decode_features(&feats, &floors, &latents))
    });
    g.bench_function("decoder_network_burn", |b| {
        b.iter(|| model.decode_features_burn(&feats, &floors, &latents))
    });
    g.bench_function("decode_and_pose", |b| {
        b.iter(|| model.decode_each(&ctx, &world_seeds, &zs).unwrap())
    });
    g.bench_function("decode_pose_reward", |b| {
        b.iter(|| env.propose(&latents, 1).unwrap())
    });
    g.bench_function("observations", |b| b.iter(|| env.observations()));
    g.bench_function("step", |b| b.iter(|| env.step(&latents).unwrap()));
    let obs = env.observations();
    for hidden in [128usize, 512] {
        let arch = PolicyArch {
            hidden,
            ..PolicyArch::default()
        };
        let device = Default::default();
        let net = arch.init::<InferBackend>(&device);
        g.bench_with_input(
            BenchmarkId::new("policy_forward", hidden),
            &hidden,
            |b, _| b.iter(|| egogen::policy::ppo::act(&net, obs.clone(), Some(&mut rng), &device)),
        );
    }
    g.finish();

    let mut g = c.benchmark_group("ppo_update");
    g.sample_size(10);
    let m = 256;
    g.throughput(Throughput::Elements(m as u64));
    let obs: Vec<f32> = (0..m)
        .flat_map(|i| obs[(i % B) * OBS_DIM..(i % B + 1) * OBS_DIM].to_vec())
        .collect();
    let acts = normal_samples(&mut rng, m * l);
    for hidden in [128usize, 512] {
        let arch = PolicyArch {
            hidden,
            ..PolicyArch::default()
        };
        let device = Default::default();
        let mut net = arch.init::<TrainBackend>(&device);
        let mut optim = AdamWConfig::new().init::<TrainBackend, _>();
        eprintln!("policy H = {hidden}: {} parameters", net.num_params());
        g.bench_with_input(
            BenchmarkId::new("minibatch_256", hidden),
            &hidden,
            |b, _| {
                b.iter(|| {
                    let o = Tensor::<TrainBackend, 2>::from_data(
                        TensorData::new(obs.clone(), [m, OBS_DIM]),
                        &device,
                    );
                    let a = Tensor::<TrainBackend, 2>::from_data(
                        TensorData::new(acts.clone(), [m, l]),
                        &device,
                    );
                    let out = net.forward(o);
                    let loss =
                        -log_prob(a, out.mean, out.logvar).mean() + out.value.square().mean();
                    let mut grads = GradientsParams::from_grads(loss.backward(), &net);
                    egogen::policy::ppo::clip_global_norm::<TrainBackend, _>(&net, &mut grads, 0.1);
                    net = optim.step(3e-4, net.clone(), grads);
                    net.valid()
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
