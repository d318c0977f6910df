//! What the supervisor keeps of a finished frame, so that no frame file is read again after
//! it is written: the frame file's size and SHA-256, the files the take's outputs made of it
//! (COLMAP's image, written from the same pixels: [`crate::export::TakeExport::frame_file`])
//! with theirs, and its annotation (agents in view, 2D joints and their visibility, boxes,
//! colour exposure). All of it is computed in [`Dataset::finish_frame`] from the frame's bytes
//! while they are in memory; the outputs of the finished take are then built from the records.
//!
//! A record lives in `work/frames/<camera>/frame_NNNNN.json` (scratch, not data). It is written
//! before its frame file is renamed into place, so every finished frame has one; a resume reads
//! the finished frames once anyway (to find damaged ones) and rebuilds any record that is
//! missing or does not match its file.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::staged::Dataset;
use crate::atomic_file::write_atomically;
use crate::export::annotate::annotate_frame;
use crate::export::take::{slashed, FileFacts, FinishedFrame, FrameRecord};
use crate::exr_file::ExrContents;

impl Dataset {
    /// Where a camera's frame record is kept.
    pub(crate) fn record_path(&self, camera: usize, frame: u32) -> PathBuf {
        self.staging
            .join("work/frames")
            .join(&self.cameras[camera].camera.name)
            .join(format!("frame_{frame:05}.json"))
    }

    /// Computes a frame's record from its validated `contents` (what the frame file holds,
    /// whose own facts are `frame_file`), writes the files the take's outputs make of it, and
    /// keeps the record.
    pub(crate) fn record_frame(
        &self,
        camera: usize,
        frame: u32,
        contents: &ExrContents,
        frame_file: FileFacts,
    ) -> Result<FrameRecord> {
        let work = &self.cameras[camera];
        let annotation = annotate_frame(work, frame, &self.agents, contents);
        let finished = FinishedFrame {
            contents,
            annotation: &annotation,
        };
        let mut exported = BTreeMap::new();
        for export in self.exports.iter() {
            let Some(relative) = export.frame_file_path(work, frame) else {
                continue;
            };
            let bytes = export.frame_file(&finished)?;
            let path = self.staging.join(&relative);
            create_parent(&path)?;
            write_atomically(&path, &bytes)
                .with_context(|| format!("writing {}", path.display()))?;
            exported.insert(slashed(&relative), FileFacts::of(&bytes));
        }
        let record = FrameRecord {
            frame_file,
            exported,
            annotation,
        };
        let path = self.record_path(camera, frame);
        create_parent(&path)?;
        write_atomically(&path, serde_json::to_string(&record)?.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(record)
    }

    /// A finished frame's record.
    pub(crate) fn load_record(&self, camera: usize, frame: u32) -> Result<FrameRecord> {
        let path = self.record_path(camera, frame);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("{}: not a frame record", path.display()))
    }

    /// Whether a finished frame's record is there and matches what is on disk: the frame
    /// file's `facts`, and exactly the files the take's outputs make of the frame, each at the
    /// size recorded.
    pub(crate) fn record_matches(&self, camera: usize, frame: u32, facts: &FileFacts) -> bool {
        let Ok(record) = self.load_record(camera, frame) else {
            return false;
        };
        let work = &self.cameras[camera];
        let expected: Vec<String> = self
            .exports
            .iter()
            .filter_map(|e| e.frame_file_path(work, frame))
            .map(|p| slashed(&p))
            .collect();
        let files_ok = expected.len() == record.exported.len()
            && expected.iter().all(|p| {
                record.exported.get(p).is_some_and(|f| {
                    std::fs::metadata(self.staging.join(p)).is_ok_and(|m| m.len() == f.bytes)
                })
            });
        record.frame_file == *facts && files_ok
    }

    /// Every planned frame's record, camera by camera: all frames must be finished.
    pub(crate) fn records(&self) -> Result<Vec<Vec<FrameRecord>>> {
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
}

fn create_parent(path: &std::path::Path) -> Result<()> {
    let dir = path.parent().unwrap_or(path);
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))
}
