//! Egocentric sensing: what the walking policy sees. 2D rays from the eye anchor over the
//! walkable map (static geometry, grid DDA) and dynamic obstacles (analytic), or an
//! ego-centred occupancy patch, or an egocentric depth image cast from the same world, behind
//! one [`EgoSensor`] interface.
//!
//! Ray scan (paper): `N = 32` rays spread evenly over [−90°, 90°] around the floor projection of
//! the viewing direction, from the CPF, `7 m` long. Beam `k` points at
//! `heading − 90° + 180°·k/(N−1)` (so beam 0 is on the right, beam N−1 on the left, angles
//! counter-clockwise about +z). Value per beam: `−1 + 2·hit/7` with `hit` the free distance
//! (m); no hit within range gives `+1`; a ray starting inside an obstacle gives `−1`.

pub(crate) mod depth_image;
pub(crate) mod ego;
pub(crate) mod local_map;
pub mod ray;
pub(crate) mod spec;

pub use depth_image::{DepthImage, DepthImageSettings};
pub use ego::{EgoPose2, EgoSensor, RayScan, RayScanSettings, SensingWorld};
pub use local_map::{LocalMap, LocalMapSettings};
pub use ray::Ray2;
pub use spec::{SensingSpec, Sensor};
