//! Pictures for people: a small software rasteriser for mesh previews, and PNG writing.

pub(crate) mod map;
pub(crate) mod raster;
pub(crate) mod sticks;

pub use raster::{MeshView, RgbImage};
