//! A campaign config (`[campaign]`) and the takes it defines: the run config every take starts
//! from, and what varies per take — scene (paths, globs, generated floor plans, each with the
//! frame it is read in), seed, crowd size, duration, rig, activity mix. Each take is that run
//! config with `egogen-run`'s command-line overrides, so a take rendered alone is the same command; its id
//! is derived from what defines it.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use rand_core::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::cli::config_file::load_toml;
use crate::cli::overrides::{resume_fingerprint, RunOverrides};
use crate::cli::RawRun;
use crate::manifest::sha256_hex;
use crate::scene::{SceneFrame, UpAxis};
use crate::synth::activity::ActivityWeights;

/// A campaign config file: `[campaign]` only.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCampaignFile {
    pub campaign: RawCampaign,
}

/// `[campaign]`. Paths are relative to the campaign file's folder.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCampaign {
    /// The run config every take starts from (it needs a `[render]` section).
    pub run: PathBuf,
    /// The campaign folder: `takes/<id>/`, `index.parquet`, `campaign.json`, `logs/`.
    pub out: PathBuf,
    /// How many takes.
    pub takes: usize,
    /// Take k has seed `first_seed + k` (every seed of the run: motion, lighting, wear, skin, outfits).
    #[serde(default)]
    pub first_seed: u64,
    /// Scene files or globs (`rooms/*.obj`); take k walks scene k mod (number of scenes),
    /// the globs' matches in name order, then the floor plans. An entry is a path, read as
    /// the run config's `[scene] up_axis` and `unit_m` say, or a table `{ path = "…",
    /// up_axis = "y", unit_m = 0.01 }` giving the frame its files are in ([`scene_entry`]).
    #[serde(default)]
    pub scenes: Vec<toml::Value>,
    /// Generated four-room dwellings, by seed (as `egogen policy rooms --seed S --count 1
    /// --obj-dir`), written to `scenes/plan_<seed>.obj` in the campaign folder.
    #[serde(default)]
    pub floor_plans: Vec<u64>,
    /// Generated furnished dwellings, by seed (as `egogen scene generate --seed S`: the
    /// `dwelling_settings`, the shipped catalogue), written to `scenes/dwelling_<seed>.glb` with its
    /// sidecar `scenes/dwelling_<seed>.json` in the campaign folder; after `floor_plans` in
    /// the scenes' order. A list of seeds, or `{ first = N, count = M }` for seeds N … N+M−1
    /// ([`dwelling_seeds`]).
    #[serde(default)]
    pub dwellings: Option<toml::Value>,
    /// Opt-in furniture libraries added to the shipped catalogue for `dwellings` (folders
    /// `tools/furniture_catalogue.py --library` made, relative to the campaign file): the
    /// campaign then carries `ATTRIBUTION.md`, and so does each take in a dwelling using one.
    #[serde(default)]
    pub dwelling_catalogues: Vec<PathBuf>,
    /// The generator's settings for `dwellings` (a TOML file of the keys `egogen scene
    /// generate --settings` reads, relative to the campaign file; default: the defaults).
    pub dwelling_settings: Option<PathBuf>,
    /// People per take, drawn uniformly in `[lo, hi]` from the take's seed (default: the run
    /// config's `crowd.count`).
    pub crowd_count: Option<[usize; 2]>,
    /// Seconds of motion per take, drawn uniformly in `[lo, hi]` (0.1 s steps) from the take's
    /// seed (default: the run config's).
    pub duration_s: Option<[f64; 2]>,
    /// Camera rigs, take k wearing rig k mod (number of rigs) (default: the run config's).
    #[serde(default)]
    pub rigs: Vec<PathBuf>,
    /// What people do when a walk ends, take k using entry k mod (number of entries) as its
    /// `activities.weights`, e.g. `[{ walk = 1 }, { walk = 1, sit = 1, stand = 1 }]`;
    /// weights an entry does not name are 0 (default: the run config's).
    #[serde(default)]
    pub activity_weights: Vec<toml::Table>,
    /// Takes are staged only while the campaign folder's file system has this much free
    /// space; below it the campaign pauses (and says so) until space is freed (default 1 GB).
    pub min_free_disk_gb: Option<f64>,
}

