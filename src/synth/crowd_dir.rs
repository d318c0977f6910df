//! The folder a crowd take is written to, staged in `<dir>.partial/` and renamed into place
//! at the end (a failed or killed run never leaves a half-written take under the final name).
//!
//! Layout: `agents/<name>/motion.npz` (AMASS-style SMPL-X at 40 fps: `poses` N×165, `trans`,
//! `betas`, `gender`, `mocap_frame_rate`), `agents/<name>/cpf_trajectory.json`
//! (`world_from_cpf` per frame), `agents/<name>/markers.npy` (float32 N×67×3, world, m),
//! `agents/<name>/held_objects.npy` where it picked something up (float64 K×N×4×4: each
//! object's `world_from_object` per frame, row-major, in the summary's `held_objects` order),
//! `agents/<name>/moved_objects.npy` where it moved a scene object (a chair pulled out from its
//! table: float64 K×N×2, each move's horizontal offset from where the scene has the object per
//! frame, in the summary's `moved_objects` order);
//! `paths.png` (top view: walkable map, obstacles, every agent's pelvis path, starts,
//! goals and activities done);
//! `summary.json` (what was asked, per agent goals and state, totals, wall time);
//! `manifest.json` (files with sizes and SHA-256).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use glam::DVec2;
use serde::Serialize;

use super::activity::Activity;
use super::crowd::{AgentState, AgentTrack, CrowdTake, CrowdWorld};
use crate::atomic_file::{partial_of, refuse_existing_folder, write_atomically};
use crate::body::BodyModel;
use crate::manifest::{build_manifest, MANIFEST};
use crate::preview::map::{MapPicture, AGENT_COLOURS};
use crate::scene::Obstacle2;
use crate::walker::state::footprint;

/// What a finished take folder holds.
#[derive(Debug, Clone, Serialize)]
pub struct CrowdOutputs {
    pub dir: PathBuf,
    pub summary: TakeSummary,
}

/// Totals over the agents of a take.
#[derive(Debug, Clone, Serialize)]
pub struct TakeTotals {
    pub agents: usize,
    pub goals: usize,
    pub goals_reached: usize,
    pub agents_fallen: usize,
    /// Share of all primitives spent stuck (hardly moving, goal not reached).
    pub stuck_share: f64,
    pub agents_decoder_failure: usize,
    /// Mean over agents of their mean foot contact (3-D, Eq. 12).
    pub contact_mean: f64,
    /// Mean over agents of the share of new frames with a marker in an obstacle or in
    /// another agent's 2D box, as judged while walking.
    pub penetration_share_mean: f64,
    /// Share of (agent, frame) pairs in which one of the agent's markers lies inside another
    /// agent's 2D box (the bounding box of that agent's markers in its own horizontal frame) at
    /// the same frame.
    pub human_overlap_share: f64,
    /// Vertices of one body inside another's capsule volume (docs/SYNTH.md), every 4th frame.
    pub human_penetration: super::penetration::HumanPenetration,
    /// Seconds of motion (agents × take length) per wall second; absent where the wall time
    /// is left out (a rendered dataset's take: see [`TakeSummary::wall_s`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub agent_seconds_per_wall_s: Option<f64>,
    pub checks: TakeChecks,
}

/// Sanity of every frame of every agent: finite, upright, feet on the floor, in the region.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct TakeChecks {
    /// Frames with a non-finite pose, translation or marker.
    pub non_finite_frames: usize,
    /// Lowest eye (CPF) height above the floor under the pelvis over all frames (m).
    pub min_eye_height_m: f64,
    /// Largest distance of the lowest body marker from the floor under the pelvis over all
    /// frames (m): a body floating or sinking shows here.
    pub max_lowest_marker_gap_m: f64,
    /// Deepest any body marker went below the floor of the map cell under it, over all
    /// frames (m; 0 when none did): a foot in a floor, or in the edge of a step it crosses
    /// on stepped floors.
    pub max_marker_below_floor_m: f64,
    /// Share of frames whose pelvis stands outside the region starts and goals are drawn in
    /// (0 without a region).
    pub outside_region_share: f64,
    /// How far such a pelvis stood from the walkable floor at most (m): a body brushing a
    /// doorway stands a few centimetres out, one that left the dwelling metres.
    pub outside_region_max_m: f64,
    /// Frames, over all agents, whose pelvis path from the frame before passes over a cell
    /// that is not walkable: the pelvis in or through a wall or furniture (0 with the swept
    /// scene test, [`crate::walker::WalkerSettings::scene_every_frame`]).
    pub pelvis_off_floor_frames: usize,
    /// Walkable floor, and the part of it starts and goals are drawn on (m²).
    pub walkable_m2: f64,
    pub region_m2: f64,
}

