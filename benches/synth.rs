//! Crowd synthesis speed (paper Alg. 1, `egogen synth`): one take of 8 primitives per agent
//! (3.65 s of motion) on an open 12 m floor, agents on a circle walking to the opposite points,
//! for 1, 4 and 16 agents steered by the shipped policy, and for one agent steered by the best of
//! K = 16 random latents (the no-training controller). Throughput is in frames of motion at
//! 40 Hz summed over agents: divide by 40 for seconds of motion per wall second.
//!
//! `synth_dwelling`: three people wander 20 s through a generated four-room dwelling (0.24 m
//! walls, `egogen policy rooms --seed 1004 --wall-m 0.24`), each primitive tested against the
//! scene at every frame (`swept`, the default: redraws, then holding still, instead of stepping
//! through a wall) or at its end alone (`end_only`, EgoGen's test): what the swept test costs;
//! and swept with the guide round walls 2 m ahead, planned on the whole map
//! (`swept_guided_by_map`) or on what each walker's rays have shown it (`swept_guided_on_memory`,
//! `guide_memory`): what the memory costs.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use egogen::body::BodyModel;
use egogen::motion::cvae::infer::InferBackend;
use egogen::motion::cvae::train::shipped_weights_path;
use egogen::motion::cvae::{BodyContext, MotionModel, PrimitiveSeed};
use egogen::motion::MotionSequence;
use egogen::scene::WalkableMap;
use egogen::synth::crowd::{
    run_crowd, AgentPlan, CrowdParts, CrowdSettings, CrowdWorld, NEW_FRAMES,
};
use egogen::walker::pose_prior::shipped_pose_prior_path;
use egogen::walker::ControllerSpec;
use egogen::walker::SeedBank;
use egogen::walker::{PosePrior, WalkerSettings};
use glam::DVec2;

const PRIMITIVES: usize = 8;

