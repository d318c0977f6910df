//! Body markers: a fixed set of surface vertices the motion loop tracks instead of the mesh.
//!
//! EgoGen's motion model sees 67 markers (the SSM2 set of GAMMA on SMPL-X's topology). Those
//! vertex ids do not exist on other topologies, so egogen picks markers on any model by
//! farthest-point sampling of the rest template (Euclidean, seeded at the vertex nearest the
//! pelvis joint): deterministic, spread over the whole surface, and cheap to recompute.

use super::lbs::{PoseError, PosedSkeleton, ShapedBody};
use super::model::BodyModel;
use super::skeleton::POSE_DIM;
use crate::math::{Real, Vec3};

/// Number of markers the motion model uses (paper).
pub const NUM_MARKERS: usize = 67;

/// `count` marker vertex ids by farthest-point sampling of the rest template.
pub fn farthest_point_markers(model: &BodyModel, count: usize) -> Vec<u32> {
    let verts = &model.v_template;
    if verts.is_empty() || count == 0 {
        return Vec::new();
    }
    let pelvis: Vec3 = model.j_regressor[0]
        .iter()
        .map(|&(v, w)| verts[v as usize] * w)
        .sum();
    let nearest = |p: Vec3| {
        (0..verts.len())
            .min_by(|&a, &b| {
                verts[a]
                    .distance_squared(p)
                    .total_cmp(&verts[b].distance_squared(p))
            })
            .unwrap_or(0)
    };
    let mut chosen = vec![nearest(pelvis) as u32];
    let mut dist: Vec<Real> = verts
        .iter()
        .map(|v| v.distance_squared(verts[chosen[0] as usize]))
        .collect();
    while chosen.len() < count.min(verts.len()) {
        let (next, _) =
            dist.iter().enumerate().fold(
                (0, -1.0),
                |best, (i, &d)| if d > best.1 { (i, d) } else { best },
            );
        chosen.push(next as u32);
        let p = verts[next];
        for (d, v) in dist.iter_mut().zip(verts) {
            *d = d.min(v.distance_squared(p));
        }
    }
    chosen
}

/// What the motion loop needs per frame: joints, markers, nothing else.
#[derive(Debug, Clone)]
pub struct MarkerFrame {
    pub skeleton: PosedSkeleton,
    pub markers: Vec<Vec3>,
}

impl ShapedBody<'_> {
    /// Joints, joint transforms and marker positions only (the motion loop's fast path).
    pub fn marker_frame(
        &self,
        pose: &[Real; POSE_DIM],
        transl: Vec3,
        marker_ids: &[u32],
    ) -> Result<MarkerFrame, PoseError> {
        let skeleton = self.skeleton(pose, transl)?;
        let markers = self.pose_vertices(&skeleton, pose, marker_ids);
        Ok(MarkerFrame { skeleton, markers })
    }
}
