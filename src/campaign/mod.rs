//! Campaigns: a dataset of many takes across scenes in one command (`egogen-run CAMPAIGN.toml`).
//! A campaign file (`plan`) names the run config every take starts from and what varies per
//! take; each take is a complete dataset of `egogen-run`'s form in `takes/<id>/`, the same
//! bytes as that take rendered alone (its command is in `campaign.json`). All takes' shards go
//! to one pool (local workers or Slurm), takes staged on demand (`feed`, pausing below the
//! free-disk floor); `campaign.json` (`state`) is rewritten at every change and `--resume`
//! continues a killed campaign (a finished take checked by its `stamp`, or in full when it
//! changed or with `--rehash`; the state rebuilt from the take folders when `campaign.json` is
//! lost, or was written for another place: a campaign folder moved or copied); the frames of every finished take are listed in `index.parquet` (`index`) and shown
//! on `contact_sheet.png` (`sheet`). Before any work every take is checked as staging would
//! check it (scene, rig, crowd) and the budget (takes, frames, disk, core-hours from measured
//! throughput) is stated (`budget`). The scenes a campaign generates (`floor_plans`,
//! `dwellings`) are written once into its `scenes/` before the first take, with the campaign's
//! `ATTRIBUTION.md` where its dwellings place models of an added CC-BY library.

pub(crate) mod budget;
pub(crate) mod feed;
pub mod index;
pub mod plan;
pub(crate) mod sheet;
pub mod stamp;
pub(crate) mod state;
pub mod takes;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{bail, Context, Result};

use crate::plan::Backend;
use crate::render::BlenderRuntime;
use crate::run_job::{prepare, RunRequest};
use crate::supervisor::{shard_pool, PoolRun};
pub use plan::{is_campaign, plan_campaign, CampaignPlan, TakeDef};
pub(crate) use state::STATE_FILE;
pub use state::{CampaignState, TakeStatus};

/// How a campaign runs, beside its file.
#[derive(Debug, Clone, Default)]
pub(crate) struct CampaignRequest {
    /// Continue the campaign in `campaign.out`.
    pub resume: bool,
    /// With `resume`: verify every finished take in full (every checksum, every frame file
    /// opened) instead of only the ones whose files changed since they were finished.
    pub rehash: bool,
    /// State the plan and budget; render nothing, write nothing.
    pub dry_run: bool,
    pub blender: Option<PathBuf>,
    pub workers: Option<usize>,
    pub backend: Option<Backend>,
    /// A campaign or dataset folder whose pool reports give the throughput for the budget
    /// (default: this campaign's earlier starts).
    pub throughput_from: Option<PathBuf>,
}

/// What a campaign start did.
#[derive(Debug, Clone)]
pub struct CampaignSummary {
    pub out: PathBuf,
    /// Takes complete, and those given up (id, reason).
    pub complete: usize,
    pub failed: Vec<(String, String)>,
    /// Rows of `index.parquet`.
    pub frames_indexed: usize,
    /// The pool's report of this start (`None` for a dry run).
    pub report: Option<crate::supervisor::PoolReport>,
}

/// The index file's name in the campaign folder.
pub(crate) const INDEX_FILE: &str = "index.parquet";

