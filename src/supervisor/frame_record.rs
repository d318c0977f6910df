//! What the supervisor keeps of a finished frame, so that no frame file is read again after
//! it is written: the frame file's size and SHA-256, its COLMAP image's (written from the same
//! pixels), and its annotation (agents in view, 2D joints and their visibility, boxes, colour
//! exposure). All of it is computed in [`Dataset::finish_frame`] from the frame's bytes while
//! they are in memory; annotations, the COLMAP export and the manifest are then built from the
//! records.
//!
//! A record lives in `work/frames/<camera>/frame_NNNNN.json` (scratch, not data). It is written
//! before its frame file is renamed into place, so every finished frame has one; a resume reads
//! the finished frames once anyway (to find damaged ones) and rebuilds any record that is
//! missing or does not match its file.

use std::path::PathBuf;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use super::annotations::{AgentAnnotation, FrameAnnotation, JointVisibility, SmplxParams};
use super::colmap::image_name;
use super::staged::{CameraWork, Dataset, RenderedAgent};
use crate::atomic_file::write_atomically;
use crate::camera::CameraModel;
use crate::exr_file::ExrContents;
use crate::inspect::preview::{auto_exposure, pass_preview_exposed};
use crate::manifest::{sha256_hex, ManifestEntry};
use crate::render::passes::Pass;

/// A joint is occluded when the rendered surface at its pixel is nearer than this (m): joints
/// lie inside the body, up to about this deep under its surface.
pub const JOINT_OCCLUSION_TOLERANCE_M: f64 = 0.10;

/// A dataset file's size and SHA-256 (lower-case hex), as the manifest lists it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileFacts {
    pub bytes: u64,
    pub sha256: String,
}

impl FileFacts {
    pub fn of(bytes: &[u8]) -> Self {
        Self {
            bytes: bytes.len() as u64,
            sha256: sha256_hex(bytes),
        }
    }
}

/// One finished frame of one camera.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// `cameras/<camera>/frame_NNNNN.exr`.
    pub frame_file: FileFacts,
    /// `images/<camera>/frame_NNNNN.png`, when the run asks for the `colmap` pass.
    pub colmap_image: Option<FileFacts>,
    pub annotation: FrameAnnotation,
}

impl Dataset {
    /// Where a camera's frame record is kept.
    pub fn record_path(&self, camera: usize, frame: u32) -> PathBuf {
        self.staging
            .join("work/frames")
            .join(&self.cameras[camera].camera.name)
            .join(format!("frame_{frame:05}.json"))
    }

    /// A frame's COLMAP image.
    pub fn colmap_image_path(&self, camera: usize, frame: u32) -> PathBuf {
        self.staging
            .join("images")
            .join(&self.cameras[camera].camera.name)
            .join(image_name(frame))
    }

    /// Computes a frame's record from its validated `contents` (what the frame file holds,
    /// whose own facts are `frame_file`), writes its COLMAP image when the run asks for one,
    /// and keeps the record.
    pub fn record_frame(
        &self,
        camera: usize,
        frame: u32,
        contents: &ExrContents,
        frame_file: FileFacts,
    ) -> Result<FrameRecord> {
        let plane = |name: &str| contents.channel(name).map(|c| c.values.as_slice());
        let mut annotation = frame_annotation(
            &self.cameras[camera],
            frame,
            &self.agents,
            plane("depth.Z"),
            plane("segmentation.id"),
        );
        let colour = colour_pass(contents);
        annotation.colour_exposure = colour.map(|p| auto_exposure(contents, p));
        let colmap_image = match (colour, annotation.colour_exposure) {
            (Some(colour), Some(exposure)) if self.passes.has(Pass::Colmap) => {
                let png = pass_preview_exposed(contents, colour, exposure).encode_png()?;
                let path = self.colmap_image_path(camera, frame);
                create_parent(&path)?;
                write_atomically(&path, &png)
                    .with_context(|| format!("writing {}", path.display()))?;
                Some(FileFacts::of(&png))
            }
            _ if self.passes.has(Pass::Colmap) => anyhow::bail!(
                "{}: no colour (`rgb` or `gray`) for the COLMAP image",
                contents.path.display()
            ),
            _ => None,
        };
        let record = FrameRecord {
            frame_file,
            colmap_image,
            annotation,
        };
        let path = self.record_path(camera, frame);
        create_parent(&path)?;
        write_atomically(&path, serde_json::to_string(&record)?.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(record)
    }

    /// A finished frame's record.
    pub fn load_record(&self, camera: usize, frame: u32) -> Result<FrameRecord> {
        let path = self.record_path(camera, frame);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("{}: not a frame record", path.display()))
    }

    /// Whether a finished frame's record is there and matches what is on disk: the frame
    /// file's `facts` and the COLMAP image's size when the run asks for one.
    pub fn record_matches(&self, camera: usize, frame: u32, facts: &FileFacts) -> bool {
        let Ok(record) = self.load_record(camera, frame) else {
            return false;
        };
        let image_ok = match (&record.colmap_image, self.passes.has(Pass::Colmap)) {
            (Some(png), true) => std::fs::metadata(self.colmap_image_path(camera, frame))
                .is_ok_and(|m| m.len() == png.bytes),
            (None, false) => true,
            _ => false,
        };
        record.frame_file == *facts && image_ok
    }

