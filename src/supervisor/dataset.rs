//! A rendered dataset on disk and the work that makes it: which frames of which camera,
//! grouped into shards; the shard specs Blender receives; turning a shard's raw renders into
//! validated frame files; per-camera annotations.
//!
//! Layout of a dataset folder (built in `<dir>.partial/`, renamed to `<dir>` when complete):
//! - `sequence/` — the synthesized sequence (motion, CPF trajectory, meshes, preview).
//! - `cameras/<camera>/frame_NNNNN.exr` — one frame file per camera and frame
//!   (see [`crate::render::frame_file`]); `cameras/<camera>/annotations.json`.
//! - `images/<camera>/frame_NNNNN.png`, `colmap/<camera>/` — the COLMAP export
//!   (see [`super::colmap`]).
//! - `manifest.json` — every dataset file with size and SHA-256.
//! - `work/` (raw renders, body caches, shard specs, frame records: see
//!   [`super::frame_record`]) and `logs/` (worker stderr per attempt) are scratch; they are not
//!   part of the manifest.

use std::path::PathBuf;

use anyhow::{Context, Result};
use serde_json::json;

use super::annotations::{
    AgentSkin, CameraAnnotations, Conventions, SegmentationId, ANNOTATIONS_VERSION,
};
use super::frame_record::{FileFacts, FrameRecord, JOINT_OCCLUSION_TOLERANCE_M};
use crate::camera::CameraModel;
use crate::exr_file::ExrContents;
use crate::math::{Affine3, Real, Vec3};
use crate::motion::MotionSequence;
use crate::render::depth_noise::{DepthNoise, NoiseSeed};
use crate::render::frame_file::{
    assemble_frame, validate_frame_contents, FrameFileError, FrameImage,
};
use crate::render::lens_polynomial::{native_error, ERROR_GRID};
use crate::render::passes::Passes;
use crate::render::render_camera::RenderCamera;
use crate::render::shard_plan::{raw_frame_paths, shard_camera, RawRenders};
use crate::render::ShardSpec;
use crate::rig::{Rig, RigCamera};
use crate::synth::BodyTrack;

/// One camera's share of the work.
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

/// One Blender process's work: some frames of one camera.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Shard {
    pub id: usize,
    pub camera: usize,
    pub frames: Vec<u32>,
}

/// Everything needed to render and finish a dataset.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// Where the dataset is built (`<dir>.partial`).
    pub staging: PathBuf,
    /// Everything of the shard spec but its cameras.
    pub base_spec: ShardSpec,
    pub cameras: Vec<CameraWork>,
    /// What the dataset holds (`[render] passes`).
    pub passes: Passes,
    pub keys_per_frame: u32,
    pub frames_per_shard: usize,
    pub near_clip_m: f64,
    /// Every body in the scene (the annotations list them all).
    pub agents: Vec<RenderedAgent>,
    /// Which start of the run this is (1 for the first, one more for every `--resume`): each
    /// start keeps its logs in its own folder, so a resume never overwrites what an earlier
    /// start wrote (an error message may name those logs).
    pub start: u32,
}

impl Dataset {
    /// The frame file of a camera's frame.
    pub fn frame_path(&self, camera: usize, frame: u32) -> PathBuf {
        self.staging
            .join("cameras")
            .join(&self.cameras[camera].camera.name)
            .join(format!("frame_{frame:05}.exr"))
    }

    pub fn raw_dir(&self) -> PathBuf {
        self.staging.join("work/raw")
    }

    /// Which of Blender's two renders this dataset's passes need.
    pub fn raw_renders(&self) -> RawRenders {
        RawRenders {
            colour: self.base_spec.rgb.is_some(),
            ground_truth: !self.base_spec.ground_truth_passes.is_empty(),
        }
    }

    /// The raw renders a camera's frame is made from (one or two files).
    pub fn raw_frame_files(&self, camera: usize, frame: u32) -> Vec<PathBuf> {
        let name = &self.cameras[camera].camera.name;
        let (rgb, gt) = raw_frame_paths(&self.raw_dir(), name, frame, self.raw_renders());
        rgb.into_iter().chain(gt).collect()
    }

