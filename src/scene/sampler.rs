//! Seeded start/goal sampling on walkable, connected cells with a clearance margin.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};

use super::walkable::WalkableMap;

/// A start and a goal in the same connected walkable region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartGoal {
    pub start: DVec2,
    pub goal: DVec2,
}

/// Samples `count` start/goal pairs (cell centres) with at least `clearance_m` to any
/// non-walkable cell and at least `min_distance_m` apart; fewer if the map cannot hold them.
pub fn sample_start_goals(
    map: &WalkableMap,
    seed: u64,
    count: usize,
    clearance_m: f64,
    min_distance_m: f64,
) -> Vec<StartGoal> {
    sample_start_goals_in(map, None, seed, count, clearance_m, min_distance_m)
}

/// The same with starts and goals only on the cells of `region` (one flag per cell, e.g.
/// [`WalkableMap::indoor_cells`]) when given.
pub(crate) fn sample_start_goals_in(
    map: &WalkableMap,
    region: Option<&[bool]>,
    seed: u64,
    count: usize,
    clearance_m: f64,
    min_distance_m: f64,
) -> Vec<StartGoal> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let candidates: Vec<usize> = (0..map.nx * map.ny)
        .filter(|&k| map.walkable[k] && map.sdf_m[k] >= clearance_m && region.is_none_or(|r| r[k]))
        .collect();
    let mut out = Vec::new();
    if candidates.is_empty() {
        return out;
    }
    let pick =
        |rng: &mut ChaCha8Rng| candidates[(rng.next_u64() % candidates.len() as u64) as usize];
    let centre = |k: usize| map.centre(k % map.nx, k / map.nx);
    for _ in 0..count * 100 {
        if out.len() == count {
            break;
        }
        let (s, g) = (pick(&mut rng), pick(&mut rng));
        if map.component[s] == map.component[g] && centre(s).distance(centre(g)) >= min_distance_m {
            out.push(StartGoal {
                start: centre(s),
                goal: centre(g),
            });
        }
    }
    out
}
