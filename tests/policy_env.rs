//! The locomotion environment: box scenes put the box between start and goal; episodes are
//! deterministic per episode base and differ between bases; observations have EgoGen's layout
//! and ranges; episodes end by timeout after 11 primitives and restart; the best of K
//! candidates never scores below the first; the pose prior tells mocap from bent joints and
//! refuses broken files with their path.

mod common;

use egogen::body::BodyModel;
use egogen::motion::cvae::train::{normal_samples, shipped_weights_path};
use egogen::motion::cvae::{BodyContext, MotionModel, PrimitiveSeed};
use egogen::policy::env::Ending;
use egogen::policy::sampling::sampling_step;
use egogen::policy::{EnvSettings, PolicyEnv};
use egogen::scene::generated::box_scene::{BoxScene, BoxSceneSettings};
use egogen::walker::pose_prior::{prior_values, PosePrior, PRIOR_DIM};
use egogen::walker::reward::Judged;
use egogen::walker::ObsLayout;
use egogen::walker::SeedBank;
use egogen::walker::STATE_FRAME_DIM;

/// The paper's observation layout (32 rays), which environments use unless told otherwise.
const LAYOUT: ObsLayout = ObsLayout::PAPER;
const OBS_DIM: usize = LAYOUT.dim();
const RAYS: usize = LAYOUT.sensing_per_frame;
const OBS_RAYS_OFFSET: usize = LAYOUT.sensing_offset();
const OBS_DIST_OFFSET: usize = LAYOUT.dist_offset();
use egogen::scene::Obstacle2;
use glam::DVec2;
use proptest::prelude::*;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

fn clip() -> egogen::motion::MotionSequence {
    egogen::motion::MotionSequence::read(&common::repo_root().join("assets/motion/cmu_01_03.npz"))
        .unwrap()
}

fn seeds() -> Vec<PrimitiveSeed> {
    let c = clip();
    [40usize, 80, 120, 160]
        .iter()
        .map(|&f| PrimitiveSeed {
            frames: [c.frame(f), c.frame(f + 1)],
            floor_z: 0.0,
        })
        .collect()
}

/// A prior fitted on the clip's own frames (small and quick).
fn clip_prior() -> PosePrior {
    let c = clip();
    let poses: Vec<[f64; PRIOR_DIM]> = (0..c.len())
        .step_by(2)
        .map(|i| prior_values(&c.frame(i)))
        .collect();
    let mut p = PosePrior::fit(&poses, 4, 20, 0, "cmu_01_03");
    let means: Vec<f64> = poses.iter().map(|v| p.nll(v)).collect();
    p.set_plausible_limit(&means, 0.99);
    p
}

/// Binds what the environment tests share: the shipped body as `body` and its context `ctx`,
/// the shipped motion model `model`, a seed bank of the clip's seeds `bank`, and `prior`.
macro_rules! env_parts {
    ($body:ident, $ctx:ident, $model:ident, $bank:ident, $prior:ident) => {
        let $body =
            BodyModel::load(common::repo_root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
        let $ctx = BodyContext::new(&$body, &[]).unwrap();
        let $model = MotionModel::load(shipped_weights_path()).unwrap();
        let $bank = SeedBank::from_world_seeds(&$ctx, &seeds()).unwrap();
        let $prior = clip_prior();
    };
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn the_box_stands_between_start_and_goal(seed in any::<u64>()) {
        let s = BoxSceneSettings::default();
        let scene = BoxScene::sample(&s, &mut ChaCha8Rng::seed_from_u64(seed));
        let Obstacle2::Box { centre, half_extents, .. } = scene.obstacle else { panic!("a box") };
        prop_assert!(half_extents.min_element() >= 0.25 && half_extents.max_element() <= 0.5);
        // Goal mirrored through the box centre: the straight path crosses the box.
        prop_assert!(((scene.start + scene.goal) * 0.5 - centre).length() < 1e-12);
        prop_assert!(scene.obstacle.contains(centre));
        for p in [scene.start, scene.goal] {
            prop_assert!(scene.map.is_walkable_at(p));
            prop_assert!(scene.map.sdf_at(p) >= s.clearance_m - 0.15, "sdf {}", scene.map.sdf_at(p));
            prop_assert!(p.abs().max_element() < s.floor_m / 2.0 - 0.5);
        }
        prop_assert!(scene.start.distance(scene.goal) >= 2.0 * (0.25 + s.clearance_m) - 1e-9);
    }
}

#[test]
fn episodes_are_deterministic_observed_as_egogen_and_time_out() {
    env_parts!(body, ctx, model, bank, prior);
    let settings = EnvSettings::default();
    let b = 4;
    let mut a = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 7).unwrap();
    let twin = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 7).unwrap();
    let other = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 8).unwrap();
    let obs = a.observations();
    assert_eq!(obs.len(), b * OBS_DIM);
    assert_eq!(obs, twin.observations());
    assert_ne!(obs, other.observations());
    for o in obs.chunks(OBS_DIM) {
        assert!(o.iter().all(|v| v.is_finite()));
        // Goal directions are unit vectors; markers lie within 2 m of the canonical origin.
        for k in 0..2 {
            let f = &o[k * STATE_FRAME_DIM..(k + 1) * STATE_FRAME_DIM];
            for m in 0..67 {
                let p = &f[3 * m..3 * m + 3];
                assert!(p.iter().map(|x| x * x).sum::<f32>().sqrt() < 2.0);
                let d = &f[201 + 3 * m..201 + 3 * m + 3];
                let len = d.iter().map(|x| x * x).sum::<f32>().sqrt();
                assert!((len - 1.0).abs() < 1e-4, "direction length {len}");
            }
        }
        let rays = &o[OBS_RAYS_OFFSET..OBS_RAYS_OFFSET + 2 * RAYS];
        assert!(rays.iter().all(|r| (-1.0..=1.0).contains(r)));
        // The box stands ahead within 7 m: some ray in the fan sees something nearer.
        assert!(rays.iter().any(|r| *r < 0.9), "{rays:?}");
        let d = o[OBS_DIST_OFFSET];
        assert!(d > 0.1 && d < 0.5, "1/(1+d) = {d}");
        assert_eq!(o[OBS_DIST_OFFSET + 1], 1.0);
    }
    // Observed through a 0.8 m local map instead: the same state, the patch in place of the
    // rays (the box scenes' floor is free around the start).
    let lm = egogen::sensing::SensingSpec::centred_map(0.8, 16);
    let mapped = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 7)
        .unwrap()
        .with_sensing(&lm);
    let layout = mapped.obs_layout();
    assert_eq!(layout.sensing_per_frame, 256);
    let mo = mapped.observations();
    assert_eq!(mo.len(), b * layout.dim());
    for (m, o) in mo.chunks(layout.dim()).zip(obs.chunks(OBS_DIM)) {
        assert_eq!(m[..layout.sensing_offset()], o[..OBS_RAYS_OFFSET]);
        assert_eq!(m[layout.dist_offset()..], o[OBS_DIST_OFFSET..]);
        let patch = &m[layout.sensing_offset()..layout.dist_offset()];
        assert!(patch.iter().all(|&v| v == 0.0 || v == 1.0));
        assert!(patch.contains(&0.0));
    }
    // Random latents: deterministic rewards, every episode over after 11 primitives.
    let l = a.latent_dim();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut b_env = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 7).unwrap();
    let mut ended = Vec::new();
    for step in 0..settings.walker.max_primitives_per_goal {
        let z = normal_samples(&mut rng, b * l);
        let out = a.step(&z).unwrap();
        let twin_out = b_env.step(&z).unwrap();
        assert_eq!(out.reward, twin_out.reward);
        assert!(out.reward.iter().all(|r| r.is_finite()));
        for s in &out.finished {
            assert!(s.primitives <= step + 1);
        }
        ended.extend(out.finished);
    }
    let first: Vec<_> = ended.iter().filter(|s| s.id < b as u64).collect();
    assert_eq!(
        first.len(),
        b,
        "all first episodes end within 11 primitives"
    );
    for s in &first {
        assert!(matches!(s.ending, Ending::Timeout | Ending::Success));
        assert!(s.contact > 0.0 && s.contact <= 1.0);
        assert!(s.speed_m_s.is_finite());
    }
    assert!(a.episode_ids().iter().all(|&id| id >= b as u64));
}