/// Checks every frame of a take.
pub(crate) fn take_checks(world: &CrowdWorld, take: &CrowdTake) -> TakeChecks {
    let mut c = TakeChecks {
        non_finite_frames: 0,
        min_eye_height_m: f64::INFINITY,
        max_lowest_marker_gap_m: 0.0,
        max_marker_below_floor_m: 0.0,
        outside_region_share: 0.0,
        outside_region_max_m: 0.0,
        pelvis_off_floor_frames: take.agents.iter().map(|a| a.pelvis_off_floor_frames).sum(),
        walkable_m2: world.map.walkable_count() as f64 * world.map.cell_m * world.map.cell_m,
        region_m2: 0.0,
    };
    let cell_m2 = world.map.cell_m * world.map.cell_m;
    c.region_m2 = match &world.region {
        Some(r) => r.iter().filter(|&&x| x).count() as f64 * cell_m2,
        None => c.walkable_m2,
    };
    let (mut outside, mut frames) = (0usize, 0usize);
    for a in &take.agents {
        for f in 0..a.frames.len() {
            frames += 1;
            let finite = a.frames[f].pose.iter().all(|v| v.is_finite())
                && a.frames[f].transl.is_finite()
                && a.markers[f].iter().all(|m| m.is_finite());
            if !finite {
                c.non_finite_frames += 1;
                continue;
            }
            let floor = world.map.floor_under(a.pelvis_xy[f]);
            c.min_eye_height_m = c
                .min_eye_height_m
                .min(a.world_from_cpf[f].translation.z - floor);
            let lowest = a.markers[f]
                .iter()
                .map(|m| m.z)
                .fold(f64::INFINITY, f64::min);
            c.max_lowest_marker_gap_m = c.max_lowest_marker_gap_m.max((lowest - floor).abs());
            for m in &a.markers[f] {
                if let Some(under) = world.map.cell_floor_at(DVec2::new(m.x, m.y)) {
                    c.max_marker_below_floor_m = c.max_marker_below_floor_m.max(under - m.z);
                }
            }
            if let Some(region) = &world.region {
                let inside = world
                    .map
                    .cell_of(a.pelvis_xy[f])
                    .is_some_and(|(i, j)| region[j * world.map.nx + i]);
                if !inside {
                    outside += 1;
                    let off = -world.map.sdf_at(a.pelvis_xy[f]);
                    c.outside_region_max_m = c.outside_region_max_m.max(off);
                }
            }
        }
    }
    c.outside_region_share = outside as f64 / frames.max(1) as f64;
    c
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct TakeSummary {
    pub about: serde_json::Value,
    pub frames: usize,
    pub frame_rate_hz: f64,
    pub primitives: usize,
    /// Seconds the walk took. Absent in a rendered dataset's `sequence/`, so that one config
    /// gives the same bytes (and manifest) run after run; `egogen-run` prints it instead.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_s: Option<f64>,
    pub totals: TakeTotals,
    pub agents: Vec<AgentTrack>,
}

/// Refuses an output folder that exists and is not empty (nothing is overwritten), or a
/// `.partial` folder beside it that is not a take's leftover.
pub(crate) fn check_out_dir(dir: &Path) -> Result<()> {
    refuse_existing_folder(dir, "output.dir")?;
    let staging = partial_of(dir);
    if staging.exists() && !is_take_leftover(&staging) {
        bail!(
            "{} exists and is not an interrupted synth take; move it away or delete it (nothing was touched)",
            staging.display()
        );
    }
    Ok(())
}

const TAKE_ENTRIES: [&str; 4] = ["agents", "paths.png", "summary.json", "manifest.json"];

fn is_take_leftover(dir: &Path) -> bool {
    super::sequence_dir::holds_only(dir, &TAKE_ENTRIES)
}

/// A progress bar over the take's rounds (hidden when `show` is false).
pub(crate) fn progress_bar(show: bool, rounds: usize) -> indicatif::ProgressBar {
    match show {
        true => crate::progress::progress_bar(
            "egogen synth",
            "walking",
            "primitives per agent",
            rounds as u64,
            0,
        ),
        false => indicatif::ProgressBar::hidden(),
    }
}

/// Share of (agent, frame) pairs with a marker inside another agent's 2D box.
pub(crate) fn human_overlap_share(agents: &[AgentTrack]) -> f64 {
    let frames = agents.iter().map(|a| a.frames.len()).min().unwrap_or(0);
    if agents.len() < 2 || frames == 0 {
        return 0.0;
    }
    let mut hits = 0usize;
    for f in 0..frames {
        let boxes: Vec<Obstacle2> = agents
            .iter()
            .map(|a| footprint(a.markers[f].iter(), &a.world_from_cpf[f], a.pelvis_xy[f]))
            .collect();
        for (i, a) in agents.iter().enumerate() {
            let inside = a.markers[f].iter().any(|m| {
                let q = m.truncate();
                boxes
                    .iter()
                    .enumerate()
                    .any(|(k, b)| k != i && b.contains(q))
            });
            hits += usize::from(inside);
        }
    }
    hits as f64 / (frames * agents.len()) as f64
}

fn markers_npy(track: &AgentTrack) -> Result<Vec<u8>> {
    let n = track.markers.len() as u64;
    let m = track.markers.first().map_or(0, Vec::len) as u64;
    let mut bytes = Vec::new();
    {
        use npyz::WriterBuilder;
        let mut w = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[n, m, 3])
            .writer(&mut bytes)
            .begin_nd()?;
        for frame in &track.markers {
            for v in frame {
                for c in v.to_array() {
                    w.push(&(c as f32))?;
                }
            }
        }
        w.finish()?;
    }
    Ok(bytes)
}

