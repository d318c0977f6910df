//! Exact signed distance from a point to the scene's triangles: closest point through a BVH
//! (parry3d, off the hot path: used to build the 3D SDF), sign from the angle-weighted
//! pseudo-normal of the closest feature (Bærentzen & Aanæs 2005).
//!
//! The sign is exact for closed, consistently oriented meshes (furniture, thick walls). Open
//! surfaces (a floor plane, a single-sided table top, any connected part with a boundary edge)
//! have no inside, and neither have parts whose winding is inconsistent: their distance is
//! always positive, so only closed parts count as penetrable. Closed parts wound inward
//! (negative volume) are flipped.

use std::collections::HashMap;

use parry3d_f64::math::Vector as PVec3;
use parry3d_f64::shape::composite_shape::CompositeShapeRef;
use parry3d_f64::shape::{TriMesh, TrianglePointLocation};

use super::mesh::SceneMesh;
use crate::math::Vec3;

/// A scene mesh prepared for distance queries.
pub struct MeshDistance {
    trimesh: TriMesh,
    /// Per triangle: unit face normal.
    face_normals: Vec<Vec3>,
    /// Per triangle and edge (AB, BC, AC): pseudo-normal (sum of the adjacent face normals).
    edge_normals: Vec<[Vec3; 3]>,
    /// Per triangle and corner: angle-weighted pseudo-normal of the (merged) vertex.
    vertex_normals: Vec<[Vec3; 3]>,
    /// Per triangle: orientation of its connected part (see [`part_orientation`]).
    orientation: Vec<Option<f64>>,
}

