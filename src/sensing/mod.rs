//! Egocentric sensing: what the walking policy sees. 2D rays from the eye anchor over the
//! walkable map (static geometry, grid DDA) and dynamic obstacles (analytic), or an
//! ego-centred occupancy patch, or an egocentric depth image cast from the same world, behind
//! one [`EgoSensor`] interface.
//!
//! Here: `ego` (the ego pose on the floor plane, the sensing world, the ray-scan sensor), `ray`
//! (2D ray casting against the grid and obstacles), `local_map` (the occupancy patch of the
//! paper's Tab. 2), `depth_image` (the depth image of its Tab. 3), `spec` (which of them a
//! policy observes, as its config and weights say); `properties_tests` (the rays' accuracy and
//! invariants, tests only).

pub(crate) mod depth_image;
pub(crate) mod ego;
pub(crate) mod local_map;
#[cfg(test)]
mod properties_tests;
pub(crate) mod ray;
pub(crate) mod spec;

pub use depth_image::{DepthImage, DepthImageSettings};
pub use ego::{EgoPose2, EgoSensor, RayScan, RayScanSettings, SensingWorld};
pub use local_map::{LocalMap, LocalMapSettings};
pub(crate) use ray::Ray2;
pub use spec::{SensingSpec, Sensor};
