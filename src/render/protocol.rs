//! The shard spec: plain serde messages Rust writes and `blender_scripts/render_shard.py` reads.
//! All geometry is final here — Blender receives camera poses in its own axes, lens numbers in
//! its own units and body vertices as caches, and computes nothing.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::scene::small_object::ObjectShape;

pub(crate) use super::materials::ShardMaterial;
pub(crate) use super::skin_tone::{RegionPaint, Skin};

/// How Blender's camera images: either the rig camera itself (a pinhole) or the wider ideal
/// camera that egogen remaps to a distorted model afterwards.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ShardLens {
    /// Perspective: focal length (mm) for a sensor fitted horizontally, shift in units of the
    /// larger image side.
    Perspective {
        width_px: u32,
        height_px: u32,
        focal_mm: f64,
        sensor_width_mm: f64,
        shift_x: f64,
        shift_y: f64,
    },
    /// Cycles' equidistant fisheye: square image, `fov_rad` across its width.
    EquidistantFisheye { size_px: u32, fov_rad: f64 },
    /// Cycles' polynomial fisheye (`FISHEYE_LENS_POLYNOMIAL`, sensor fitted horizontally):
    /// `θ = −(k0 + k1·r + … + k4·r⁴)` at sensor radius `r` (mm) from the image centre moved
    /// by the shifts (units of each image side), as `render/lens_polynomial.rs` measured it.
    PolynomialFisheye {
        width_px: u32,
        height_px: u32,
        sensor_width_mm: f64,
        k: [f64; 5],
        shift_x: f64,
        shift_y: f64,
        /// Cycles' `fisheye_fov`: pixels seeing farther than half of it off the axis are not
        /// traced (the image's corners beyond the camera's valid field of view).
        fov_rad: f64,
    },
}

/// A pose key at a (sub)frame of a camera or a held object: Blender `location` and
/// `rotation_quaternion` (w, x, y, z) of the object (a camera's axes in Blender: x right, y up,
/// looking along −z). Keys are interpolated linearly.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PoseKey {
    pub frame: f64,
    pub location: [f64; 3],
    pub rotation_wxyz: [f64; 4],
}

/// One frame of a camera and its raw outputs: the renders the run's passes need.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardFrame {
    pub frame: u32,
    /// Blurred colour (Combined pass), when colour is rendered.
    pub rgb_exr: Option<PathBuf>,
    /// Unblurred ground truth (the spec's `ground_truth_passes`), when any is asked for.
    pub ground_truth_exr: Option<PathBuf>,
}

/// One camera of a shard with its pose keys and frames.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardCamera {
    pub name: String,
    pub lens: ShardLens,
    /// Near clipping distance (m); head cameras use it to keep the wearer's head out.
    pub clip_start_m: f64,
    /// Pose keys covering every rendered frame, its neighbours (motion vectors) and the
    /// shutter interval.
    pub keys: Vec<PoseKey>,
    pub frames: Vec<ShardFrame>,
}

/// A body: topology (`faces_npy`, int32 F×3), vertices (`vertices_npy`) and a PC2 vertex
/// cache, played back by `cache_keys`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardBody {
    pub name: String,
    /// Segmentation id (object pass index).
    pub pass_index: u32,
    pub faces_npy: PathBuf,
    /// The mesh's vertices before the cache plays (float32 N×3, the cache's first sample).
    pub vertices_npy: PathBuf,
    pub pc2: PathBuf,
    /// The grid the cache's samples lie on: `samples_per_frame` a frame.
    pub samples_per_frame: u32,
    /// How the cache plays: `(frame, sample)` keys, linear between them, held before the
    /// first and after the last (`synth::body_cache::playback_keys`). A cache of the rendered
    /// times only (`synth::body_cache::rendered_sample_indices`) has a run of keys around each
    /// rendered frame; a full cache two keys.
    pub cache_keys: Vec<[f64; 2]>,
    /// Cycles deformation motion steps: `2^steps + 1` time samples across the shutter
    /// (`shard_plan::deform_motion_steps`).
    pub motion_steps: u32,
    /// Its skin material ([`super::skin_tone`]).
    pub skin: Skin,
    /// Texture coordinates per triangle corner (float32 (F·3)×2, corner for corner with
    /// `faces_npy`), when the body model has UVs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uvs_npy: Option<PathBuf>,
    /// Skin regions painted through masks in that UV layout ([`super::skin_tone::SKIN_REGIONS`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skin_regions: Vec<ShardSkinRegion>,
    /// The skin's detail map in that UV layout (grey; the skin's colour is multiplied by twice
    /// it: [`super::skin_tone::SKIN_DETAIL_FILE`]), when the body model has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin_detail: Option<PathBuf>,
    /// Its outfit, when outfits are on ([`super::outfit`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outfit: Option<super::outfit::ShardOutfit>,
    /// Each face's body part (float32 F×1, `body::parts::BodyPart` as a number), written to
    /// the ground truth's `part` AOV, when the segmentation is rendered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parts_npy: Option<PathBuf>,
}

