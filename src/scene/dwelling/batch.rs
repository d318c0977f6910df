//! `egogen scene generate`'s job: dwellings generated from consecutive seeds, written (unless
//! only checked) and summarised, a line each and one for all (`--summary`: a JSON line per
//! dwelling, read by `tools/dwelling_survey.py`). `cli::scene_jobs` checks the flags and loads
//! the settings file.

use std::path::PathBuf;

use anyhow::{bail, Result};
use indicatif::ProgressBar;

use super::DwellingSettings;

/// What `egogen scene generate` was asked, checked.
pub(crate) struct DwellingBatch {
    /// Seed of the first dwelling.
    pub(crate) seed: u64,
    /// Dwellings to make (at least 1), from seeds `seed`, `seed + 1`, …
    pub(crate) count: u64,
    /// Folder to write into (its dwelling files must not exist); none: generate and check only.
    pub(crate) out: Option<PathBuf>,
    /// The generator's settings.
    pub(crate) settings: DwellingSettings,
    /// Furniture catalogue folder.
    pub(crate) catalogue_dir: PathBuf,
    /// Opt-in libraries added to it.
    pub(crate) added_catalogues: Vec<PathBuf>,
    /// Where to write one JSON line per dwelling, if anywhere.
    pub(crate) summary: Option<PathBuf>,
}

/// Generates `args.count` dwellings, writes them (unless checking only) and prints a line per
/// dwelling and a summary (time, rooms, area, objects, models, seats); `progress_bar` makes the
/// bar over the dwellings (its length given).
pub(crate) fn generate_dwellings(
    args: &DwellingBatch,
    progress_bar: impl FnOnce(u64) -> ProgressBar,
) -> Result<()> {
    use super::{dwelling_files, generate, Catalogue};
    let (out, settings) = (&args.out, &args.settings);
    let catalogue = Catalogue::load_with(&args.catalogue_dir, &args.added_catalogues)?;
    let dir_of = |seed: u64| {
        out.as_ref().map(|o| {
            if args.count == 1 {
                o.clone()
            } else {
                o.join(format!("seed_{seed}"))
            }
        })
    };
    let last = args
        .seed
        .checked_add(args.count - 1)
        .ok_or_else(|| anyhow::anyhow!("--seed + --count overflows"))?;
    for seed in args.seed..=last {
        if let Some(dir) = dir_of(seed) {
            let (glb, json) = dwelling_files(&dir);
            for f in [super::attribution::file_beside(&glb), glb, json] {
                crate::atomic_file::refuse_existing(&f)?;
            }
        }
    }
    if let Some(summary) = &args.summary {
        crate::atomic_file::refuse_existing(summary)?;
    }
    let bar = progress_bar(args.count);
    let mut times = Vec::new();
    let mut models = std::collections::BTreeSet::new();
    let mut lines = String::new();
    let mut failed = Vec::new();
    for seed in args.seed..=last {
        let t = std::time::Instant::now();
        let d = match generate(settings, &catalogue, seed) {
            Ok(d) => d,
            Err(e @ super::DwellingError::NoDwelling { .. }) if args.count > 1 => {
                bar.println(format!("seed {seed}: {e}"));
                failed.push(seed);
                bar.inc(1);
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        if let Some(dir) = dir_of(seed) {
            d.write(&catalogue, &dir)?;
        }
        let seconds = t.elapsed().as_secs_f64();
        if args.summary.is_some() {
            lines.push_str(&dwelling_summary_line(&d, seconds).to_string());
            lines.push('\n');
        }
        times.push(seconds);
        models.extend(d.placed.iter().map(|p| p.model.clone()));
        let area: f64 = d.plan.rooms.iter().map(|r| r.area_m2()).sum();
        let line = format!(
            "seed {seed}: {} rooms, {area:.1} m², {} pieces ({} models), {} seats, {} tries, {seconds:.2} s",
            d.plan.rooms.len(),
            d.placed.len(),
            d.placed.iter().map(|p| &p.model).collect::<std::collections::BTreeSet<_>>().len(),
            d.seats_per_room.iter().sum::<usize>(),
            d.tries
        );
        if args.count == 1 {
            println!("{line}");
        } else {
            bar.inc(1);
            bar.println(line);
        }
    }
    bar.finish_and_clear();
    if let Some(summary) = &args.summary {
        crate::atomic_file::write_atomically(summary, lines.as_bytes())
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", summary.display()))?;
    }
    if times.is_empty() {
        bail!("no dwelling could be made (seeds {failed:?})");
    }
    times.sort_by(f64::total_cmp);
    let q = |p: f64| times[((times.len() - 1) as f64 * p).round() as usize];
    println!(
        "{} dwellings: {:.2} s median, {:.2} s p95 each; {} catalogue models used",
        times.len(),
        q(0.5),
        q(0.95),
        models.len()
    );
    if let Some(o) = out {
        println!("written to {}", o.display());
    }
    if !failed.is_empty() {
        bail!(
            "{} of {} seeds made no dwelling: {failed:?}",
            failed.len(),
            args.count
        );
    }
    Ok(())
}

/// One dwelling's line of `--summary`.
fn dwelling_summary_line(d: &super::Dwelling, seconds: f64) -> serde_json::Value {
    use super::Role;
    let seating = [
        Role::Sofa,
        Role::Armchair,
        Role::DiningChair,
        Role::DeskChair,
        Role::Stool,
        Role::Bed,
    ];
    let (mut seating_with, mut seating_without, mut other_with, mut built_with) = (0, 0, 0, 0);
    for o in &d.objects {
        let seating = o.piece.map(|k| seating.contains(&d.placed[k].role));
        match (seating, o.seats > 0) {
            (Some(true), true) => seating_with += 1,
            (Some(true), false) => seating_without += 1,
            (Some(false), true) => other_with += 1,
            (None, true) => built_with += 1,
            _ => {}
        }
    }
    serde_json::json!({
        "seed": d.seed,
        "seconds": seconds,
        "tries": d.tries,
        "redrawn": d.redrawn,
        "rooms": d.plan.rooms.iter().map(|r| r.kind.name()).collect::<Vec<_>>(),
        "area_m2": d.plan.rooms.iter().map(|r| r.area_m2()).sum::<f64>(),
        "pieces": d.placed.len(),
        "models": d.placed.iter().map(|p| p.model.as_str()).collect::<Vec<_>>(),
        "roles": d.placed.iter().map(|p| format!("{:?}", p.role)).collect::<Vec<_>>(),
        "piece_rooms": d.placed.iter().map(|p| d.plan.rooms[p.room].kind.name()).collect::<Vec<_>>(),
        "seats": d.seats_per_room.iter().sum::<usize>(),
        "seating_with_seat": seating_with,
        "seating_without_seat": seating_without,
        "other_with_seat": other_with,
        "built_with_seat": built_with,
        "triangles": d.mesh.triangles.len(),
    })
}
