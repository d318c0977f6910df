//! Rendering: the Blender runtime egogen drives (PyPI `bpy` 4.5 LTS in a managed virtual
//! environment, or a user's own), and — as rendering lands — the backend trait and the wire
//! protocol of shard specs. `render` knows nothing of bodies, motion or policies.

pub mod blender_runtime;
pub mod camera_setup;
pub mod protocol;
pub mod shard;

pub use blender_runtime::{BlenderKind, BlenderRuntime, RuntimeError, SUPPORTED_SERIES};
pub use protocol::{ShardCamera, ShardFrame, ShardSpec};
