//! Pictures for people: a small software rasteriser for mesh previews, and PNG writing.

pub mod map;
pub mod raster;
pub mod sticks;

pub use raster::{MeshView, RgbImage};