/// A checked campaign.
#[derive(Debug, Clone)]
pub struct CampaignPlan {
    /// The campaign file.
    pub config: PathBuf,
    /// The run config every take starts from.
    pub run: PathBuf,
    pub out: PathBuf,
    pub takes: Vec<TakeDef>,
    pub min_free_disk_bytes: u64,
    /// Floor plans to write before the first take (seed, file): those some take walks.
    pub floor_plans: Vec<(u64, PathBuf)>,
    /// Dwellings to generate before the first take (seed, GLB file): those some take walks.
    pub dwellings: Vec<(u64, PathBuf)>,
    /// Opt-in furniture libraries the dwellings are furnished from besides the shipped one.
    pub dwelling_catalogues: Vec<PathBuf>,
    /// How the dwellings are drawn.
    pub dwelling_settings: crate::scene::dwelling::DwellingSettings,
    /// SHA-256 of what defines the campaign (its takes' definitions): a resume must match.
    pub fingerprint: String,
}

/// One take: the run config with these overrides.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct TakeDef {
    /// Position in the campaign (index order).
    pub index: usize,
    /// `<scene>-s<seed>[-n<count>]-<8 hex>`: the hex from the take's effective config.
    pub id: String,
    pub scene: PathBuf,
    /// The scene file's up axis where its campaign entry gives one (else the run config's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up_axis: Option<UpAxis>,
    /// The scene file's metres per unit where its campaign entry gives them (else the run
    /// config's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_m: Option<f64>,
    pub seed: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crowd_count: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig: Option<PathBuf>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub activity_weights: Option<ActivityWeights>,
}

impl TakeDef {
    /// The take's overrides of the run config, output in `takes_dir/<id>`.
    pub(crate) fn overrides(&self, takes_dir: &Path) -> RunOverrides {
        RunOverrides {
            out: Some(takes_dir.join(&self.id)),
            seed: Some(self.seed),
            rig: self.rig.clone(),
            scene: Some(self.scene.clone()),
            up_axis: self.up_axis,
            unit_m: self.unit_m,
            crowd_count: self.crowd_count,
            duration_s: self.duration_s,
            activity_weights: self.activity_weights,
            materials: None,
            workers: None,
            backend: None,
        }
    }

    /// The `egogen-run` command that renders this take alone, byte for byte the same.
    pub fn command(&self, run: &Path, takes_dir: &Path) -> String {
        let o = self.overrides(takes_dir);
        let mut c = format!("egogen-run {}", quote(run));
        if let Some(out) = &o.out {
            c += &format!(" --out {}", quote(out));
        }
        c += &format!(" --seed {}", self.seed);
        c += &format!(" --scene {}", quote(&self.scene));
        if let Some(up) = self.up_axis {
            c += &format!(" --up {}", up.name());
        }
        if let Some(unit) = self.unit_m {
            c += &format!(" --unit-m {unit}");
        }
        if let Some(n) = self.crowd_count {
            c += &format!(" --crowd-count {n}");
        }
        if let Some(d) = self.duration_s {
            c += &format!(" --duration {d}");
        }
        if let Some(r) = &self.rig {
            c += &format!(" --rig {}", quote(r));
        }
        if let Some(w) = &self.activity_weights {
            c += &format!(" --activity-weights {}", w.flag());
        }
        c
    }
}

