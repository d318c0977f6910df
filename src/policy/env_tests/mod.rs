//! The locomotion environment: box scenes put the box between start and goal; episodes are
//! deterministic per episode base and differ between bases; observations have EgoGen's layout
//! and ranges; episodes end by timeout after 11 primitives and restart; the best of K
//! candidates never scores below the first; the pose prior tells mocap from bent joints and
//! refuses broken files with their path.

use crate::motion::cvae::train::normal_samples;
use crate::motion::cvae::PrimitiveSeed;
use crate::policy::env::Ending;
use crate::policy::sampling::sampling_step;
use crate::policy::{EnvSettings, PolicyEnv};
use crate::scene::generated::box_scene::{BoxScene, BoxSceneSettings};
use crate::walker::pose_prior::{prior_values, PosePrior, PRIOR_DIM};
use crate::walker::reward::Judged;
use crate::walker::ObsLayout;
use crate::walker::STATE_FRAME_DIM;

/// The paper's observation layout (32 rays), which environments use unless told otherwise.
const LAYOUT: ObsLayout = ObsLayout::PAPER;
const OBS_DIM: usize = LAYOUT.dim();
const RAYS: usize = LAYOUT.sensing_per_frame;
const OBS_RAYS_OFFSET: usize = LAYOUT.sensing_offset();
const OBS_DIST_OFFSET: usize = LAYOUT.dist_offset();
use crate::scene::Obstacle2;
use glam::DVec2;
use proptest::prelude::*;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

pub(crate) fn clip() -> crate::motion::MotionSequence {
    crate::motion::MotionSequence::read(
        &crate::paths::crate_root().join("assets/motion/cmu_01_03.npz"),
    )
    .unwrap()
}

pub(crate) fn seeds() -> Vec<PrimitiveSeed> {
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
pub(crate) fn clip_prior() -> PosePrior {
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
        let $body = crate::body::BodyModel::load(
            crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap();
        let $ctx = crate::motion::cvae::BodyContext::new(&$body, &[]).unwrap();
        let $model = crate::motion::cvae::MotionModel::load(
            crate::motion::cvae::train::shipped_weights_path(),
        )
        .unwrap();
        let $bank =
            crate::walker::SeedBank::from_world_seeds(&$ctx, &crate::policy::env_tests::seeds())
                .unwrap();
        let $prior = crate::policy::env_tests::clip_prior();
    };
}
pub(crate) use env_parts;

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
    let lm = crate::sensing::SensingSpec::centred_map(0.8, 16);
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
            aa + crate::math::Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
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
    use crate::policy::env::FixedScene;
    use crate::scene::{StartGoal, WalkableMap};
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
    use crate::policy::env::{EnvParts, FixedScene};
    use crate::scene::{StartGoal, WalkableMap};
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
    use crate::policy::env::FixedScene;
    use crate::scene::{SceneMesh, SceneSdf, StartGoal, WalkableMap};
    use crate::walker::reward::EQ11_VERTICES;
    env_parts!(body, ctx, model, bank, prior);
    // An open floor (the map sees nothing) with a closed 1.6 × 1.6 × 2 m pillar over the first
    // pair's start, which only the 3D SDF knows of; the second pair starts 4 m from it.
    let n = 100;
    let map = WalkableMap::from_walkable(DVec2::splat(-5.0), 0.1, n, n, vec![true; n * n]);
    let mut mesh = SceneMesh::default();
    mesh.add_box(
        "pillar",
        crate::math::Vec3::new(-2.8, -2.8, 0.0),
        crate::math::Vec3::new(-1.2, -1.2, 2.0),
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
    let test = crate::walker::reward::SceneTest::new(&body, 1024);
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
    use crate::policy::env::FixedScene;
    use crate::scene::{StartGoal, WalkableMap};
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
    let scaled = |f: f64| crate::walker::reward::WeightChanges {
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
    use crate::scene::generated::crossing_scene::CrossingSettings;
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
            let rewards = |c: &[crate::policy::env::Candidate]| {
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

mod walls;