#[test]
fn the_best_of_k_candidates_scores_at_least_the_first() {
    env_parts!(body, ctx, model, bank, prior);
    let env = PolicyEnv::new(&model, &ctx, &bank, &prior, EnvSettings::default(), 3, 1).unwrap();
    let k = 8;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let z = normal_samples(&mut rng, 3 * k * env.latent_dim());
    let candidates = env.propose(&z, k).unwrap();
    assert_eq!(candidates.len(), 3 * k);
    let best: Vec<f64> = (0..3)
        .map(|e| {
            candidates[e * k..(e + 1) * k]
                .iter()
                .map(|c| c.reward)
                .fold(f64::MIN, f64::max)
        })
        .collect();
    // The same draw through the controller keeps the best.
    let mut env2 =
        PolicyEnv::new(&model, &ctx, &bank, &prior, EnvSettings::default(), 3, 1).unwrap();
    let out = sampling_step(&mut env2, k, &mut ChaCha8Rng::seed_from_u64(5)).unwrap();
    for e in 0..3 {
        assert!((out.reward[e] as f64 - best[e]).abs() < 1e-6);
        assert!(best[e] >= candidates[e * k].reward);
    }
    // A decreasing distance is rewarded: the goal term is the distance decrease.
    for c in &candidates {
        let j = c.judged.unwrap();
        assert!(
            j.terms.goal.abs() < 1.5,
            "a primitive moves < 1.5 m in 0.5 s"
        );
        assert!((0.0..=1.0).contains(&j.terms.orientation));
        assert!((0.0..=1.0).contains(&j.terms.attention));
    }
    let _ = DVec2::ZERO;
}