fn quote(p: &Path) -> String {
    let s = p.display().to_string();
    if s.chars()
        .all(|c| c.is_ascii_alphanumeric() || "/._-+:".contains(c))
    {
        s
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// Whether a TOML file is a campaign (it has a `[campaign]` table).
pub fn is_campaign(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| t.parse::<toml::Table>().ok())
        .is_some_and(|t| t.contains_key("campaign"))
}

/// Reads and checks a campaign file and defines its takes.
pub fn plan_campaign(path: &Path) -> Result<CampaignPlan> {
    let raw: RawCampaignFile = load_toml(path)?;
    let c = raw.campaign;
    let bad = |key: &str, what: String| -> anyhow::Error {
        anyhow::anyhow!("campaign {}: key `campaign.{key}`: {what}", path.display())
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let at = |p: &Path| lexical(&std::path::absolute(dir.join(p)).unwrap_or_else(|_| dir.join(p)));
    let run = at(&c.run);
    if run.canonicalize().ok() == path.canonicalize().ok() {
        return Err(bad(
            "run",
            format!(
                "\"{}\" is the campaign file itself; expected the run config (egogen-run's) \
                 every take varies",
                c.run.display()
            ),
        ));
    }
    if !run.is_file() {
        return Err(bad("run", format!("{} is not a file", run.display())));
    }
    let out = at(&c.out);
    if c.takes == 0 {
        return Err(bad("takes", "expected at least 1 take".into()));
    }
    const MAX_TAKES: usize = 1_000_000;
    if c.takes > MAX_TAKES {
        return Err(bad(
            "takes",
            format!("{}: at most {MAX_TAKES} takes in one campaign", c.takes),
        ));
    }
    // Seeds are TOML integers in each take's config (signed 64-bit): the last take's too.
    let last_seed = c.first_seed.checked_add(c.takes as u64 - 1);
    if last_seed.is_none_or(|s| s > i64::MAX as u64) {
        return Err(bad(
            "first_seed",
            format!(
                "{}: the takes' seeds first_seed … first_seed + takes − 1 ({} takes) must stay below 2^63 = 9223372036854775808",
                c.first_seed, c.takes
            ),
        ));
    }
    let mut scenes = scene_files(&c, dir, &at, &bad)?;
    let floor_plans: Vec<(u64, PathBuf)> = c
        .floor_plans
        .iter()
        .map(|&s| (s, out.join("scenes").join(format!("plan_{s}.obj"))))
        .collect();
    let base = RawRun::load(&run)?;
    // The floor plans are written z up in metres: said so per take where the run config reads
    // its scenes in another frame.
    let plan_frame = if base.scene.up_axis.is_some() || base.scene.unit_m.is_some() {
        (Some(UpAxis::Z), Some(1.0))
    } else {
        (None, None)
    };
    scenes.extend(floor_plans.iter().map(|(_, p)| (p.clone(), plan_frame)));
    let dwelling_seeds = match &c.dwellings {
        Some(value) => dwelling_seeds(value).map_err(|what| bad("dwellings", what))?,
        None => Vec::new(),
    };
    let dwellings: Vec<(u64, PathBuf)> = dwelling_seeds
        .iter()
        .map(|&s| (s, out.join("scenes").join(format!("dwelling_{s}.glb"))))
        .collect();
    // Dwellings are glTF (y up, metres): said so per take where the run config reads its
    // scenes in another frame.
    let dwelling_frame = if base.scene.up_axis.is_some() || base.scene.unit_m.is_some() {
        (Some(UpAxis::Y), Some(1.0))
    } else {
        (None, None)
    };
    scenes.extend(dwellings.iter().map(|(_, p)| (p.clone(), dwelling_frame)));
    if base.render.is_none() {
        return Err(bad(
            "run",
            format!(
                "{} has no [render] section: a campaign renders its takes",
                run.display()
            ),
        ));
    }
    if scenes.is_empty() {
        // The run config's own scene.
        scenes.push((
            match &base.scene.path {
                Some(p) => at(&run.parent().unwrap_or(Path::new(".")).join(p)),
                None => crate::cli::config_file::crate_root().join("assets/scenes/apartment.glb"),
            },
            (None, None),
        ));
    }
    check_crowd_count(&c, &base, &run, &bad)?;
    check_duration(&c, &bad)?;
    let rigs: Vec<PathBuf> = c.rigs.iter().map(|r| at(r)).collect();
    for r in &rigs {
        if !r.is_file() {
            return Err(bad("rigs", format!("{} is not a file", r.display())));
        }
    }
    let mixes = activity_mixes(&c, &bad)?;
    if !mixes.is_empty() && base.motion.source != crate::cli::config::MotionSource::Agents {
        return Err(bad(
            "activity_weights",
            format!(
                "{} does not make agents (`motion.source = \"agents\"`): nobody to do activities",
                run.display()
            ),
        ));
    }
    let min_free_disk_gb = c.min_free_disk_gb.unwrap_or(1.0);
    if !(min_free_disk_gb.is_finite() && min_free_disk_gb >= 0.0) {
        return Err(bad(
            "min_free_disk_gb",
            format!("expected a size >= 0, got {min_free_disk_gb}"),
        ));
    }
    let takes = draw_takes(&c, &scenes, &rigs, &mixes, &base)?;
    let mut ids: Vec<&str> = takes.iter().map(|t| t.id.as_str()).collect();
    ids.sort_unstable();
    if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
        bail!(
            "campaign {}: two takes are the same take ({}): vary the seed, scene or crowd",
            path.display(),
            w[0]
        );
    }
    let dwelling_catalogues = added_catalogues(&c.dwelling_catalogues, dir)
        .map_err(|what| bad("dwelling_catalogues", what))?;
    let dwelling_settings = match &c.dwelling_settings {
        Some(file) => crate::cli::scene_jobs::load_dwelling_settings(&dir.join(file))
            .map_err(|e| bad("dwelling_settings", format!("{e:#}")))?,
        None => Default::default(),
    };
    let fingerprint = fingerprint(&run, &takes, &dwelling_catalogues, &dwelling_settings)?;
    Ok(CampaignPlan {
        config: path.to_path_buf(),
        run,
        out,
        floor_plans: walked(&takes, floor_plans),
        dwellings: walked(&takes, dwellings),
        takes,
        min_free_disk_bytes: (min_free_disk_gb * 1e9) as u64,
        dwelling_catalogues,
        dwelling_settings,
        fingerprint,
    })
}

/// The generated scenes (seed, file) some take walks: only those are made, so that fewer takes
/// than dwellings make no more dwellings than takes.
fn walked(takes: &[TakeDef], generated: Vec<(u64, PathBuf)>) -> Vec<(u64, PathBuf)> {
    generated
        .into_iter()
        .filter(|(_, file)| takes.iter().any(|t| &t.scene == file))
        .collect()
}

/// A campaign's `dwelling_catalogues`, relative to its folder `dir`: each a catalogue folder.
fn added_catalogues(named: &[PathBuf], dir: &Path) -> Result<Vec<PathBuf>, String> {
    let folders: Vec<PathBuf> = named.iter().map(|d| dir.join(d)).collect();
    match folders.iter().find(|d| !d.join("catalogue.json").is_file()) {
        Some(d) => Err(format!(
            "{} holds no catalogue.json: expected a folder tools/furniture_catalogue.py --library made",
            d.display()
        )),
        None => Ok(folders),
    }
}

/// SHA-256 of what defines a campaign: the run config and its takes' definitions, and the
/// libraries added to its dwellings' catalogue and the generator's settings, which change the
/// dwellings (a campaign with neither keeps the fingerprint it always had).
fn fingerprint(
    run: &Path,
    takes: &[TakeDef],
    catalogues: &[PathBuf],
    settings: &crate::scene::dwelling::DwellingSettings,
) -> Result<String> {
    let default = *settings == Default::default();
    let json = match (catalogues.is_empty(), default) {
        (true, true) => serde_json::to_string(&(run, takes)),
        (false, true) => serde_json::to_string(&(run, takes, catalogues)),
        (_, false) => serde_json::to_string(&(run, takes, catalogues, settings)),
    };
    Ok(sha256_hex(
        json.context("fingerprinting the campaign")?.as_bytes(),
    ))
}

/// The campaign's scene files, globs expanded (sorted), each with the frame its entry gives
/// (none: the run config's).
fn scene_files(
    c: &RawCampaign,
    dir: &Path,
    at: &impl Fn(&Path) -> PathBuf,
    bad: &impl Fn(&str, String) -> anyhow::Error,
) -> Result<Vec<(PathBuf, Framed)>> {
    let mut scenes: Vec<(PathBuf, Framed)> = Vec::new();
    for (i, entry) in c.scenes.iter().enumerate() {
        let field = format!("scenes[{i}]");
        let (s, frame) = scene_entry(entry).map_err(|m| bad(&field, m))?;
        let s = s.as_str();
        let pattern = dir.join(s);
        if s.contains(['*', '?', '[']) {
            let mut found: Vec<PathBuf> = glob::glob(&pattern.to_string_lossy())
                .map_err(|e| bad(&field, format!("{s:?} is not a valid glob: {e}")))?
                .filter_map(|p| p.ok())
                .filter(|p| p.is_file())
                .collect();
            if found.is_empty() {
                return Err(bad(&field, format!("{s:?} matches no file")));
            }
            found.sort();
            scenes.extend(found.into_iter().map(|p| (at(&p), frame)));
        } else {
            let p = at(Path::new(s));
            if !p.is_file() {
                return Err(bad(&field, format!("{} is not a file", p.display())));
            }
            scenes.push((p, frame));
        }
    }
    Ok(scenes)
}

/// Checks `crowd_count` against the run config's crowd and agents.
fn check_crowd_count(
    c: &RawCampaign,
    base: &RawRun,
    run: &Path,
    bad: &impl Fn(&str, String) -> anyhow::Error,
) -> Result<()> {
    if let Some([lo, hi]) = c.crowd_count {
        if lo == 0 || lo > hi {
            return Err(bad(
                "crowd_count",
                format!("expected [lo, hi] with 1 <= lo <= hi, got [{lo}, {hi}]"),
            ));
        }
        if base.crowd.is_none() {
            return Err(bad(
                "crowd_count",
                format!("{} has no [crowd] section to vary", run.display()),
            ));
        }
        let max = crate::cli::synth_config::MAX_AGENTS.saturating_sub(base.agents.len());
        if hi > max {
            return Err(bad(
                "crowd_count",
                format!(
                    "[{lo}, {hi}]: at most {max} people per take (1–{} agents, {} of them the run config's [[agents]])",
                    crate::cli::synth_config::MAX_AGENTS,
                    base.agents.len()
                ),
            ));
        }
    }
    Ok(())
}

/// Checks `duration_s`: drawn in 0.1 s steps, at most the synth's longest take.
fn check_duration(c: &RawCampaign, bad: &impl Fn(&str, String) -> anyhow::Error) -> Result<()> {
    if let Some([lo, hi]) = c.duration_s {
        let max = crate::cli::synth_config::MAX_DURATION_S;
        // Drawn in 0.1 s steps from lo rounded to one: a take is at least 0.1 s.
        if !(lo.is_finite()
            && hi.is_finite()
            && (lo * 10.0).round() >= 1.0
            && lo <= hi
            && hi <= max)
        {
            return Err(bad(
                "duration_s",
                format!(
                    "expected [lo, hi] seconds with 0.1 <= lo <= hi <= {max} (drawn in 0.1 s \
                     steps, so a take is at least 0.1 s), got [{lo}, {hi}]"
                ),
            ));
        }
    }
    Ok(())
}

/// The `activity_weights` mixes, each checked.
fn activity_mixes(
    c: &RawCampaign,
    bad: &impl Fn(&str, String) -> anyhow::Error,
) -> Result<Vec<ActivityWeights>> {
    let mut mixes = Vec::with_capacity(c.activity_weights.len());
    for (i, entry) in c.activity_weights.iter().enumerate() {
        let field = format!("activity_weights[{i}]");
        let mut named = Vec::new();
        for (name, v) in entry {
            let v = match v {
                toml::Value::Float(f) => *f,
                toml::Value::Integer(n) => *n as f64,
                other => {
                    return Err(bad(
                        &format!("{field}.{name}"),
                        format!("expected a weight ≥ 0, got {}", other.type_str()),
                    ))
                }
            };
            named.push((name.as_str(), v));
        }
        mixes.push(ActivityWeights::from_named(named).map_err(|m| bad(&field, m))?);
    }
    Ok(mixes)
}

/// The takes: each one's seed, its draws of crowd and duration, and its scene, rig and mix in
/// turn.
fn draw_takes(
    c: &RawCampaign,
    scenes: &[(PathBuf, Framed)],
    rigs: &[PathBuf],
    mixes: &[ActivityWeights],
    base: &RawRun,
) -> Result<Vec<TakeDef>> {
    let mut takes = Vec::with_capacity(c.takes);
    for k in 0..c.takes {
        let seed = c.first_seed + k as u64;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x6361_6d70_6169_676e);
        let crowd_count = c
            .crowd_count
            .map(|[lo, hi]| lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize);
        let duration_s = c.duration_s.map(|[lo, hi]| {
            let steps = ((hi - lo) * 10.0).round() as u64;
            let step = if steps == 0 {
                0
            } else {
                rng.next_u64() % (steps + 1)
            };
            ((lo * 10.0).round() + step as f64) / 10.0
        });
        let (scene, (up_axis, unit_m)) = scenes[k % scenes.len()].clone();
        let mut take = TakeDef {
            index: k,
            id: String::new(),
            scene,
            up_axis,
            unit_m,
            seed,
            crowd_count,
            duration_s,
            rig: (!rigs.is_empty()).then(|| rigs[k % rigs.len()].clone()),
            activity_weights: (!mixes.is_empty()).then(|| mixes[k % mixes.len()]),
        };
        take.id = take_id(&take, base)?;
        takes.push(take);
    }
    Ok(takes)
}