/// Each held object's pose per frame: float64 K×N×4×4 (`world_from_object`, row-major), in
/// the order of the summary's `held_objects`.
fn held_objects_npy(track: &AgentTrack) -> Result<Vec<u8>> {
    let k = track.held_objects.len() as u64;
    let n = track.frames.len() as u64;
    let mut bytes = Vec::new();
    {
        use npyz::WriterBuilder;
        let mut w = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[k, n, 4, 4])
            .writer(&mut bytes)
            .begin_nd()?;
        for o in &track.held_objects {
            for pose in &o.world_from_object {
                for v in crate::math::row_major(*pose).as_flattened() {
                    w.push(v)?;
                }
            }
        }
        w.finish()?;
    }
    Ok(bytes)
}

/// Each scene object move's horizontal offset per frame: float64 K×N×2 (m), in the order of
/// the summary's `moved_objects`.
fn moved_objects_npy(track: &AgentTrack) -> Result<Vec<u8>> {
    let k = track.moved_objects.len() as u64;
    let n = track.frames.len();
    let mut bytes = Vec::new();
    {
        use npyz::WriterBuilder;
        let mut w = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[k, n as u64, 2])
            .writer(&mut bytes)
            .begin_nd()?;
        for m in &track.moved_objects {
            for f in 0..n {
                for v in m.offset_at(f) {
                    w.push(&v)?;
                }
            }
        }
        w.finish()?;
    }
    Ok(bytes)
}

fn paths_png(world: &CrowdWorld, take: &CrowdTake, path: &Path) -> Result<()> {
    paths_picture(world, &[take], 900).image.write_png(path)?;
    Ok(())
}