#[test]
fn the_pose_prior_tells_mocap_from_bent_joints_and_refuses_broken_files() {
    let prior = clip_prior();
    let c = clip();
    let mut bent_worse = 0;
    let mut n = 0;
    for i in (1..c.len()).step_by(7) {
        let f = c.frame(i);
        let mut b = f.clone();
        // Left knee bent 90° sideways.
        let aa = b.joint_axis_angle(4);
        b.set_joint_axis_angle(
            4,
            aa + egogen::math::Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        n += 1;
        if prior.pose_nll(&b) > prior.plausible_max_nll && prior.pose_nll(&f) < prior.pose_nll(&b) {
            bent_worse += 1;
        }
    }
    assert!(bent_worse as f64 >= 0.95 * n as f64, "{bent_worse} of {n}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("prior.json");
    prior.save(&path).unwrap();
    assert!(
        PosePrior::load(&path).unwrap() == prior,
        "the prior reads back exactly"
    );
    let text = std::fs::read_to_string(&path).unwrap().replacen(
        "\"variance\":[",
        "\"variance\":[-1.0,",
        1,
    );
    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, text).unwrap();
    let err = PosePrior::load(&broken).unwrap_err().to_string();
    assert!(
        err.contains("broken.json") && err.contains("component 0"),
        "{err}"
    );
    std::fs::write(&broken, "{").unwrap();
    let err = PosePrior::load(&broken).unwrap_err().to_string();
    assert!(
        err.contains("broken.json") && err.contains("not a pose prior"),
        "{err}"
    );
}

#[test]
fn fixed_scene_episodes_walk_its_pairs_in_turn_on_its_floor() {
    use egogen::policy::env::FixedScene;
    use egogen::scene::{StartGoal, WalkableMap};
    env_parts!(body, ctx, model, bank, prior);
    // A 6 × 6 m room at floor height 0.5 m with a wall across half of it.
    let n = 60;
    let walkable = (0..n * n)
        .map(|k| !((k / n) == 30 && (k % n) < 30))
        .collect();
    let mut map = WalkableMap::from_walkable(DVec2::splat(-3.0), 0.1, n, n, walkable);
    map.floor_z_m = 0.5;
    let pairs = vec![
        StartGoal {
            start: DVec2::new(-1.5, -1.5),
            goal: DVec2::new(-1.5, 1.5),
        },
        StartGoal {
            start: DVec2::new(1.5, -1.5),
            goal: DVec2::new(1.5, 1.5),
        },
    ];
    let fixed = FixedScene {
        map: std::sync::Arc::new(map),
        pairs,
        sdf: None,
    };
    let env = PolicyEnv::with_scene(
        &model,
        &ctx,
        &bank,
        &prior,
        Some(&fixed),
        EnvSettings::default(),
        3,
        0,
    )
    .unwrap();
    let obs = env.observations();
    for (e, o) in obs.chunks(OBS_DIM).enumerate() {
        // Episode e walks pair e mod 2: start 3 m from its goal.
        let d = 1.0 / o[OBS_DIST_OFFSET] - 1.0;
        assert!((d - 3.0).abs() < 0.3, "episode {e}: distance {d}");
    }
    // The wall stands ahead of pair 0 only: its rays see it nearer than pair 1's.
    let nearest = |o: &[f32]| {
        o[OBS_RAYS_OFFSET..OBS_RAYS_OFFSET + RAYS]
            .iter()
            .copied()
            .fold(1.0f32, f32::min)
    };
    assert!(nearest(&obs[..OBS_DIM]) < nearest(&obs[OBS_DIM..2 * OBS_DIM]));
    // Decoded on the scene's floor: feet within a few cm of z = 0.5 m.
    let z = normal_samples(&mut ChaCha8Rng::seed_from_u64(9), 3 * env.latent_dim());
    let c = env.propose(&z, 1).unwrap();
    for cand in &c {
        let p = cand.primitive.as_ref().unwrap();
        assert_eq!(p.floor_z, 0.5);
        let lowest = p
            .markers
            .iter()
            .flatten()
            .map(|m| m.z)
            .fold(f64::INFINITY, f64::min);
        assert!((lowest - 0.5).abs() < 0.08, "lowest marker at {lowest}");
        assert_eq!(cand.judged.unwrap().frames_in_obstacle, 0);
    }
    // Snapshots of fixed-scene episodes restore into a fixed-scene environment only.
    let snap = env.snapshot();
    let mut twin = PolicyEnv::with_scene(
        &model,
        &ctx,
        &bank,
        &prior,
        Some(&fixed),
        EnvSettings::default(),
        3,
        0,
    )
    .unwrap();
    twin.restore(&snap).unwrap();
    assert_eq!(twin.observations(), obs);
    let mut boxes =
        PolicyEnv::new(&model, &ctx, &bank, &prior, EnvSettings::default(), 3, 0).unwrap();
    assert!(boxes
        .restore(&snap)
        .unwrap_err()
        .to_string()
        .contains("not of this environment's kind"));
}

/// Episodes in generated dwellings (`[stages.env.dwellings]`): with a share of 1 every episode
/// walks a pair of one of the dwellings given, on its floor; its snapshot restores into an
/// environment with the same dwellings and is refused by one without.
#[test]
fn dwelling_episodes_walk_their_pairs_and_restore_only_where_the_dwellings_are() {
    use egogen::policy::env::{EnvParts, FixedScene};
    use egogen::scene::{StartGoal, WalkableMap};
    env_parts!(body, ctx, model, bank, prior);
    // Two open 6 × 6 m floors far apart, at floor heights 0 and 2.5 m, one pair each: 2 m
    // and 4 m from start to goal.
    let dwelling = |origin: DVec2, floor_z: f64, length: f64| {
        let mut map = WalkableMap::from_walkable(origin, 0.1, 60, 60, vec![true; 3600]);
        map.floor_z_m = floor_z;
        let start = origin + DVec2::splat(1.0);
        FixedScene {
            map: std::sync::Arc::new(map),
            pairs: vec![StartGoal {
                start,
                goal: start + DVec2::new(length, 0.0),
            }],
            sdf: None,
        }
    };
    let dwellings = [
        dwelling(DVec2::ZERO, 0.0, 2.0),
        dwelling(DVec2::splat(1000.0), 2.5, 4.0),
    ];
    let parts = EnvParts {
        model: &model,
        body: &ctx,
        bank: &bank,
        prior: &prior,
        fixed: None,
        dwellings: &dwellings,
    };
    let mut settings = EnvSettings::default();
    settings.dwellings.share = 1.0;
    let envs = 8;
    let env = parts.env(settings, envs, 3).unwrap();
    let obs = env.observations();
    let mut lengths = std::collections::BTreeSet::new();
    for (e, o) in obs.chunks(OBS_DIM).enumerate() {
        let d = 1.0 / o[OBS_DIST_OFFSET] as f64 - 1.0;
        let length = [2.0, 4.0]
            .into_iter()
            .find(|l| (d - l).abs() < 0.3)
            .unwrap_or_else(|| panic!("episode {e}: {d} m from its goal, no pair's"));
        lengths.insert(length as u32);
    }
    assert_eq!(lengths.len(), 2, "every episode in one dwelling");
    let snap = env.snapshot();
    let mut twin = parts.env(settings, envs, 3).unwrap();
    twin.restore(&snap).unwrap();
    assert_eq!(twin.observations(), obs);
    let without = EnvParts {
        dwellings: &dwellings[..1],
        ..parts
    };
    let mut other = without.env(settings, envs, 3).unwrap();
    let err = other.restore(&snap).unwrap_err().to_string();
    assert!(err.contains("dwelling is not one of"), "{err}");
}

#[test]
fn scene_penetration_counts_body_vertices_inside_the_scene_sdf() {
    use egogen::policy::env::FixedScene;
    use egogen::scene::{SceneMesh, SceneSdf, StartGoal, WalkableMap};
    use egogen::walker::reward::EQ11_VERTICES;
    env_parts!(body, ctx, model, bank, prior);
    // An open floor (the map sees nothing) with a closed 1.6 × 1.6 × 2 m pillar over the first
    // pair's start, which only the 3D SDF knows of; the second pair starts 4 m from it.
    let n = 100;
    let map = WalkableMap::from_walkable(DVec2::splat(-5.0), 0.1, n, n, vec![true; n * n]);
    let mut mesh = SceneMesh::default();
    mesh.add_box(
        "pillar",
        egogen::math::Vec3::new(-2.8, -2.8, 0.0),
        egogen::math::Vec3::new(-1.2, -1.2, 2.0),
    );
    let sdf = SceneSdf::build(&mesh, 0.05, 0.2).unwrap();
    let fixed = FixedScene {
        map: std::sync::Arc::new(map),
        pairs: vec![
            StartGoal {
                start: DVec2::new(-2.0, -2.0),
                goal: DVec2::new(-2.0, 1.0),
            },
            StartGoal {
                start: DVec2::new(2.0, -2.0),
                goal: DVec2::new(2.0, 1.0),
            },
        ],
        sdf: Some(std::sync::Arc::new(sdf)),
    };
    let env = PolicyEnv::with_scene(
        &model,
        &ctx,
        &bank,
        &prior,
        Some(&fixed),
        EnvSettings::default(),
        2,
        0,
    )
    .unwrap();
    let z = normal_samples(&mut ChaCha8Rng::seed_from_u64(3), 2 * env.latent_dim());
    let c = env.propose(&z, 1).unwrap();
    let inside = c[0].judged.unwrap();
    let free = c[1].judged.unwrap();
    // Standing in the pillar: every new frame penetrates, with far more than 40 vertices.
    assert_eq!(inside.scene_penetrating_frames, 18);
    assert!(
        inside.scene_vertices_inside_max > 10 * EQ11_VERTICES,
        "{}",
        inside.scene_vertices_inside_max
    );
    // In free space: none.
    assert_eq!(free.scene_penetrating_frames, 0);
    assert_eq!(free.scene_vertices_inside_max, 0);
    // The map sees nothing, so Eq. 7 passes both.
    assert!(!inside.penetrated && !free.penetrated);

    // Training's test (Eq. 11 on a vertex subset) decides instead of Eq. 7: the body in the
    // pillar penetrates and loses the penetration term, the free one does not.
    let test = egogen::walker::reward::SceneTest::new(&body, 1024);
    assert_eq!(test.vertices(), 1024);
    let expected = (40.0 * 1024.0 / body.num_vertices() as f64)
        .round()
        .max(1.0) as usize;
    assert_eq!(test.threshold(), expected);
    let settings = EnvSettings {
        scene_test_vertices: 1024,
        ..EnvSettings::default()
    };
    let env =
        PolicyEnv::with_scene(&model, &ctx, &bank, &prior, Some(&fixed), settings, 2, 0).unwrap();
    let c = env.propose(&z, 1).unwrap();
    let (inside, free) = (c[0].judged.unwrap(), c[1].judged.unwrap());
    assert!(inside.penetrated && !free.penetrated);
    assert_eq!(inside.terms.penetration, 0.0);
    assert!(free.terms.penetration > 0.0);
    // Only the fast test runs in training: nothing measured on every vertex.
    assert_eq!(inside.scene_penetrating_frames, 0);
    let primitive = c[0].primitive.as_ref().unwrap();
    assert!(test
        .penetrates(&ctx, primitive, fixed.sdf.as_deref().unwrap())
        .unwrap());

    // Keeping the cells: on a map that blocks everything, the body in free 3D space penetrates
    // by Eq. 7 and so penetrates; without them it does not.
    let n = 100;
    let walled = FixedScene {
        map: std::sync::Arc::new(WalkableMap::from_walkable(
            DVec2::splat(-5.0),
            0.1,
            n,
            n,
            vec![false; n * n],
        )),
        ..fixed.clone()
    };
    let free_in = |keep: bool| {
        let settings = EnvSettings {
            scene_test_vertices: 1024,
            scene_test_keeps_cells: keep,
            ..EnvSettings::default()
        };
        let env = PolicyEnv::with_scene(&model, &ctx, &bank, &prior, Some(&walled), settings, 2, 0)
            .unwrap();
        env.propose(&z, 1).unwrap()[1].judged.unwrap().penetrated
    };
    assert!(free_in(true) && !free_in(false));
}

#[test]
fn a_fixed_share_mixes_scene_pairs_with_box_scenes_each_on_its_own_clock() {
    use egogen::policy::env::FixedScene;
    use egogen::scene::{StartGoal, WalkableMap};
    env_parts!(body, ctx, model, bank, prior);
    // An open 20 × 20 m floor; its one pair is 9 m long, longer than any box scene's
    // start–goal distance (at most 4.8 m).
    let n = 200;
    let map = WalkableMap::from_walkable(DVec2::splat(-10.0), 0.1, n, n, vec![true; n * n]);
    let fixed = FixedScene {
        map: std::sync::Arc::new(map),
        pairs: vec![StartGoal {
            start: DVec2::new(-4.5, 0.0),
            goal: DVec2::new(4.5, 0.0),
        }],
        sdf: None,
    };
    let settings = EnvSettings {
        fixed_share: 0.5,
        fixed_max_primitives: Some(13),
        ..EnvSettings::default()
    };
    let envs = 24;
    let mut env =
        PolicyEnv::with_scene(&model, &ctx, &bank, &prior, Some(&fixed), settings, envs, 0)
            .unwrap();
    let env_start_obs = env.observations().to_vec();
    let distance = |o: &[f32]| 1.0 / o[OBS_DIST_OFFSET] as f64 - 1.0;
    let in_scene: Vec<bool> = env
        .observations()
        .chunks(OBS_DIM)
        .map(|o| distance(o) > 8.0)
        .collect();
    let scene_count = in_scene.iter().filter(|&&f| f).count();
    assert!(
        (4..=20).contains(&scene_count),
        "{scene_count} of {envs} episodes in the scene"
    );
    // After one primitive the time left is 1 − 1/13 in the scene and 1 − 1/11 in box scenes.
    let z = normal_samples(&mut ChaCha8Rng::seed_from_u64(3), envs * env.latent_dim());
    let out = env.step(&z).unwrap();
    let snap = env.snapshot();
    for (e, o) in env.observations().chunks(OBS_DIM).enumerate() {
        if out.done[e] {
            continue;
        }
        let left = o[OBS_DIST_OFFSET + 1] as f64;
        let expected = if in_scene[e] {
            1.0 - 1.0 / 13.0
        } else {
            1.0 - 1.0 / 11.0
        };
        assert!(
            (left - expected).abs() < 1e-6,
            "episode {e}: time left {left}"
        );
    }
    // Indoor weights apply to the scene's pairs, box weights to the box scenes: every weight
    // doubled indoors and tripled in box scenes doubles and triples their rewards (the reward
    // is linear in the weights).
    let w = settings.weights;
    let scaled = |f: f64| egogen::walker::reward::WeightChanges {
        floor: Some(f * w.floor),
        skate: Some(f * w.skate),
        goal: Some(f * w.goal),
        orientation: Some(f * w.orientation),
        attention: Some(f * w.attention),
        penetration: Some(f * w.penetration),
        pose: Some(f * w.pose),
        success: Some(f * w.success),
        arrival: Some(f * w.arrival),
        attention_gap: Some(f * w.attention_gap),
        penetration_cost: Some(f * w.penetration_cost),
    };
    let reweighted = EnvSettings {
        indoor_weights: scaled(2.0),
        box_weights: scaled(3.0),
        ..settings
    };
    let mut weighted = PolicyEnv::with_scene(
        &model,
        &ctx,
        &bank,
        &prior,
        Some(&fixed),
        reweighted,
        envs,
        0,
    )
    .unwrap();
    assert_eq!(weighted.observations(), &env_start_obs[..]);
    let out_weighted = weighted.step(&z).unwrap();
    for e in 0..envs {
        let (plain, changed) = (out.reward[e], out_weighted.reward[e]);
        let expected = if in_scene[e] {
            2.0 * plain
        } else {
            3.0 * plain
        };
        assert!(
            (changed - expected).abs() <= 1e-5 * expected.abs().max(1.0),
            "episode {e} (in the scene: {}): reward {changed}, expected {expected}",
            in_scene[e]
        );
    }
    for indoors in [true, false] {
        assert!(
            in_scene
                .iter()
                .zip(&out.reward)
                .any(|(&s, &r)| s == indoors && r.abs() > 1e-3),
            "no reward to scale (indoors: {indoors})"
        );
    }
    // Mixed episodes restore into a mixed environment, not into a scene-only or box-only one.
    let mut twin =
        PolicyEnv::with_scene(&model, &ctx, &bank, &prior, Some(&fixed), settings, envs, 0)
            .unwrap();
    twin.restore(&snap).unwrap();
    assert_eq!(twin.observations(), env.observations());
    let mut scene_only = PolicyEnv::with_scene(
        &model,
        &ctx,
        &bank,
        &prior,
        Some(&fixed),
        EnvSettings::default(),
        envs,
        0,
    )
    .unwrap();
    assert!(scene_only.restore(&snap).is_err());
    let mut boxes = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, envs, 0).unwrap();
    assert!(boxes.restore(&snap).is_err());
}

