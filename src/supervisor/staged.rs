//! A staged take's rendering work, as data: which frames of which camera (the take's cameras
//! and bodies as `export::take` describes them), grouped into shards, where each frame's files
//! live, the shard specs Blender receives, the outputs the take is finished into, and each
//! camera's remap from its render to its frames (made once per take).
//! Finishing frames into files and records (`dataset`, `frame_record`) builds on it.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use crate::camera::CameraModel;
pub use crate::export::take::CameraWork;
pub use crate::export::take::RenderedAgent;
pub(crate) use crate::export::take::RenderedMove;
pub(crate) use crate::export::take::RenderedObject;
use crate::export::take::{frame_file_path, TakeExports};
use crate::exr_file::ExrContents;
use crate::render::frame_file::{
    check_encoded_header, validate_frame_contents, FrameFileError, RemapTable,
};
use crate::render::passes::Passes;
use crate::render::shard_plan::{raw_frame_paths, shard_camera, RawRenders};
use crate::render::ShardSpec;

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
    /// What the take is finished into (annotations, COLMAP, manifest, …), in order.
    pub exports: TakeExports,
    /// Which start of the run this is (1 for the first, one more for every `--resume`): each
    /// start keeps its logs in its own folder, so a resume never overwrites what an earlier
    /// start wrote (an error message may name those logs).
    pub start: u32,
    /// Each camera's remap from its render to its frames, made when its first frame is
    /// finished ([`Dataset::remap`]).
    pub(crate) remaps: Vec<OnceLock<Arc<RemapTable>>>,
}

impl Dataset {
    /// A camera's remap table, made on first use and kept for the take.
    pub(crate) fn remap(&self, camera: usize) -> Arc<RemapTable> {
        let work = &self.cameras[camera];
        self.remaps[camera]
            .get_or_init(|| Arc::new(RemapTable::new(&work.render, &work.camera.model)))
            .clone()
    }

    /// The frame file of a camera's frame.
    pub(crate) fn frame_path(&self, camera: usize, frame: u32) -> PathBuf {
        self.staging
            .join(frame_file_path(&self.cameras[camera].camera.name, frame))
    }

    pub(crate) fn raw_dir(&self) -> PathBuf {
        self.staging.join("work/raw")
    }

    /// Which of Blender's two renders this dataset's passes need.
    pub(crate) fn raw_renders(&self) -> RawRenders {
        RawRenders {
            colour: self.base_spec.rgb.is_some(),
            ground_truth: !self.base_spec.ground_truth_passes.is_empty(),
        }
    }

    /// The raw renders a camera's frame is made from (one or two files).
    pub(crate) fn raw_frame_files(&self, camera: usize, frame: u32) -> Vec<PathBuf> {
        let name = &self.cameras[camera].camera.name;
        let (rgb, gt) = raw_frame_paths(&self.raw_dir(), name, frame, self.raw_renders());
        rgb.into_iter().chain(gt).collect()
    }

    /// The channels a camera's frame files hold.
    pub(crate) fn frame_channels(&self, camera: usize) -> Vec<&'static str> {
        let work = &self.cameras[camera];
        self.passes.frame_channels(
            work.camera.monochrome,
            work.depth_noise.is_some(),
            self.base_spec.dresses_people(),
        )
    }

    /// Checks a camera's frame file, read from disk or about to be written (`bytes`, named
    /// by `path`): it opens, holds exactly the camera's channels at its size, all finite.
    pub(crate) fn validate_frame_bytes(
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

    /// Checks a camera's frame about to be written: `contents` (from [`crate::render::frame_file::FrameImage::contents`])
    /// hold exactly the camera's channels at its size, all finite, and `bytes` are their
    /// encoding ([`check_encoded_header`]); nothing is decoded.
    pub(crate) fn validate_encoded_frame(
        &self,
        camera: usize,
        contents: ExrContents,
        bytes: &[u8],
    ) -> Result<ExrContents, FrameFileError> {
        let res = self.cameras[camera].camera.model.resolution();
        let contents = validate_frame_contents(
            contents,
            res.width_px,
            res.height_px,
            &self.frame_channels(camera),
        )?;
        check_encoded_header(&contents, bytes)?;
        Ok(contents)
    }

    /// This start's logs: `logs/start_<n>/`.
    pub(crate) fn logs_dir(&self) -> PathBuf {
        self.staging
            .join("logs")
            .join(format!("start_{:02}", self.start))
    }

    /// Whether a frame is done: its file exists. A frame file appears only by a rename after it
    /// validated and its record was kept; [`Dataset::check_finished_frames`] clears any damaged
    /// since, before planning.
    pub(crate) fn frame_done(&self, camera: usize, frame: u32) -> bool {
        self.frame_path(camera, frame).is_file()
    }

    /// Shards covering the frames not done yet, `frames_per_shard` consecutive planned frames
    /// of one camera each, taken from the cameras in turn (the camera of the most pixels
    /// first): every camera's pace is measured early (the ETA, [`super::pace`]) and the
    /// costliest shards do not all come last.
    pub(crate) fn pending_shards(&self) -> Vec<Shard> {
        let mut cameras: Vec<(usize, Vec<Vec<u32>>)> = self
            .cameras
            .iter()
            .enumerate()
            .map(|(c, work)| {
                let blocks = work
                    .frames
                    .chunks(self.frames_per_shard)
                    .map(|block| {
                        block
                            .iter()
                            .copied()
                            .filter(|&f| !self.frame_done(c, f))
                            .collect::<Vec<u32>>()
                    })
                    .filter(|frames| !frames.is_empty())
                    .collect();
                (c, blocks)
            })
            .collect();
        cameras.sort_by_key(|(c, _)| std::cmp::Reverse(self.camera_pixels(*c)));
        let rounds = cameras.iter().map(|(_, b)| b.len()).max().unwrap_or(0);
        let mut shards = Vec::new();
        for round in 0..rounds {
            for (c, blocks) in &cameras {
                if let Some(frames) = blocks.get(round) {
                    shards.push(Shard {
                        id: shards.len(),
                        camera: *c,
                        frames: frames.clone(),
                    });
                }
            }
        }
        shards
    }

    /// Pixels Blender renders for a frame of camera `camera`.
    pub(crate) fn camera_pixels(&self, camera: usize) -> u64 {
        let r = self.cameras[camera].render.resolution();
        u64::from(r.width_px) * u64::from(r.height_px)
    }

    /// Total planned frames over all cameras.
    pub(crate) fn total_frames(&self) -> usize {
        self.cameras.iter().map(|c| c.frames.len()).sum()
    }

    /// The spec rendering `frames` of a shard's camera.
    pub(crate) fn shard_spec(&self, camera: usize, frames: &[u32]) -> ShardSpec {
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
}

/// The number of the next start of a run staged in `staging`: one more than the highest
/// `logs/start_<n>` folder there.
pub(crate) fn next_start(staging: &std::path::Path) -> u32 {
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