/// A top view of the takes' paths over the walkable map: the region shaded, static
/// obstacles dark red, moving ones at the first take's start (light) and end (dark), per
/// agent its pelvis path, start (dot in a ring), goals (dots; a white centre: missed),
/// activities done ([`activity_mark`]) and end (a disc; black: fell or failed). Several takes
/// of one world draw over each other.
pub(crate) fn paths_picture<'a>(
    world: &'a CrowdWorld,
    takes: &[&CrowdTake],
    max_side_px: usize,
) -> MapPicture<'a> {
    let mut pic = MapPicture::new(&world.map, max_side_px);
    if let Some(region) = &world.region {
        // Walkable ground outside the region starts and goals are drawn in.
        let outside: Vec<bool> = world
            .map
            .walkable
            .iter()
            .zip(region)
            .map(|(&w, &r)| w && !r)
            .collect();
        pic.shade_cells(&outside, [222, 226, 212]);
    }
    for o in &world.obstacles {
        pic.obstacle(o, [120, 30, 30]);
    }
    let end_s = takes
        .first()
        .map_or(0.0, |t| t.frames as f64 / t.frame_rate_hz);
    for m in &world.moving {
        pic.obstacle(&m.at(0.0), [200, 150, 150]);
        pic.obstacle(&m.at(end_s), [120, 30, 30]);
        pic.line(m.at(0.0).centre(), m.at(end_s).centre(), [200, 150, 150]);
    }
    for (i, a) in takes.iter().flat_map(|t| t.agents.iter().enumerate()) {
        let c = AGENT_COLOURS[i % AGENT_COLOURS.len()];
        for w in a.pelvis_xy.windows(2) {
            pic.line(w[0], w[1], c);
        }
        for g in &a.goals {
            let p = DVec2::from_array(g.goal);
            pic.dot(p, 5, c);
            if !g.reached {
                pic.dot(p, 2, [255, 255, 255]);
            }
        }
        for r in &a.activities {
            activity_mark(&mut pic, r.activity, DVec2::from_array(r.place), c);
        }
        if let Some(&s) = a.pelvis_xy.first() {
            pic.dot(s, 4, [0, 0, 0]);
            pic.dot(s, 2, c);
        }
        if let Some(&e) = a.pelvis_xy.last() {
            let mark = match a.state {
                AgentState::Fell | AgentState::DecoderFailure => [0, 0, 0],
                _ => c,
            };
            pic.obstacle(
                &Obstacle2::Circle {
                    centre: e,
                    radius_m: 0.15,
                },
                mark,
            );
        }
    }
    pic
}

/// Where an activity was done, in the agent's colour on black: a sit as a square on the seat,
/// a pick-up as a cross, a stand (and any other) as a ring.
fn activity_mark(pic: &mut MapPicture, activity: Activity, p: DVec2, c: [u8; 3]) {
    let square = |half: f64| Obstacle2::Box {
        centre: p,
        half_extents: DVec2::splat(half),
        yaw_rad: 0.0,
    };
    match activity {
        Activity::Sit => {
            pic.obstacle(&square(0.16), [0, 0, 0]);
            pic.obstacle(&square(0.1), c);
        }

        Activity::PickUp => {
            let black: &[f64] = &[-0.045, -0.015, 0.015, 0.045];
            for (d, rgb, offsets) in [(0.22, [0, 0, 0], black), (0.18, c, &[-0.015, 0.0, 0.015])] {
                for &o in offsets {
                    // Each diagonal drawn thick: moved across itself.
                    let (n, m) = (DVec2::new(o, -o), DVec2::new(o, o));
                    pic.line(p + DVec2::new(-d, -d) + n, p + DVec2::new(d, d) + n, rgb);
                    pic.line(p + DVec2::new(-d, d) + m, p + DVec2::new(d, -d) + m, rgb);
                }
            }
        }
        Activity::Walk => {}
        // Standing, and any other activity done where the walk ended.
        _ => {
            pic.dot(p, 8, [0, 0, 0]);
            pic.dot(p, 6, c);
            pic.dot(p, 3, [255, 255, 255]);
        }
    }
}

