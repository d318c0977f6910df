//! Skinning throughput on the shipped model: full single-frame skinning (shape + pose + LBS),
//! a batch of 64 bodies, a sequence frame with the shape cached, and the joints-only fast path;
//! on a model with official SMPL-X sizes, single frames and 64-frame sequences with and without
//! pose correctives; the finger motion of a take per frame (`motion::hands`).
//! `tools/bench_skinning.py` runs this and `smplx` in one go and writes the ratio table.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use egogen::body::{BodyModel, BodyParams};
use egogen::math::Vec3;

fn params(seed: usize) -> BodyParams {
    let mut p = BodyParams::default();
    for (i, v) in p.pose.iter_mut().enumerate() {
        *v = (((seed * 165 + i) as f64 * 0.7548776662).fract() - 0.5) * 0.8;
    }
    p.betas = (0..10)
        .map(|i| (((seed * 10 + i) as f64 * 0.5698402910).fract() - 0.5) * 2.0)
        .collect();
    p.transl = Vec3::new(0.1, 0.2, 0.3);
    p
}

fn bench(c: &mut Criterion) {
    let path = std::env::var("EGOGEN_BENCH_MODEL").unwrap_or_else(|_| {
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/body/SMPLX_NEUTRAL.npz").into()
    });
    let model = BodyModel::load(&path).expect("body model");
    let one = params(1);
    let batch: Vec<BodyParams> = (0..64).map(params).collect();
    let mut g = c.benchmark_group("skinning");
    g.throughput(Throughput::Elements(1));
    g.bench_function("full_single", |b| b.iter(|| model.pose(&one).unwrap()));
    let shaped = model.shape(&one.betas, &[]).unwrap();
    g.bench_function("pose_cached_shape", |b| {
        b.iter(|| shaped.pose(&one.pose, one.transl).unwrap())
    });
    g.bench_function("joints_only", |b| {
        b.iter(|| shaped.skeleton(&one.pose, one.transl).unwrap())
    });
    let markers = egogen::body::farthest_point_markers(&model, egogen::body::NUM_MARKERS);
    g.bench_function("joints_markers_cpf", |b| {
        let cal = egogen::body::CpfCalibration::from_rest_joints(&shaped.rest_joints);
        b.iter(|| {
            let f = shaped
                .marker_frame(&one.pose, one.transl, &markers)
                .unwrap();
            (cal.world_from_cpf(&f.skeleton), f)
        })
    });
    // The fingers of 400 frames (10 s) moved with what the hands do (`motion::hands`), per
    // frame beside the joints, markers and eye frame a take poses again after it.
    {
        use egogen::motion::hands::{move_fingers, HandAxes, HandDoing, HandStyle};
        use rand_core::SeedableRng;
        let axes = HandAxes::from_rest(&shaped.rest_joints);
        let style = HandStyle::draw(&mut rand_chacha::ChaCha8Rng::seed_from_u64(0));
        let doing: Vec<[HandDoing; 2]> = (0..400)
            .map(|f| [[HandDoing::Walking, HandDoing::HOLDING_A_CUP][f / 200]; 2])
            .collect();
        let mut frames = vec![one.clone(); 400];
        g.throughput(Throughput::Elements(400));
        g.bench_function("finger_motion_per_frame", |b| {
            b.iter(|| move_fingers(&mut frames, &doing, &axes, &style, 40.0))
        });
    }
    g.throughput(Throughput::Elements(64));
    g.bench_with_input(BenchmarkId::new("full_batch", 64), &batch, |b, batch| {
        b.iter(|| model.pose_batch(batch).unwrap())
    });
    g.finish();

    // Official SMPL-X sizes (random values): the cost of pose correctives, and what skipping
    // them saves when they are all zero (as in our default model).
    let dir = tempfile::tempdir().unwrap();
    let mut arrays = common::random_model_arrays();
    let with_path = dir.path().join("with.npz");
    common::write_npz(&with_path, &arrays);
    let at = arrays.iter().position(|(k, _)| *k == "posedirs").unwrap();
    arrays[at].1 = common::Arr::F64(vec![10475, 3, 486], vec![0.0; 10475 * 3 * 486]);
    let without_path = dir.path().join("without.npz");
    common::write_npz(&without_path, &arrays);
    drop(arrays);
    let with = BodyModel::load(&with_path).unwrap();
    let without = BodyModel::load(&without_path).unwrap();
    assert!(with.has_pose_correctives() && !without.has_pose_correctives());
    let mut g = c.benchmark_group("official_shaped");
    g.throughput(Throughput::Elements(1));
    g.bench_function("full_single_with_correctives", |b| {
        b.iter(|| with.pose(&one).unwrap())
    });
    g.bench_function("full_single_zero_correctives", |b| {
        b.iter(|| without.pose(&one).unwrap())
    });
    // A sequence of 64 frames of one shape (what a vertex cache poses): the correctives of the
    // batch come from one f32 matrix product.
    let poses: Vec<_> = batch.iter().map(|p| p.pose).collect();
    let transl: Vec<_> = batch.iter().map(|p| p.transl).collect();
    let shaped_with = with.shape(&one.betas, &[]).unwrap();
    let shaped_without = without.shape(&one.betas, &[]).unwrap();
    g.bench_function("cached_shape_single_with_correctives", |b| {
        b.iter(|| shaped_with.pose(&one.pose, one.transl).unwrap())
    });
    g.throughput(Throughput::Elements(64));
    g.bench_function("sequence_64_with_correctives", |b| {
        b.iter(|| shaped_with.pose_sequence(&poses, &transl).unwrap())
    });
    g.bench_function("sequence_64_zero_correctives", |b| {
        b.iter(|| shaped_without.pose_sequence(&poses, &transl).unwrap())
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(4));
    targets = bench
}
criterion_main!(benches);