#[test]
fn crossing_episodes_see_the_other_person_and_restore_from_snapshots() {
    use egogen::scene::generated::crossing_scene::CrossingSettings;
    env_parts!(body, ctx, model, bank, prior);
    let crossing = |share: f64| EnvSettings {
        crossing: CrossingSettings {
            share,
            ..CrossingSettings::default()
        },
        ..EnvSettings::default()
    };
    let b = 6;
    let mut env = PolicyEnv::new(&model, &ctx, &bank, &prior, crossing(1.0), b, 5).unwrap();
    // The same episodes with the other person taken away: the floor's edges only.
    let mut alone_settings = crossing(1.0);
    alone_settings.crossing.footprint_m = (1e-6, 1e-6);
    let mut alone = PolicyEnv::new(&model, &ctx, &bank, &prior, alone_settings, b, 5).unwrap();
    let l = env.latent_dim();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut seen_nearer = 0;
    for step in 0..6 {
        let (o, a) = (env.observations(), alone.observations());
        for (x, y) in o.chunks(OBS_DIM).zip(a.chunks(OBS_DIM)) {
            let rays = OBS_RAYS_OFFSET..OBS_RAYS_OFFSET + 2 * RAYS;
            // The person only ever shortens rays.
            assert!(x[rays.clone()]
                .iter()
                .zip(&y[rays.clone()])
                .all(|(p, q)| p <= q));
            if x[rays.clone()] != y[rays] {
                seen_nearer += 1;
            }
        }
        if step == 3 {
            // A snapshot mid-episode restores to the same observations and rewards.
            let snap = env.snapshot();
            let mut twin =
                PolicyEnv::new(&model, &ctx, &bank, &prior, crossing(1.0), b, 5).unwrap();
            twin.restore(&snap).unwrap();
            assert_eq!(twin.observations(), env.observations());
            let z = normal_samples(&mut ChaCha8Rng::seed_from_u64(2), b * l);
            let (r1, r2) = (env.propose(&z, 1).unwrap(), twin.propose(&z, 1).unwrap());
            let rewards = |c: &[egogen::policy::env::Candidate]| {
                c.iter().map(|c| c.reward).collect::<Vec<_>>()
            };
            assert_eq!(rewards(&r1), rewards(&r2));
        }
        let z = normal_samples(&mut rng, b * l);
        env.step(&z).unwrap();
        alone.step(&z).unwrap();
    }
    assert!(seen_nearer > 0, "the other person was never in view");
}

/// Settings whose every episode walks a floor plan of its own.
fn floor_plans_only() -> EnvSettings {
    EnvSettings {
        rooms: egogen::scene::generated::room_scene::RoomSettings {
            share: 1.0,
            ..Default::default()
        },
        ..EnvSettings::default()
    }
}

/// Walks the same random primitives (`steps` of them, `per` candidates each) in two
/// environments, episode base `env_seed`, and hands each candidate's two judgements to `check`:
/// `end_only`'s, then `every`'s.
fn judged_in_lockstep(
    (end_only, every): (EnvSettings, EnvSettings),
    (env_seed, rng_seed, steps): (u64, u64, usize),
    mut check: impl FnMut(&Judged, &Judged),
) {
    env_parts!(body, ctx, model, bank, prior);
    let (b, per) = (4, 8);
    let mut end_only = PolicyEnv::new(&model, &ctx, &bank, &prior, end_only, b, env_seed).unwrap();
    let mut every = PolicyEnv::new(&model, &ctx, &bank, &prior, every, b, env_seed).unwrap();
    let l = end_only.latent_dim();
    let mut rng = ChaCha8Rng::seed_from_u64(rng_seed);
    for _ in 0..steps {
        let z = normal_samples(&mut rng, b * per * l);
        let (a, e) = (
            end_only.propose(&z, per).unwrap(),
            every.propose(&z, per).unwrap(),
        );
        for (a, e) in a.iter().zip(&e) {
            if let (Some(a), Some(e)) = (&a.judged, &e.judged) {
                check(a, e);
            }
        }
        let z = normal_samples(&mut rng, b * l);
        end_only.step(&z).unwrap();
        every.step(&z).unwrap();
    }
}

