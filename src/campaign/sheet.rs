//! The campaign's contact sheet (`contact_sheet.png`): the middle frame of each finished take's
//! first camera, automatically exposed as its COLMAP image is, tiled in campaign order (the
//! first 48 takes), so a user looks across the campaign before reading it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::index::IndexRow;
use crate::exr_file::ExrContents;
use crate::inspect::preview::pass_preview_exposed;
use crate::preview::RgbImage;

/// The sheet's name in the campaign folder.
pub(crate) const SHEET_FILE: &str = "contact_sheet.png";
/// Takes on the sheet at most, and its cell size.
const MAX_TAKES: usize = 48;
const CELL_PX: usize = 176;

/// The frame of a take's rows on the sheet: the middle one of its first camera.
pub(crate) fn middle_frame(rows: &[IndexRow]) -> Option<&IndexRow> {
    let camera = &rows.first()?.camera;
    let of_camera: Vec<&IndexRow> = rows.iter().filter(|r| &r.camera == camera).collect();
    Some(of_camera[of_camera.len() / 2])
}

/// Writes `contact_sheet.png` from each take's frame ([`middle_frame`], in take order; the
/// first 48); `None` when there is none.
pub(crate) fn write_contact_sheet(campaign: &Path, frames: &[IndexRow]) -> Result<Option<PathBuf>> {
    let mut tiles = Vec::new();
    for row in frames.iter().take(MAX_TAKES) {
        let path = campaign.join(&row.file);
        let contents =
            ExrContents::read(&path).with_context(|| format!("reading {}", path.display()))?;
        if let Some(colour) = contents
            .passes
            .iter()
            .find(|p| p.name == "rgb" || p.name == "gray")
        {
            let image = pass_preview_exposed(&contents, colour, row.colour_exposure.unwrap_or(1.0));
            tiles.push(image.downscaled_to(CELL_PX - 4));
        }
    }
    if tiles.is_empty() {
        return Ok(None);
    }
    let per_row = (tiles.len() as f64).sqrt().ceil() as usize;
    let sheet = RgbImage::contact_sheet(&tiles, CELL_PX, per_row.max(1), [24, 24, 24]);
    let path = campaign.join(SHEET_FILE);
    sheet
        .write_png(&path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(Some(path))
}
