//! Whether a point lies inside a posed body: the winding number of the body's closed surface
//! (SMPL-X's mesh is closed: every edge joins exactly two faces), counted exactly as the signed
//! crossings of one ray from the point through a BVH of the posed triangles (parry3d). A ray
//! leaving through a face adds one, entering subtracts one, so the count is the winding number
//! even where the posed surface passes through itself (an arm pressed into the chest), where
//! a parity test would call the overlap outside. A ray that grazes an edge or a vertex, where
//! the count is ambiguous, is cast again in another direction.

use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector as PVec3;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::query::Ray;

use crate::math::Vec3;

/// Directions tried in turn (none along an axis or in a plane of two: a body's surfaces are
/// often axis-aligned nowhere, but generated tests are).
const DIRECTIONS: [[f64; 3]; 4] = [
    [0.801_784, 0.267_261, 0.534_522],
    [-0.348_743, 0.871_857, -0.343_622],
    [0.223_607, -0.424_853, -0.877_260],
    [-0.666_667, -0.333_333, 0.666_667],
];

/// Barycentric margin (and |cos| between ray and face) below which a hit is ambiguous.
const GRAZE: f64 = 1e-9;

/// A posed body's surface, ready for inside tests.
pub(crate) struct BodyOccupancy {
    triangles: Vec<[Vec3; 3]>,
    bvh: Bvh,
    bounds: (Vec3, Vec3),
}

impl BodyOccupancy {
    /// The surface of `vertices` joined by `faces` (outward winding, as SMPL-X's). Faces with an
    /// index past `vertices` are skipped; an empty surface contains nothing.
    pub(crate) fn new(vertices: &[Vec3], faces: &[[u32; 3]]) -> Self {
        let triangles: Vec<[Vec3; 3]> = faces
            .iter()
            .filter(|f| f.iter().all(|&i| (i as usize) < vertices.len()))
            .map(|f| f.map(|i| vertices[i as usize]))
            .collect();
        let aabbs: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let lo = t[0].min(t[1]).min(t[2]);
                let hi = t[0].max(t[1]).max(t[2]);
                Aabb::new(
                    PVec3::from_array(lo.to_array()),
                    PVec3::from_array(hi.to_array()),
                )
            })
            .collect();
        // Empty: bounds no point lies in.
        let bounds = crate::math::point_bounds(triangles.iter().flatten())
            .unwrap_or((Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)));
        Self {
            bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &aabbs),
            triangles,
            bounds,
        }
    }

    /// The surface's axis-aligned bounds (min, max); no point outside them is inside.
    #[cfg(test)]
    pub(crate) fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Whether `p` lies inside the surface (winding number not zero).
    pub(crate) fn contains(&self, p: Vec3) -> bool {
        let (lo, hi) = self.bounds;
        p.cmpge(lo).all() && p.cmple(hi).all() && self.winding_number(p) != 0
    }

    /// The surface's winding number about `p`: 1 inside a closed outward-wound surface, 0
    /// outside, 2 where it overlaps itself.
    pub(crate) fn winding_number(&self, p: Vec3) -> i32 {
        for d in DIRECTIONS {
            if let Some(n) = self.signed_crossings(p, Vec3::from_array(d)) {
                return n;
            }
        }
        // Every direction grazed an edge: a point on the surface itself, inside by convention.
        1
    }

    /// Signed crossings of the ray from `p` along `dir`; `None` if a hit is ambiguous.
    fn signed_crossings(&self, p: Vec3, dir: Vec3) -> Option<i32> {
        let ray = Ray::new(
            PVec3::from_array(p.to_array()),
            PVec3::from_array(dir.to_array()),
        );
        let mut sum = 0;
        for leaf in self
            .bvh
            .leaves(|node| node.cast_ray(&ray, f64::MAX) < f64::MAX)
        {
            let [a, b, c] = self.triangles[leaf as usize];
            match crossing(p, dir, a, b, c) {
                Crossing::Miss => {}
                Crossing::Leaving => sum += 1,
                Crossing::Entering => sum -= 1,
                Crossing::Ambiguous => return None,
            }
        }
        Some(sum)
    }
}

