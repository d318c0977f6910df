//! Pictures for people: a small software rasteriser for mesh previews, and PNG writing.
//!
//! Here: `raster` (a z-buffered, flat-shaded triangle rasteriser with an orthographic camera, and
//! the image it writes as PNG), `sticks` (skeletons as stick figures for it), `map` (a walkable
//! map with sensing rays drawn on it).

pub(crate) mod map;
pub(crate) mod raster;
pub(crate) mod sticks;

pub use raster::{MeshView, RgbImage};