/// A skin region: its colour and the grey mask (in the body's UV layout) that places it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardSkinRegion {
    pub paint: RegionPaint,
    pub mask: PathBuf,
}

impl ShardSkinRegion {
    /// Each region of `textures` painted on `skin`, with its mask.
    pub(crate) fn painted(textures: &super::skin_tone::SkinTextures, skin: &Skin) -> Vec<Self> {
        textures
            .masks
            .iter()
            .map(|(region, mask)| Self {
                paint: region.paint(skin),
                mask: mask.clone(),
            })
            .collect()
    }
}

/// Colour render settings.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardRgb {
    pub samples: u32,
    /// 0 turns adaptive sampling off.
    pub adaptive_threshold: f64,
    /// OpenImageDenoise, guided as it says; `None` leaves the colour undenoised.
    pub denoise: Option<DenoisePrefilter>,
    /// Shutter open time in frames, centred on the frame; 0 turns motion blur off.
    pub shutter_frames: f64,
    pub seed: u32,
}

/// A point light.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PointLight {
    pub position: [f64; 3],
    pub watts: f64,
}

/// Lights egogen adds to the scene ([`super::lighting`]).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardLighting {
    /// Uniform world (background) colour, linear RGB; unused with an HDRI.
    pub world_rgb: [f64; 3],
    /// World light from an HDRI shipped with Blender, instead of the colour.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub world_hdri: Option<WorldHdri>,
    pub point_lights: Vec<PointLight>,
}

/// An HDRI of Blender's `datafiles/studiolights/world/` as the world light.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WorldHdri {
    /// File name without `.exr` (e.g. `sunset`).
    pub name: String,
    /// Rotation about the vertical (rad).
    pub rotation_rad: f64,
    /// Blender's Background strength.
    pub strength: f64,
}

/// Asks the worker to write the evaluated body vertices at some (sub)frames as JSON
/// (`[{frame, vertices: [[x, y, z, …] per body]}]`) — how tests check the cache read-back.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodyProbe {
    pub frames: Vec<f64>,
    pub output_json: PathBuf,
}

fn one_metre() -> f64 {
    1.0
}

/// A shard: one Blender process renders all of it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardSpec {
    /// Scene file: glTF (`.glb`/`.gltf`), Wavefront OBJ (with its MTL and textures) or PLY
    /// (vertex colours kept), imported by Blender's own importer for its extension.
    pub scene_file: PathBuf,
    /// Which axis of the scene file points up (`"y"` or `"z"`), as the scene loader reads
    /// it (`scene::SceneFrame::up_for`): Blender turns the file so that z is up.
    pub scene_up_axis: String,
    /// Metres per unit of the scene file (`scene::SceneFrame::unit_m`): Blender scales the
    /// imported scene by it (1 in specs written before the key).
    #[serde(default = "one_metre")]
    pub scene_unit_m: f64,
    /// Object name → segmentation id (Blender's object pass index; 0 = none).
    pub object_ids: Vec<(String, u32)>,
    /// Scene frame rate as Blender stores it: `fps / fps_base`.
    pub fps: u32,
    pub fps_base: f64,
    pub bodies: Vec<ShardBody>,
    pub lighting: ShardLighting,
    /// Scene objects whose materials egogen replaces with drawn procedural ones
    /// (`[render.materials]`); the others keep the scene's own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<ShardMaterial>,
    /// The colour render's settings; none: no colour is rendered.
    pub rgb: Option<ShardRgb>,
    /// Blender view-layer passes of the ground-truth render (`use_pass_<name>`: `position`,
    /// `normal`, `object_index`, `vector`, and `z`, which egogen itself never needs); empty: no
    /// ground-truth render.
    pub ground_truth_passes: Vec<String>,
    /// Motion frames between two saved frames: the ground-truth render runs on a timeline
    /// scaled by it, so that motion vectors reach the next and previous *saved* frame.
    pub ground_truth_frame_step: u32,
    /// Where Cycles renders.
    pub device: RenderDevice,
    pub cameras: Vec<ShardCamera>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body_probe: Option<BodyProbe>,
    /// A ceiling egogen adds to a scene that has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ceiling: Option<ShardCeiling>,
    /// Boxes egogen adds for the run's `[[obstacles]]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<ShardObstacle>,
    /// Objects people pick up and carry, each with its pose keys.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held_objects: Vec<ShardHeldObject>,
    /// Objects of the scene that people move (chairs pulled out from their tables), each with
    /// its offset keys.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub moved_objects: Vec<ShardMovedObject>,
    /// A PLY scan whose faces or vertices carry object ids, imported as one mesh, split into
    /// the scene loader's objects.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_split: Option<ShardSceneSplit>,
}

