//! The campaign's index: one Parquet table (`index.parquet`) listing every rendered frame of
//! every finished take — take, scene, seed, camera, frame, time, file, agents in view,
//! exposure, what the wearer and the people in view do — the form ML data loaders open
//! directly (pandas, pyarrow, polars). Each finished take's rows are kept in
//! `work/index/<id>.json` so the index is rewritten from small files, in take order, to the
//! same bytes however the campaign was interrupted.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, FloatType, Int32Type, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::SerializedFileWriter;
use serde::{Deserialize, Serialize};

use super::plan::TakeDef;
use crate::export::annotations::CameraAnnotations;

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
    /// What the wearer does (`walk`, `stand`, `sit`, `pick_up`), in a take with activities
    /// (absent where people only walk). Required in kept rows, so rows kept before the column
    /// existed are read again from the take's annotations.
    #[serde(deserialize_with = "Option::deserialize")]
    pub activity: Option<String>,
    /// Its phase (`approach`, `transition`, `hold`; absent while walking).
    #[serde(deserialize_with = "Option::deserialize")]
    pub activity_phase: Option<String>,
    /// What the agents in view do, each activity once, in name order, comma-separated
    /// (`sit,walk`; empty with no one in view), in a take with activities.
    #[serde(deserialize_with = "Option::deserialize")]
    pub activities_in_view: Option<String>,
}

/// The Parquet schema of `index.parquet`.
pub(crate) const SCHEMA: &str = "message egogen_index {
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
  OPTIONAL BYTE_ARRAY activity (UTF8);
  OPTIONAL BYTE_ARRAY activity_phase (UTF8);
  OPTIONAL BYTE_ARRAY activities_in_view (UTF8);
}";

/// The rows of a finished take, read from its cameras' annotations.
pub(crate) fn take_rows(take: &TakeDef, take_dir: &Path, campaign: &Path) -> Result<Vec<IndexRow>> {
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
            let wearer = f.agents.iter().find(|a| a.wearer);
            let labelled = f.agents.iter().any(|a| a.activity.is_some());
            let in_view = labelled.then(|| {
                let mut names: Vec<&str> = f
                    .agents
                    .iter()
                    .filter(|a| a.in_view && !a.wearer)
                    .map(|a| a.activity.map_or("walk", |l| l.activity.name()))
                    .collect();
                names.sort_unstable();
                names.dedup();
                names.join(",")
            });
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
                activity: wearer
                    .and_then(|a| a.activity)
                    .map(|l| l.activity.name().to_string()),
                activity_phase: wearer
                    .and_then(|a| a.activity)
                    .and_then(|l| l.phase)
                    .map(|p| p.name().to_string()),
                activities_in_view: in_view,
            });
        }
    }
    Ok(rows)
}

/// Where a finished take's rows are kept.
pub(crate) fn rows_path(campaign: &Path, take: &str) -> PathBuf {
    campaign.join("work/index").join(format!("{take}.json"))
}

/// Keeps a finished take's rows for the index.
pub(crate) fn keep_rows(campaign: &Path, take: &str, rows: &[IndexRow]) -> Result<()> {
    let path = rows_path(campaign, take);
    std::fs::create_dir_all(path.parent().unwrap())
        .with_context(|| format!("creating {}", path.parent().unwrap().display()))?;
    crate::atomic_file::write_atomically(&path, &serde_json::to_vec(rows)?)
        .with_context(|| format!("writing {}", path.display()))
}

/// Reads a finished take's kept rows (`None` when they are not kept).
pub(crate) fn kept_rows(campaign: &Path, take: &str) -> Option<Vec<IndexRow>> {
    let text = std::fs::read_to_string(rows_path(campaign, take)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Writes the index as a Parquet file from `groups` (each take's rows, in order): whole takes
/// gathered into row groups of at least [`GROUP_ROWS`] rows, uncompressed, so the bytes depend
/// on the rows only and about one group is in memory at a time. Written under a temporary name and renamed. Returns the rows written.
pub fn write_index<I>(path: &Path, groups: I) -> Result<usize>
where
    I: IntoIterator<Item = Result<Vec<IndexRow>>>,
{
    let tmp = path.with_extension("parquet.tmp");
    match write_groups(&tmp, groups) {
        Ok(n) => {
            std::fs::rename(&tmp, path)
                .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
            Ok(n)
        }
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e.context(format!("writing {}", path.display())))
        }
    }
}

fn write_groups<I>(tmp: &Path, groups: I) -> Result<usize>
where
    I: IntoIterator<Item = Result<Vec<IndexRow>>>,
{
    let schema = Arc::new(parquet::schema::parser::parse_message_type(SCHEMA)?);
    let props = Arc::new(
        WriterProperties::builder()
            .set_created_by("egogen".into())
            .build(),
    );
    let file = std::fs::File::create(tmp).with_context(|| format!("creating {}", tmp.display()))?;
    let mut writer = SerializedFileWriter::new(std::io::BufWriter::new(file), schema, props)?;
    let mut total = 0;
    let mut pending: Vec<IndexRow> = Vec::new();
    for rows in groups {
        pending.extend(rows?);
        if pending.len() >= GROUP_ROWS {
            total += pending.len();
            write_group(&mut writer, &pending)?;
            pending.clear();
        }
    }
    if !pending.is_empty() {
        total += pending.len();
        write_group(&mut writer, &pending)?;
    }
    let file = writer.into_inner()?;
    file.into_inner()
        .map_err(|e| e.into_error())?
        .sync_all()
        .with_context(|| format!("writing {}", tmp.display()))?;
    Ok(total)
}

/// Rows per row group at least (whole takes are added until a group has this many): groups
/// large enough for Parquet's per-group overhead to vanish, small enough to bound memory.
pub(crate) const GROUP_ROWS: usize = 65_536;

/// Writes `rows` as one row group.
fn write_group<W: std::io::Write + Send>(
    writer: &mut SerializedFileWriter<W>,
    rows: &[IndexRow],
) -> Result<()> {
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
            9 => {
                let v: Vec<f32> = rows.iter().filter_map(|r| r.colour_exposure).collect();
                let def: Vec<i16> = rows
                    .iter()
                    .map(|r| i16::from(r.colour_exposure.is_some()))
                    .collect();
                col.typed::<FloatType>().write_batch(&v, Some(&def), None)?;
            }
            10 => write_optional_text(&mut col, rows, |r| r.activity.as_deref())?,
            11 => write_optional_text(&mut col, rows, |r| r.activity_phase.as_deref())?,
            _ => write_optional_text(&mut col, rows, |r| r.activities_in_view.as_deref())?,
        }
        col.close()?;
        column += 1;
    }
    group.close()?;
    Ok(())
}

fn write_optional_text(
    col: &mut parquet::file::writer::SerializedColumnWriter,
    rows: &[IndexRow],
    f: fn(&IndexRow) -> Option<&str>,
) -> Result<()> {
    let v: Vec<ByteArray> = rows.iter().filter_map(f).map(ByteArray::from).collect();
    let def: Vec<i16> = rows.iter().map(|r| i16::from(f(r).is_some())).collect();
    col.typed::<ByteArrayType>()
        .write_batch(&v, Some(&def), None)?;
    Ok(())
}

fn write_text(
    col: &mut parquet::file::writer::SerializedColumnWriter,
    v: &[ByteArray],
) -> Result<()> {
    col.typed::<ByteArrayType>().write_batch(v, None, None)?;
    Ok(())
}