    /// The channels a camera's frame files hold.
    pub fn frame_channels(&self, camera: usize) -> Vec<&'static str> {
        let work = &self.cameras[camera];
        self.passes
            .frame_channels(work.camera.monochrome, work.depth_noise.is_some())
    }

    /// Checks a camera's frame file, read from disk or about to be written (`bytes`, named
    /// by `path`): it opens, holds exactly the camera's channels at its size, all finite.
    pub fn validate_frame_bytes(
        &self,
        camera: usize,
        path: &std::path::Path,
        bytes: &[u8],
    ) -> Result<ExrContents, FrameFileError> {
        let res = self.cameras[camera].camera.model.resolution();
        validate_frame_contents(
            ExrContents::from_bytes(path, bytes)?,
            res.width_px,
            res.height_px,
            &self.frame_channels(camera),
        )
    }

    /// A path inside the dataset as the pool report records it: relative to the dataset folder,
    /// so it stays true after `<dir>.partial` is renamed to `<dir>`.
    pub fn relative(&self, path: &std::path::Path) -> String {
        path.strip_prefix(&self.staging)
            .unwrap_or(path)
            .display()
            .to_string()
    }

    /// This start's logs: `logs/start_<n>/`.
    pub fn logs_dir(&self) -> PathBuf {
        self.staging
            .join("logs")
            .join(format!("start_{:02}", self.start))
    }

    /// Whether a frame is done: its file exists. A frame file appears only by a rename after it
    /// validated and its record was kept; [`Dataset::check_finished_frames`] clears any damaged
    /// since, before planning.
    pub fn frame_done(&self, camera: usize, frame: u32) -> bool {
        self.frame_path(camera, frame).is_file()
    }

    /// Reads every frame file of the plan that exists: one that does not validate (a damaged
    /// or truncated frame left by an interrupted run, or changed since) is removed, so that it
    /// is rendered again; one whose record is missing or does not match it gets its record
    /// again. Returns each removed file with the reason it failed.
    pub fn check_finished_frames(&self) -> Result<Vec<(PathBuf, String)>> {
        let mut removed = Vec::new();
        for (c, work) in self.cameras.iter().enumerate() {
            for &f in &work.frames {
                let path = self.frame_path(c, f);
                if !path.is_file() {
                    continue;
                }
                let bytes =
                    std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
                match self.validate_frame_bytes(c, &path, &bytes) {
                    Err(e) => {
                        std::fs::remove_file(&path)
                            .with_context(|| format!("removing damaged {}", path.display()))?;
                        removed.push((path, e.to_string()));
                    }
                    Ok(contents) => {
                        let facts = FileFacts::of(&bytes);
                        if !self.record_matches(c, f, &facts) {
                            self.record_frame(c, f, &contents, facts)?;
                        }
                    }
                }
            }
        }
        Ok(removed)
    }

    /// Shards covering the frames not done yet, `frames_per_shard` consecutive planned frames
    /// of one camera each.
    pub fn pending_shards(&self) -> Vec<Shard> {
        let mut shards = Vec::new();
        for (c, work) in self.cameras.iter().enumerate() {
            for block in work.frames.chunks(self.frames_per_shard) {
                let frames: Vec<u32> = block
                    .iter()
                    .copied()
                    .filter(|&f| !self.frame_done(c, f))
                    .collect();
                if !frames.is_empty() {
                    shards.push(Shard {
                        id: shards.len(),
                        camera: c,
                        frames,
                    });
                }
            }
        }
        shards
    }

    /// Total planned frames over all cameras.
    pub fn total_frames(&self) -> usize {
        self.cameras.iter().map(|c| c.frames.len()).sum()
    }

    /// The spec rendering `frames` of a shard's camera.
    pub fn shard_spec(&self, camera: usize, frames: &[u32]) -> ShardSpec {
        let work = &self.cameras[camera];
        let mut cam = shard_camera(
            &work.camera.name,
            &work.render,
            &work.world_from_cam,
            frames,
            self.keys_per_frame,
            self.base_spec.ground_truth_frame_step,
            &self.raw_dir(),
            self.raw_renders(),
        );
        cam.clip_start_m = self.near_clip_m;
        ShardSpec {
            cameras: vec![cam],
            ..self.base_spec.clone()
        }
    }

    /// Turns a frame's raw renders into its frame file: assembled, encoded, validated and
    /// recorded (annotation, COLMAP image, checksum: [`super::frame_record`]) from the bytes
    /// in memory, written under a temporary name and renamed; then the raw files are removed.
    pub fn finish_frame(&self, camera: usize, frame: u32) -> Result<PathBuf> {
        let work = &self.cameras[camera];
        let (rgb, gt) = raw_frame_paths(
            &self.raw_dir(),
            &work.camera.name,
            frame,
            self.raw_renders(),
        );
        let mut image: FrameImage = assemble_frame(
            rgb.as_deref(),
            gt.as_deref(),
            &work.render,
            &work.camera.model,
            work.world_from_cam[frame as usize],
        )?;
        image.monochrome = work.camera.monochrome;
        // A camera has a noise model only when the run asks for the depth_noise pass.
        if let Some((model, seed)) = &work.depth_noise {
            let cam_from_world = work.world_from_cam[frame as usize].inverse();
            let (Some(depth), Some(normal), Some(position)) =
                (&image.depth, &image.normal, &image.position)
            else {
                anyhow::bail!("depth noise needs the position and normal passes");
            };
            let ray = |i: usize| {
                let p = Vec3::from(position[i].map(Real::from));
                cam_from_world.transform_point3(p).normalize_or_zero()
            };
            let seed = NoiseSeed {
                seed: *seed,
                camera: &work.camera.name,
                frame,
            };
            image.depth_noisy = Some(model.apply(depth, normal, ray, seed));
        }
        image.keep_only(self.passes);
        let out = self.frame_path(camera, frame);
        std::fs::create_dir_all(out.parent().unwrap())
            .with_context(|| format!("creating {}", out.parent().unwrap().display()))?;
        let bytes = image.encode(&out)?;
        let contents = self.validate_frame_bytes(camera, &out, &bytes)?;
        self.record_frame(camera, frame, &contents, FileFacts::of(&bytes))?;
        let tmp = out.with_extension("exr.tmp");
        if let Err(e) = std::fs::write(&tmp, &bytes) {
            let _ = std::fs::remove_file(&tmp);
            return Err(e).with_context(|| format!("writing {}", tmp.display()));
        }
        std::fs::rename(&tmp, &out).with_context(|| format!("renaming to {}", out.display()))?;
        for raw in self.raw_frame_files(camera, frame) {
            let _ = std::fs::remove_file(raw);
        }
        Ok(out)
    }
}