fn circle(n: usize, radius_m: f64, steering: ControllerSpec) -> Vec<AgentPlan> {
    (0..n)
        .map(|i| {
            let p = DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64) * radius_m;
            AgentPlan {
                name: format!("a{i}"),
                betas: Vec::new(),
                start: p,
                facing_rad: None,
                goals: vec![-p],
                wander: false,
                steering,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let model = MotionModel::load(shipped_weights_path()).expect("primitive weights");
    let body = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let ctx = BodyContext::new(&body, &[]).unwrap();
    let clip = MotionSequence::read(&root.join("assets/motion/cmu_01_03.npz")).unwrap();
    let seeds: Vec<PrimitiveSeed> = (0..16)
        .map(|i| PrimitiveSeed {
            frames: [clip.frame(30 * i + 20), clip.frame(30 * i + 21)],
            floor_z: 0.0,
        })
        .collect();
    let bank = SeedBank::from_world_seeds(&ctx, &seeds).unwrap();
    let prior = PosePrior::load(&shipped_pose_prior_path()).unwrap();
    let (_, policy) = egogen::policy::weights::load_policy::<InferBackend>(
        &root.join(egogen::policy::weights::SHIPPED_POLICY),
        &Default::default(),
    )
    .unwrap();
    let actor = egogen::policy::Actor::of(&policy);
    let parts = CrowdParts {
        model: &model,
        body_model: &body,
        prior: &prior,
        bank: &bank,
        policy: Some(&actor),
    };
    let n = 120;
    let map = WalkableMap::from_walkable(DVec2::splat(-6.0), 0.1, n, n, vec![true; n * n]);
    let world = CrowdWorld {
        map: std::sync::Arc::new(map),
        region: None,
        obstacles: Vec::new(),
        moving: Vec::new(),
    };
    let settings = CrowdSettings {
        walker: WalkerSettings {
            max_primitives_per_goal: 100,
            ..Default::default()
        },
        primitives: PRIMITIVES,
        stop_when_done: false,
        ..CrowdSettings::default()
    };
    let mut g = c.benchmark_group("synth_crowd");
    g.sample_size(10);
    let steer = ControllerSpec::POLICY;
    let cases = [
        ("policy", 1usize, steer),
        ("policy", 4, steer),
        ("policy", 16, steer),
        ("sampling_k16", 1, ControllerSpec::Sampling { k: 16 }),
    ];
    for (name, agents, steering) in cases {
        let plans = circle(agents, 4.0, steering);
        g.throughput(Throughput::Elements(
            (agents * PRIMITIVES * NEW_FRAMES) as u64,
        ));
        g.bench_with_input(BenchmarkId::new(name, agents), &agents, |b, _| {
            b.iter(|| run_crowd(&parts, &world, &plans, &settings, |_, _| {}).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group("synth_dwelling");
    g.sample_size(10);
    let rooms = egogen::scene::generated::room_scene::RoomSettings {
        wall_m: 0.24,
        ..Default::default()
    };
    let dwelling = egogen::scene::generated::room_scene::RoomScene::sample(
        &rooms,
        &mut <rand_chacha::ChaCha8Rng as rand_core::SeedableRng>::seed_from_u64(1004),
    );
    let house = CrowdWorld {
        map: std::sync::Arc::new(dwelling.map.clone()),
        region: None,
        obstacles: Vec::new(),
        moving: Vec::new(),
    };
    let mut draw = <rand_chacha::ChaCha8Rng as rand_core::SeedableRng>::seed_from_u64(7);
    let wanderers: Vec<AgentPlan> = (0..3)
        .map(|i| AgentPlan {
            name: format!("w{i}"),
            betas: Vec::new(),
            start: egogen::synth::crowd::sample_point(&house.map, None, 0.4, &mut draw).unwrap(),
            facing_rad: None,
            goals: Vec::new(),
            wander: true,
            steering: steer,
        })
        .collect();
    for (name, swept, guide_lookahead_m, guide_memory) in [
        ("swept", true, 0.0, false),
        ("end_only", false, 0.0, false),
        ("swept_guided_by_map", true, 2.0, false),
        ("swept_guided_on_memory", true, 2.0, true),
    ] {
        let settings = CrowdSettings {
            walker: WalkerSettings {
                scene_every_frame: swept,
                guide_lookahead_m,
                guide_memory,
                ..Default::default()
            },
            primitives: 40,
            stop_when_done: false,
            ..CrowdSettings::default()
        };
        g.throughput(Throughput::Elements((3 * 40 * NEW_FRAMES) as u64));
        g.bench_function(name, |b| {
            b.iter(|| run_crowd(&parts, &house, &wanderers, &settings, |_, _| {}).unwrap())
        });
    }
    g.finish();

    // Where one agent's primitive goes: the parts of a step at batch 1.
    let mut g = c.benchmark_group("synth_step_parts");
    g.sample_size(20);
    let seed = bank.seeds[0].clone();
    let view_seed = egogen::walker::state::place_seed(
        &seed.0,
        seed.1,
        DVec2::new(-2.0, 0.0),
        0.0,
        0.0,
        ctx.shaped.rest_joints[0],
    );
    let view = egogen::walker::state::SeedView::new(&ctx, view_seed.clone()).unwrap();
    let walker = egogen::walker::state::Walker::new(view, DVec2::new(2.0, 0.0));
    let sensor = egogen::sensing::Sensor::default();
    let around = egogen::walker::state::Surroundings {
        map: &world.map,
        obstacle: None,
        moving: &[],
    };
    let mut obs = vec![0f32; egogen::walker::ObsLayout::PAPER.dim()];
    g.bench_function("observe", |b| {
        b.iter(|| {
            walker.observe_into(
                &ctx,
                &sensor,
                DVec2::new(2.0, 0.0),
                &around,
                0.0,
                1.0,
                &mut obs,
            )
        })
    });
    let device = Default::default();
    let mut rng = <rand_chacha::ChaCha8Rng as rand_core::SeedableRng>::seed_from_u64(0);
    // The actor as acting runs it (plain f32, `policy::Actor`), and the same actions through
    // burn's network.
    g.bench_function("policy_forward", |b| {
        b.iter(|| actor.actions(&obs, Some(&mut rng)))
    });
    g.bench_function("policy_forward_burn", |b| {
        b.iter(|| egogen::policy::ppo::actions(&policy, obs.clone(), Some(&mut rng), &device))
    });
    let z = vec![vec![0f32; model.latent_dim()]];
    g.bench_function("decode_and_pose", |b| {
        b.iter(|| {
            model
                .decode_each(&ctx, std::slice::from_ref(&view_seed), &z)
                .unwrap()
        })
    });
    let p = model
        .decode(&ctx, std::slice::from_ref(&view_seed), &z)
        .unwrap()
        .remove(0);
    let feet = egogen::motion::cvae::tensor_body::RigGeometry::new(&body, &[])
        .unwrap()
        .foot_markers;
    let situation = walker.situation(&around, DVec2::new(2.0, 0.0), 0.0);
    let limits = egogen::walker::reward::Limits::eq7(0.3);
    g.bench_function("judge", |b| {
        b.iter(|| egogen::walker::reward::judge(&p, &situation, &feet, &prior, &limits))
    });
    // The same with the scene tested at every frame (what a take's agents pay per draw).
    let swept = egogen::walker::reward::Limits::swept(0.3);
    g.bench_function("judge_swept", |b| {
        b.iter(|| egogen::walker::reward::judge(&p, &situation, &feet, &prior, &swept))
    });
    g.bench_function("agent_setup", |b| {
        b.iter(|| BodyContext::new(&body, &[0.5, -0.5]).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