/// Writes a take folder (see the module docs); `dir` must pass [`check_out_dir`]. `wall_s`:
/// the seconds the walk took, when the summary should record them.
pub(crate) fn write_crowd_dir(
    dir: &Path,
    world: &CrowdWorld,
    body: &BodyModel,
    take: &CrowdTake,
    wall_s: Option<f64>,
    about: serde_json::Value,
) -> Result<CrowdOutputs> {
    check_out_dir(dir)?;
    let staging = partial_of(dir);
    if staging.exists() {
        std::fs::remove_dir_all(&staging)
            .with_context(|| format!("removing stale {}", staging.display()))?;
    }
    for a in &take.agents {
        let folder = staging.join("agents").join(&a.name);
        std::fs::create_dir_all(&folder)
            .with_context(|| format!("creating {}", folder.display()))?;
        a.motion_sequence(take.frame_rate_hz)
            .write_amass(&folder.join("motion.npz"))?;
        write_atomically(
            &folder.join("cpf_trajectory.json"),
            &super::sequence_dir::cpf_trajectory_json(&a.world_from_cpf, take.frame_rate_hz)?,
        )?;
        write_atomically(&folder.join("markers.npy"), &markers_npy(a)?)?;
        if !a.held_objects.is_empty() {
            write_atomically(&folder.join("held_objects.npy"), &held_objects_npy(a)?)?;
        }
        if !a.moved_objects.is_empty() {
            write_atomically(&folder.join("moved_objects.npy"), &moved_objects_npy(a)?)?;
        }
    }
    paths_png(world, take, &staging.join("paths.png"))?;
    let n = take.agents.len().max(1) as f64;
    let totals = TakeTotals {
        agents: take.agents.len(),
        goals: take.agents.iter().map(|a| a.goals.len()).sum(),
        goals_reached: take
            .agents
            .iter()
            .map(|a| a.goals.iter().filter(|g| g.reached).count())
            .sum(),
        agents_fallen: take
            .agents
            .iter()
            .filter(|a| a.state == AgentState::Fell)
            .count(),
        stuck_share: take
            .agents
            .iter()
            .map(|a| a.stuck_primitives)
            .sum::<usize>() as f64
            / take
                .agents
                .iter()
                .map(|a| a.primitives)
                .sum::<usize>()
                .max(1) as f64,
        agents_decoder_failure: take
            .agents
            .iter()
            .filter(|a| a.state == AgentState::DecoderFailure)
            .count(),
        contact_mean: take.agents.iter().map(|a| a.contact).sum::<f64>() / n,
        penetration_share_mean: take.agents.iter().map(|a| a.penetration_share).sum::<f64>() / n,
        human_overlap_share: human_overlap_share(&take.agents),
        human_penetration: super::penetration::human_penetration(body, &take.agents, 4)?,
        checks: take_checks(world, take),
        agent_seconds_per_wall_s: wall_s.map(|w| {
            take.agents.len() as f64 * take.frames as f64 / take.frame_rate_hz / w.max(1e-9)
        }),
    };
    let summary = TakeSummary {
        about,
        frames: take.frames,
        frame_rate_hz: take.frame_rate_hz,
        primitives: take.primitives,
        wall_s,
        totals,
        agents: take.agents.clone(),
    };
    let mut summary_json = serde_json::to_value(&summary)?;
    summary_json["body_model"] = serde_json::to_value(&body.source)?;
    write_atomically(
        &staging.join("summary.json"),
        &serde_json::to_vec_pretty(&summary_json)?,
    )?;
    let listed = build_manifest(&staging)?;
    write_atomically(
        &staging.join(MANIFEST),
        &serde_json::to_vec_pretty(&listed)?,
    )?;
    if dir.exists() {
        std::fs::remove_dir(dir)?;
    }
    std::fs::rename(&staging, dir)
        .with_context(|| format!("moving {} into place", staging.display()))?;
    Ok(CrowdOutputs {
        dir: dir.into(),
        summary,
    })
}
