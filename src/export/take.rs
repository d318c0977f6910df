//! The seam every output of a rendered take goes through: what a take is to its outputs (its
//! cameras with their poses and finished frames, every body with its motion and track and the
//! scene objects it moves ([`moved_offset_at`]: where the renders and the annotations place
//! them), the rig, the scene's segmentation ids) and the [`TakeExport`] trait its outputs implement — the
//! annotations, the COLMAP export and the manifest today (`take_exports` lists them in the
//! order they are written). An output may make one file of each finished frame while the
//! frame's pixels are in memory (COLMAP's image); the frame's record keeps that file's size and
//! SHA-256 so that nothing is read or hashed twice, then every output writes its files from
//! the finished take.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Result;
use serde::{Deserialize, Serialize};

use super::annotations::{FrameAnnotation, SegmentationId};
use crate::exr_file::ExrContents;
use crate::manifest::{sha256_hex, ManifestEntry};
use crate::math::Affine3;
use crate::motion::MotionSequence;
use crate::render::depth_noise::DepthNoise;
use crate::render::render_camera::RenderCamera;
use crate::render::ShardSpec;
use crate::rig::{Rig, RigCamera};
use crate::synth::BodyTrack;

/// One camera of a take: what it renders and where it was at every frame.
#[derive(Debug, Clone)]
pub struct CameraWork {
    pub camera: RigCamera,
    pub render: RenderCamera,
    /// Depth-noise model and seed, for a `depth_noisy.Z` channel.
    pub depth_noise: Option<(DepthNoise, u64)>,
    /// OpenCV `world_from_cam` for every frame of the sequence (the headset's offset on
    /// the wearer's head applied).
    pub world_from_cam: Vec<Affine3>,
    /// The rig's offset on the wearer's head, when drawn.
    pub headset_wear: Option<crate::rig::wear::WearOffset>,
    /// Frames to render.
    pub frames: Vec<u32>,
    /// The agent wearing the camera (index into the run's agents).
    pub wearer: usize,
}

/// One body in the rendered scene.
#[derive(Debug, Clone)]
pub struct RenderedAgent {
    pub name: String,
    /// Segmentation id.
    pub id: u32,
    pub motion: MotionSequence,
    pub track: BodyTrack,
    /// Its activities' segments, in a take with activities; `None` where people only walk.
    pub activities: Option<Vec<crate::synth::activity::ActivitySegment>>,
    /// What it picks up and carries.
    pub held_objects: Vec<RenderedObject>,
    /// Scene objects it moves (chairs pulled out from their tables).
    pub(crate) moved_objects: Vec<RenderedMove>,
}

/// A scene object a body moves, with the object's segmentation id.
#[derive(Debug, Clone)]
pub(crate) struct RenderedMove {
    pub(crate) id: u32,
    pub(crate) movement: crate::synth::activity::ObjectMove,
}

/// The scene objects the agents move, each once with its segmentation id, by name.
pub(crate) fn moved_scene_objects(agents: &[RenderedAgent]) -> Vec<(&str, u32)> {
    let mut objects: Vec<(&str, u32)> = agents
        .iter()
        .flat_map(|a| a.moved_objects.iter())
        .map(|m| (m.movement.name.as_str(), m.id))
        .collect();
    objects.sort_unstable();
    objects.dedup();
    objects
}

/// Where the agents have moved scene object `name` at take frame `f`, from where the scene
/// places it (horizontal, m): every agent's move of it added, as the renders key it.
pub(crate) fn moved_offset_at(agents: &[RenderedAgent], name: &str, f: usize) -> [f64; 2] {
    agents
        .iter()
        .flat_map(|a| a.moved_objects.iter())
        .filter(|m| m.movement.name == name)
        .map(|m| m.movement.offset_at(f))
        .fold([0.0, 0.0], |a, b| [a[0] + b[0], a[1] + b[1]])
}

/// An object a body picks up and carries, with its segmentation id.
#[derive(Debug, Clone)]
pub struct RenderedObject {
    pub id: u32,
    pub object: crate::synth::held_object::HeldObject,
}

/// A camera's frame file, relative to the take's folder: `cameras/<camera>/frame_NNNNN.exr`.
pub(crate) fn frame_file_path(camera: &str, frame: u32) -> PathBuf {
    Path::new("cameras")
        .join(camera)
        .join(format!("frame_{frame:05}.exr"))
}

