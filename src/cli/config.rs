//! The run configuration file (TOML) as written by users: parsed strictly, unknown keys refused.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::render::render_camera::FisheyeRendering;
use crate::synth::activity::ActivitySettings;
use crate::walker::WalkerSettings;

pub(crate) use super::config_file::{load_toml, Bad, ConfigError};

/// `[body]`: which body model and shape.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawBody {
    /// SMPL-X `.npz` model file; relative paths resolve against the config's folder.
    /// Default: the shipped CC0 model `assets/body/SMPLX_NEUTRAL.npz`.
    pub model: Option<PathBuf>,
    /// Shape coefficients (betas), each in standard deviations.
    #[serde(default)]
    pub betas: Vec<f64>,
}

/// Where motion comes from.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MotionSource {
    /// The scripted walk cycle (`duration_s`, `frame_rate_hz`, `speed_m_s`).
    ScriptedWalk,
    /// An AMASS- or SAMP-style `.npz` motion file (`path`).
    File,
    /// Agents steered to their goals in the scene (`[crowd]`, `[[agents]]`, `[[obstacles]]`
    /// and the keys of `egogen synth`'s `[motion]`; docs/SYNTH.md).
    Agents,
}

/// `[motion]`: one flat table so that type errors name their key; `resolve` checks which
/// keys the chosen `source` needs.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawMotion {
    pub source: MotionSource,
    /// Length of the scripted walk (s).
    pub duration_s: Option<f64>,
    /// Frame rate of the scripted walk (Hz).
    pub frame_rate_hz: Option<f64>,
    /// Walking speed of the scripted walk (m/s, default 1.2; `speed_m_per_s`, its older name,
    /// is read too).
    #[serde(alias = "speed_m_per_s")]
    pub speed_m_s: Option<f64>,
    /// Motion file, relative to the config's folder.
    pub path: Option<PathBuf>,
    /// With `source = "agents"`: `egogen synth`'s `[motion]` keys (docs/SYNTH.md).
    pub weights: Option<PathBuf>,
    pub policy: Option<PathBuf>,
    pub pose_prior: Option<PathBuf>,
    pub train_config: Option<PathBuf>,
    pub stop_when_done: Option<bool>,
    pub wander_distance_m: Option<[f64; 2]>,
    pub clearance_m: Option<f64>,
    pub seed: Option<u64>,
}

/// `[output]`: where the run writes.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawOutput {
    /// Output folder; must not exist yet (or be empty).
    pub dir: PathBuf,
    /// Write a posed mesh (OBJ) every this many frames (a scripted walk or a motion file; a
    /// take of agents writes none); 0 writes none.
    #[serde(default = "default_mesh_every")]
    pub mesh_every_n_frames: usize,
}

fn default_mesh_every() -> usize {
    10
}

/// `[scene]`: where the body walks.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    /// Scene file (GLB/glTF, OBJ, PLY; metres, z up). Default: the shipped apartment.
    pub path: Option<PathBuf>,
    /// Seed for placing the walk in the scene (default 0; not with agents).
    pub seed: Option<u64>,
    /// With agents: draw starts and goals inside the walls only, and let the agents sense the
    /// ground around the walls as blocked (default true).
    pub indoors: Option<bool>,
    /// Close a scene that has no ceiling with one at the top of its walls when rendering
    /// (default true; a scene with its own ceiling is left as it is).
    pub ceiling: Option<bool>,
    /// Walk the floor at this height (m): a building's upper storey (default: the lowest
    /// floor holding a quarter of the largest floor area).
    pub floor_z_m: Option<f64>,
    /// Walk floors that step up or down by at most this (m) from cell to cell as one floor:
    /// steps between rooms, a sunken room, a ramp (0 < steps ≤ 0.5; default: one flat
    /// floor). Bodies follow the floor under them.
    pub floor_steps_m: Option<f64>,
    /// Which axis of the scene file points up, `"y"` or `"z"` (default: glTF y, OBJ and PLY z).
    pub up_axis: Option<crate::scene::UpAxis>,
    /// Metres per unit of the scene file (default 1; 0.01 for centimetres, 0.001 for
    /// millimetres).
    pub unit_m: Option<f64>,
}