/// How to split a scene file Blender imports as one mesh into the scene's objects: an int32
/// `.npy` with an index into `names` for each face of the file, in file order (−1: none).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardSceneSplit {
    pub face_objects: PathBuf,
    pub names: Vec<String>,
}

/// A box standing on the floor, still or moving in a straight line (an `[[obstacles]]` entry
/// the agents sensed), with its own segmentation id.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardObstacle {
    pub name: String,
    pub pass_index: u32,
    /// Full extents along its own axes (m): length, width, height.
    pub size_m: [f64; 3],
    /// Rotation about the vertical (rad).
    pub yaw_rad: f64,
    /// Its centre at (sub)frames; linear in between, held outside.
    pub keys: Vec<ObstacleKey>,
}

/// A small object a person picks up and carries (`synth::held_object`): a solid of its
/// shape and size (centred, z up), one colour, its own segmentation id, posed by its keys.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardHeldObject {
    pub name: String,
    pub pass_index: u32,
    pub shape: ObjectShape,
    /// Full extents along its own x, y and up (m); a cylinder's x is its diameter.
    pub size_m: [f64; 3],
    /// Linear RGB.
    pub colour_rgb: [f64; 3],
    pub keys: Vec<PoseKey>,
}

/// An object of the imported scene that people move (a chair pulled out, a thing picked up):
/// its name (as in `object_ids`) and its keys.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardMovedObject {
    pub name: String,
    pub keys: Vec<MovedKey>,
}

/// How a moved scene object stands at a (sub)frame: the world motion from where the scene
/// file has it — turned by `rotation_wxyz` (none: not turned) about the world's origin, then
/// moved by `centre` (m); linear in between, held outside.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MovedKey {
    pub frame: f64,
    pub centre: [f64; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_wxyz: Option<[f64; 4]>,
}

/// Where an obstacle's centre is at a frame.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObstacleKey {
    pub frame: f64,
    pub centre: [f64; 3],
}

/// A horizontal rectangle facing down, named [`CEILING_OBJECT`] (its segmentation id comes
/// from `object_ids` like the scene's objects).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardCeiling {
    pub z_m: f64,
    pub min_xy: [f64; 2],
    pub max_xy: [f64; 2],
}

/// The name of the ceiling object in the rendered scene and its annotations.
pub(crate) const CEILING_OBJECT: &str = "egogen_ceiling";

/// How OpenImageDenoise is guided (`[render] denoise_prefilter`): Cycles' denoiser reads the
/// colour with the first hit's albedo and normal, which at a few samples with motion blur are
/// noisy themselves.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DenoisePrefilter {
    /// The albedo and normal denoised first, each by its own OIDN filter (Cycles' default).
    #[default]
    Accurate,
    /// The albedo and normal taken as they are: one OIDN filter instead of three, a fifth less
    /// colour path tracing and denoising at the default run's size (docs/RENDERING.md).
    Fast,
}

/// Where Cycles renders (`[render] device`).
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RenderDevice {
    /// The CPU (every machine).
    #[default]
    Cpu,
    /// A GPU as Blender finds one (OptiX, CUDA, HIP, oneAPI or Metal, in that order); the
    /// worker fails at set-up, naming what it looked for, when there is none.
    Gpu,
}

impl ShardSpec {
    /// Number of files the worker writes.
    #[cfg(test)]
    pub(crate) fn num_outputs(&self) -> usize {
        self.cameras
            .iter()
            .flat_map(|c| &c.frames)
            .map(|f| f.rgb_exr.is_some() as usize + f.ground_truth_exr.is_some() as usize)
            .sum()
    }

    /// Whether people wear outfits: then the segmentation carries each pixel's garment
    /// (`segmentation.garment`) beside its ids and body parts.
    pub(crate) fn dresses_people(&self) -> bool {
        self.bodies.iter().any(|b| b.outfit.is_some())
    }
}