/// The up axis and metres per unit a campaign's scene entry gives (none: the run config's).
type Framed = (Option<UpAxis>, Option<f64>);

/// One entry of `campaign.scenes`: a path or glob, or a table `{ path, up_axis, unit_m }`
/// (both frame keys optional, checked as `[scene]`'s are). The message names what is wrong;
/// the caller names the entry.
fn scene_entry(entry: &toml::Value) -> Result<(String, Framed), String> {
    let table = match entry {
        toml::Value::String(s) => return Ok((s.clone(), (None, None))),
        toml::Value::Table(t) => t,
        other => {
            return Err(format!(
            "expected a path or a table {{ path = \"…\", up_axis = \"y\", unit_m = 0.01 }}, got {}",
            other.type_str()
        ))
        }
    };
    if let Some(key) = table
        .keys()
        .find(|k| !["path", "up_axis", "unit_m"].contains(&k.as_str()))
    {
        return Err(format!(
            "unknown key `{key}` (a scene entry has path, up_axis and unit_m)"
        ));
    }
    let path = match table.get("path") {
        Some(toml::Value::String(p)) => p.clone(),
        Some(other) => {
            return Err(format!(
                "`path`: expected a string, got {}",
                other.type_str()
            ))
        }
        None => return Err("`path` is missing (the scene file or glob)".into()),
    };
    let up = match table.get("up_axis") {
        None => None,
        Some(v) => Some(
            v.as_str()
                .and_then(UpAxis::from_name)
                .ok_or_else(|| format!("`up_axis`: expected \"y\" or \"z\", got {v}"))?,
        ),
    };
    let unit_m = match table.get("unit_m") {
        None => None,
        Some(toml::Value::Float(f)) => Some(*f),
        Some(toml::Value::Integer(i)) => Some(*i as f64),
        Some(other) => {
            return Err(format!(
                "`unit_m`: expected metres per unit of the scene file, got {}",
                other.type_str()
            ))
        }
    };
    SceneFrame::new(up, unit_m).map_err(|m| format!("`unit_m`: {m}"))?;
    Ok((path, (up, unit_m)))
}