/// Walks the same random primitives in two environments, one testing an obstacle in every
/// frame (`every`) and one Eq. 7's cells alone (`end_only`), and checks that the test adds
/// exactly the primitives with a marker inside an obstacle; returns how many met one and how
/// many only the test caught. Scenes with one kind of obstacle: people or a box.
fn every_frame_counts(end_only: EnvSettings, every: EnvSettings, rng_seed: u64) -> (usize, usize) {
    let (mut touching, mut only_within) = (0, 0);
    judged_in_lockstep((end_only, every), (3, rng_seed, 4), |a, e| {
        // The same primitive, judged alike but for the every-frame test.
        assert_eq!(a.frames_in_obstacle, e.frames_in_obstacle);
        assert_eq!(a.blocked_cells, e.blocked_cells);
        assert_eq!(e.penetrated, a.penetrated || a.frames_in_obstacle > 0);
        touching += usize::from(a.frames_in_obstacle > 0);
        only_within += usize::from(e.penetrated && !a.penetrated);
    });
    (touching, only_within)
}

#[test]
fn people_tested_in_every_frame_penetrate_exactly_when_a_marker_enters_their_box() {
    use egogen::scene::generated::crossing_scene::CrossingSettings;
    // Four wide people: bodies meet them often within a few primitives.
    let settings = |people_every_frame: bool| EnvSettings {
        crossing: CrossingSettings {
            share: 1.0,
            people: (4, 4),
            footprint_m: (1.2, 1.2),
            ..CrossingSettings::default()
        },
        people_every_frame,
        ..EnvSettings::default()
    };
    let (touching, only_within) = every_frame_counts(settings(false), settings(true), 4);
    assert!(touching > 0, "no primitive met a person");
    assert!(
        only_within > 0,
        "every primitive that met a person was caught by the cells at its end"
    );
}

/// The view's angle to the direction of travel: a body walking on from mocap seeds with the
/// prior's mean latent looks about the way it walks, never backwards.
#[test]
fn a_body_walking_on_looks_about_the_way_it_walks() {
    env_parts!(body, ctx, model, bank, prior);
    let b = 8;
    let mut env =
        PolicyEnv::new(&model, &ctx, &bank, &prior, EnvSettings::default(), b, 9).unwrap();
    let z = vec![0f32; b * env.latent_dim()];
    let mut angles = Vec::new();
    for _ in 0..3 {
        for c in env.propose(&z, 1).unwrap() {
            let a = c.judged.unwrap().view_off_travel_rad;
            if !a.is_nan() {
                assert!((0.0..=std::f64::consts::PI).contains(&a), "{a}");
                angles.push(a.to_degrees());
            }
        }
        env.step(&z).unwrap();
    }
    angles.sort_by(f64::total_cmp);
    assert!(angles.len() >= b, "{} primitives travelled", angles.len());
    let median = angles[angles.len() / 2];
    assert!(
        median < 30.0,
        "median {median}° off the way walked: {angles:?}"
    );
}

