//! The environment's walls, guides and crossings: what `super` sets up, tested where walls
//! and people are (every-frame tests, the guide, the way round, progress through walls).

use super::*;

/// Settings whose every episode walks a floor plan of its own.
fn floor_plans_only() -> EnvSettings {
    EnvSettings {
        rooms: crate::scene::generated::room_scene::RoomSettings {
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
    use crate::scene::generated::crossing_scene::CrossingSettings;
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
    use crate::scene::generated::crossing_scene::CrossingSettings;
    env_parts!(body, ctx, model, bank, prior);
    let settings = |ahead: bool, speed_m_s: (f64, f64)| EnvSettings {
        crossing: CrossingSettings {
            share: 1.0,
            people: (2, 3),
            speed_m_s,
            ..CrossingSettings::default()
        },
        walker: crate::walker::WalkerSettings {
            anticipate_people: ahead,
            ..crate::walker::WalkerSettings::PAPER
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
            let rewards = |c: Vec<crate::policy::env::Candidate>| {
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
    use crate::scene::path_plan::line_is_clear;
    use crate::scene::path_plan::GUIDE_CLEARANCE_M;
    env_parts!(body, ctx, model, bank, prior);
    let rooms = |guide_lookahead_m: f64| EnvSettings {
        walker: crate::walker::WalkerSettings {
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
    use crate::scene::path_plan::line_is_clear;
    use crate::scene::path_plan::GUIDE_CLEARANCE_M;
    env_parts!(body, ctx, model, bank, prior);
    let rooms = |guide_memory: bool| EnvSettings {
        walker: crate::walker::WalkerSettings {
            guide_lookahead_m: 2.0,
            guide_memory,
            ..floor_plans_only().walker
        },
        ..floor_plans_only()
    };
    let plain_settings = EnvSettings {
        walker: crate::walker::WalkerSettings {
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
        walker: crate::walker::WalkerSettings {
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
            let rewards = |c: Vec<crate::policy::env::Candidate>| {
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
        walker: crate::walker::WalkerSettings {
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
        walker: crate::walker::WalkerSettings {
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
fn with_an_arrival_radius_walks_go_on_and_are_scored_where_they_end() {
    env_parts!(body, ctx, model, bank, prior);
    let b = 3;
    // Every start lies within 100 m of its goal.
    let scored_at_100m = |arrival_m| EnvSettings {
        walker: crate::walker::WalkerSettings {
            success_m: 100.0,
            ..crate::walker::WalkerSettings::PAPER
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
        walker: crate::walker::WalkerSettings {
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
        |c: Vec<crate::policy::env::Candidate>| c.iter().map(|c| c.reward).collect::<Vec<_>>();
    assert_eq!(
        rewards(env.propose(&z, 1).unwrap()),
        rewards(twin.propose(&z, 1).unwrap())
    );
}