/// The number of the next start of a run staged in `staging`: one more than the highest
/// `logs/start_<n>` folder there.
pub fn next_start(staging: &std::path::Path) -> u32 {
    std::fs::read_dir(staging.join("logs"))
        .map(|entries| {
            entries
                .flatten()
                .filter_map(|e| {
                    e.file_name()
                        .to_str()?
                        .strip_prefix("start_")?
                        .parse::<u32>()
                        .ok()
                })
                .max()
                .unwrap_or(0)
        })
        .unwrap_or(0)
        + 1
}

/// One body in the rendered scene.
#[derive(Debug, Clone)]
pub struct RenderedAgent {
    pub name: String,
    /// Segmentation id.
    pub id: u32,
    pub motion: MotionSequence,
    pub track: BodyTrack,
}

/// Writes `cameras/<camera>/annotations.json` for every camera (OpenCV conventions) from the
/// frames' records (`records[camera][k]`: the camera's k-th planned frame).
pub fn write_annotations(
    dataset: &Dataset,
    rig: &Rig,
    records: &[Vec<FrameRecord>],
    object_ids: &[(String, u32)],
) -> Result<()> {
    let agents = &dataset.agents;
    for (work, records) in dataset.cameras.iter().zip(records) {
        let model_json = camera_json(rig, &work.camera)?;
        let frames = records.iter().map(|r| r.annotation.clone()).collect();
        let mut segmentation_ids: Vec<SegmentationId> = object_ids
            .iter()
            .map(|(name, id)| SegmentationId {
                name: name.clone(),
                id: *id,
            })
            .collect();
        segmentation_ids.extend(agents.iter().map(|a| SegmentationId {
            name: a.name.clone(),
            id: a.id,
        }));
        let doc = CameraAnnotations {
            egogen_annotations: ANNOTATIONS_VERSION,
            conventions: Conventions {
                world: "metres, z up".into(),
                camera_frame: "OpenCV: x right, y down, z forward".into(),
                pixels: "centre of the top-left pixel at (0, 0)".into(),
                t_world_cam: "row-major 4x4 mapping camera-frame points to the world".into(),
                depth: "planar: z of the surface point in the camera frame (m); 0 = no surface".into(),
                joint_visibility: format!("visible | occluded (the pixel shows another object or agent, > {JOINT_OCCLUSION_TOLERANCE_M} m nearer than the joint) | outside (not in the valid field of view) | in_view (inside it; occlusion not known: the run rendered no depth or no segmentation)"),
                bbox_xyxy: "tight box of the agent's segmentation pixels, inclusive pixel indices; null without the segmentation pass".into(),
            },
            camera: model_json,
            image_model: image_model(work),
            depth_noise: work.depth_noise.map(|(model, seed)| json!({
                "channel": "depth_noisy.Z",
                "model": "sigma = a + b (z - c)^2 + d theta^2 / (sqrt(z) (pi/2 - theta)^2), Nguyen et al. 2012; 0 = no measurement",
                "parameters": model,
                "seed": seed,
            })),
            wearer: agents[work.wearer].name.clone(),
            headset_wear: work.headset_wear,
            lighting: dataset.base_spec.lighting.clone(),
            skins: dataset
                .base_spec
                .bodies
                .iter()
                .map(|b| AgentSkin {
                    name: b.name.clone(),
                    skin: b.skin,
                    regions: b.skin_regions.iter().map(|r| r.paint.clone()).collect(),
                })
                .collect(),
            frame_rate_hz: agents[0].motion.frame_rate_hz,
            segmentation_ids,
            frames,
        };
        let path = dataset
            .staging
            .join("cameras")
            .join(&work.camera.name)
            .join("annotations.json");
        crate::atomic_file::write_atomically(&path, serde_json::to_string_pretty(&doc)?.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// What lens the image was rendered with: `exact` (the camera model itself), or Cycles'
/// polynomial fisheye standing in for it, with its pixel error against the camera model.
fn image_model(work: &CameraWork) -> serde_json::Value {
    match &work.render {
        RenderCamera::PolynomialFisheye(lens) => json!({
            "kind": "cycles_polynomial_fisheye",
            "note": "rendered by this radially symmetric lens instead of `camera`: pixel channels (depth, normals, position, segmentation, flow) follow the image; 2D joints follow `camera`, off the image by `error_vs_camera_px`",
            "centre_px": [lens.centre_px.x, lens.centre_px.y],
            "theta_rad_of_radius_px": lens.theta_coeffs,
            "max_radius_px": lens.max_radius_px,
            "error_vs_camera_px": native_error(&work.camera.model, lens, ERROR_GRID),
        }),
        _ => json!({"kind": "exact"}),
    }
}

fn camera_json(rig: &Rig, camera: &RigCamera) -> Result<serde_json::Value> {
    let one = Rig {
        cameras: vec![camera.clone()],
        ..rig.clone()
    };
    let mut value: serde_json::Value = serde_json::from_str(&one.to_json())?;
    Ok(value["cameras"][0].take())
}
