//! A body's volume as capsules around its bones, for telling when another body's surface
//! enters it. One capsule per bone of the 22 body joints (parent → joint, hands and face
//! left out); its radius is the median distance to the bone of the rest-pose vertices skinned
//! mostly to the bone's parent (or, at the head, wrists and feet, to the joint itself) that
//! project onto the bone. Medians keep the capsules inside the skin, so a count of vertices
//! inside them is a lower bound of the true penetration.

use super::lbs::ShapedBody;
use super::model::BodyModel;
use super::skeleton::PARENTS;
use crate::math::Vec3;

/// Body joints (SMPL-X's first 22: pelvis to wrists).
const BODY_JOINTS: usize = 22;
/// Body joints with no body-joint child: head, feet, wrists.
const LEAVES: [usize; 5] = [10, 11, 15, 20, 21];

/// Capsules of one body shape.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CapsuleVolume {
    /// (parent joint, joint, radius m) per bone.
    pub bones: Vec<(usize, usize, f64)>,
}

/// Distance from `p` to the segment `a`–`b`, and where along it `p` projects (0 at `a`).
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> (f64, f64) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        (p - a).dot(ab) / len2
    } else {
        0.0
    };
    let q = a + ab * t.clamp(0.0, 1.0);
    (p.distance(q), t)
}

impl CapsuleVolume {
    /// The capsules of a shaped body (see the module docs).
    pub(crate) fn new(model: &BodyModel, shaped: &ShapedBody) -> Self {
        let owner: Vec<usize> = model
            .skin_weights
            .iter()
            .map(|row| {
                row.iter()
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .map_or(0, |&(j, _)| j as usize)
            })
            .collect();
        let rest = &shaped.rest_joints;
        let bones = (1..BODY_JOINTS)
            .filter_map(|j| {
                let p = PARENTS[j]?;
                let mut d: Vec<f64> = shaped
                    .v_shaped
                    .iter()
                    .zip(&owner)
                    .filter(|(_, &o)| o == p || (o == j && LEAVES.contains(&j)))
                    .map(|(v, _)| segment_distance(*v, rest[p], rest[j]))
                    .filter(|(_, t)| (0.0..=1.0).contains(t))
                    .map(|(d, _)| d)
                    .collect();
                if d.is_empty() {
                    return None;
                }
                d.sort_by(f64::total_cmp);
                Some((p, j, d[d.len() / 2]))
            })
            .collect();
        Self { bones }
    }

    /// The largest radius.
    pub(crate) fn max_radius_m(&self) -> f64 {
        self.bones.iter().map(|b| b.2).fold(0.0, f64::max)
    }

    /// Whether `p` lies inside a capsule of the body posed with `joints`.
    pub(crate) fn contains(&self, joints: &[Vec3], p: Vec3) -> bool {
        self.bones
            .iter()
            .any(|&(a, b, r)| segment_distance(p, joints[a], joints[b]).0 < r)
    }

    /// Axis-aligned bounds of the posed capsules.
    pub(crate) fn bounds(&self, joints: &[Vec3]) -> (Vec3, Vec3) {
        let r = Vec3::splat(self.max_radius_m());
        let (lo, hi) = joints[..BODY_JOINTS].iter().fold(
            (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), j| (lo.min(*j), hi.max(*j)),
        );
        (lo - r, hi + r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_distance_projects_and_clamps() {
        let (a, b) = (Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0));
        let (d, t) = segment_distance(Vec3::new(0.5, 0.2, 0.0), a, b);
        assert!((d - 0.2).abs() < 1e-12 && (t - 0.5).abs() < 1e-12);
        let (d, t) = segment_distance(Vec3::new(2.0, 0.0, 0.0), a, b);
        assert!((d - 1.0).abs() < 1e-12 && (t - 2.0).abs() < 1e-12);
        // A degenerate bone is a sphere.
        let (d, _) = segment_distance(Vec3::new(0.0, 3.0, 4.0), a, a);
        assert!((d - 5.0).abs() < 1e-12);
    }
}