/// `people_seen_ahead`: the crossing people are seen where they will stand when the
/// primitive ends, which changes the rays only (and not at all for people standing still),
/// never how a primitive is judged.
#[test]
fn people_seen_ahead_change_the_rays_only_and_not_for_people_standing_still() {
    use egogen::scene::generated::crossing_scene::CrossingSettings;
    env_parts!(body, ctx, model, bank, prior);
    let settings = |ahead: bool, speed_m_s: (f64, f64)| EnvSettings {
        crossing: CrossingSettings {
            share: 1.0,
            people: (2, 3),
            speed_m_s,
            ..CrossingSettings::default()
        },
        walker: egogen::walker::WalkerSettings {
            anticipate_people: ahead,
            ..egogen::walker::WalkerSettings::PAPER
        },
        ..EnvSettings::default()
    };
    let b = 6;
    let rays = OBS_RAYS_OFFSET..OBS_RAYS_OFFSET + 2 * RAYS;
    for (speed, moving) in [((0.6, 1.3), true), ((0.0, 0.0), false)] {
        let mut now =
            PolicyEnv::new(&model, &ctx, &bank, &prior, settings(false, speed), b, 7).unwrap();
        let mut ahead =
            PolicyEnv::new(&model, &ctx, &bank, &prior, settings(true, speed), b, 7).unwrap();
        let l = now.latent_dim();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut rays_differ = 0;
        for _ in 0..6 {
            let (o, a) = (now.observations(), ahead.observations());
            for (x, y) in o.chunks(OBS_DIM).zip(a.chunks(OBS_DIM)) {
                assert_eq!(x[..rays.start], y[..rays.start]);
                assert_eq!(x[rays.end..], y[rays.end..]);
                rays_differ += usize::from(x[rays.clone()] != y[rays.clone()]);
            }
            let z = normal_samples(&mut rng, b * l);
            let rewards = |c: Vec<egogen::policy::env::Candidate>| {
                c.iter().map(|c| c.reward.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(
                rewards(now.propose(&z, 1).unwrap()),
                rewards(ahead.propose(&z, 1).unwrap())
            );
            now.step(&z).unwrap();
            ahead.step(&z).unwrap();
        }
        assert_eq!(rays_differ > 0, moving, "speeds {speed:?}: {rays_differ}");
    }
}

#[test]
fn a_box_tested_in_every_frame_penetrates_exactly_when_a_marker_enters_it() {
    // Starts near large boxes: bodies walking at random brush them within a few primitives.
    let settings = |box_every_frame: bool| EnvSettings {
        scene: BoxSceneSettings {
            box_side_m: (1.5, 2.0),
            start_margin_m: 0.3,
            clearance_m: 0.2,
            ..BoxSceneSettings::default()
        },
        box_every_frame,
        ..EnvSettings::default()
    };
    let (touching, only_within) = every_frame_counts(settings(false), settings(true), 8);
    assert!(touching > 0, "no primitive met the box");
    assert!(
        only_within > 0,
        "every primitive that met the box was caught by the cells at its end"
    );
}

/// The guide (`guide_lookahead_m`): in floor plans, an episode whose goal the straight way
/// reaches is observed as without it; one whose goal a wall hides sees other goal
/// directions (towards the way round), and the same distance and rays.
#[test]
fn a_guided_walker_sees_the_way_round_only_where_a_wall_hides_its_goal() {
    use egogen::scene::{line_is_clear, GUIDE_CLEARANCE_M};
    env_parts!(body, ctx, model, bank, prior);
    let rooms = |guide_lookahead_m: f64| EnvSettings {
        walker: egogen::walker::WalkerSettings {
            guide_lookahead_m,
            ..floor_plans_only().walker
        },
        ..floor_plans_only()
    };
    let b = 12;
    let plain = PolicyEnv::new(&model, &ctx, &bank, &prior, rooms(0.0), b, 8).unwrap();
    let guided = PolicyEnv::new(&model, &ctx, &bank, &prior, rooms(2.0), b, 8).unwrap();
    let (o, g) = (plain.observations(), guided.observations());
    let pelvis = plain.pelvis_positions();
    let mut hidden = 0;
    for i in 0..b {
        let c = plain.course_view(i);
        let (x, y) = (
            &o[i * OBS_DIM..(i + 1) * OBS_DIM],
            &g[i * OBS_DIM..(i + 1) * OBS_DIM],
        );
        let at = pelvis[i].1;
        if line_is_clear(&c.map, c.obstacle.as_slice(), GUIDE_CLEARANCE_M, at, c.goal) {
            assert_eq!(x, y, "episode {i}: its goal is in plain view");
        } else {
            hidden += 1;
            assert_ne!(x, y, "episode {i}: its goal is hidden");
            let rays = OBS_RAYS_OFFSET..OBS_DIST_OFFSET;
            assert_eq!(x[rays.clone()], y[rays], "episode {i}: the rays");
            assert_eq!(
                x[OBS_DIST_OFFSET..],
                y[OBS_DIST_OFFSET..],
                "episode {i}: distance, time"
            );
        }
    }
    assert!(hidden > 0, "no goal hidden by a wall in {b} floor plans");
}

/// The guide on memory (`guide_memory`): it plans only on what the walker's rays have shown
/// it. A goal in plain view is shown as the goal; some goals behind a wall the walker has
/// seen are shown as a way round it; only the goal directions change, never the rays, the
/// distance or the time; the memory is part of an episode's snapshot, and a snapshot with a
/// memory is refused by an environment whose walkers keep none.
#[test]
fn a_guide_on_memory_plans_on_what_the_walker_saw_and_restores_from_snapshots() {
    use egogen::scene::{line_is_clear, GUIDE_CLEARANCE_M};
    env_parts!(body, ctx, model, bank, prior);
    let rooms = |guide_memory: bool| EnvSettings {
        walker: egogen::walker::WalkerSettings {
            guide_lookahead_m: 2.0,
            guide_memory,
            ..floor_plans_only().walker
        },
        ..floor_plans_only()
    };
    let plain_settings = EnvSettings {
        walker: egogen::walker::WalkerSettings {
            guide_lookahead_m: 0.0,
            ..rooms(false).walker
        },
        ..rooms(false)
    };
    let b = 12;
    let mut plain = PolicyEnv::new(&model, &ctx, &bank, &prior, plain_settings, b, 8).unwrap();
    let mut memory = PolicyEnv::new(&model, &ctx, &bank, &prior, rooms(true), b, 8).unwrap();
    // The same memory, ground never seen costing its guide twice as much to cross.
    let wary_settings = EnvSettings {
        walker: egogen::walker::WalkerSettings {
            guide_unknown_cost: 1.0,
            ..rooms(true).walker
        },
        ..rooms(true)
    };
    let mut wary = PolicyEnv::new(&model, &ctx, &bank, &prior, wary_settings, b, 8).unwrap();
    let l = plain.latent_dim();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut shown_a_way = 0;
    let mut wary_aims_elsewhere = 0;
    for step in 0..4 {
        let (o, g) = (plain.observations(), memory.observations());
        let w = wary.observations();
        wary_aims_elsewhere += (0..b)
            .filter(|i| g[i * OBS_DIM..(i + 1) * OBS_DIM] != w[i * OBS_DIM..(i + 1) * OBS_DIM])
            .count();
        let pelvis = plain.pelvis_positions();
        assert_eq!(pelvis, memory.pelvis_positions());
        for i in 0..b {
            let c = plain.course_view(i);
            let (x, y) = (
                &o[i * OBS_DIM..(i + 1) * OBS_DIM],
                &g[i * OBS_DIM..(i + 1) * OBS_DIM],
            );
            let rays = OBS_RAYS_OFFSET..OBS_DIST_OFFSET;
            assert_eq!(
                x[rays.clone()],
                y[rays],
                "step {step}, episode {i}: the rays"
            );
            assert_eq!(x[OBS_DIST_OFFSET..], y[OBS_DIST_OFFSET..], "distance, time");
            let at = pelvis[i].1;
            if line_is_clear(&c.map, c.obstacle.as_slice(), GUIDE_CLEARANCE_M, at, c.goal) {
                assert_eq!(x, y, "step {step}, episode {i}: its goal is in plain view");
            } else if x != y {
                shown_a_way += 1;
            }
        }
        if step == 2 {
            let snap = memory.snapshot();
            let mut twin = PolicyEnv::new(&model, &ctx, &bank, &prior, rooms(true), b, 8).unwrap();
            twin.restore(&snap).unwrap();
            assert_eq!(twin.observations(), memory.observations());
            let mut forgetful =
                PolicyEnv::new(&model, &ctx, &bank, &prior, rooms(false), b, 8).unwrap();
            let err = forgetful.restore(&snap).unwrap_err().to_string();
            assert!(err.contains("memory"), "{err}");
        }
        // Both walk the same primitives: one environment's latents, the other's the same.
        let z = normal_samples(&mut rng, b * l);
        plain.step(&z).unwrap();
        memory.step(&z).unwrap();
        wary.step(&z).unwrap();
    }
    assert!(
        shown_a_way > 0,
        "no walker was shown a way round a wall it saw"
    );
    assert!(
        wary_aims_elsewhere > 0,
        "a cost of unseen ground changed no walker's aim"
    );
}

#[test]
fn floor_plan_episodes_see_walls_time_out_after_13_primitives_and_restore_from_snapshots() {
    env_parts!(body, ctx, model, bank, prior);
    let rooms = EnvSettings {
        ..floor_plans_only()
    };
    let b = 4;
    let mut env = PolicyEnv::new(&model, &ctx, &bank, &prior, rooms, b, 9).unwrap();
    // Every episode walks its own plan, ringed by walls: every ray of the first scans ends
    // within the dwelling (at most 10 m across, so below 7 m for some ray).
    for (i, o) in env.observations().chunks(OBS_DIM).enumerate() {
        let rays = &o[OBS_RAYS_OFFSET..OBS_RAYS_OFFSET + RAYS];
        assert!(rays.iter().all(|r| (-1.0..=1.0).contains(r)));
        assert!(rays.iter().any(|&r| r < 0.99), "episode {i} sees no wall");
    }
    let maps: Vec<_> = (0..b).map(|i| env.course_view(i).map).collect();
    assert!(maps
        .windows(2)
        .any(|w| w[0].walkable != w[1].walkable || w[0].nx != w[1].nx));
    let l = env.latent_dim();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut ended = Vec::new();
    for step in 0..14 {
        if step == 5 {
            let snap = env.snapshot();
            let mut twin = PolicyEnv::new(&model, &ctx, &bank, &prior, rooms, b, 9).unwrap();
            twin.restore(&snap).unwrap();
            assert_eq!(twin.observations(), env.observations());
            let z = normal_samples(&mut ChaCha8Rng::seed_from_u64(2), b * l);
            let rewards = |c: Vec<egogen::policy::env::Candidate>| {
                c.iter().map(|c| c.reward).collect::<Vec<_>>()
            };
            assert_eq!(
                rewards(env.propose(&z, 1).unwrap()),
                rewards(twin.propose(&z, 1).unwrap())
            );
        }
        // Random latents: each episode ends by step 13 at the latest.
        let z = normal_samples(&mut rng, b * l);
        ended.extend(env.step(&z).unwrap().finished);
    }
    assert!(!ended.is_empty());
    for s in &ended {
        if s.ending == Ending::Timeout {
            assert_eq!(s.primitives, 13, "{s:?}");
        }
    }
}

/// Evaluations measure how far each indoor goal lies on foot: the walking distance round walls
/// is at least the straight distance, longer where a wall stands between, and absent in box
/// scenes (their box is not on the map) and unless asked. Asked to, an indoor episode has time
/// for its way round: it times out after as many primitives as the way round needs at the
/// given metres per primitive, never fewer than its own limit.
#[test]
fn floor_plans_measure_the_way_round_walls_and_may_have_time_for_it() {
    env_parts!(body, ctx, model, bank, prior);
    let rooms = EnvSettings {
        ..floor_plans_only()
    };
    let finished = |settings: EnvSettings, measure: bool, steps: usize| {
        let b = 8;
        let mut env = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 9).unwrap();
        if measure {
            env = env.measuring_way_round();
        }
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut ended = Vec::new();
        for _ in 0..steps {
            let z = normal_samples(&mut rng, b * env.latent_dim());
            ended.extend(env.step(&z).unwrap().finished);
        }
        ended
    };
    let measured = finished(rooms, true, 14);
    assert!(measured.len() >= 8);
    let mut behind_a_wall = 0;
    for s in &measured {
        let way = s.way_round_m.unwrap_or_else(|| panic!("{s:?}"));
        assert!(
            way >= s.start_distance_m - 1e-3,
            "{way} < {}",
            s.start_distance_m
        );
        behind_a_wall += usize::from(way > s.start_distance_m + 1.0);
    }
    assert!(
        behind_a_wall > 0,
        "no goal behind a wall in {} plans",
        measured.len()
    );
    assert!(finished(rooms, false, 14)
        .iter()
        .all(|s| s.way_round_m.is_none()));
    let boxes = finished(EnvSettings::default(), true, 12);
    assert!(!boxes.is_empty());
    assert!(boxes.iter().all(|s| s.way_round_m.is_none()));

    // 0.3 m a primitive: a way round longer than 3.9 m is given more than 13 primitives.
    let timed = EnvSettings {
        time_by_way_round_m: 0.3,
        ..rooms
    };
    let mut longer = 0;
    for s in finished(timed, true, 30)
        .iter()
        .filter(|s| s.ending == Ending::Timeout)
    {
        let way = s.way_round_m.unwrap();
        let expected = ((way / 0.3).ceil() as usize).max(13);
        assert_eq!(s.primitives, expected, "{s:?}");
        longer += usize::from(expected > 13);
    }
    assert!(longer > 0);
}

/// `scene_every_frame` in training: floor-plan primitives judged alike but for the swept scene
/// test, which adds exactly those whose body box lies on blocked cells in some frame or whose
/// pelvis passes over a wall — and some that the cells at the primitive's end let through.
#[test]
fn the_scene_tested_in_every_frame_adds_exactly_the_primitives_that_pass_through_walls() {
    let settings = |scene_every_frame: bool| EnvSettings {
        walker: egogen::walker::WalkerSettings {
            scene_every_frame,
            ..floor_plans_only().walker
        },
        ..floor_plans_only()
    };
    let (mut through, mut only_within) = (0, 0);
    judged_in_lockstep((settings(false), settings(true)), (9, 5, 8), |a, e| {
        assert_eq!(a.blocked_cells, e.blocked_cells);
        assert_eq!(a.pelvis_off_floor_frames, e.pelvis_off_floor_frames);
        let swept = e.blocked_cells_swept_max > 3 || e.pelvis_off_floor_frames > 0;
        assert_eq!(e.penetrated, a.penetrated || swept);
        through += usize::from(e.pelvis_off_floor_frames > 0);
        only_within += usize::from(e.penetrated && !a.penetrated);
    });
    assert!(through > 0, "no primitive's pelvis passed over a wall");
    assert!(
        only_within > 0,
        "every primitive through a wall was caught by the cells at its end"
    );
}

/// `no_progress_through_walls`: a primitive that penetrates earns no progress towards its goal,
/// every other term and every clear primitive as before.
#[test]
fn a_primitive_through_a_wall_earns_no_progress_when_asked() {
    let settings = |no_progress_through_walls: bool| EnvSettings {
        walker: egogen::walker::WalkerSettings {
            scene_every_frame: true,
            ..floor_plans_only().walker
        },
        no_progress_through_walls,
        ..floor_plans_only()
    };
    let mut gained_through = 0;
    judged_in_lockstep((settings(false), settings(true)), (9, 5, 8), |a, e| {
        assert_eq!(a.penetrated, e.penetrated);
        let goal = match a.penetrated {
            true => a.terms.goal.min(0.0),
            false => a.terms.goal,
        };
        assert_eq!(e.terms.goal, goal);
        assert_eq!(
            (a.terms.skate, a.terms.attention),
            (e.terms.skate, e.terms.attention)
        );
        gained_through += usize::from(a.penetrated && a.terms.goal > 0.0);
    });
    assert!(gained_through > 0, "no penetrating primitive gained ground");
}

#[test]
fn floor_plans_and_evaluated_walks_are_drawn_and_existing_pictures_kept() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_egogen");
    let root = common::repo_root();
    let dir = tempfile::tempdir().unwrap();
    let plans = dir.path().join("plans.png");
    common::succeeds(
        Command::new(bin)
            .args(["policy", "rooms", "--count", "4", "--out"])
            .arg(&plans),
    );
    // Three tiles of 320 px to a row, two rows.
    assert_eq!(common::png_size(&plans), (960, 640));
    let walks = dir.path().join("walks.png");
    let eval = |png: &std::path::Path| {
        let mut cmd = Command::new(bin);
        cmd.current_dir(&root)
            .args([
                "policy",
                "eval",
                "--rooms-share",
                "1",
                "--episodes",
                "3",
                "--envs",
                "3",
            ])
            .args([
                "--paths",
                "2",
                "--policy",
                "assets/policy/policy.safetensors",
                "--paths-png",
            ])
            .arg(png);
        cmd
    };
    let out = common::succeeds(&mut eval(&walks));
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(report.contains("\"report\""), "{report}");
    assert_eq!(common::png_size(&walks), (640, 320));
    // An existing picture is not overwritten; two controllers cannot share one picture.
    let before = std::fs::read(&walks).unwrap();
    assert!(!eval(&walks).output().unwrap().status.success());
    assert_eq!(std::fs::read(&walks).unwrap(), before);
    let both = eval(&dir.path().join("other.png"))
        .args(["--k", "1"])
        .output()
        .unwrap();
    assert!(!both.status.success());
    assert!(String::from_utf8_lossy(&both.stderr).contains("--paths-png"));
}

