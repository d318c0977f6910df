//! The shard spec: plain serde messages Rust writes and `blender_scripts/render_shard.py` reads.
//! All geometry is final here — Blender receives camera matrices in its own convention and
//! lens numbers in its own units, and computes nothing.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// One camera of a shard with its frames.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardCamera {
    pub name: String,
    pub width_px: u32,
    pub height_px: u32,
    /// Blender lens: focal length (mm) for a 36 mm wide sensor fitted horizontally.
    pub focal_mm: f64,
    pub sensor_width_mm: f64,
    /// Blender lens shift, in units of the image width.
    pub shift_x: f64,
    pub shift_y: f64,
    pub frames: Vec<ShardFrame>,
}

/// One frame of a camera: Blender's `matrix_world` (row-major 4×4; Blender camera axes: x right,
/// y up, looking along −z) and the output file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardFrame {
    pub frame: u32,
    pub matrix_world: [[f64; 4]; 4],
    pub output_exr: PathBuf,
}

/// A shard: one Blender process renders all of it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardSpec {
    /// Scene file (glTF binary, y up as glTF specifies; Blender's importer makes it z up).
    pub scene_glb: PathBuf,
    /// Object name → segmentation id (Blender's object pass index; 0 = none).
    pub object_ids: Vec<(String, u32)>,
    /// Cycles samples per pixel.
    pub samples: u32,
    pub cameras: Vec<ShardCamera>,
}
