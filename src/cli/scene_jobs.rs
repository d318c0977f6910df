//! `egogen scene inspect|generate`: the scene flags read (`--up`, `--unit-m`; the binary calls
//! `synth::scene_inspect` with them), generate's flags checked and its settings file loaded,
//! and the thin call that generates dwellings (`scene::dwelling::batch`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::scene::dwelling::batch::DwellingBatch;

/// How a scene file named on the command line is read: `--up y|z` (none: the format's default)
/// and `--unit-m` (metres per unit of the file; none: 1), checked.
pub(crate) fn scene_frame_flags(
    up: Option<&str>,
    unit_m: Option<f64>,
) -> Result<crate::scene::SceneFrame> {
    let up = match up {
        None => None,
        Some(name) => Some(
            crate::scene::UpAxis::from_name(name)
                .ok_or_else(|| anyhow::anyhow!("--up: expected y or z, got `{name}`"))?,
        ),
    };
    crate::scene::SceneFrame::new(up, unit_m).map_err(|m| anyhow::anyhow!("--unit-m: {m}"))
}

/// `egogen scene generate`'s flags.
#[derive(clap::Args, Debug)]
pub(crate) struct GenerateArgs {
    /// Seed of the (first) dwelling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Dwellings to make, from seeds --seed, --seed + 1, …
    #[arg(long, default_value_t = 1)]
    pub count: u64,
    /// Folder to write into (its dwelling files must not exist).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Generate and check only, write nothing (to measure generation).
    #[arg(long, conflicts_with = "out")]
    pub check_only: bool,
    /// TOML file of generator settings (keys of docs/SCENES.md "Generated dwellings"; every
    /// key optional).
    #[arg(long)]
    pub settings: Option<PathBuf>,
    /// Furniture catalogue folder (default: the shipped CC0 one, assets/furniture).
    #[arg(long)]
    pub catalogue: Option<PathBuf>,
    /// An opt-in furniture library added to the catalogue (a folder `tools/furniture_catalogue.py
    /// --library` made, e.g. a CC-BY one); repeatable. A dwelling that places one of its models
    /// gets `dwelling.attribution.md`, and every take made in it an `ATTRIBUTION.md`.
    #[arg(long = "with-catalogue", value_name = "DIR")]
    pub with_catalogue: Vec<PathBuf>,
    /// Also write one JSON line per dwelling here (seed, seconds, tries, rooms, area, pieces,
    /// models, seats, seating pieces with and without a seat found): `tools/dwelling_survey.py`
    /// reads it.
    #[arg(long)]
    pub summary: Option<PathBuf>,
}

/// Reads and checks a dwelling settings file (`scene generate --settings`); errors name the
/// file and the key.
pub fn load_dwelling_settings(path: &Path) -> Result<crate::scene::dwelling::DwellingSettings> {
    let settings: crate::scene::dwelling::DwellingSettings =
        crate::cli::config_file::load_toml(path)?;
    if let Some((key, message)) = settings.problem() {
        bail!("{}: `{key}`: {message}", path.display());
    }
    Ok(settings)
}

/// Generates `args.count` dwellings, writes them (unless checking only) and prints a line per
/// dwelling and a summary (time, rooms, area, objects, models, seats).
pub(crate) fn scene_generate(args: &GenerateArgs) -> Result<()> {
    use crate::scene::dwelling::{shipped_catalogue_dir, DwellingSettings};
    let out = match (&args.out, args.check_only) {
        (Some(out), _) => Some(out.clone()),
        (None, true) => None,
        (None, false) => bail!("--out DIR is required (or --check-only to write nothing)"),
    };
    if args.count == 0 {
        bail!("--count must be at least 1");
    }
    let settings = match &args.settings {
        Some(path) => load_dwelling_settings(path)?,
        None => DwellingSettings::default(),
    };
    let batch = DwellingBatch {
        seed: args.seed,
        count: args.count,
        out,
        settings,
        catalogue_dir: args.catalogue.clone().unwrap_or_else(shipped_catalogue_dir),
        added_catalogues: args.with_catalogue.clone(),
        summary: args.summary.clone(),
    };
    crate::scene::dwelling::batch::generate_dwellings(&batch, |count| {
        crate::progress::progress_bar("egogen scene generate", "dwellings", "dwellings", count, 0)
    })
}