#[test]
fn with_an_arrival_radius_walks_go_on_and_are_scored_where_they_end() {
    env_parts!(body, ctx, model, bank, prior);
    let b = 3;
    // Every start lies within 100 m of its goal.
    let scored_at_100m = |arrival_m| EnvSettings {
        walker: egogen::walker::WalkerSettings {
            success_m: 100.0,
            ..egogen::walker::WalkerSettings::PAPER
        },
        arrival_m,
        ..EnvSettings::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut run = |settings: EnvSettings| {
        let mut env = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 11).unwrap();
        let l = env.latent_dim();
        let mut ended = Vec::new();
        for _ in 0..settings.walker.max_primitives_per_goal {
            let z = normal_samples(&mut rng, b * l);
            ended.extend(env.step(&z).unwrap().finished);
        }
        ended.retain(|s| s.id < b as u64);
        ended
    };
    // Without one, a walk ends as soon as it is within the success radius: the first primitive.
    let at_once = run(scored_at_100m(None));
    assert_eq!(at_once.len(), b);
    assert!(at_once
        .iter()
        .all(|s| s.primitives == 1 && matches!(s.ending, Ending::Success)));
    // With one no walk reaches (0 m), each walks all its primitives and, ending within the
    // success radius, succeeds.
    let settings = scored_at_100m(Some(0.0));
    let walked_on = run(settings);
    assert_eq!(walked_on.len(), b);
    assert!(walked_on
        .iter()
        .all(|s| s.primitives == settings.walker.max_primitives_per_goal
            && matches!(s.ending, Ending::Success)));
    // Scored at 0 m instead, the same walks time out.
    let missed = run(EnvSettings {
        walker: egogen::walker::WalkerSettings {
            success_m: 0.0,
            ..settings.walker
        },
        ..settings
    });
    assert!(missed.iter().all(|s| matches!(s.ending, Ending::Timeout)));
}