/// Runs (or, with `dry_run`, plans) the campaign at `path`.
pub(crate) fn run_campaign(path: &Path, request: &CampaignRequest) -> Result<CampaignSummary> {
    let plan = plan_campaign(path)?;
    let out = plan.out.clone();
    let earlier = check_out(&plan, request)?;
    check_disk_floor(&plan)?;
    check_takes(&plan)?;
    let run_request = RunRequest {
        resume: true,
        blender: request.blender.clone(),
    };
    // The first take's plan carries what every take shares: render settings and supervisor.
    let mut first = plan.takes[0].overrides(&out.join("takes"));
    if !plan.takes[0].scene.is_file() {
        // A scene the campaign generates and has not written yet (a dwelling, a floor plan):
        // what is shared does not depend on the scene, so the run config's own serves.
        (first.scene, first.up_axis, first.unit_m) = (None, None, None);
    }
    first.workers = request.workers;
    first.backend = request.backend;
    let shared = prepare(&plan.run, &first, &run_request)
        .with_context(|| format!("the campaign's first take ({})", plan.takes[0].id))?;
    let estimate = budget::estimate(&plan, &shared.plan, request.throughput_from.as_deref())?;
    for line in estimate.lines() {
        eprintln!("egogen-run: campaign: {line}");
    }
    if request.dry_run {
        return Ok(CampaignSummary {
            out,
            complete: 0,
            failed: Vec::new(),
            frames_indexed: 0,
            report: None,
        });
    }
    let runtime = BlenderRuntime::resolve(request.blender.as_deref())?;
    if shared.plan.supervisor.backend == Backend::Slurm {
        crate::supervisor::slurm::check_slurm_tools()?;
    } else if let Some(render) = &shared.plan.render {
        // Once, before any take is staged (on Slurm the compute nodes' GPUs: the workers check).
        crate::render::shard::check_device(&runtime, render.device).map_err(anyhow::Error::msg)?;
    }
    std::fs::create_dir_all(out.join("takes"))
        .with_context(|| format!("creating {}", out.display()))?;
    let mut state = CampaignState::new(&plan);
    if let Some(earlier) = earlier {
        // Keep what an earlier start recorded of failures until the take is tried again.
        for (t, e) in state.takes.iter_mut().zip(earlier.takes) {
            t.reason = e.reason;
        }
    }
    state.write(&out)?;
    plan::write_generated_scenes(&plan)?;
    let done_before = check_finished_takes(&plan, &mut state, request.rehash)?;
    state.write(&out)?;
    let mut maker = takes::StagedTakes::new(out.clone(), plan.run.clone(), run_request);
    maker.workers = request.workers;
    maker.backend = request.backend;
    let start = crate::supervisor::staged::next_start(&out);
    let run = PoolRun {
        logs_dir: out.join("logs").join(format!("start_{start:02}")),
        work_dir: out.join("work"),
        stop_on_failure: false,
    };
    let pool = shard_pool(&shared.plan.supervisor);
    let frames = estimate.frames_per_take.clone();
    render_takes(
        &plan,
        state,
        Box::new(maker),
        frames,
        done_before,
        &*pool,
        runtime,
        &run,
        true,
    )
}

/// Renders every take of `state` not yet complete through one `pool`, made by `maker`
/// (`frames`: each take's estimated frames, `done_before` of them finished in earlier starts);
/// keeps `campaign.json` and each finished take's index rows, then writes `index.parquet` over
/// every complete take (also after an interrupted start, before its error) and, with
/// `contact_sheet`, `contact_sheet.png` of their middle frames. Returns what was made.
#[allow(clippy::too_many_arguments)]
pub fn render_takes(
    plan: &CampaignPlan,
    state: CampaignState,
    maker: Box<dyn takes::TakeMaker>,
    frames: Vec<usize>,
    done_before: usize,
    pool: &dyn crate::supervisor::ShardPool,
    runtime: BlenderRuntime,
    run: &PoolRun,
    contact_sheet: bool,
) -> Result<CampaignSummary> {
    let feed = feed::CampaignFeed::new(plan.clone(), state, maker, frames, done_before);
    let feed = Arc::new(Mutex::new(feed));
    let report = pool.run(feed.clone(), runtime, run);
    let mut feed = feed.lock().unwrap();
    feed.save_now();
    // The index lists what is finished, also after an interrupted start.
    let (frames_indexed, middles) = write_campaign_index(plan, &feed.state)?;
    if contact_sheet {
        sheet::write_contact_sheet(&plan.out, &middles)?;
    }
    let report = report?;
    eprintln!(
        "egogen-run: campaign: rendered {} frames in {:.1} s on {} worker(s), utilisation {:.0} %",
        report.frames_finished,
        report.wall_seconds,
        report.workers,
        100.0 * report.utilisation
    );
    let failed: Vec<(String, String)> = feed
        .state
        .takes
        .iter()
        .filter(|t| t.status == TakeStatus::Failed)
        .map(|t| (t.def.id.clone(), t.reason.clone().unwrap_or_default()))
        .collect();
    Ok(CampaignSummary {
        out: plan.out.clone(),
        complete: feed.state.count(TakeStatus::Complete),
        failed,
        frames_indexed,
        report: Some(report),
    })
}