/// An absolute path with `.` and `..` taken out by name (the path need not exist).
fn lexical(p: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// `<scene stem>-s<seed>[-n<count>]-<8 hex>`, the hex of the take's effective config (the run
/// config with the take's overrides but its output folder; the rig file's path included).
fn take_id(take: &TakeDef, base: &RawRun) -> Result<String> {
    let mut raw = base.clone();
    let mut o = take.overrides(Path::new("."));
    o.out = None;
    o.apply(&mut raw)?;
    let text = resume_fingerprint(&raw).context("fingerprinting a take")?;
    let hash = sha256_hex(format!("{text}\n{:?}", take.rig).as_bytes());
    let stem: String = take
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into())
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .take(40)
        .collect();
    Ok(format!(
        "{stem}-s{}{}-{}",
        take.seed,
        take.crowd_count
            .map_or_else(String::new, |n| format!("-n{n}")),
        &hash[..8]
    ))
}

/// The most dwellings one campaign generates.
const MAX_DWELLINGS: u64 = 100_000;

/// A campaign's `dwellings`: a list of seeds, or `{ first = N, count = M }` for the seeds
/// N … N+M−1; what is wrong with it otherwise.
fn dwelling_seeds(value: &toml::Value) -> Result<Vec<u64>, String> {
    let seed = |v: &toml::Value, what: &str| match v.as_integer() {
        Some(s) if s >= 0 => Ok(s as u64),
        _ => Err(format!("{what} is {v}; expected a seed (an integer ≥ 0)")),
    };
    let seeds: Vec<u64> = match value {
        toml::Value::Array(items) => items
            .iter()
            .enumerate()
            .map(|(k, v)| seed(v, &format!("entry {k}")))
            .collect::<Result<_, _>>()?,
        toml::Value::Table(t) => {
            if let Some(key) = t.keys().find(|k| !["first", "count"].contains(&k.as_str())) {
                return Err(format!(
                    "unknown key `{key}`; expected `{{ first = SEED, count = N }}`"
                ));
            }
            let get = |key: &str| {
                t.get(key)
                    .ok_or_else(|| format!("`{key}` is missing; expected `{{ first = SEED, count = N }}`"))
                    .and_then(|v| seed(v, &format!("`{key}`")))
            };
            let (first, count) = (get("first")?, get("count")?);
            if count == 0 || count > MAX_DWELLINGS {
                return Err(format!("`count` is {count}; expected 1 to {MAX_DWELLINGS}"));
            }
            if first.checked_add(count).is_none_or(|end| end > i64::MAX as u64) {
                return Err(format!("`first` + `count` ({first} + {count}) must stay below 2^63"));
            }
            (first..first + count).collect()
        }
        other => {
            return Err(format!(
                "{other} is not a list of seeds; expected `[SEED, …]` or `{{ first = SEED, count = N }}`"
            ))
        }
    };
    if seeds.len() as u64 > MAX_DWELLINGS {
        return Err(format!("{} seeds; at most {MAX_DWELLINGS}", seeds.len()));
    }
    Ok(seeds)
}

