//! Rendering: the Blender runtime egogen drives (`blender_runtime`: PyPI `bpy` 4.5 LTS in a
//! managed virtual environment, or a user's own) and how a worker is started on a shard
//! (`shard`), the wire protocol of shard specs (`protocol`) and how they are planned
//! (`shard_plan`, `camera_setup`), what Blender renders for each rig camera (`render_camera`,
//! `lens_polynomial`), the drawn appearance it is given (`lighting`, `materials`, `skin_tone`:
//! each agent's skin, `outfit`: each person's clothes and hair, their regions measured on the
//! body model's rest shape; `outfit_sheet`: `egogen body outfits`), and turning its raw
//! renders into frame files (`frame_file`, `passes`, `depth_noise`; the segmentation's ids,
//! a person's body parts and, where people are dressed, garments). `render` knows nothing of motion or policies: posed bodies reach
//! it as files (`crate::vertex_cache`) that `synth` writes.

pub mod blender_runtime;
pub(crate) mod camera_setup;
pub mod depth_noise;
pub(crate) mod frame_file;
pub mod lens_polynomial;
pub mod lighting;
pub(crate) mod materials;
pub(crate) mod outfit;
pub(crate) mod outfit_sheet;
pub(crate) mod passes;
pub(crate) mod protocol;
pub mod render_camera;
pub(crate) mod shard;
pub(crate) mod shard_plan;
pub mod skin_tone;

pub use blender_runtime::{BlenderKind, BlenderRuntime, RuntimeError};
pub(crate) use outfit_sheet::outfit_sheet;
pub(crate) use protocol::{
    DenoisePrefilter, RenderDevice, ShardBody, ShardLighting, ShardMaterial, ShardRgb, ShardSpec,
};
