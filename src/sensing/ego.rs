//! The ego pose on the floor plane, the sensing world, and the ray-scan sensor.

use glam::DVec2;
use rayon::prelude::*;

use super::ray::grid::hit_grid;
use super::ray::{hit_obstacle, Ray2};
use crate::math::Affine3;
use crate::scene::{Obstacle2, WalkableMap};

/// Where a sensor sits on the floor plane: position (m) and heading (rad, counter-clockwise
/// from +x about +z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EgoPose2 {
    pub position: DVec2,
    pub heading_rad: f64,
}

impl EgoPose2 {
    /// From `world_from_cpf` (z-up world): the CPF origin and the floor projection of its
    /// viewing direction (CPF +z). A gaze straight up or down keeps heading 0.
    pub(crate) fn from_world_from_cpf(world_from_cpf: &Affine3) -> Self {
        let f = world_from_cpf.matrix3.z_axis;
        let heading_rad = if f.x == 0.0 && f.y == 0.0 {
            0.0
        } else {
            f.y.atan2(f.x)
        };
        Self {
            position: DVec2::new(world_from_cpf.translation.x, world_from_cpf.translation.y),
            heading_rad,
        }
    }
}

/// What sensors look at: the static walkable map and the dynamic obstacles at this instant.
#[derive(Debug, Clone, Copy)]
pub struct SensingWorld<'a> {
    pub map: &'a WalkableMap,
    pub obstacles: &'a [Obstacle2],
}

impl SensingWorld<'_> {
    /// Free distance along a ray (≤ `max_t`): static geometry and dynamic obstacles.
    pub(crate) fn cast(&self, ray: Ray2, max_t: f64) -> Option<f64> {
        let mut best = hit_grid(self.map, ray, max_t);
        for o in self.obstacles {
            if let Some(t) = hit_obstacle(o, ray, best.unwrap_or(max_t)) {
                best = Some(best.map_or(t, |b: f64| b.min(t)));
            }
        }
        best
    }
}

/// A sensor that turns an ego pose into an observation vector.
pub trait EgoSensor: Sync {
    /// Length of the observation vector.
    fn dim(&self) -> usize;
    /// Writes the observation of `pose` into `out` (`out.len() == dim()`).
    fn observe_into(&self, world: &SensingWorld, pose: EgoPose2, out: &mut [f32]);
    /// Observation of one pose.
    fn observe(&self, world: &SensingWorld, pose: EgoPose2) -> Vec<f32> {
        let mut out = vec![0.0; self.dim()];
        self.observe_into(world, pose, &mut out);
        out
    }
    /// Observations of many poses (many agents), in parallel; row-major `[poses, dim]`.
    fn observe_batch(&self, world: &SensingWorld, poses: &[EgoPose2]) -> Vec<f32> {
        let d = self.dim();
        let mut out = vec![0.0; poses.len() * d];
        out.par_chunks_mut(d)
            .zip(poses)
            .for_each(|(o, p)| self.observe_into(world, *p, o));
        out
    }
}

/// Settings of the ray scan (paper values by default).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RayScanSettings {
    pub num_rays: usize,
    /// Half of the fan's opening (rad); beams span `[−half, +half]` around the heading.
    pub half_fov_rad: f64,
    pub max_range_m: f64,
}

impl Default for RayScanSettings {
    fn default() -> Self {
        Self {
            num_rays: 32,
            half_fov_rad: std::f64::consts::FRAC_PI_2,
            max_range_m: 7.0,
        }
    }
}

/// The paper's egocentric ray scan.
#[derive(Debug, Clone)]
pub struct RayScan {
    pub settings: RayScanSettings,
    /// Beam angles relative to the heading (rad), precomputed as unit vectors.
    offsets: Vec<DVec2>,
}

impl RayScan {
    pub(crate) fn new(settings: RayScanSettings) -> Self {
        let n = settings.num_rays.max(1);
        let offsets = (0..n)
            .map(|k| {
                let a = if n == 1 {
                    0.0
                } else {
                    -settings.half_fov_rad + 2.0 * settings.half_fov_rad * k as f64 / (n - 1) as f64
                };
                DVec2::from_angle(a)
            })
            .collect();
        Self { settings, offsets }
    }

    /// Free distance (m) per beam, `max_range_m` where nothing is hit.
    pub(crate) fn distances(&self, world: &SensingWorld, pose: EgoPose2) -> Vec<f64> {
        let heading = DVec2::from_angle(pose.heading_rad);
        self.offsets
            .iter()
            .map(|o| {
                let ray = Ray2 {
                    origin: pose.position,
                    dir: heading.rotate(*o),
                };
                world
                    .cast(ray, self.settings.max_range_m)
                    .unwrap_or(self.settings.max_range_m)
            })
            .collect()
    }

    /// World direction of beam `k` for a pose.
    pub(crate) fn beam_dir(&self, pose: EgoPose2, k: usize) -> DVec2 {
        DVec2::from_angle(pose.heading_rad).rotate(self.offsets[k])
    }
}

impl Default for RayScan {
    fn default() -> Self {
        Self::new(RayScanSettings::default())
    }
}

impl EgoSensor for RayScan {
    fn dim(&self) -> usize {
        self.offsets.len()
    }

    fn observe_into(&self, world: &SensingWorld, pose: EgoPose2, out: &mut [f32]) {
        let range = self.settings.max_range_m;
        let heading = DVec2::from_angle(pose.heading_rad);
        for (o, off) in out.iter_mut().zip(&self.offsets) {
            let ray = Ray2 {
                origin: pose.position,
                dir: heading.rotate(*off),
            };
            let hit = world.cast(ray, range).unwrap_or(range);
            *o = (-1.0 + 2.0 * hit / range) as f32;
        }
    }
}
