//! One walker, two callers: the same seed, start, goal and controller give the same primitives
//! through `egogen policy eval`'s environment and through a take's agent (the environment's
//! parts from `policy::env_tests`).

use crate::policy::env_tests::env_parts;
use crate::policy::{EnvSettings, PolicyEnv};
use crate::walker::SeedBank;
use glam::DVec2;

/// One walker: the same seed, start, goal and policy give the same primitives through `egogen
/// policy eval`'s environment (the f32 actor's mean actions stepping a [`PolicyEnv`], as
/// `eval::policy_tasks` does) and through a take's agent (`synth::crowd::run_crowd`, steered
/// by the policy's mean action), frame for frame, bit for bit: both choose by the one step
/// (`walker::step::choose_primitive`).
#[test]
fn policy_eval_and_a_takes_agent_walk_the_same_primitives() {
    walk_both(crate::walker::ControllerSpec::Policy {
        mean_action: true,
        spread: 1.0,
    });
}

/// The sampling controller of `egogen policy eval` is the walker layer's, the one a take's
/// person steps with (`walker::controller`): from the same generator state (a take's walker
/// draws its seed pose first) both walk the same primitives, bit for bit.
#[test]
fn policy_eval_and_a_takes_agent_sample_the_same_primitives() {
    walk_both(crate::walker::ControllerSpec::Sampling { k: 4 });
}

/// Walks one walker steered by `steering` through `egogen policy eval`'s environment and
/// through a take, and compares every primitive's seed frames.
fn walk_both(steering: crate::walker::ControllerSpec) {
    use crate::policy::env::FixedScene;
    use crate::scene::generated::crossing_scene::{CrossingScene, CrossingSettings};
    use crate::scene::StartGoal;
    use crate::synth::crowd::{run_crowd, AgentPlan, CrowdParts, CrowdSettings, CrowdWorld};
    use crate::walker::ControllerSpec;
    use std::sync::Arc;

    env_parts!(body, ctx, model, bank, prior);
    // One seed: both walkers start from it.
    let bank = SeedBank {
        seeds: vec![bank.seeds[1].clone()],
    };
    let actor = crate::policy::Actor::of(
        &crate::policy::weights::load_policy_for(
            &crate::paths::crate_root().join("assets/policy/policy.safetensors"),
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
        walker: crate::walker::WalkerSettings {
            max_primitives_per_goal: PER_GOAL,
            success_m: 0.1,
            ..crate::walker::WalkerSettings::PAPER
        },
        ..EnvSettings::default()
    };
    let mut env = PolicyEnv::with_scene(&model, &ctx, &bank, &prior, Some(&fixed), settings, 1, 7)
        .unwrap()
        .with_sensing(&actor.sensing());
    let mut eval_seeds = Vec::new();
    // The take's walker 0 of seed 0 draws its seed pose (of a bank of one), then proposes.
    let mut rng = crate::walker::controller::walker_rng(0, 0);
    rand_core::Rng::next_u64(&mut rng);
    for _ in 0..PRIMITIVES {
        let out = match steering {
            ControllerSpec::Policy { .. } => {
                let a = actor.actions_with_spread(&env.observations(), None, 1.0);
                env.step(&a).unwrap()
            }
            spec => crate::policy::sampling::controller_step(&mut env, spec, &mut rng).unwrap(),
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
        walker: crate::walker::WalkerSettings {
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
