//! Where a crowd's people start and what they walk to: points drawn on the walkable map.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;

use crate::math::random::uniform_open01;
use crate::scene::WalkableMap;

/// Whether cell `k` may hold a drawn start or goal: walkable, in the region, with
/// `clearance_m` of free space.
fn drawable(map: &WalkableMap, region: Option<&[bool]>, clearance_m: f64, k: usize) -> bool {
    map.walkable[k] && map.sdf_m[k] >= clearance_m && region.is_none_or(|r| r[k])
}

/// A point on the walkable map (in `region` when given) with `clearance_m` of free space,
/// uniform over such cells.
pub fn sample_point(
    map: &WalkableMap,
    region: Option<&[bool]>,
    clearance_m: f64,
    rng: &mut ChaCha8Rng,
) -> Option<DVec2> {
    let cells: Vec<usize> = (0..map.nx * map.ny)
        .filter(|&k| drawable(map, region, clearance_m, k))
        .collect();
    if cells.is_empty() {
        return None;
    }
    let k = cells[(rng.next_u64() % cells.len() as u64) as usize];
    Some(map.centre(k % map.nx, k / map.nx))
}

/// A goal on the walkable map, in the same connected region as `from`, `distance_m` away,
/// with `clearance_m` of free space; `None` when the map has none after many draws.
pub(crate) fn sample_goal(
    map: &WalkableMap,
    region: Option<&[bool]>,
    from: DVec2,
    distance_m: (f64, f64),
    clearance_m: f64,
    rng: &mut ChaCha8Rng,
) -> Option<DVec2> {
    let component = map
        .cell_of(from)
        .map(|(i, j)| map.component[j * map.nx + i])
        .unwrap_or(0);
    for _ in 0..2000 {
        let d = distance_m.0 + (distance_m.1 - distance_m.0) * uniform_open01(rng);
        let a = std::f64::consts::TAU * uniform_open01(rng);
        let p = from + DVec2::from_angle(a) * d;
        let Some((i, j)) = map.cell_of(p) else {
            continue;
        };
        let k = j * map.nx + i;
        if drawable(map, region, clearance_m, k)
            && (component == 0 || map.component[k] == component)
        {
            return Some(p);
        }
    }
    None
}
