//! Fixed scenes of training and evaluation: a scene file loaded with its walkable map as people
//! walk it (inside the walls when asked), its start/goal pairs drawn, and its 3D SDF where
//! scene penetration (paper Eq. 11) is measured.

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::env::FixedScene;
use super::ppo::TrainScene;

/// A scene for evaluation (its file read as `frame` says): `pairs` start/goal pairs
/// `pair_distance_m` apart — straight, or with `on_foot` on foot round walls — 0.4 m from
/// anything blocking, drawn under `seed` with another stream than training's pairs, its 3D SDF
/// built with `sdf_voxel_m` voxels so that paper Eq. 11 is measured.
#[allow(clippy::too_many_arguments)]
pub(crate) fn held_out_scene(
    path: &Path,
    frame: crate::scene::SceneFrame,
    pairs: usize,
    pair_distance_m: (f64, f64),
    on_foot: bool,
    indoors: bool,
    seed: u64,
    sdf_voxel_m: f64,
) -> Result<FixedScene> {
    scene_with_pairs(
        &TrainScene {
            path: path.into(),
            frame,
            pairs,
            pair_distance_m,
            clearance_m: 0.4,
            indoors,
            seed: seed ^ 0x5CE7E,
        },
        Some(sdf_voxel_m),
        on_foot,
    )
}

/// A fixed scene loaded, with its start/goal pairs drawn as `spec` says (with `spec.indoors`,
/// when the scene encloses anything: inside the walls, on a map whose ground around them is
/// blocked); too few pairs is an error. With
/// `sdf_voxel_m` its 3D SDF is built too with voxels that size (`docs/SCENES.md`), so that
/// scene penetration (paper Eq. 11) is measured.
pub(crate) fn fixed_scene(spec: &TrainScene, sdf_voxel_m: Option<f64>) -> Result<FixedScene> {
    scene_with_pairs(spec, sdf_voxel_m, false)
}

/// [`fixed_scene`], its pairs' distance range taken on foot round walls with `on_foot`.
fn scene_with_pairs(
    spec: &TrainScene,
    sdf_voxel_m: Option<f64>,
    on_foot: bool,
) -> Result<FixedScene> {
    let path = &spec.path;
    let mesh = crate::scene::load_scene(path, spec.frame)?;
    let (map, region) = crate::scene::indoor_map(
        crate::scene::walkable_map(&mesh, path, Default::default())?,
        spec.indoors,
    );
    let (lo, hi) = spec.pair_distance_m;
    let pairs = scene_pairs(
        &map,
        region.as_deref(),
        spec.pairs,
        lo,
        hi,
        spec.clearance_m,
        spec.seed,
        on_foot,
    );
    if pairs.len() < spec.pairs {
        bail!(
            "{}: only {} start/goal pairs {lo}–{hi} m apart{} with {} m clearance{} (asked for {})",
            path.display(),
            pairs.len(),
            if on_foot { " on foot" } else { "" },
            spec.clearance_m,
            if region.is_some() {
                " inside the walls"
            } else {
                ""
            },
            spec.pairs
        );
    }
    let sdf = if let Some(voxel_m) = sdf_voxel_m {
        let sdf = crate::scene::SceneSdf::build(&mesh, voxel_m, crate::scene::sdf3d::MARGIN_M)
            .with_context(|| format!("{}: no triangles to build a 3D SDF from", path.display()))?;
        Some(std::sync::Arc::new(sdf))
    } else {
        None
    };
    Ok(FixedScene {
        map: std::sync::Arc::new(map),
        pairs,
        sdf,
    })
}

/// Start/goal pairs of a fixed scene for evaluation: `count` pairs between `min_m` and
/// `max_m` apart — horizontally, or with `on_foot` by the walking distance round what blocks
/// walking (`scene::PathField`, the way round an evaluation reports) — at least `clearance_m`
/// from anything blocking, on the cells of `region` when given, drawn with `seed`. Straight
/// pairs are as they always were; pairs on foot are drawn from the same stream (a walk is never
/// shorter than the straight line, so the straight minimum still applies), each kept when its
/// way round lies in the range.
#[allow(clippy::too_many_arguments)]
pub(crate) fn scene_pairs(
    map: &crate::scene::WalkableMap,
    region: Option<&[bool]>,
    count: usize,
    min_m: f64,
    max_m: f64,
    clearance_m: f64,
    seed: u64,
    on_foot: bool,
) -> Vec<crate::scene::StartGoal> {
    if !on_foot {
        return crate::scene::sample_start_goals_in(
            map,
            region,
            seed,
            count * 8,
            clearance_m,
            min_m,
        )
        .into_iter()
        .filter(|p| p.start.distance(p.goal) <= max_m)
        .take(count)
        .collect();
    }
    let within = |p: &crate::scene::StartGoal| {
        crate::scene::PathField::to_goal(map, p.goal)
            .and_then(|f| f.at(p.start))
            .is_some_and(|d| (min_m..=max_m).contains(&d))
    };
    crate::scene::sample_start_goals_in(map, region, seed, count * 32, clearance_m, 0.0)
        .into_iter()
        .filter(|p| p.start.distance(p.goal) <= max_m && within(p))
        .take(count)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    /// Pairs on foot in a room split by a wall with a doorway at one end: every kept pair's
    /// way round lies in the range, never shorter than its straight line, some of them behind
    /// the wall (a straight line shorter than the walk by more than 0.5 m); a straight range of
    /// the same metres lets in walks beyond it.
    #[test]
    fn pairs_on_foot_keep_the_way_round_in_range() {
        let (nx, ny) = (80, 40);
        // An 8 × 4 m room, a wall at x = 4 m with a 1 m doorway at its top (y 3–4 m).
        let walkable = (0..nx * ny)
            .map(|k| {
                let (i, j) = (k % nx, k / nx);
                !((39..41).contains(&i) && j < 30)
            })
            .collect();
        let map = crate::scene::WalkableMap::from_walkable(DVec2::ZERO, 0.1, nx, ny, walkable);
        let (lo, hi) = (4.0, 6.0);
        let pairs = scene_pairs(&map, None, 40, lo, hi, 0.3, 7, true);
        assert_eq!(pairs.len(), 40);
        let mut behind_the_wall = 0;
        for p in &pairs {
            let way = crate::scene::PathField::to_goal(&map, p.goal)
                .and_then(|f| f.at(p.start))
                .unwrap();
            assert!((lo..=hi).contains(&way), "way round {way} m");
            let straight = p.start.distance(p.goal);
            assert!(
                straight <= way + 1e-9,
                "{p:?}: {straight} m straight, {way} m on foot"
            );
            if (p.start.x < 4.0) != (p.goal.x < 4.0) && straight < way - 0.5 {
                behind_the_wall += 1;
            }
        }
        assert!(behind_the_wall > 0, "no pair behind the wall");
        // Straight pairs in the same range include walks beyond it.
        let straight = scene_pairs(&map, None, 40, lo, hi, 0.3, 7, false);
        assert!(straight.iter().any(|p| {
            crate::scene::PathField::to_goal(&map, p.goal)
                .and_then(|f| f.at(p.start))
                .unwrap()
                > hi
        }));
    }
}
