//! Fixed scenes of training and evaluation: a scene file loaded with its walkable map as people
//! walk it (inside the walls when asked), its start/goal pairs drawn, and its 3D SDF where
//! scene penetration (paper Eq. 11) is measured.

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::env::FixedScene;
use super::ppo::TrainScene;

/// A scene for evaluation: `pairs` start/goal pairs `pair_distance_m` apart, 0.4 m from
/// anything blocking, drawn under `seed` with another stream than training's pairs, its 3D SDF
/// built with `sdf_voxel_m` voxels so that paper Eq. 11 is measured.
pub(crate) fn held_out_scene(
    path: &Path,
    pairs: usize,
    pair_distance_m: (f64, f64),
    indoors: bool,
    seed: u64,
    sdf_voxel_m: f64,
) -> Result<FixedScene> {
    fixed_scene(
        &TrainScene {
            path: path.into(),
            pairs,
            pair_distance_m,
            clearance_m: 0.4,
            indoors,
            seed: seed ^ 0x5CE7E,
        },
        Some(sdf_voxel_m),
    )
}

/// A fixed scene loaded, with its start/goal pairs drawn as `spec` says (with `spec.indoors`,
/// when the scene encloses anything: inside the walls, on a map whose ground around them is
/// blocked); too few pairs is an error. With
/// `sdf_voxel_m` its 3D SDF is built too with voxels that size (`docs/SCENES.md`), so that
/// scene penetration (paper Eq. 11) is measured.
pub(crate) fn fixed_scene(spec: &TrainScene, sdf_voxel_m: Option<f64>) -> Result<FixedScene> {
    let path = &spec.path;
    let mesh = crate::scene::load_scene(path, None)?;
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
    );
    if pairs.len() < spec.pairs {
        bail!(
            "{}: only {} start/goal pairs {lo}–{hi} m apart with {} m clearance{} (asked for {})",
            path.display(),
            pairs.len(),
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
/// `max_m` apart (horizontal), at least `clearance_m` from anything blocking, on the cells of
/// `region` when given, drawn with `seed`.
pub(crate) fn scene_pairs(
    map: &crate::scene::WalkableMap,
    region: Option<&[bool]>,
    count: usize,
    min_m: f64,
    max_m: f64,
    clearance_m: f64,
    seed: u64,
) -> Vec<crate::scene::StartGoal> {
    crate::scene::sample_start_goals_in(map, region, seed, count * 8, clearance_m, min_m)
        .into_iter()
        .filter(|p| p.start.distance(p.goal) <= max_m)
        .take(count)
        .collect()
}
