//! A rendered dataset on disk: turning a shard's raw renders into validated frame files,
//! checking the frames an interrupted run left, per-camera annotations. The work itself
//! (cameras, shards, paths, specs) is `staged`.
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
use super::staged::{CameraWork, Dataset};
use crate::math::{Real, Vec3};
use crate::render::depth_noise::NoiseSeed;
use crate::render::frame_file::{assemble_frame, FrameImage};
use crate::render::lens_polynomial::{native_error, ERROR_GRID};
use crate::render::render_camera::RenderCamera;
use crate::render::shard_plan::raw_frame_paths;
use crate::rig::{Rig, RigCamera};

impl Dataset {
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

    /// Turns a frame's raw renders into its frame file: assembled, encoded, validated and
    /// recorded (annotation, COLMAP image, checksum: [`super::frame_record`]) from the bytes
    /// in memory, written under a temporary name and renamed; then the raw files are removed.
    pub fn finish_frame(&self, camera: usize, frame: u32) -> Result<FinishedFrame> {
        let started = std::time::Instant::now();
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
        let assembled = std::time::Instant::now();
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
        let mut seconds = image.render_seconds.clone();
        seconds.push(("assemble", (assembled - started).as_secs_f64()));
        seconds.push(("finish", assembled.elapsed().as_secs_f64()));
        Ok(FinishedFrame { path: out, seconds })
    }
}

/// A frame file written by [`Dataset::finish_frame`], and where its time went (stages of
/// [`super::pool::StageSeconds`]).
#[derive(Debug, Clone)]
pub struct FinishedFrame {
    pub path: PathBuf,
    pub seconds: Vec<(&'static str, f64)>,
}

/// Writes `cameras/<camera>/annotations.json` for every camera (OpenCV conventions) from the
/// frames' records (`records[camera][k]`: the camera's k-th planned frame).
pub fn write_annotations(
    dataset: &Dataset,
    rig: &Rig,
    records: &[Vec<FrameRecord>],
    object_ids: &[(String, u32)],
    object_labels: &std::collections::BTreeMap<u32, String>,
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
                label: object_labels.get(id).cloned(),
            })
            .collect();
        segmentation_ids.extend(agents.iter().map(|a| SegmentationId {
            name: a.name.clone(),
            id: a.id,
            label: None,
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
