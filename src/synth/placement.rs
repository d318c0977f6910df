//! Placing a motion in a scene: a seeded start on the walkable map and a heading along which
//! the motion's path stays clear of obstacles, applied as one rigid move of the whole motion.

use crate::body::{BodyModel, PoseError};
use crate::math::{Affine3, Mat3, Vec3};
use crate::motion::MotionSequence;
use crate::scene::{sample_start_goals, WalkableMap};

/// Distance kept from obstacles along the path (m).
pub(crate) const PATH_CLEARANCE_M: f64 = 0.35;
/// Free floor required beyond the path's end along the heading (m), so that head cameras look
/// into the room rather than at a wall or out of a window.
pub(crate) const LOOK_AHEAD_M: f64 = 2.0;

/// Why no placement was found.
#[derive(Debug, thiserror::Error)]
pub(crate) enum PlacementError {
    #[error("no straight path of {length_m:.2} m with {clearance_m} m clearance found in the scene's walkable area (tried {tried} starts × 32 headings); use a shorter motion or another scene")]
    NoRoom {
        length_m: f64,
        clearance_m: f64,
        tried: usize,
    },
    #[error(transparent)]
    Pose(#[from] PoseError),
}

/// Moves `motion` so that its pelvis path (floor projection) starts at a seeded free spot and
/// keeps `PATH_CLEARANCE_M` from obstacles, inside the largest connected walkable region, and
/// raises each frame from the motion's floor (z = 0) to the map's floor under its pelvis
/// ([`WalkableMap::floor_under`]: an upper storey, stepped floors). Returns the moved motion
/// and the horizontal move.
pub(crate) fn place_motion(
    model: &BodyModel,
    motion: &MotionSequence,
    map: &WalkableMap,
    seed: u64,
) -> Result<(MotionSequence, Affine3), PlacementError> {
    let rest_pelvis = model.rest_joints(&motion.betas, &[])?[0];
    // Pelvis floor path relative to the first frame's pelvis.
    let path: Vec<Vec3> = motion
        .trans
        .iter()
        .map(|t| {
            let d = *t - motion.trans[0];
            Vec3::new(d.x, d.y, 0.0)
        })
        .collect();
    let length_m = path.iter().map(|p| p.length()).fold(0.0, f64::max);
    // The largest connected walkable region: scenes often have slivers of floor outside.
    let mut sizes = std::collections::BTreeMap::<u32, usize>::new();
    for &c in map.component.iter().filter(|&&c| c > 0) {
        *sizes.entry(c).or_default() += 1;
    }
    let largest = sizes
        .iter()
        .max_by_key(|(c, n)| (**n, std::cmp::Reverse(**c)))
        .map(|(c, _)| *c);
    // Walking direction: the path's overall displacement (x if it hardly moves).
    let heading = match path.last().unwrap().length() {
        l if l > 0.1 => *path.last().unwrap() / l,
        _ => Vec3::X,
    };
    let starts: Vec<_> = sample_start_goals(map, seed, 256, PATH_CLEARANCE_M, 0.0)
        .into_iter()
        .filter(|s| {
            map.cell_of(s.start)
                .map(|(i, j)| map.component[j * map.nx + i])
                == largest
        })
        .collect();
    for start in &starts {
        for k in 0..32 {
            let yaw = k as f64 / 32.0 * std::f64::consts::TAU;
            let rot = Mat3::from_rotation_z(yaw);
            let target = Vec3::new(start.start.x, start.start.y, 0.0);
            let end = rot * *path.last().unwrap();
            let ahead = rot * heading;
            let clear = path
                .iter()
                .map(|p| rot * *p)
                .chain((1..=20).map(|k| end + ahead * (LOOK_AHEAD_M * k as f64 / 20.0)))
                .all(|q| {
                    let q = target + q;
                    map.sdf_at(glam::DVec2::new(q.x, q.y)) >= PATH_CLEARANCE_M
                });
            if !clear {
                continue;
            }
            let p0 = rest_pelvis + motion.trans[0];
            // new = target + R (old − p0_floor)
            let p0_floor = Vec3::new(p0.x, p0.y, 0.0);
            let new_from_old = Affine3 {
                matrix3: rot,
                translation: target - rot * p0_floor,
            };
            let mut moved = motion.clone();
            for i in 0..motion.len() {
                let params = motion.frame(i).moved_rigidly(new_from_old, rest_pelvis);
                let pelvis = target + rot * path[i];
                moved.poses[i] = params.pose;
                moved.trans[i] =
                    params.transl + Vec3::Z * map.floor_under(glam::DVec2::new(pelvis.x, pelvis.y));
            }
            return Ok((moved, new_from_old));
        }
    }
    Err(PlacementError::NoRoom {
        length_m,
        clearance_m: PATH_CLEARANCE_M,
        tried: starts.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk placed on a floor at z = 1.3 m (an upper storey, a scan's own height) stands
    /// 1.3 m higher at every frame than the same walk placed on a floor at z = 0.
    #[test]
    fn a_placed_walk_stands_on_the_scenes_floor() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let model = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
        let shaped = model.shape(&[], &[]).unwrap();
        let walk = crate::motion::scripted::WalkCycle::default().sequence(
            1.0,
            40.0,
            &[],
            shaped.rest_joints[0],
            shaped.rest_sole_y(),
        );
        let placed = |floor_z: f64| {
            let mut scene = crate::scene::SceneMesh::default();
            scene.add_box(
                "slab",
                Vec3::new(-6.0, -6.0, floor_z - 0.1),
                Vec3::new(6.0, 6.0, floor_z),
            );
            let map = WalkableMap::build(&scene, Default::default()).unwrap();
            place_motion(&model, &walk, &map, 0).unwrap().0
        };
        let (ground, upper) = (placed(0.0), placed(1.3));
        for (a, b) in ground.trans.iter().zip(&upper.trans) {
            assert!((b.z - a.z - 1.3).abs() < 1e-9, "{} against {}", b.z, a.z);
            assert!((b.x - a.x).abs() < 1e-9 && (b.y - a.y).abs() < 1e-9);
        }
    }
}
