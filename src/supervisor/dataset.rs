//! A rendered dataset on disk: turning a shard's raw renders into validated frame files,
//! checking the frames an interrupted run left. The work itself (cameras, shards, paths,
//! specs) is `staged`; the outputs made from the frames are `export`'s.
//!
//! Layout of a dataset folder (built in `<dir>.partial/`, renamed to `<dir>` when complete):
//! - `sequence/` — the synthesized sequence (motion, CPF trajectory, meshes, preview).
//! - `cameras/<camera>/frame_NNNNN.exr` — one frame file per camera and frame
//!   (see [`crate::render::frame_file`]); `cameras/<camera>/annotations.json`
//!   (see [`crate::export::annotations`]).
//! - `images/<camera>/frame_NNNNN.png`, `colmap/<camera>/` — the COLMAP export
//!   (see [`crate::export::colmap`]).
//! - `manifest.json` — every dataset file with size and SHA-256.
//! - `work/` (raw renders, body caches, shard specs, frame records: see
//!   [`super::frame_record`]) and `logs/` (worker stderr per attempt) are scratch; they are not
//!   part of the manifest.

use std::path::PathBuf;

use anyhow::{Context, Result};

use super::pool::{RenderTake, WrittenFrame};
use super::staged::Dataset;
use crate::export::take::FileFacts;
use crate::math::{Real, Vec3};
use crate::render::depth_noise::NoiseSeed;
use crate::render::frame_file::FrameImage;
use crate::render::shard_plan::raw_frame_paths;

impl Dataset {
    /// Reads every frame file of the plan that exists: one that does not validate (a damaged
    /// or truncated frame left by an interrupted run, or changed since) is removed, so that it
    /// is rendered again; one whose record is missing or does not match it gets its record
    /// again. Returns each removed file with the reason it failed.
    pub(crate) fn check_finished_frames(&self) -> Result<Vec<(PathBuf, String)>> {
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
    /// recorded (annotation, the outputs' files of it such as COLMAP's image, checksum:
    /// [`super::frame_record`]) from the bytes
    /// in memory, written under a temporary name and renamed; then the raw files are removed.
    pub(crate) fn finish_frame(&self, camera: usize, frame: u32) -> Result<WrittenFrame> {
        let started = std::time::Instant::now();
        let work = &self.cameras[camera];
        let (rgb, gt) = raw_frame_paths(
            &self.raw_dir(),
            &work.camera.name,
            frame,
            self.raw_renders(),
        );
        let mut image: FrameImage = self.remap(camera).assemble(
            rgb.as_deref(),
            gt.as_deref(),
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
        let encoded = std::time::Instant::now();
        let contents = self.validate_encoded_frame(camera, image.contents(&out), &bytes)?;
        let checked = std::time::Instant::now();
        self.record_frame(camera, frame, &contents, FileFacts::of(&bytes))?;
        let recorded = std::time::Instant::now();
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
        let between = |a: std::time::Instant, b: std::time::Instant| (b - a).as_secs_f64();
        seconds.push(("assemble", between(started, assembled)));
        seconds.push(("finish", assembled.elapsed().as_secs_f64()));
        seconds.push(("finish_encode", between(assembled, encoded)));
        seconds.push(("finish_check", between(encoded, checked)));
        seconds.push(("finish_record", between(checked, recorded)));
        seconds.push(("finish_write", recorded.elapsed().as_secs_f64()));
        Ok(WrittenFrame { path: out, seconds })
    }
}

impl RenderTake for Dataset {
    fn folder(&self) -> &std::path::Path {
        &self.staging
    }
    fn logs_dir(&self) -> PathBuf {
        Dataset::logs_dir(self)
    }
    fn camera_name(&self, camera: usize) -> &str {
        &self.cameras[camera].camera.name
    }
    fn camera_pixels(&self, camera: usize) -> u64 {
        Dataset::camera_pixels(self, camera)
    }
    fn total_frames(&self) -> usize {
        Dataset::total_frames(self)
    }
    fn shard_spec_json(&self, camera: usize, frames: &[u32]) -> Result<Vec<u8>> {
        Ok(serde_json::to_vec_pretty(&self.shard_spec(camera, frames))?)
    }
    fn raw_frame_files(&self, camera: usize, frame: u32) -> Vec<PathBuf> {
        Dataset::raw_frame_files(self, camera, frame)
    }
    fn frame_done(&self, camera: usize, frame: u32) -> bool {
        Dataset::frame_done(self, camera, frame)
    }
    fn finish_frame(&self, camera: usize, frame: u32) -> Result<WrittenFrame> {
        Dataset::finish_frame(self, camera, frame)
    }
}
