//! Motion-primitive decoding on the CPU with the shipped weights: the network alone (1, 16, 64
//! and 256 primitives) in f32 through the plain f32 decoder (what inference runs; one primitive
//! alone reads its weights in f16, and once more in f32) and through
//! burn, burn in f16 and bf16 (1 and 64), and the whole inference call (network, world frames,
//! 67 markers and CPF per frame in f64) for one primitive and for 16.
//! Prints the network's multiply-adds per primitive so that achieved FLOP/s can be read off.
//! `half_matvec`: one GRU step's f16 products (frame rows, hidden gates, output layer) with
//! sixteen lanes (AVX-512F, where the processor has it) and with eight (AVX2), side by side.
//! `EGOGEN_PRIMITIVE_WEIGHTS=path` benches other weights (e.g. the narrow knob model).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use egogen::body::BodyModel;
use egogen::motion::cvae::features::FRAME_DIM;
use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
use egogen::motion::cvae::{BodyContext, MotionModel, PrimitiveSeed};
use egogen::motion::primitive::SEED_FRAMES;
use egogen::motion::MotionSequence;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

fn bench(c: &mut Criterion) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let weights = std::env::var_os("EGOGEN_PRIMITIVE_WEIGHTS")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(shipped_weights_path);
    let model = MotionModel::load(&weights).expect("primitive weights");
    let l = model.latent_dim();
    eprintln!(
        "decoder: {} multiply-adds = {:.1} MFLOP per primitive ({:?})",
        model.arch.decoder_macs(),
        2.0 * model.arch.decoder_macs() as f64 * 1e-6,
        model.arch
    );
    let clip = MotionSequence::read(&root.join("assets/motion/cmu_01_03.npz")).unwrap();
    let body = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let seeds: Vec<PrimitiveSeed> = (0..64)
        .map(|i| PrimitiveSeed {
            frames: [clip.frame(10 * i), clip.frame(10 * i + 1)],
            floor_z: 0.0,
        })
        .collect();
    let latents: Vec<Vec<f32>> = (0..64).map(|_| normal_samples(&mut rng, l)).collect();
    // Canonical seed features and floors for the network-only runs.
    let decoded = model.decode(&ctx, &seeds, &latents).unwrap();
    let floors: Vec<f32> = decoded
        .iter()
        .map(|p| -p.primitive.world_from_canon.translation.z as f32)
        .collect();
    let seed_features: Vec<f32> = decoded
        .iter()
        .flat_map(|p| {
            p.primitive.frames[..SEED_FRAMES]
                .iter()
                .flat_map(egogen::motion::cvae::features::frame_features)
        })
        .collect();
    let flat_z: Vec<f32> = latents.iter().flatten().copied().collect();
    // 256 primitives (a policy-training step): the 64 repeated.
    let tile = |v: &[f32]| v.repeat(4);
    let (seed_features, floors, flat_z) = (tile(&seed_features), tile(&floors), tile(&flat_z));

    let mut g = c.benchmark_group("primitive");
    // One primitive with its weights in f32 (the default reads them in f16).
    let all_f32 = MotionModel::load(&weights)
        .unwrap()
        .without_half_precision();
    g.throughput(Throughput::Elements(1));
    g.bench_function(BenchmarkId::new("network_f32_f32_weights", 1), |b| {
        let s = &seed_features[..SEED_FRAMES * FRAME_DIM];
        b.iter(|| all_f32.decode_features(s, &floors[..1], &flat_z[..l]))
    });
    for batch in [1usize, 16, 64, 256] {
        g.throughput(Throughput::Elements(batch as u64));
        let s = &seed_features[..batch * SEED_FRAMES * FRAME_DIM];
        let z = &flat_z[..batch * l];
        let f = &floors[..batch];
        g.bench_with_input(BenchmarkId::new("network_f32", batch), &batch, |b, _| {
            b.iter(|| model.decode_features(s, f, z))
        });
        g.bench_with_input(
            BenchmarkId::new("network_f32_burn", batch),
            &batch,
            |b, _| b.iter(|| model.decode_features_burn(s, f, z)),
        );
    }
    for (name, dtype) in [
        ("f16", burn::tensor::FloatDType::F16),
        ("bf16", burn::tensor::FloatDType::BF16),
    ] {
        let m = MotionModel::load(&weights).unwrap().with_precision(dtype);
        for batch in [1usize, 64] {
            g.throughput(Throughput::Elements(batch as u64));
            let s = &seed_features[..batch * SEED_FRAMES * FRAME_DIM];
            let z = &flat_z[..batch * l];
            let f = &floors[..batch];
            g.bench_with_input(
                BenchmarkId::new(format!("network_{name}"), batch),
                &batch,
                |b, _| b.iter(|| m.decode_features(s, f, z)),
            );
        }
    }
    for batch in [1usize, 16] {
        g.throughput(Throughput::Elements(batch as u64));
        g.bench_with_input(
            BenchmarkId::new("with_markers_cpf", batch),
            &batch,
            |b, &n| b.iter(|| model.decode(&ctx, &seeds[..n], &latents[..n]).unwrap()),
        );
    }
    g.finish();

    use egogen::motion::cvae::half_matvec::HalfMatrix;
    if HalfMatrix::supported() {
        let mut g = c.benchmark_group("half_matvec");
        let step: Vec<(HalfMatrix, Vec<f32>, Vec<f32>)> = [(270, 768), (256, 768), (256, 135)]
            .into_iter()
            .map(|(k, n)| {
                let w: Vec<f32> = (0..k * n).map(|i| ((i as f32) * 0.0137).cos()).collect();
                let x: Vec<f32> = (0..k).map(|i| ((i as f32) * 0.71).sin()).collect();
                (HalfMatrix::new(k, n, &w), x, vec![0f32; n])
            })
            .collect();
        let mut ys: Vec<Vec<f32>> = step.iter().map(|s| s.2.clone()).collect();
        g.bench_function("gru_step_sixteen_lanes", |b| {
            b.iter(|| {
                for ((m, x, _), y) in step.iter().zip(ys.iter_mut()) {
                    m.mul_add(x, y);
                }
            })
        });
        g.bench_function("gru_step_eight_lanes", |b| {
            b.iter(|| {
                for ((m, x, _), y) in step.iter().zip(ys.iter_mut()) {
                    m.mul_add_eight_lanes(x, y);
                }
            })
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