/// `egogen-run CAMPAIGN.toml`: runs the campaign and says what it made; an error when any take
/// failed (after all the others were made), naming each with its reason.
pub(crate) fn run(path: &Path, request: &CampaignRequest) -> Result<()> {
    let summary = run_campaign(path, request)?;
    if request.dry_run {
        return Ok(());
    }
    eprintln!(
        "egogen-run: campaign {}: {} take(s) complete, {} frames in {}",
        summary.out.display(),
        summary.complete,
        summary.frames_indexed,
        summary.out.join(INDEX_FILE).display()
    );
    if !summary.failed.is_empty() {
        let list: Vec<String> = summary
            .failed
            .iter()
            .map(|(id, why)| format!("  {id}: {why}"))
            .collect();
        bail!(
            "{} take(s) failed (recorded in {}; --resume tries them again):\n{}",
            summary.failed.len(),
            summary.out.join(STATE_FILE).display(),
            list.join("\n")
        );
    }
    Ok(())
}

/// Checks the campaign folder: absent or empty for a new campaign; with `--resume`, a campaign
/// of the same takes (returned), or one whose `campaign.json` is missing or unreadable but
/// whose folder holds only this campaign's takes (`None`: its state is rebuilt from the take
/// folders; an unreadable file is moved to `work/`). Nothing else is touched.
fn check_out(plan: &CampaignPlan, request: &CampaignRequest) -> Result<Option<CampaignState>> {
    let out = &plan.out;
    if out.exists() && !out.is_dir() {
        bail!(
            "campaign folder {} exists and is a file; choose another `campaign.out` (nothing was written)",
            out.display()
        );
    }
    let resuming = request.resume || request.dry_run;
    // The state rebuilt from the take folders: said, and `None` (a new state from the plan).
    let rebuilt = |why: String| {
        let done = if request.resume {
            "rebuilt"
        } else {
            "--resume rebuilds it"
        };
        eprintln!(
            "egogen-run: campaign: {why}; {done} from the take folders in {}",
            out.join("takes").display()
        );
        Ok(None)
    };
    if out.join(STATE_FILE).is_file() {
        let found = match CampaignState::read(out) {
            Ok(found) => found,
            Err(e) if resuming => {
                check_rebuildable(plan)?;
                // The unreadable file is kept, out of the way, for whoever wants to look.
                let (kept, keeps) = set_state_aside(out, "unreadable", request.resume)?;
                return rebuilt(format!("{e:#} ({keeps} as {})", kept.display()));
            }
            Err(e) => {
                bail!("{e:#}: --resume rebuilds it from the take folders (nothing was written)")
            }
        };
        if !resuming {
            bail!(
                "{} holds a campaign; rerun with --resume to continue it, or choose another `campaign.out` (nothing was written)",
                out.display()
            );
        }
        // The same takes (a take's id hashes its effective config) under another fingerprint:
        // the campaign's files lie elsewhere now (the run config, the output folder), as when a
        // campaign folder is moved or copied. Its state is rebuilt for where it lies.
        let same_takes = found.takes.len() == plan.takes.len()
            && found
                .takes
                .iter()
                .zip(&plan.takes)
                .all(|(f, p)| f.def.id == p.id);
        if found.fingerprint != plan.fingerprint && same_takes {
            check_rebuildable(plan)?;
            let (kept, keeps) = set_state_aside(out, "before_move", request.resume)?;
            return rebuilt(format!(
                "{} holds this campaign's takes under a {STATE_FILE} written for other paths (the campaign was moved or copied here; the old one {keeps} as {})",
                out.display(),
                kept.display()
            ));
        }
        if found.fingerprint != plan.fingerprint {
            bail!(
                "{} holds a campaign of other takes than {} defines (its run config, scenes, seeds, crowds, durations or rigs differ; a take names its scene and rig files by path, so a campaign whose scenes lie inside the folder that moved, such as its generated floor plans, resumes only where it was made); resuming would mix two campaigns (nothing was touched)",
                out.display(),
                plan.config.display()
            );
        }
        return Ok(Some(found));
    }
    if std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some()) {
        return match (check_rebuildable(plan), resuming) {
            (Ok(()), true) => rebuilt(format!("{} has no {STATE_FILE}", out.display())),
            (Ok(()), false) => bail!(
                "{} holds this campaign's takes but no {STATE_FILE}; rerun with --resume to rebuild it from the take folders (nothing was written)",
                out.display()
            ),
            (Err(e), true) if request.resume => Err(e),
            (Err(_), _) => bail!(
                "campaign folder {} already exists and is not empty; choose another `campaign.out` (nothing was written)",
                out.display()
            ),
        };
    }
    Ok(None)
}

