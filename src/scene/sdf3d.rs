//! The scene's 3D signed distance field on a voxel grid, for body–scene penetration (paper
//! Eq. 8 and 11): exact signed distance at every voxel centre (`MeshDistance`), trilinear in
//! between. Resolution is a knob (`voxel_m`): build time grows as 1/voxel³, the interpolation
//! error shrinks with it (`docs/SCENES.md` has the measured trade).

use rayon::prelude::*;

use super::mesh::SceneMesh;
use super::mesh_distance::MeshDistance;
use crate::math::Vec3;

/// Voxel size of the default trade: under a second to build for the apartment, 2 cm
/// worst-case error (`docs/SCENES.md`).
pub(crate) const DEFAULT_VOXEL_M: f64 = 0.05;
/// Free space kept around the scene's bounds (m), so that lookups clamped to the grid stay
/// positive.
pub(crate) const MARGIN_M: f64 = 0.2;

/// Signed distances (m) on a regular grid; voxel `(i, j, k)` centre at
/// `origin + (i, j, k)·voxel_m`. Stored as `f32` (error < 1e-6 m at scene scale).
#[derive(Debug, Clone)]
pub struct SceneSdf {
    pub origin: Vec3,
    pub voxel_m: f64,
    pub dims: [usize; 3],
    pub values_m: Vec<f32>,
}

impl SceneSdf {
    /// Builds the field over the scene's bounds plus `margin_m`, in parallel over z slices.
    /// `None` for a mesh without usable triangles.
    pub fn build(mesh: &SceneMesh, voxel_m: f64, margin_m: f64) -> Option<Self> {
        let dist = MeshDistance::new(mesh)?;
        let (lo, hi) = mesh.bounds()?;
        let origin = lo - Vec3::splat(margin_m);
        let extent = hi - lo + Vec3::splat(2.0 * margin_m);
        let dims = [0, 1, 2].map(|a| (extent[a] / voxel_m).ceil() as usize + 1);
        let slice = dims[0] * dims[1];
        let mut values_m = vec![0.0f32; slice * dims[2]];
        values_m
            .par_chunks_mut(slice)
            .enumerate()
            .for_each(|(k, out)| {
                for j in 0..dims[1] {
                    for i in 0..dims[0] {
                        let p = origin + Vec3::new(i as f64, j as f64, k as f64) * voxel_m;
                        out[j * dims[0] + i] = dist.signed_distance(p) as f32;
                    }
                }
            });
        Some(Self {
            origin,
            voxel_m,
            dims,
            values_m,
        })
    }

    #[inline]
    fn at(&self, i: usize, j: usize, k: usize) -> f64 {
        self.values_m[(k * self.dims[1] + j) * self.dims[0] + i] as f64
    }

    /// Signed distance at a point (trilinear); points outside the grid are clamped to it (the
    /// margin keeps them in free space, so the value stays positive).
    pub fn sample(&self, p: Vec3) -> f64 {
        let q = (p - self.origin) / self.voxel_m;
        let max = Vec3::new(
            self.dims[0] as f64 - 1.0,
            self.dims[1] as f64 - 1.0,
            self.dims[2] as f64 - 1.0,
        );
        let q = q.clamp(Vec3::ZERO, max);
        let b = q.floor().min(max - Vec3::ONE).max(Vec3::ZERO);
        let f = q - b;
        let (i, j, k) = (b.x as usize, b.y as usize, b.z as usize);
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c00 = lerp(self.at(i, j, k), self.at(i + 1, j, k), f.x);
        let c10 = lerp(self.at(i, j + 1, k), self.at(i + 1, j + 1, k), f.x);
        let c01 = lerp(self.at(i, j, k + 1), self.at(i + 1, j, k + 1), f.x);
        let c11 = lerp(self.at(i, j + 1, k + 1), self.at(i + 1, j + 1, k + 1), f.x);
        lerp(lerp(c00, c10, f.y), lerp(c01, c11, f.y), f.z)
    }
}