    /// Every planned frame's record, camera by camera: all frames must be finished.
    pub fn records(&self) -> Result<Vec<Vec<FrameRecord>>> {
        self.cameras
            .iter()
            .enumerate()
            .map(|(c, work)| {
                work.frames
                    .iter()
                    .map(|&f| self.load_record(c, f))
                    .collect()
            })
            .collect()
    }

    /// The manifest entries the records vouch for (frame files and COLMAP images), so that
    /// the manifest need not hash those files again.
    pub fn recorded_files(&self, records: &[Vec<FrameRecord>]) -> Vec<ManifestEntry> {
        let mut entries = Vec::new();
        for (c, (work, records)) in self.cameras.iter().zip(records).enumerate() {
            for (&f, r) in work.frames.iter().zip(records) {
                let mut add = |path: PathBuf, facts: &FileFacts| {
                    entries.push(ManifestEntry {
                        path: self.relative(&path),
                        bytes: facts.bytes,
                        sha256: facts.sha256.clone(),
                    })
                };
                add(self.frame_path(c, f), &r.frame_file);
                if let Some(png) = &r.colmap_image {
                    add(self.colmap_image_path(c, f), png);
                }
            }
        }
        entries
    }
}

fn create_parent(path: &std::path::Path) -> Result<()> {
    let dir = path.parent().unwrap_or(path);
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))
}

/// A frame file's colour: `rgb`, or `gray` of a monochrome camera.
pub fn colour_pass(contents: &ExrContents) -> Option<&crate::exr_file::Pass> {
    contents
        .passes
        .iter()
        .find(|p| p.name == "rgb" || p.name == "gray")
}

/// A frame's annotation from the camera's pose, the agents' bodies and, where the frame holds
/// them, its depth and segmentation planes (joint visibility, boxes). `colour_exposure` is
/// left for the caller.
fn frame_annotation(
    work: &CameraWork,
    f: u32,
    agents: &[RenderedAgent],
    depth: Option<&[f32]>,
    ids: Option<&[f32]>,
) -> FrameAnnotation {
    let i = f as usize;
    let res = work.camera.model.resolution();
    let w = res.width_px as usize;
    let world_from_cam = work.world_from_cam[i];
    let cam_from_world = world_from_cam.inverse();
    let pelvis = |a: &RenderedAgent| a.track.frames[i].joints[0];
    let listed = agents
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let joints = &a.track.frames[i].joints;
            let mut joints_2d = Vec::with_capacity(joints.len());
            let mut visibility = Vec::with_capacity(joints.len());
            for j in joints {
                let p = cam_from_world.transform_point3(*j);
                match work.camera.model.project(p) {
                    Some(px) => {
                        let (x, y) = (px.x.round() as usize, px.y.round() as usize);
                        let at = y.min(res.height_px as usize - 1) * w + x.min(w - 1);
                        joints_2d.push(Some([px.x, px.y]));
                        visibility.push(match (depth, ids) {
                            (Some(depth), Some(ids)) => {
                                let d = depth[at] as f64;
                                // Hidden when the pixel shows something else, nearer than the
                                // joint; the agent's own surface over its joint is the joint seen.
                                if ids[at] as u32 != a.id
                                    && d > 0.0
                                    && d < p.z - JOINT_OCCLUSION_TOLERANCE_M
                                {
                                    JointVisibility::Occluded
                                } else {
                                    JointVisibility::Visible
                                }
                            }
                            _ => JointVisibility::InView,
                        });
                    }
                    None => {
                        joints_2d.push(None);
                        visibility.push(JointVisibility::Outside);
                    }
                }
            }
            let bbox = ids.and_then(|ids| bbox_of(ids, w, a.id));
            // With segmentation: its pixels are in the image; without: a joint is.
            let in_view = match ids {
                Some(_) => bbox.is_some(),
                None => joints_2d.iter().any(Option::is_some),
            };
            // Distance to the nearest other agent (pelvis to pelvis); none alone.
            let nearest = agents
                .iter()
                .enumerate()
                .filter(|(o, _)| *o != k)
                .map(|(_, o)| pelvis(o).distance(pelvis(a)))
                .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.min(d))));
            AgentAnnotation {
                name: a.name.clone(),
                id: a.id,
                wearer: k == work.wearer,
                in_view,
                smplx: SmplxParams::new(
                    &a.motion.betas,
                    &a.motion.poses[i],
                    a.motion.trans[i].to_array(),
                ),
                joints_3d: joints.iter().map(|j| j.to_array()).collect(),
                joints_2d,
                joint_visibility: visibility,
                bbox_xyxy: bbox,
                interaction_distance_m: nearest,
            }
        })
        .collect();
    FrameAnnotation {
        frame: f,
        time_s: f as f64 / agents[0].motion.frame_rate_hz,
        file: format!("frame_{f:05}.exr"),
        t_world_cam: crate::math::row_major(world_from_cam),
        colour_exposure: None,
        agents: listed,
    }
}

/// Inclusive pixel box of the pixels labelled `id`, if any.
fn bbox_of(ids: &[f32], width: usize, id: u32) -> Option<[usize; 4]> {
    let mut b: Option<[usize; 4]> = None;
    for (i, &v) in ids.iter().enumerate() {
        if v as u32 == id {
            let (x, y) = (i % width, i / width);
            b = Some(match b {
                None => [x, y, x, y],
                Some([x0, y0, x1, y1]) => [x0.min(x), y0.min(y), x1.max(x), y1.max(y)],
            });
        }
    }
    b
}