/// `[render]`: which cameras render what, and how well.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawRender {
    /// Camera rig JSON (or an Aria device calibration). Default `camera_rigs/aria_gen1.json`.
    pub rig: Option<PathBuf>,
    /// Cameras of the rig to render (default: all).
    pub cameras: Option<Vec<String>>,
    /// Scales every camera's image (e.g. 0.25 renders Aria RGB at 352×352); default 1.
    pub resolution_scale: Option<f64>,
    /// Render every n-th frame of the motion (default 1).
    pub every_n_frames: Option<usize>,
    /// Cycles samples per pixel of the colour image (default 16).
    pub samples: Option<u32>,
    /// Cycles adaptive sampling noise threshold; 0 = off (default).
    pub adaptive_threshold: Option<f64>,
    /// OpenImageDenoise on the colour image (default false).
    pub denoise: Option<bool>,
    /// How OpenImageDenoise is guided: `accurate` (default: albedo and normal denoised first)
    /// or `fast` (taken as they are); only with `denoise = true`.
    pub denoise_prefilter: Option<crate::render::DenoisePrefilter>,
    /// Shutter open time in frames, centred on the frame; 0 = no motion blur (default 0.5).
    pub shutter_frames: Option<f64>,
    /// Body vertex-cache samples per frame (default 4).
    pub cache_samples_per_frame: Option<u32>,
    /// Frames per shard (one Blender process; default 20).
    pub frames_per_shard: Option<usize>,
    /// Near clipping distance of head cameras, keeping the wearer's own head out (default 0.12 m).
    pub near_clip_m: Option<f64>,
    /// How distorted cameras render: `exact` (default; remapped to the model from the tightest
    /// lens Cycles has for it), `equidistant` (remapped from a wider equidistant render, the
    /// earlier default) or `native` (Fisheye624 by Cycles' polynomial fisheye fitted to the
    /// model, unremapped; off by the fit's pixel error, see docs/RENDERING.md).
    pub fisheye: Option<FisheyeRendering>,
    /// `[render.depth_noise]`: a noisy depth channel for some cameras (default: none).
    pub depth_noise: Option<RawDepthNoise>,
    /// With agents: the agents wearing the rig (names; default the first agent).
    pub wearers: Option<Vec<String>>,
    /// `[render.headset_wear]`: each wearer's rig moved a little on the head, drawn per
    /// wearer (default: none, the rig as its file places it).
    pub headset_wear: Option<RawHeadsetWear>,
    /// `[render.lighting]`: the world light and the lamp (default: a grey world, 300 W).
    pub lighting: Option<RawLighting>,
    /// `[render.materials]`: procedural materials drawn per object (default: the scene's own).
    pub materials: Option<RawMaterials>,
    /// What the frame files hold: any of `colour`, `depth`, `normals`, `segmentation`,
    /// `position`, `flow`, `depth_noise` (default: all, `depth_noise` where
    /// `[render.depth_noise]` is given). Only these are rendered, assembled and listed.
    pub passes: Option<Vec<String>>,
    /// Whether to write the COLMAP export (`images/`, `colmap/`; needs the `colour` pass;
    /// default: when the colour pass is rendered).
    pub colmap: Option<bool>,
    /// `cpu` (default) or `gpu` (Cycles on a GPU as Blender finds one).
    pub device: Option<crate::render::RenderDevice>,
    /// `[render.skin]`: how each agent's skin tone is drawn (default: any of the ten Monk
    /// tones, seed 0).
    pub skin: Option<RawSkin>,
    /// `[render.outfits]`: each person's clothes, shoes and hair (default: dressed, seed 0;
    /// `mode = "off"` for bare bodies).
    pub(crate) outfits: Option<RawOutfits>,
    /// `[render.aria]`: each wearer's Project Aria streams (docs/ARIA.md); none by default.
    pub aria: Option<RawAria>,
}

/// `[render.aria]` (docs/ARIA.md).
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawAria {
    /// Any of `trajectory`, `calibration`, `imu`, `gaze` (default: none).
    pub streams: Option<Vec<String>>,
    /// Rows per second of the device trajectory (default 1000).
    pub trajectory_rate_hz: Option<f64>,
    /// The IMUs' errors on (default) or ideal sensors.
    pub imu_errors: Option<bool>,
    /// Draws the IMU errors (default 0).
    pub seed: Option<u64>,
    /// Seconds between online calibration lines (default 1).
    pub calibration_every_s: Option<f64>,
    /// Eye gaze samples per second (default 30).
    pub gaze_rate_hz: Option<f64>,
    /// Error models per IMU name, replacing the Aria gen1 defaults of that IMU.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub imu: std::collections::BTreeMap<String, crate::export::imu::ImuErrors>,
}

/// `[render.skin]` (docs/RENDERING.md).
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawSkin {
    /// Monk Skin Tones to draw from, each in 1..=10 (default: all ten).
    pub tones: Option<Vec<u8>>,
    /// Default 0.
    pub seed: Option<u64>,
}

