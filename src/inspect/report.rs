//! `egogen inspect`'s job: EXR files' channels and statistics printed, and a PNG contact sheet
//! of their passes (one pass each with `--pass`, exposed as asked).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};

use crate::atomic_file::refuse_existing;

/// Prints every file's parts, passes and channel statistics (only the pass `only`, when
/// given) and, with `preview`, writes one sheet of their tiles; `exposure` is `none`, `auto`
/// or stops.
pub(crate) fn inspect_exr(
    files: &[PathBuf],
    preview: Option<&Path>,
    only: Option<&str>,
    exposure: &str,
) -> Result<()> {
    use super::preview::{auto_exposure, pass_preview_exposed, preview_kind};
    use super::ExrContents;
    let stops: Option<f32> = match exposure {
        "auto" => None,
        "none" => Some(0.0),
        s => Some(
            s.parse()
                .ok()
                .filter(|v: &f32| v.is_finite())
                .with_context(|| {
                    format!("--exposure: expected `none`, `auto` or a number of stops, found `{s}`")
                })?,
        ),
    };
    if let Some(p) = preview {
        refuse_existing(p)?;
    }
    let white = [255, 255, 255];
    let mut sheet: Option<crate::preview::RgbImage> = None;
    for file in files {
        let contents = ExrContents::read(file)?;
        let first = &contents.channels[0];
        println!(
            "{}: {} part(s), {} channel(s), {} x {} px",
            file.display(),
            contents.parts,
            contents.channels.len(),
            first.width,
            first.height
        );
        let passes: Vec<_> = contents
            .passes
            .iter()
            .filter(|p| only.is_none_or(|n| p.name == n))
            .collect();
        if passes.is_empty() {
            let names: Vec<&str> = contents.passes.iter().map(|p| p.name.as_str()).collect();
            bail!(
                "{}: no pass `{}`; it has {}",
                file.display(),
                only.unwrap_or_default(),
                names.join(", ")
            );
        }
        for (k, pass) in passes.iter().enumerate() {
            let name = if pass.name.is_empty() {
                "(unnamed)"
            } else {
                pass.name.as_str()
            };
            println!(
                "pass {k}: {name}  [{:?} preview]",
                preview_kind(&contents, pass)
            );
            for (comp, i) in &pass.components {
                let c = &contents.channels[*i];
                let s = c.stats();
                println!(
                    "  {comp:<6} {:<4} {:<6} min {:>12.6} max {:>12.6} mean {:>12.6}  NaN {} Inf {}",
                    c.sample_type, c.compression, s.min, s.max, s.mean, s.nan, s.inf
                );
            }
        }
        if preview.is_some() {
            for pass in passes {
                let scale = stops.map_or_else(|| auto_exposure(&contents, pass), f32::exp2);
                if stops.is_none() {
                    println!("{} {}: exposure ×{scale:.4}", file.display(), pass.name);
                }
                let tile = pass_preview_exposed(&contents, pass, scale);
                sheet = Some(match sheet {
                    None => tile,
                    Some(s) => {
                        let gap = crate::preview::RgbImage::new(8, s.height, white);
                        s.hconcat(&gap, white).hconcat(&tile, white)
                    }
                });
            }
        }
    }
    if let (Some(p), Some(sheet)) = (preview, sheet) {
        sheet.write_png(p)?;
        println!("wrote {}", p.display());
    }
    Ok(())
}