/// Writes the campaign's floor plans and dwellings that are not there yet (a resumed campaign
/// keeps them).
pub(crate) fn write_generated_scenes(plan: &CampaignPlan) -> Result<()> {
    use crate::scene::generated::room_scene::{RoomScene, RoomSettings};
    let settings = RoomSettings::default();
    for (seed, file) in &plan.floor_plans {
        if file.is_file() {
            continue;
        }
        let dir = file.parent().expect("a floor plan lies in scenes/");
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(*seed);
        let scene = RoomScene::sample(&settings, &mut rng);
        let tmp = file.with_extension("obj.tmp");
        scene
            .params
            .scene_mesh(&settings)
            .write_obj(&tmp)
            .with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, file).with_context(|| format!("writing {}", file.display()))?;
    }
    if !plan.dwellings.is_empty() {
        use crate::scene::dwelling::{generate, shipped_catalogue_dir, Catalogue};
        let catalogue = Catalogue::load_with(&shipped_catalogue_dir(), &plan.dwelling_catalogues)?;
        let settings = &plan.dwelling_settings;
        for (seed, file) in &plan.dwellings {
            // The GLB is written last: a dwelling whose GLB is there is whole.
            if file.is_file() {
                continue;
            }
            generate(settings, &catalogue, *seed)?.write_glb(&catalogue, file)?;
        }
        write_campaign_attribution(plan)?;
    }
    Ok(())
}

/// Writes the campaign's `ATTRIBUTION.md` where its dwellings place models of an opt-in
/// (CC-BY) library: every such model of every dwelling, once.
fn write_campaign_attribution(plan: &CampaignPlan) -> Result<()> {
    use crate::scene::dwelling::attribution::{of_sidecars, ATTRIBUTION_FILE};
    if plan.dwelling_catalogues.is_empty() {
        return Ok(());
    }
    let sidecars = plan
        .dwellings
        .iter()
        .map(|(_, glb)| {
            let json = glb.with_extension("json");
            std::fs::read(&json).with_context(|| format!("reading {}", json.display()))
        })
        .collect::<Result<Vec<_>>>()?;
    let views: Vec<&[u8]> = sidecars.iter().map(Vec::as_slice).collect();
    if let Some(text) = of_sidecars(&views).map_err(anyhow::Error::msg)? {
        let path = plan.out.join(ATTRIBUTION_FILE);
        crate::atomic_file::write_atomically(&path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