impl MeshDistance {
    /// Prepares a mesh (duplicate vertex positions are merged for adjacency). `None` if the
    /// mesh has no non-degenerate triangle.
    pub fn new(mesh: &SceneMesh) -> Option<Self> {
        // Merge vertices with identical positions so that objects exported with split
        // vertices still share edges.
        let mut key_of: HashMap<[u64; 3], u32> = HashMap::new();
        let welded: Vec<u32> = mesh
            .vertices
            .iter()
            .map(|v| {
                let k = [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
                let n = key_of.len() as u32;
                *key_of.entry(k).or_insert(n)
            })
            .collect();
        let tris = non_degenerate_triangles(mesh);
        if tris.is_empty() {
            return None;
        }
        let corner = |t: &[u32; 3], k: usize| mesh.vertices[t[k] as usize];
        let face_normals: Vec<Vec3> = tris
            .iter()
            .map(|t| {
                (corner(t, 1) - corner(t, 0))
                    .cross(corner(t, 2) - corner(t, 0))
                    .normalize()
            })
            .collect();
        let mut vertex_sum = vec![Vec3::ZERO; key_of.len()];
        let mut edge_sum: HashMap<(u32, u32), Vec3> = HashMap::new();
        let edge_key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
        for (t, n) in tris.iter().zip(&face_normals) {
            let w = t.map(|i| welded[i as usize]);
            for k in 0..3 {
                let p = corner(t, k);
                let e1 = (corner(t, (k + 1) % 3) - p).normalize();
                let e2 = (corner(t, (k + 2) % 3) - p).normalize();
                vertex_sum[w[k] as usize] += *n * e1.dot(e2).clamp(-1.0, 1.0).acos();
            }
            for (a, b) in [(0, 1), (1, 2), (0, 2)] {
                *edge_sum.entry(edge_key(w[a], w[b])).or_default() += *n;
            }
        }
        let edge_normals = tris
            .iter()
            .map(|t| {
                let w = t.map(|i| welded[i as usize]);
                [(0, 1), (1, 2), (0, 2)].map(|(a, b)| edge_sum[&edge_key(w[a], w[b])])
            })
            .collect();
        let vertex_normals = tris
            .iter()
            .map(|t| t.map(|i| vertex_sum[welded[i as usize] as usize]))
            .collect();
        let orientation = part_orientation(&tris, &welded, &mesh.vertices, key_of.len());
        let trimesh = parry_trimesh(mesh, tris)?;
        Some(Self {
            trimesh,
            face_normals,
            edge_normals,
            vertex_normals,
            orientation,
        })
    }

    /// Number of triangles in closed, consistently wound parts (the penetrable ones) and in all.
    pub fn closed_triangles(&self) -> (usize, usize) {
        (
            self.orientation.iter().filter(|o| o.is_some()).count(),
            self.orientation.len(),
        )
    }

    /// Signed distance (m) from `p` to the mesh: negative behind the closest surface.
    pub fn signed_distance(&self, p: Vec3) -> f64 {
        let Some((tri, proj, loc)) = CompositeShapeRef(&self.trimesh)
            .project_local_point_and_get_location(PVec3::from_array(p.to_array()), f64::MAX, false)
        else {
            return f64::INFINITY;
        };
        let t = tri as usize;
        let d = p - Vec3::from_array(proj.point.to_array());
        let dist = d.length();
        let Some(outward) = self.orientation[t] else {
            return dist;
        };
        let normal = match loc {
            TrianglePointLocation::OnVertex(k) => self.vertex_normals[t][k as usize],
            TrianglePointLocation::OnEdge(k, _) => self.edge_normals[t][k as usize],
            _ => self.face_normals[t],
        };
        if d.dot(normal) * outward < 0.0 {
            -dist
        } else {
            dist
        }
    }
}

/// Per triangle: the orientation of its edge-connected part — `Some(+1.0)` closed and
/// outward, `Some(-1.0)` closed but wound inward (normals flipped), `None` open or
/// inconsistently wound (every edge must be used exactly twice, once in each direction).
fn part_orientation(
    tris: &[[u32; 3]],
    welded: &[u32],
    vertices: &[Vec3],
    num_welded: usize,
) -> Vec<Option<f64>> {
    let mut parent: Vec<u32> = (0..num_welded as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    // Directed edge counts: a closed, consistently wound part uses (a→b) once and (b→a) once.
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in tris {
        let w = t.map(|i| welded[i as usize]);
        for (a, b) in [(w[0], w[1]), (w[1], w[2]), (w[2], w[0])] {
            *directed.entry((a, b)).or_default() += 1;
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra as usize] = rb;
        }
    }
    let mut bad_root = vec![false; num_welded];
    for (&(a, b), &n) in &directed {
        if n != 1 || directed.get(&(b, a)) != Some(&1) {
            let r = find(&mut parent, a);
            bad_root[r as usize] = true;
        }
    }
    // Signed volume per part (divergence theorem) decides inward or outward winding.
    let mut volume = vec![0.0; num_welded];
    for t in tris {
        let r = find(&mut parent, welded[t[0] as usize]);
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        volume[r as usize] += a.dot(b.cross(c)) / 6.0;
    }
    tris.iter()
        .map(|t| {
            let r = find(&mut parent, welded[t[0] as usize]) as usize;
            (!bad_root[r]).then(|| if volume[r] >= 0.0 { 1.0 } else { -1.0 })
        })
        .collect()
}

/// The mesh's triangles with a non-zero area.
fn non_degenerate_triangles(mesh: &SceneMesh) -> Vec<[u32; 3]> {
    mesh.triangles
        .iter()
        .copied()
        .filter(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            (b - a).cross(c - a).length_squared() > 0.0
        })
        .collect()
}

/// parry's triangle mesh of `tris` (parry has its own glam version: converted through arrays).
fn parry_trimesh(mesh: &SceneMesh, tris: Vec<[u32; 3]>) -> Option<TriMesh> {
    let verts: Vec<PVec3> = mesh
        .vertices
        .iter()
        .map(|v| PVec3::from_array(v.to_array()))
        .collect();
    TriMesh::new(verts, tris).ok()
}

/// First hits of rays against the scene's triangles (parry3d's BVH), both sides of every
/// triangle: what a line of sight meets first.
pub(crate) struct SceneRays {
    trimesh: TriMesh,
}

impl SceneRays {
    /// `None` if the mesh has no non-degenerate triangle.
    pub(crate) fn new(mesh: &SceneMesh) -> Option<Self> {
        let tris = non_degenerate_triangles(mesh);
        if tris.is_empty() {
            return None;
        }
        Some(Self {
            trimesh: parry_trimesh(mesh, tris)?,
        })
    }

    /// Distance along the unit direction `dir` from `origin` to the first triangle, within
    /// `max_m`.
    pub(crate) fn first_hit(&self, origin: Vec3, dir: Vec3, max_m: f64) -> Option<f64> {
        use parry3d_f64::query::{Ray, RayCast};
        let ray = Ray::new(
            PVec3::from_array(origin.to_array()),
            PVec3::from_array(dir.to_array()),
        );
        self.trimesh.cast_local_ray(&ray, max_m, false)
    }
}