/// Refuses a free-disk floor larger than the whole file system the campaign is written to: the
/// campaign would pause before its first take and wait for ever.
fn check_disk_floor(plan: &CampaignPlan) -> Result<()> {
    let Some(existing) = plan.out.ancestors().find(|p| p.exists()) else {
        return Ok(());
    };
    if let Some((_, size)) = feed::disk_space(existing) {
        if plan.min_free_disk_bytes > size {
            bail!(
                "campaign {}: key `campaign.min_free_disk_gb`: {:.2} GB is more than the whole file system under {} ({:.2} GB); the campaign would wait for ever (nothing was written)",
                plan.config.display(),
                plan.min_free_disk_bytes as f64 / 1e9,
                existing.display(),
                size as f64 / 1e9
            );
        }
    }
    Ok(())
}

/// Checks every take as staging would, before any is staged, without synthesising: the run
/// config with the take's flags resolves (its scene file, rig and the rig's cameras, crowd),
/// and each scene loads in its frame with a walkable floor (each scene, frame and floor once;
/// its warnings said). Errors name the take and its scene. Floor plans the campaign generates
/// are checked once written.
fn check_takes(plan: &CampaignPlan) -> Result<()> {
    let base = crate::cli::RawRun::load(&plan.run)?;
    let mut scenes_seen = std::collections::HashSet::new();
    for t in &plan.takes {
        if t.scene.starts_with(plan.out.join("scenes")) && !t.scene.is_file() {
            continue;
        }
        let what = || {
            format!(
                "campaign {}: take {} (scene {})",
                plan.config.display(),
                t.id,
                t.scene.display()
            )
        };
        let mut raw = base.clone();
        t.overrides(&plan.out.join("takes"))
            .apply(&mut raw)
            .with_context(what)?;
        let run = crate::cli::resolve_run(raw, &plan.run).with_context(what)?;
        if scenes_seen.insert(format!("{:?}", (&run.scene, run.scene_frame, run.walkable))) {
            let mesh = crate::scene::load_scene(&run.scene, run.scene_frame).with_context(what)?;
            let map =
                crate::scene::walkable_map(&mesh, &run.scene, run.walkable).with_context(what)?;
            if let Some(warning) = crate::scene::scene_frame_warning(&mesh, &map, &run.scene) {
                eprintln!("egogen-run: campaign: take {}: {warning}", t.id);
            }
        }
    }
    Ok(())
}

/// What a campaign folder may hold besides `takes/`: its scratch, logs, generated scenes,
/// index, contact sheet and state (with their atomic writes' `.partial` files).
const CAMPAIGN_ENTRIES: [&str; 6] = [
    "work",
    "logs",
    "scenes",
    INDEX_FILE,
    "contact_sheet.png",
    STATE_FILE,
];

/// Where the state file of a campaign folder `out` is kept when it is rebuilt
/// (`work/campaign.json.<suffix>`), moved there when `resume`; and how to say so.
fn set_state_aside(out: &Path, suffix: &str, resume: bool) -> Result<(PathBuf, &'static str)> {
    let kept = out.join("work").join(format!("{STATE_FILE}.{suffix}"));
    if !resume {
        return Ok((kept, "--resume keeps it"));
    }
    std::fs::create_dir_all(out.join("work"))
        .and_then(|_| std::fs::rename(out.join(STATE_FILE), &kept))
        .with_context(|| format!("moving {STATE_FILE} to {}", kept.display()))?;
    Ok((kept, "kept"))
}

/// Whether the campaign folder holds only what this campaign writes — `takes/` only this
/// plan's takes, finished (`<id>`) or staged (`<id>.partial`) — so that its state can be
/// rebuilt from the take folders; else an error saying what is foreign.
fn check_rebuildable(plan: &CampaignPlan) -> Result<()> {
    let out = &plan.out;
    let foreign = |what: String| {
        anyhow::anyhow!(
            "{}: cannot rebuild its {STATE_FILE}: {what}, not this campaign's (nothing was touched)",
            out.display()
        )
    };
    for e in std::fs::read_dir(out).with_context(|| format!("reading {}", out.display()))? {
        let name = e?.file_name().to_string_lossy().into_owned();
        let known = name == "takes"
            || CAMPAIGN_ENTRIES
                .iter()
                .any(|k| name == *k || name.strip_prefix(k) == Some(".partial"));
        if !known {
            return Err(foreign(format!("it holds `{name}`")));
        }
    }
    let ids: std::collections::HashSet<&str> = plan.takes.iter().map(|t| t.id.as_str()).collect();
    if let Ok(takes) = std::fs::read_dir(out.join("takes")) {
        for e in takes {
            let name = e?.file_name().to_string_lossy().into_owned();
            if !ids.contains(name.strip_suffix(".partial").unwrap_or(&name)) {
                return Err(foreign(format!("takes/{name} is a take")));
            }
        }
    }
    Ok(())
}