#[test]
fn paid_along_the_way_round_walls_only_the_goal_terms_change_and_only_indoors() {
    env_parts!(body, ctx, model, bank, prior);
    let b = 8;
    let terms = |settings: EnvSettings, z: &[f32]| {
        let env = PolicyEnv::new(&model, &ctx, &bank, &prior, settings, b, 21).unwrap();
        env.propose(z, 1)
            .unwrap()
            .into_iter()
            .map(|c| c.judged.expect("decoded").terms)
            .collect::<Vec<_>>()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let probe = PolicyEnv::new(&model, &ctx, &bank, &prior, EnvSettings::default(), b, 21).unwrap();
    let z = normal_samples(&mut rng, b * probe.latent_dim());
    // Box scenes: the setting changes nothing.
    let by_path = |s: EnvSettings| EnvSettings {
        goal_by_path: true,
        ..s
    };
    let boxes = EnvSettings::default();
    assert_eq!(terms(boxes, &z), terms(by_path(boxes), &z));
    // Floor plans: the goal's terms move, every other term stays.
    let rooms = EnvSettings {
        ..floor_plans_only()
    };
    let (straight, along) = (terms(rooms, &z), terms(by_path(rooms), &z));
    let mut moved = 0;
    for (s, a) in straight.iter().zip(&along) {
        assert_eq!(
            (s.floor, s.skate, s.penetration, s.pose, s.success),
            (a.floor, a.skate, a.penetration, a.pose, a.success)
        );
        assert!(a.goal.is_finite() && (0.0..=1.0).contains(&a.orientation));
        moved += usize::from(s.goal != a.goal);
    }
    assert!(moved > 0, "no floor plan's goal term changed");
    // A restored environment pays the same (the field is rebuilt from the plan).
    let mut env = PolicyEnv::new(&model, &ctx, &bank, &prior, by_path(rooms), b, 21).unwrap();
    env.step(&z).unwrap();
    let mut twin = PolicyEnv::new(&model, &ctx, &bank, &prior, by_path(rooms), b, 21).unwrap();
    twin.restore(&env.snapshot()).unwrap();
    let rewards =
        |c: Vec<egogen::policy::env::Candidate>| c.iter().map(|c| c.reward).collect::<Vec<_>>();
    assert_eq!(
        rewards(env.propose(&z, 1).unwrap()),
        rewards(twin.propose(&z, 1).unwrap())
    );
}

/// One walker: the same seed, start, goal and policy give the same primitives through `egogen
/// policy eval`'s environment (the f32 actor's mean actions stepping a [`PolicyEnv`], as
/// `eval::policy_tasks` does) and through a take's agent (`synth::crowd::run_crowd`, steered
/// by the policy's mean action), frame for frame, bit for bit: both choose by the one step
/// (`walker::step::choose_primitive`).
#[test]
fn policy_eval_and_a_takes_agent_walk_the_same_primitives() {
    walk_both(egogen::walker::ControllerSpec::Policy {
        mean_action: true,
        spread: 1.0,
    });
}

/// The sampling controller of `egogen policy eval` is the walker layer's, the one a take's
/// person steps with (`walker::controller`): from the same generator state (a take's walker
/// draws its seed pose first) both walk the same primitives, bit for bit.
#[test]
fn policy_eval_and_a_takes_agent_sample_the_same_primitives() {
    walk_both(egogen::walker::ControllerSpec::Sampling { k: 4 });
}

/// Walks one walker steered by `steering` through `egogen policy eval`'s environment and
/// through a take, and compares every primitive's seed frames.
fn walk_both(steering: egogen::walker::ControllerSpec) {
    use egogen::policy::env::FixedScene;
    use egogen::scene::generated::crossing_scene::{CrossingScene, CrossingSettings};
    use egogen::scene::StartGoal;
    use egogen::synth::crowd::{run_crowd, AgentPlan, CrowdParts, CrowdSettings, CrowdWorld};
    use egogen::walker::ControllerSpec;
    use std::sync::Arc;

    env_parts!(body, ctx, model, bank, prior);
    // One seed: both walkers start from it.
    let bank = SeedBank {
        seeds: vec![bank.seeds[1].clone()],
    };
    let actor = egogen::policy::Actor::of(
        &egogen::policy::weights::load_policy_for(
            &common::repo_root().join("assets/policy/policy.safetensors"),
            &model,
        )
        .unwrap(),
    );
    let map = Arc::new(CrossingScene::floor(&CrossingSettings::default()));
    let (start, goal) = (DVec2::new(-1.5, 0.3), DVec2::new(2.5, -0.4));
    const PRIMITIVES: usize = 6;
    const PER_GOAL: usize = 20;

    // `egogen policy eval`: a fixed scene of one pair, facing the goal.
    let fixed = FixedScene {
        map: map.clone(),
        pairs: vec![StartGoal { start, goal }],
        sdf: None,
    };
    let settings = EnvSettings {
        seed_yaw_jitter_rad: 0.0,
        walker: egogen::walker::WalkerSettings {
            max_primitives_per_goal: PER_GOAL,
            success_m: 0.1,
            ..egogen::walker::WalkerSettings::PAPER
        },
        ..EnvSettings::default()
    };
    let mut env = PolicyEnv::with_scene(&model, &ctx, &bank, &prior, Some(&fixed), settings, 1, 7)
        .unwrap()
        .with_sensing(&actor.sensing());
    let mut eval_seeds = Vec::new();
    // The take's walker 0 of seed 0 draws its seed pose (of a bank of one), then proposes.
    let mut rng = egogen::walker::controller::walker_rng(0, 0);
    rand_core::Rng::next_u64(&mut rng);
    for _ in 0..PRIMITIVES {
        let out = match steering {
            ControllerSpec::Policy { .. } => {
                let a = actor.actions_with_spread(&env.observations(), None, 1.0);
                env.step(&a).unwrap()
            }
            spec => egogen::policy::sampling::controller_step(&mut env, spec, &mut rng).unwrap(),
        };
        assert!(!out.done[0], "the walk ends before the comparison does");
        eval_seeds.push(env.snapshot().episodes[0].clone());
    }

    // A take: one agent, the same start, goal and time per goal.
    let parts = CrowdParts {
        model: &model,
        body_model: &body,
        prior: &prior,
        bank: &bank,
        policy: Some(&actor),
    };
    let world = CrowdWorld {
        map,
        region: None,
        obstacles: vec![],
        moving: vec![],
    };
    let plan = AgentPlan {
        name: "walker".into(),
        betas: vec![],
        start,
        facing_rad: None,
        goals: vec![goal],
        wander: false,
        steering,
    };
    let crowd = CrowdSettings {
        walker: egogen::walker::WalkerSettings {
            success_m: 0.1,
            max_primitives_per_goal: PER_GOAL,
            // The frames as decoded: the take's finishing (joins smoothed, head steadied)
            // changes what is written, not which primitives are walked.
            smooth_joins: false,
            steady_head: false,
            finger_motion: false,
            // The proposals as they are, as `policy eval` takes them.
            penetration_redraws: 0,
            ..Default::default()
        },
        primitives: PRIMITIVES,
        ..CrowdSettings::default()
    };
    let take = run_crowd(&parts, &world, &[plan], &crowd, |_, _| {}).unwrap();
    let track = &take.agents[0];
    assert_eq!(track.primitives, PRIMITIVES);
    assert_eq!(track.held_primitives, 0);
    for (k, snap) in eval_seeds.iter().enumerate() {
        // The seed of the next primitive: the last two frames of primitive k.
        let end = 2 + 18 * (k + 1);
        for (f, frame) in track.frames[end - 2..end].iter().enumerate() {
            let from_eval = &snap.seed_frames()[f];
            let from_take: Vec<f64> = frame
                .pose
                .iter()
                .copied()
                .chain(frame.transl.to_array())
                .collect();
            assert_eq!(*from_eval, from_take, "primitive {k}, seed frame {f}");
        }
    }
}