/// `[render.outfits]` (docs/RENDERING.md, "Outfits").
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawOutfits {
    /// `on` (default) or `off` (bare bodies, the files as before outfits).
    pub(crate) mode: Option<crate::render::outfit::OutfitsMode>,
    /// Default 0.
    pub(crate) seed: Option<u64>,
    /// Shares of `sleeveless`, `short_sleeves`, `long_sleeves` (styles left out: none).
    pub(crate) tops: Option<std::collections::BTreeMap<String, f64>>,
    /// Shares of `shorts`, `knee`, `trousers`, `skirt`, `dress`.
    pub(crate) bottoms: Option<std::collections::BTreeMap<String, f64>>,
    /// Shares of `none`, `buzz`, `short`, `bob`, `long`.
    pub(crate) hair: Option<std::collections::BTreeMap<String, f64>>,
    /// The share of people in shoes, in [0, 1] (default 0.9).
    pub(crate) shoes: Option<f64>,
    /// `[MIN, MAX]` saturation of garment colours, in [0, 1] (default [0, 0.75]).
    pub(crate) saturation: Option<[f64; 2]>,
    /// `[MIN, MAX]` value (brightness) of garment colours, in [0, 1] (default [0.12, 0.92]).
    pub(crate) value: Option<[f64; 2]>,
}

/// `[render.lighting]` (docs/RENDERING.md).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawLighting {
    /// `"random"` (one of Blender's shipped HDRIs per sequence), an HDRI's name (`"sunset"`),
    /// or `"none"` for the uniform `world_rgb` (default `"none"`).
    pub hdri: Option<String>,
    /// `[MIN, MAX]` of the HDRI's strength (default [0.5, 1.5]).
    pub hdri_strength: Option<[f64; 2]>,
    /// The world colour without an HDRI (linear RGB; default [0.25, 0.25, 0.25]).
    pub world_rgb: Option<[f64; 3]>,
    /// `[MIN, MAX]` of the lamp's power (W; default [300, 300]).
    pub lamp_watts: Option<[f64; 2]>,
    /// Default 0.
    pub seed: Option<u64>,
}

/// `[render.materials]` (docs/RENDERING.md "Materials").
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawMaterials {
    /// `keep` (the scene's own materials; default), `fill` (objects without a texture of their
    /// own get drawn ones) or `all`.
    pub mode: Option<crate::render::materials::MaterialsMode>,
    /// Default 0.
    pub seed: Option<u64>,
}

/// `[render.headset_wear]`: the ranges of the rig's offset on each wearer's head (docs/RIGS.md).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawHeadsetWear {
    /// Each translation component uniform in ±this (m; default 0.01).
    pub translation_m: Option<f64>,
    /// Each rotation angle about the CPF's axes uniform in ±this (degrees; default 3).
    pub rotation_deg: Option<f64>,
    /// Default 0.
    pub seed: Option<u64>,
}

/// `[render.depth_noise]`: which cameras get a `depth_noisy.Z` channel, the seed, and the
/// model's parameters (each defaults to Nguyen et al.'s Kinect fit or egogen's estimate; see
/// docs/RENDERING.md and `render/depth_noise.rs`).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawDepthNoise {
    /// Rendered cameras that get the channel, e.g. `["depth-long-throw"]`.
    pub cameras: Vec<String>,
    /// Seed of the noise draws (default 0).
    pub seed: Option<u64>,
    /// `a` (default 0.0012 m).
    pub sigma_base_m: Option<f64>,
    /// `b` (default 0.0019 m⁻¹).
    pub sigma_quadratic_per_m: Option<f64>,
    /// `c` (default 0.4 m).
    pub sigma_offset_m: Option<f64>,
    /// `d` (default 0.0001 m^1.5).
    pub sigma_grazing: Option<f64>,
    /// No measurement beyond this incidence angle (default 75°).
    pub max_incidence_deg: Option<f64>,
    /// No measurement nearer than this (default 0.4 m).
    pub min_range_m: Option<f64>,
    /// No measurement farther than this (default 4 m).
    pub max_range_m: Option<f64>,
    /// Output step (default 0.001 m; 0 = none).
    pub quantisation_m: Option<f64>,
}

pub(crate) use crate::plan::Backend;

