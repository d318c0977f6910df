//! The campaign's index: one Parquet table (`index.parquet`) listing every rendered frame of
//! every finished take — take, scene, seed, camera, frame, time, file, agents in view,
//! exposure — the form ML data loaders open directly (pandas, pyarrow, polars). Each finished
//! take's rows are kept in `work/index/<id>.json` so the index is rewritten from small files,
//! in take order, to the same bytes however the campaign was interrupted.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, FloatType, Int32Type, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::SerializedFileWriter;
use serde::{Deserialize, Serialize};

use super::plan::TakeDef;
use crate::supervisor::annotations::CameraAnnotations;

/// One frame of the campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IndexRow {
    pub take: String,
    pub scene: String,
    pub seed: u64,
    pub camera: String,
    pub wearer: String,
    pub frame: u32,
    pub time_s: f64,
    /// The frame file, relative to the campaign folder.
    pub file: String,
    /// Agents other than the wearer whose segmentation shows in the frame.
    pub agents_in_view: u32,
    /// The automatic exposure of the frame's colour (absent without the colour pass).
    pub colour_exposure: Option<f32>,
}

/// The Parquet schema of `index.parquet`.
pub const SCHEMA: &str = "message egogen_index {
  REQUIRED BYTE_ARRAY take (UTF8);
  REQUIRED BYTE_ARRAY scene (UTF8);
  REQUIRED INT64 seed;
  REQUIRED BYTE_ARRAY camera (UTF8);
  REQUIRED BYTE_ARRAY wearer (UTF8);
  REQUIRED INT32 frame;
  REQUIRED DOUBLE time_s;
  REQUIRED BYTE_ARRAY file (UTF8);
  REQUIRED INT32 agents_in_view;
  OPTIONAL FLOAT colour_exposure;
}";

/// The rows of a finished take, read from its cameras' annotations.
pub fn take_rows(take: &TakeDef, take_dir: &Path, campaign: &Path) -> Result<Vec<IndexRow>> {
    let cameras = take_dir.join("cameras");
    let mut names: Vec<String> = std::fs::read_dir(&cameras)
        .with_context(|| format!("reading {}", cameras.display()))?
        .flatten()
        .filter(|e| e.path().join("annotations.json").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let rel = take_dir
        .strip_prefix(campaign)
        .unwrap_or(take_dir)
        .to_path_buf();
    let mut rows = Vec::new();
    for camera in names {
        let path = cameras.join(&camera).join("annotations.json");
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        let doc: CameraAnnotations = serde_json::from_str(&text)
            .with_context(|| format!("{}: not an annotations file", path.display()))?;
        for f in &doc.frames {
            rows.push(IndexRow {
                take: take.id.clone(),
                scene: take.scene.display().to_string(),
                seed: take.seed,
                camera: camera.clone(),
                wearer: doc.wearer.clone(),
                frame: f.frame,
                time_s: f.time_s,
                file: rel
                    .join("cameras")
                    .join(&camera)
                    .join(&f.file)
                    .display()
                    .to_string(),
                agents_in_view: f.agents.iter().filter(|a| a.in_view && !a.wearer).count() as u32,
                colour_exposure: f.colour_exposure,
            });
        }
    }
    Ok(rows)
}

/// Where a finished take's rows are kept.
pub fn rows_path(campaign: &Path, take: &str) -> PathBuf {
    campaign.join("work/index").join(format!("{take}.json"))
}

/// Keeps a finished take's rows for the index.
pub fn keep_rows(campaign: &Path, take: &str, rows: &[IndexRow]) -> Result<()> {
    let path = rows_path(campaign, take);
    std::fs::create_dir_all(path.parent().unwrap())
        .with_context(|| format!("creating {}", path.parent().unwrap().display()))?;
    crate::atomic_file::write_atomically(&path, &serde_json::to_vec(rows)?)
        .with_context(|| format!("writing {}", path.display()))
}

/// Reads a finished take's kept rows (`None` when they are not kept).
pub fn kept_rows(campaign: &Path, take: &str) -> Option<Vec<IndexRow>> {
    let text = std::fs::read_to_string(rows_path(campaign, take)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Writes `rows` as a Parquet file (one row group, uncompressed: the bytes depend on the rows
/// only), atomically.
pub fn write_index(path: &Path, rows: &[IndexRow]) -> Result<()> {
    let schema = Arc::new(parquet::schema::parser::parse_message_type(SCHEMA)?);
    let props = Arc::new(
        WriterProperties::builder()
            .set_created_by("egogen".into())
            .build(),
    );
    let mut bytes = Vec::new();
    {
        let mut writer = SerializedFileWriter::new(&mut bytes, schema, props)?;
        let mut group = writer.next_row_group()?;
        let text = |f: fn(&IndexRow) -> &str| -> Vec<ByteArray> {
            rows.iter().map(|r| ByteArray::from(f(r))).collect()
        };
        let mut column = 0;
        while let Some(mut col) = group.next_column()? {
            match column {
                0 => write_text(&mut col, &text(|r| &r.take))?,
                1 => write_text(&mut col, &text(|r| &r.scene))?,
                2 => {
                    let v: Vec<i64> = rows.iter().map(|r| r.seed as i64).collect();
                    col.typed::<Int64Type>().write_batch(&v, None, None)?;
                }
                3 => write_text(&mut col, &text(|r| &r.camera))?,
                4 => write_text(&mut col, &text(|r| &r.wearer))?,
                5 => {
                    let v: Vec<i32> = rows.iter().map(|r| r.frame as i32).collect();
                    col.typed::<Int32Type>().write_batch(&v, None, None)?;
                }
                6 => {
                    let v: Vec<f64> = rows.iter().map(|r| r.time_s).collect();
                    col.typed::<DoubleType>().write_batch(&v, None, None)?;
                }
                7 => write_text(&mut col, &text(|r| &r.file))?,
                8 => {
                    let v: Vec<i32> = rows.iter().map(|r| r.agents_in_view as i32).collect();
                    col.typed::<Int32Type>().write_batch(&v, None, None)?;
                }
                _ => {
                    let v: Vec<f32> = rows.iter().filter_map(|r| r.colour_exposure).collect();
                    let def: Vec<i16> = rows
                        .iter()
                        .map(|r| i16::from(r.colour_exposure.is_some()))
                        .collect();
                    col.typed::<FloatType>().write_batch(&v, Some(&def), None)?;
                }
            }
            col.close()?;
            column += 1;
        }
        group.close()?;
        writer.close()?;
    }
    crate::atomic_file::write_atomically(path, &bytes)
        .with_context(|| format!("writing {}", path.display()))
}

fn write_text(
    col: &mut parquet::file::writer::SerializedColumnWriter,
    v: &[ByteArray],
) -> Result<()> {
    col.typed::<ByteArrayType>().write_batch(v, None, None)?;
    Ok(())
}