/// A take file's size and SHA-256 (lower-case hex), as the manifest lists it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) struct FileFacts {
    pub bytes: u64,
    pub sha256: String,
}

impl FileFacts {
    pub(crate) fn of(bytes: &[u8]) -> Self {
        Self {
            bytes: bytes.len() as u64,
            sha256: sha256_hex(bytes),
        }
    }
}

/// What is kept of one finished frame of one camera.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct FrameRecord {
    /// `cameras/<camera>/frame_NNNNN.exr`.
    pub frame_file: FileFacts,
    /// The files outputs made of this frame ([`TakeExport::frame_file`]), by their path
    /// relative to the take's folder (`/`-separated).
    #[serde(default)]
    pub exported: BTreeMap<String, FileFacts>,
    pub annotation: FrameAnnotation,
}

/// One finished frame, its pixels in memory, as an output sees it.
pub(crate) struct FinishedFrame<'a> {
    /// The frame file's channels, validated.
    pub contents: &'a ExrContents,
    /// The frame's annotation (agents in view, the colour's exposure).
    pub annotation: &'a FrameAnnotation,
}

/// A finished take as its outputs see it: every frame rendered and recorded.
pub(crate) struct FinishedTake<'a> {
    /// The folder the take is built in (`<dir>.partial`).
    pub folder: &'a Path,
    pub rig: &'a Rig,
    pub cameras: &'a [CameraWork],
    /// Every body in the scene.
    pub agents: &'a [RenderedAgent],
    /// `records[camera][k]`: the record of the camera's k-th planned frame.
    pub records: &'a [Vec<FrameRecord>],
    /// The scene's objects' segmentation ids (the agents' are theirs), with the class where
    /// the scene file gives one.
    pub scene_ids: &'a [SegmentationId],
    /// What Blender rendered beside the cameras (lighting, skins).
    pub spec: &'a ShardSpec,
}

impl FinishedTake<'_> {
    /// The manifest entries the frames' records vouch for (frame files and the files outputs
    /// made of them), so that the manifest need not hash those files again.
    pub(crate) fn recorded_files(&self) -> Vec<ManifestEntry> {
        let mut entries = Vec::new();
        for (work, records) in self.cameras.iter().zip(self.records) {
            for (&f, r) in work.frames.iter().zip(records) {
                let path = frame_file_path(&work.camera.name, f);
                entries.push(entry(&slashed(&path), &r.frame_file));
                for (path, facts) in &r.exported {
                    entries.push(entry(path, facts));
                }
            }
        }
        entries
    }
}

fn entry(path: &str, facts: &FileFacts) -> ManifestEntry {
    ManifestEntry {
        path: path.to_string(),
        bytes: facts.bytes,
        sha256: facts.sha256.clone(),
    }
}

/// A relative path as records and the manifest write it: `/`-separated.
pub(crate) fn slashed(path: &Path) -> String {
    path.components()
        .map(|c| c.as_os_str().to_string_lossy())
        .collect::<Vec<_>>()
        .join("/")
}

/// One output of a rendered take. A new output is a new file in `src/export/` implementing
/// this, listed in `export::take_exports`.
pub(crate) trait TakeExport: Send + Sync {
    /// Its name, for messages.
    fn name(&self) -> &'static str;

    /// Where this output puts the file it makes of a camera's frame, relative to the take's
    /// folder; `None` (the default): it makes none.
    fn frame_file_path(&self, _camera: &CameraWork, _frame: u32) -> Option<PathBuf> {
        None
    }

    /// The bytes of that file, made from the finished frame's pixels in memory; the caller
    /// writes them (atomically) and records their facts in the frame's record. Called only
    /// where [`TakeExport::frame_file_path`] names a file.
    fn frame_file(&self, _frame: &FinishedFrame) -> Result<Vec<u8>> {
        anyhow::bail!("{} makes no file of a frame", self.name())
    }

    /// Writes this output's files of the finished take into its folder.
    fn finish(&self, take: &FinishedTake) -> Result<()>;
}

/// The outputs of a take, in the order they are written.
#[derive(Clone)]
pub struct TakeExports(Arc<[Box<dyn TakeExport>]>);

impl std::fmt::Debug for TakeExports {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.0.iter().map(|e| e.name()))
            .finish()
    }
}

impl TakeExports {
    pub(crate) fn new(list: Vec<Box<dyn TakeExport>>) -> Self {
        TakeExports(list.into())
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = &dyn TakeExport> {
        self.0.iter().map(|e| e.as_ref())
    }
}
