//! Checked run plans: what a run renders and how its shards run, after `cli` has read and
//! range-checked a config. `cli` makes them; `supervisor` carries them out.

use std::path::PathBuf;

use serde::Deserialize;

use crate::render::depth_noise::DepthNoise;
use crate::render::render_camera::RenderCamera;
use crate::rig::{Rig, RigCamera};
pub use crate::synth::take::{AgentDraft, MotionPlan, SynthPlan};

/// Where shards run.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    /// Blender processes on this machine.
    Local,
    /// A Slurm job array, one task per shard (`sbatch`, `squeue`, `scancel`).
    Slurm,
}

/// What to render, checked: the rig's chosen cameras already scaled.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderPlan {
    pub rig: Rig,
    pub cameras: Vec<RigCamera>,
    pub every_n_frames: usize,
    pub samples: u32,
    pub adaptive_threshold: f64,
    /// OpenImageDenoise on the colour, guided as it says; `None`: off.
    pub denoise: Option<crate::render::DenoisePrefilter>,
    pub shutter_frames: f64,
    pub cache_samples_per_frame: u32,
    pub frames_per_shard: usize,
    pub near_clip_m: f64,
    /// What Blender renders for each of `cameras` (`[render] fisheye` applied).
    pub render_cameras: Vec<RenderCamera>,
    /// The depth-noise model and seed of each of `cameras`, where it has one.
    pub depth_noise: Vec<Option<(DepthNoise, u64)>>,
    /// How the rig's offset on each wearer's head is drawn (none: the rig as placed).
    pub headset_wear: Option<crate::rig::wear::HeadsetWear>,
    /// How the sequence's lighting is drawn.
    pub lighting: crate::render::lighting::LightingPlan,
    /// Which scene objects get drawn materials, and their seed.
    pub materials: crate::render::materials::MaterialsPlan,
    /// How each agent's skin is drawn.
    pub skin: crate::render::skin_tone::SkinPlan,
    /// How each person's outfit is drawn.
    pub(crate) outfits: crate::render::outfit::OutfitPlan,
    /// What the dataset holds.
    pub passes: crate::render::passes::Passes,
    /// Whether the take gets the COLMAP export (`images/`, `colmap/`).
    pub colmap: bool,
    /// Where Cycles renders.
    pub device: crate::render::RenderDevice,
    /// `[render.aria]`: each wearer's Aria streams; `None` writes none.
    pub aria: Option<crate::export::aria::AriaSettings>,
}

/// How shards run, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct SupervisorPlan {
    pub backend: Backend,
    pub workers: usize,
    pub shard_timeout_s: f64,
    pub retries: u32,
    /// Each local worker keeps its Blender across a take's shards.
    pub keep_blender: bool,
    pub slurm: SlurmPlan,
}

/// Slurm array-task resources, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct SlurmPlan {
    pub partition: Option<String>,
    pub cpus_per_task: u32,
    pub mem_gb: f64,
    pub poll_interval_s: f64,
    pub sbatch_args: Vec<String>,
}

/// A checked run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunPlan {
    pub body_model: PathBuf,
    pub betas: Vec<f64>,
    pub motion: MotionPlan,
    pub output_dir: PathBuf,
    pub mesh_every_n_frames: usize,
    pub scene: PathBuf,
    /// How the scene file's coordinates become the world's (`[scene] up_axis`, `unit_m`).
    pub scene_frame: crate::scene::SceneFrame,
    pub scene_seed: u64,
    /// Add a ceiling when rendering a scene that has none.
    pub ceiling: bool,
    /// The walkable map's settings (`[scene] floor_z_m`, `floor_steps_m`).
    pub walkable: crate::scene::WalkableSettings,
    pub render: Option<RenderPlan>,
    pub supervisor: SupervisorPlan,
}
