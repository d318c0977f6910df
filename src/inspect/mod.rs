//! Looking inside EXR files: every channel of every part (Blender 4.5's single-part multilayer
//! files and 5.0's multi-part files alike), per-channel statistics, and PNG previews chosen by
//! pass (`preview`: tonemapped colour, colour-mapped depth, normals, id palette, flow wheel);
//! `egogen inspect`'s report of them (`report`).

pub mod preview;
pub(crate) mod report;

pub use crate::exr_file::{ExrChannel, ExrContents, ExrPass, InspectError};
pub use preview::pass_preview;
