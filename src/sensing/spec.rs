//! What a policy observes of its surroundings, as written in its config and saved in its
//! weights: the paper's ray scan (any number of rays), the local-map alternative of the
//! paper's Tab. 2 or the egocentric depth image of its Tab. 3. [`SensingSpec::sensor`] builds the sensor that produces the observation.

use serde::{Deserialize, Serialize};

use super::depth_image::{DepthImage, DepthImageSettings};
use super::ego::{EgoPose2, EgoSensor, RayScan, RayScanSettings, SensingWorld};
use super::local_map::{LocalMap, LocalMapSettings};

/// A sensor's kind and settings (TOML: `kind = "rays"`, `kind = "local_map"` or `kind =
/// "depth_image"`, then the settings of [`RayScanSettings`], [`LocalMapSettings`] or
/// [`DepthImageSettings`], each defaulted).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SensingSpec {
    Rays(RayScanSettings),
    LocalMap(LocalMapSettings),
    DepthImage(DepthImageSettings),
}

impl Default for SensingSpec {
    /// The paper's 32 rays over ±90°, 7 m.
    fn default() -> Self {
        Self::Rays(RayScanSettings::default())
    }
}

impl SensingSpec {
    /// A body-centred square occupancy patch reaching `half_side_m` in every direction,
    /// `cells × cells` cells (DIMOS's walkability map: 0.8 m, 16 cells).
    pub fn centred_map(half_side_m: f64, cells: usize) -> Self {
        Self::LocalMap(LocalMapSettings {
            rows: cells,
            cols: cells,
            cell_m: 2.0 * half_side_m / cells as f64,
            behind_m: half_side_m,
        })
    }

    /// Values per observed pose.
    pub(crate) fn dim(&self) -> usize {
        match self {
            Self::Rays(s) => s.num_rays,
            Self::LocalMap(s) => s.rows * s.cols,
            Self::DepthImage(s) => s.rows * s.cols,
        }
    }

    /// What is wrong with the settings, if anything (`None`: usable).
    pub(crate) fn problem(&self) -> Option<String> {
        let bad = |ok: bool, message: String| (!ok).then_some(message);
        match self {
            Self::Rays(s) => bad(s.num_rays >= 1, "num_rays must be ≥ 1".into())
                .or_else(|| {
                    bad(
                        s.max_range_m.is_finite() && s.max_range_m > 0.0,
                        format!("max_range_m must be > 0, got {}", s.max_range_m),
                    )
                })
                .or_else(|| {
                    bad(
                        (0.0..=std::f64::consts::PI).contains(&s.half_fov_rad),
                        format!("half_fov_rad must be in [0, π], got {}", s.half_fov_rad),
                    )
                }),
            Self::LocalMap(s) => bad(
                s.rows >= 1 && s.cols >= 1,
                format!("rows and cols must be ≥ 1, got {} × {}", s.rows, s.cols),
            )
            .or_else(|| {
                bad(
                    s.cell_m.is_finite() && s.cell_m > 0.0,
                    format!("cell_m must be > 0, got {}", s.cell_m),
                )
            })
            .or_else(|| {
                bad(
                    s.behind_m.is_finite() && s.behind_m >= 0.0,
                    format!("behind_m must be ≥ 0, got {}", s.behind_m),
                )
            }),
            Self::DepthImage(s) => s.problem(),
        }
    }

    /// The sensor.
    pub(crate) fn sensor(&self) -> Sensor {
        match *self {
            Self::Rays(s) => Sensor::Rays(RayScan::new(s)),
            Self::LocalMap(settings) => Sensor::LocalMap(LocalMap { settings }),
            Self::DepthImage(settings) => Sensor::DepthImage(DepthImage::new(settings)),
        }
    }
}

/// A built sensor of any kind.
#[derive(Debug, Clone)]
pub enum Sensor {
    Rays(RayScan),
    LocalMap(LocalMap),
    DepthImage(DepthImage),
}

impl Default for Sensor {
    fn default() -> Self {
        SensingSpec::default().sensor()
    }
}

impl EgoSensor for Sensor {
    fn dim(&self) -> usize {
        match self {
            Self::Rays(s) => s.dim(),
            Self::LocalMap(s) => s.dim(),
            Self::DepthImage(s) => s.dim(),
        }
    }

    fn observe_into(&self, world: &SensingWorld, pose: EgoPose2, out: &mut [f32]) {
        match self {
            Self::Rays(s) => s.observe_into(world, pose, out),
            Self::LocalMap(s) => s.observe_into(world, pose, out),
            Self::DepthImage(s) => s.observe_into(world, pose, out),
        }
    }
}