enum Crossing {
    Miss,
    Leaving,
    Entering,
    Ambiguous,
}

/// Möller–Trumbore: does the ray `p + t·dir` (t > 0) pass through triangle `abc`, and which way.
fn crossing(p: Vec3, dir: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Crossing {
    let e1 = b - a;
    let e2 = c - a;
    let h = dir.cross(e2);
    let det = e1.dot(h);
    let scale = e1.length() * e2.length();
    if scale == 0.0 {
        return Crossing::Miss;
    }
    let inv = 1.0 / det;
    let s = p - a;
    let u = s.dot(h) * inv;
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    let t = e2.dot(q) * inv;
    if det.abs() <= GRAZE * scale {
        // The ray runs in the triangle's plane: ambiguous only if it could touch it.
        let n = e1.cross(e2);
        return if n.dot(s).abs() <= GRAZE * scale * s.length().max(1.0) {
            Crossing::Ambiguous
        } else {
            Crossing::Miss
        };
    }
    let w = 1.0 - u - v;
    if t <= 0.0 || u < -GRAZE || v < -GRAZE || w < -GRAZE {
        return Crossing::Miss;
    }
    if u <= GRAZE || v <= GRAZE || w <= GRAZE || t <= GRAZE {
        return Crossing::Ambiguous;
    }
    // det = (dir × e2)·e1 = -dir·(e1 × e2): positive when the ray runs against the normal.
    if det < 0.0 {
        Crossing::Leaving
    } else {
        Crossing::Entering
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyModel;
    use proptest::prelude::*;

    /// A unit cube [0, 1]³ wound outward.
    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = (0..8)
            .map(|i| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let f = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        (v, f)
    }

    #[test]
    fn a_cube_contains_its_inside_and_not_its_outside() {
        let (v, f) = cube();
        let occ = BodyOccupancy::new(&v, &f);
        assert_eq!(occ.winding_number(Vec3::splat(0.5)), 1);
        assert!(occ.contains(Vec3::new(0.01, 0.99, 0.5)));
        assert!(!occ.contains(Vec3::new(1.01, 0.5, 0.5)));
        assert_eq!(occ.winding_number(Vec3::new(-3.0, 0.5, 0.5)), 0);
        // The ray from the centre along the first direction; from a point whose first ray
        // passes exactly through the cube's vertex, the next direction decides.
        let d = Vec3::from_array(DIRECTIONS[0]);
        let corner = Vec3::ONE;
        assert_eq!(occ.winding_number(corner - d * 0.3), 1);
    }

    #[test]
    fn two_overlapping_cubes_count_twice_where_they_overlap() {
        let (v, f) = cube();
        let mut v2 = v.clone();
        v2.extend(v.iter().map(|p| *p + Vec3::splat(0.5)));
        let mut f2 = f.clone();
        f2.extend(f.iter().map(|t| t.map(|i| i + 8)));
        let occ = BodyOccupancy::new(&v2, &f2);
        assert_eq!(occ.winding_number(Vec3::splat(0.75)), 2);
        assert_eq!(occ.winding_number(Vec3::splat(0.25)), 1);
        assert_eq!(occ.winding_number(Vec3::splat(1.25)), 1);
        assert_eq!(occ.winding_number(Vec3::new(0.25, 1.25, 0.25)), 0);
    }

    #[test]
    fn the_rest_body_contains_points_inside_its_skin_and_none_of_its_own_surface_offsets() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let model = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
        let occ = BodyOccupancy::new(&model.v_template, &model.faces);
        let joints = model.rest_joints(&[], &[]).unwrap();
        // Pelvis, spine, neck and head joints lie inside the skin.
        for j in [0, 3, 6, 9, 12, 15] {
            assert!(occ.contains(joints[j]), "joint {j} {:?}", joints[j]);
        }
        // 2 cm outside along each vertex normal: outside (the mesh's folds are wider).
        let normals = vertex_normals(&model.v_template, &model.faces);
        let outside = model
            .v_template
            .iter()
            .zip(&normals)
            .filter(|(v, n)| occ.contains(**v + **n * 0.002))
            .count();
        let inside = model
            .v_template
            .iter()
            .zip(&normals)
            .filter(|(v, n)| occ.contains(**v - **n * 0.002))
            .count();
        let n = model.v_template.len();
        assert!(outside * 100 < n, "{outside} of {n} offset vertices inside");
        assert!(
            inside * 100 > 99 * n,
            "{inside} of {n} inset vertices inside"
        );
    }

    /// The generalised winding number by summing every triangle's solid angle (Van Oosterom
    /// & Strackee), the slow reference.
    fn solid_angle_winding(p: Vec3, v: &[Vec3], f: &[[u32; 3]]) -> f64 {
        f.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| v[i as usize] - p);
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                let det = a.dot(b.cross(c));
                let div = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
                2.0 * det.atan2(div)
            })
            .sum::<f64>()
            / (4.0 * std::f64::consts::PI)
    }

    #[test]
    fn the_ray_count_equals_the_solid_angle_sum_on_two_overlapping_bodies() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let model = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
        // The rest body and a copy 0.12 m in front of it, as one surface passing through
        // itself: winding 2 where they overlap.
        let n = model.v_template.len() as u32;
        let mut v = model.v_template.clone();
        v.extend(
            model
                .v_template
                .iter()
                .map(|p| *p + Vec3::new(0.0, 0.0, 0.12)),
        );
        let mut f = model.faces.clone();
        f.extend(model.faces.iter().map(|t| t.map(|i| i + n)));
        let occ = BodyOccupancy::new(&v, &f);
        let (lo, hi) = occ.bounds();
        // A fixed scatter over the bounds (a Halton-like sequence), denser near the torso.
        let mut counts = [0usize; 3];
        for k in 0..400 {
            let frac = |b: f64| ((k as f64 + 0.5) * b).fract();
            let u = Vec3::new(frac(0.618_034), frac(0.754_878), frac(0.569_840));
            let p = lo + (hi - lo) * u;
            let exact = occ.winding_number(p);
            let reference = solid_angle_winding(p, &v, &f);
            assert!(
                (reference - exact as f64).abs() < 1e-6,
                "{p:?}: rays {exact}, solid angles {reference}"
            );
            counts[exact.clamp(0, 2) as usize] += 1;
        }
        // Every case was met: outside, inside one body, inside both.
        assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
    }

    fn vertex_normals(v: &[Vec3], f: &[[u32; 3]]) -> Vec<Vec3> {
        let mut n = vec![Vec3::ZERO; v.len()];
        for t in f {
            let [a, b, c] = t.map(|i| v[i as usize]);
            let face = (b - a).cross(c - a);
            for &i in t {
                n[i as usize] += face;
            }
        }
        n.into_iter().map(|x| x.normalize_or_zero()).collect()
    }

    proptest! {
        /// Far from the origin and at any scale, a cube's winding number is 1 inside and 0
        /// outside, whatever the point.
        #[test]
        fn cube_winding_holds_far_from_the_origin(
            offset in prop::array::uniform3(-1.0e4f64..1.0e4),
            scale in 0.01f64..100.0,
            p in prop::array::uniform3(-0.5f64..1.5),
        ) {
            let (v, f) = cube();
            let o = Vec3::from_array(offset);
            let moved: Vec<Vec3> = v.iter().map(|x| *x * scale + o).collect();
            let occ = BodyOccupancy::new(&moved, &f);
            let q = Vec3::from_array(p);
            let margin = 1e-6;
            let inside = q.cmpgt(Vec3::splat(margin)).all() && q.cmplt(Vec3::splat(1.0 - margin)).all();
            let outside = q.cmplt(Vec3::splat(-margin)).any() || q.cmpgt(Vec3::splat(1.0 + margin)).any();
            let w = occ.winding_number(q * scale + o);
            if inside { prop_assert_eq!(w, 1); }
            if outside { prop_assert_eq!(w, 0); }
        }
    }
}