/// `[supervisor.slurm]`: resources of each array task.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawSlurm {
    /// Partition (`--partition`); default: the cluster's default partition.
    pub partition: Option<String>,
    /// CPUs per task (`--cpus-per-task`, default 2); Blender renders with as many threads.
    pub cpus_per_task: Option<u32>,
    /// Memory per task in GB (`--mem`, default 4).
    pub mem_gb: Option<f64>,
    /// Seconds between queue polls (default 10).
    pub poll_interval_s: Option<f64>,
    /// Further `sbatch` options, passed as written (e.g. `["--account=vision", "--qos=low"]`).
    pub sbatch_args: Option<Vec<String>>,
}

/// `[supervisor]`: how shards are run.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawSupervisor {
    /// Default `local`.
    pub backend: Option<Backend>,
    /// Parallel Blender workers (default 1); with Slurm, array tasks running at once.
    pub workers: Option<usize>,
    /// A shard attempt running longer than this is killed (default 3600 s).
    pub shard_timeout_s: Option<f64>,
    /// Failed shard attempts retried before the run fails (default 2).
    pub retries: Option<u32>,
    /// Each local worker keeps one Blender across its take's shards (default false: one
    /// Blender per shard attempt).
    pub keep_blender: Option<bool>,
    /// Used with `backend = "slurm"`.
    pub slurm: Option<RawSlurm>,
}

/// The whole run config, as written.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawRun {
    pub body: RawBody,
    pub motion: RawMotion,
    pub output: RawOutput,
    #[serde(default)]
    pub scene: RawScene,
    /// Without `[render]`, the run writes the sequence only.
    pub render: Option<RawRender>,
    #[serde(default)]
    pub supervisor: RawSupervisor,
    /// With `motion.source = "agents"`: how every person steps, as in `egogen synth` configs.
    #[serde(default, skip_serializing_if = "WalkerSettings::is_default")]
    pub walker: WalkerSettings,
    /// With `motion.source = "agents"`: what people do besides walking, as in `egogen
    /// synth` configs.
    #[serde(default, skip_serializing_if = "ActivitySettings::is_default")]
    pub activities: ActivitySettings,
    /// With `motion.source = "agents"`: as in `egogen synth` configs.
    pub crowd: Option<super::synth_config::RawCrowd>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub agents: Vec<super::synth_config::RawAgent>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<super::synth_config::RawObstacle>,
}

impl RawRun {
    /// Reads and parses a config file; errors name the file, key and what was expected.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        load_toml(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_key_is_refused_and_named() {
        let text = "[body]\nbetas=[]\ncolour='red'\n[motion]\nsource='file'\npath='x.npz'\n[output]\ndir='o'\n";
        let err = toml::from_str::<RawRun>(text).unwrap_err().to_string();
        assert!(err.contains("colour"), "{err}");
    }

    #[test]
    fn wrong_type_names_the_key() {
        let text =
            "[body]\nbetas='tall'\n[motion]\nsource='file'\npath='x.npz'\n[output]\ndir='o'\n";
        let err = toml::from_str::<RawRun>(text).unwrap_err().to_string();
        assert!(err.contains("betas") && err.contains("sequence"), "{err}");
    }

    /// The walking speed has one name, `speed_m_s`, as everywhere in egogen; configs written
    /// with its older name read the same.
    #[test]
    fn the_scripted_speed_reads_by_its_name_and_its_older_one() {
        let read = |key: &str| {
            let text = format!(
                "[body]\nbetas=[]\n[motion]\nsource='scripted_walk'\n{key} = 0.9\n[output]\ndir='o'\n"
            );
            toml::from_str::<RawRun>(&text).map(|r| r.motion.speed_m_s)
        };
        assert_eq!(read("speed_m_s").unwrap(), Some(0.9));
        assert_eq!(read("speed_m_per_s").unwrap(), Some(0.9));
        assert!(read("speed_m_per_sec").is_err());
    }

    /// serde reads a struct from an array by position; a config refuses it by key.
    #[test]
    fn an_array_where_a_table_is_meant_is_refused_by_key() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.toml");
        let base = "[body]\n[motion]\nsource='file'\npath='x.npz'\n[output]\ndir='o'\n";
        std::fs::write(
            &path,
            format!("{base}[render]\nheadset_wear = [0.02, 5.0, 7]\n"),
        )
        .unwrap();
        // serde alone takes it, by position.
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(toml::from_str::<RawRun>(&text).is_ok());
        let err = RawRun::load(&path).unwrap_err().to_string();
        assert!(
            err.contains("key `render.headset_wear`") && err.contains("expected a table"),
            "{err}"
        );
        std::fs::write(
            &path,
            format!("{base}[render.headset_wear]\ntranslation_m = 0.02\n"),
        )
        .unwrap();
        RawRun::load(&path).unwrap();
    }
}