/// Checks every finished take against its manifest: a take that matches is complete (its
/// index rows kept); one that does not is recorded as failed and left as it is. A take whose
/// files are as they were when it was finished or last verified (`stamp`) is taken as it is,
/// unless `rehash`; every other one is verified in full, and stamped when it matches. Returns
/// the frames of the complete takes.
fn check_finished_takes(
    plan: &CampaignPlan,
    state: &mut CampaignState,
    rehash: bool,
) -> Result<usize> {
    let mut frames = 0;
    let (mut unchanged, mut verified) = (0, 0);
    for t in state.takes.iter_mut() {
        let dir = plan.out.join("takes").join(&t.def.id);
        if !dir.join(crate::manifest::MANIFEST).is_file() {
            // A take folder appears only by the rename that finishes it, manifest and all.
            if dir.exists() {
                t.status = TakeStatus::Failed;
                t.reason = Some(format!(
                    "{} is a finished take's folder without its {} (deleted?); left as it is: move it away and --resume renders the take again",
                    dir.display(),
                    crate::manifest::MANIFEST
                ));
            }
            continue;
        }
        let checked = if !rehash && stamp::stamp_matches(&plan.out, &t.def.id, &dir) {
            unchanged += 1;
            Ok(())
        } else {
            verified += 1;
            crate::supervisor::verify(&dir).map(|_| {
                if let Err(e) = stamp::write_stamp(&plan.out, &t.def.id, &dir) {
                    eprintln!(
                        "egogen-run: campaign: take {}: no stamp ({e:#}); the next resume verifies it in full again",
                        t.def.id
                    );
                }
            })
        };
        match checked {
            Ok(()) => {
                let rows = match index::kept_rows(&plan.out, &t.def.id) {
                    Some(rows) => rows,
                    None => {
                        let rows = index::take_rows(&t.def, &dir, &plan.out)?;
                        index::keep_rows(&plan.out, &t.def.id, &rows)?;
                        rows
                    }
                };
                frames += rows.len();
                t.status = TakeStatus::Complete;
                t.reason = None;
                t.frames = Some(rows.len());
            }
            Err(e) => {
                t.status = TakeStatus::Failed;
                t.reason = Some(format!(
                    "{} does not match its manifest ({e:#}); left as it is: move it away and --resume renders it again",
                    dir.display()
                ));
            }
        }
    }
    if unchanged + verified > 0 {
        eprintln!(
            "egogen-run: campaign: {} finished take(s): {unchanged} unchanged since they were finished, {verified} verified in full{}",
            unchanged + verified,
            if rehash { " (--rehash)" } else { "" }
        );
    }
    Ok(frames)
}

/// Writes `index.parquet` from the complete takes' kept rows, one take at a time in take
/// order; returns its rows and the middle frame of each take.
fn write_campaign_index(
    plan: &CampaignPlan,
    state: &CampaignState,
) -> Result<(usize, Vec<index::IndexRow>)> {
    let mut middles = Vec::new();
    let groups = state
        .takes
        .iter()
        .filter(|t| t.status == TakeStatus::Complete)
        .map(|t| {
            let rows = index::kept_rows(&plan.out, &t.def.id).ok_or_else(|| {
                anyhow::anyhow!(
                    "take {}: its index rows ({}) are missing",
                    t.def.id,
                    index::rows_path(&plan.out, &t.def.id).display()
                )
            })?;
            if let Some(m) = sheet::middle_frame(&rows) {
                middles.push(m.clone());
            }
            Ok(rows)
        });
    let n = index::write_index(&plan.out.join(INDEX_FILE), groups)?;
    Ok((n, middles))
}
