//! Per-episode measures of a crowd take and their means over a table row (paper S4.2):
//! success (pelvis within the goal radius), final distance, foot contact (Eq. 12 with 3-D foot
//! speed), Pene-S (frames with a body marker inside an obstacle's footprint), Pene-H (body
//! vertices inside another body: its capsule volume, a lower bound, and exactly its posed mesh,
//! [`crate::synth::penetration`]), view cos, pose-prior score, walking speed, and the spread
//! of repeated paths (diversity: lateral offsets at stations, and the paper's standard
//! deviation of pelvis locations at each time).

use glam::DVec2;
use serde::Serialize;

use crate::body::{BodyModel, PoseError};
use crate::synth::crowd::{AgentState, CrowdTake, CrowdWorld};
use crate::synth::crowd_dir::human_overlap_share;
use crate::synth::penetration::human_penetration;

/// Frames between Pene-H checks (as `egogen synth`).
pub(crate) const PENE_H_EVERY_N_FRAMES: usize = 4;

/// What one person did in one episode.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct AgentResult {
    pub agent: String,
    pub reached: bool,
    pub final_distance_m: f64,
    pub contact: f64,
    /// Share of the person's new frames with a body marker inside an obstacle's footprint
    /// (static or moving); `None` in a scene without obstacles.
    pub obstacle_penetration_share: Option<f64>,
    pub view_cos: f64,
    pub pose_score: f64,
    pub speed_m_s: f64,
    pub primitives: usize,
    pub fell: bool,
    pub decoder_failure: bool,
}

/// One episode of one scenario with one controller.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct EpisodeResult {
    pub scenario: String,
    pub controller: String,
    pub episode: u64,
    pub agents: Vec<AgentResult>,
    /// Share of (person, frame) pairs, every [`PENE_H_EVERY_N_FRAMES`]-th frame, with a vertex
    /// inside another body's capsules; `None` with one person.
    pub human_penetration_share: Option<f64>,
    /// The same with a vertex inside another body's posed mesh (exact); `None` with one person.
    #[serde(default)]
    pub human_mesh_penetration_share: Option<f64>,
    /// Mean number of vertices inside other bodies' meshes per checked (person, frame).
    #[serde(default)]
    pub human_mesh_vertices_inside_mean: Option<f64>,
    /// Share of (person, frame) pairs with a marker inside another person's 2D box.
    pub human_overlap_share: Option<f64>,
    /// The first person's pelvis path (horizontal, every 4th frame) where a scenario's
    /// diversity is measured; empty (and not written) elsewhere.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pelvis_path: Vec<[f64; 2]>,
    pub wall_s: f64,
}

/// Measures a finished take.
pub(crate) fn measure(
    body: &BodyModel,
    world: &CrowdWorld,
    take: &CrowdTake,
    scenario: String,
    controller: String,
    episode: u64,
    wall_s: f64,
) -> Result<EpisodeResult, PoseError> {
    let has_obstacles = !world.obstacles.is_empty() || !world.moving.is_empty();
    let agents = take
        .agents
        .iter()
        .map(|a| {
            let last = a.goals.last();
            let goal = a.goals.first().map(|g| DVec2::from_array(g.goal));
            let end = *a.pelvis_xy.last().expect("a take has frames");
            AgentResult {
                agent: a.name.clone(),
                reached: !a.goals.is_empty() && a.goals.iter().all(|g| g.reached),
                final_distance_m: match (last, goal) {
                    (Some(g), _) => g.final_distance_m,
                    (None, Some(g)) => end.distance(g),
                    (None, None) => f64::NAN,
                },
                contact: a.contact,
                obstacle_penetration_share: has_obstacles.then_some(a.penetration_share),
                view_cos: a.view_cos,
                pose_score: a.pose_score,
                speed_m_s: a.speed_m_s,
                primitives: a.primitives,
                fell: a.state == AgentState::Fell,
                decoder_failure: a.state == AgentState::DecoderFailure,
            }
        })
        .collect();
    let crowd = take.agents.len() > 1;
    let penetration = if crowd {
        Some(human_penetration(
            body,
            &take.agents,
            PENE_H_EVERY_N_FRAMES,
        )?)
    } else {
        None
    };
    Ok(EpisodeResult {
        scenario,
        controller,
        episode,
        agents,
        human_penetration_share: penetration.map(|p| p.penetrating_share),
        human_mesh_penetration_share: penetration.map(|p| p.mesh_penetrating_share),
        human_mesh_vertices_inside_mean: penetration.map(|p| p.mesh_vertices_inside_mean),
        human_overlap_share: crowd.then(|| human_overlap_share(&take.agents)),
        pelvis_path: take.agents[0]
            .pelvis_xy
            .iter()
            .step_by(4)
            .map(|p| p.to_array())
            .collect(),
        wall_s,
    })
}

/// Lateral offsets of a path from the line `start → goal` where it first passes each of
/// `stations` evenly spaced points of that line (from 10 % to 90 % of the way); `None` where
/// the path never gets there.
pub(crate) fn lateral_offsets(
    path: &[[f64; 2]],
    start: DVec2,
    goal: DVec2,
    stations: usize,
) -> Vec<Option<f64>> {
    let along = (goal - start).normalize_or_zero();
    let length = start.distance(goal);
    let local: Vec<DVec2> = path
        .iter()
        .map(|&p| {
            let d = DVec2::from_array(p) - start;
            DVec2::new(d.dot(along), along.perp_dot(d))
        })
        .collect();
    (0..stations)
        .map(|s| {
            let x = length * (0.1 + 0.8 * s as f64 / (stations.max(2) - 1) as f64);
            local.windows(2).find_map(|w| {
                let (a, b) = (w[0], w[1]);
                (a.x < x && b.x >= x).then(|| a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x))
            })
        })
        .collect()
}

/// Path diversity of repeated walks of one scene: the standard deviation over the walks of
/// the lateral offset at 9 stations along the line (10–90 % of the way), averaged over the
/// stations (m), and the share of walks that pass the midpoint on the left.
pub(crate) fn path_diversity(
    paths: &[&[[f64; 2]]],
    start: DVec2,
    goal: DVec2,
) -> Option<(f64, f64)> {
    const STATIONS: usize = 9;
    let offsets: Vec<Vec<Option<f64>>> = paths
        .iter()
        .map(|p| lateral_offsets(p, start, goal, STATIONS))
        .collect();
    let mut stds = Vec::new();
    for s in 0..STATIONS {
        let ys: Vec<f64> = offsets.iter().filter_map(|o| o[s]).collect();
        if ys.len() >= 2 {
            let mean = ys.iter().sum::<f64>() / ys.len() as f64;
            let var = ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (ys.len() - 1) as f64;
            stds.push(var.sqrt());
        }
    }
    if stds.is_empty() {
        return None;
    }
    let mid: Vec<f64> = offsets.iter().filter_map(|o| o[STATIONS / 2]).collect();
    let left = mid.iter().filter(|&&y| y > 0.0).count() as f64 / mid.len().max(1) as f64;
    Some((stds.iter().sum::<f64>() / stds.len() as f64, left))
}

/// Path diversity the paper's way (S5.1: "the standard deviation of pelvis locations for the
/// same start–target pairs"), as read here: at each time of the walks (the paths' common
/// sampling, a walk that has stopped staying where it stopped), the standard deviation of the
/// walks' horizontal pelvis locations (root of the summed per-axis variances), averaged over
/// the times; `None` with fewer than two walks.
pub(crate) fn location_spread(paths: &[&[[f64; 2]]]) -> Option<f64> {
    let paths: Vec<&[[f64; 2]]> = paths.iter().copied().filter(|p| !p.is_empty()).collect();
    let n = paths.len();
    let times = paths.iter().map(|p| p.len()).max()?;
    if n < 2 {
        return None;
    }
    let at = |p: &[[f64; 2]], t: usize| DVec2::from_array(p[t.min(p.len() - 1)]);
    let total: f64 = (0..times)
        .map(|t| {
            let mean = paths.iter().map(|p| at(p, t)).sum::<DVec2>() / n as f64;
            let var = paths
                .iter()
                .map(|p| at(p, t).distance_squared(mean))
                .sum::<f64>()
                / (n - 1) as f64;
            var.sqrt()
        })
        .sum();
    Some(total / times as f64)
}

/// The literal reading of the paper's diversity: the standard deviation of every pelvis
/// location of every walk pooled (root of the summed per-axis variances), which grows with the
/// walk's length as much as with how the walks differ (one straight 5 m walk at an even pace
/// alone gives 5 / √12 = 1.44 m); `None` with fewer than two locations.
pub(crate) fn pooled_location_std(paths: &[&[[f64; 2]]]) -> Option<f64> {
    let all: Vec<DVec2> = paths
        .iter()
        .flat_map(|p| p.iter().map(|&q| DVec2::from_array(q)))
        .collect();
    if all.len() < 2 {
        return None;
    }
    let mean = all.iter().sum::<DVec2>() / all.len() as f64;
    let var = all.iter().map(|q| q.distance_squared(mean)).sum::<f64>() / (all.len() - 1) as f64;
    Some(var.sqrt())
}

/// A table row: the means over every person of every episode of one scenario and controller.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub(crate) struct Row {
    pub scenario: String,
    pub controller: String,
    pub episodes: usize,
    pub people: usize,
    /// SR: share of people who reached their goal.
    pub success_rate: f64,
    pub final_distance_m: f64,
    pub contact: f64,
    /// Pene-S (share of frames), scenarios with obstacles.
    pub obstacle_penetration_share: Option<f64>,
    /// Pene-H (share of person-frames), scenarios with several people: a vertex inside another
    /// body's capsules (a lower bound) …
    pub human_penetration_share: Option<f64>,
    /// … and inside another body's posed mesh (exact; absent in rows written before it).
    #[serde(default)]
    pub human_mesh_penetration_share: Option<f64>,
    /// Mean vertices inside other bodies' meshes per checked person-frame.
    #[serde(default)]
    pub human_mesh_vertices_inside_mean: Option<f64>,
    pub human_overlap_share: Option<f64>,
    /// Std of the paths (m) and the share passing left (static box only).
    pub path_std_m: Option<f64>,
    pub path_left_share: Option<f64>,
    /// The paper's diversity: std of pelvis locations at each time ([`location_spread`]).
    #[serde(default)]
    pub path_location_std_m: Option<f64>,
    /// The literal reading: every location pooled ([`pooled_location_std`]).
    #[serde(default)]
    pub path_pooled_std_m: Option<f64>,
    pub view_cos: f64,
    pub pose_score: f64,
    /// Mean walking speed of the people who reached their goal (m/s).
    pub speed_successful_m_s: Option<f64>,
    pub fallen: usize,
    pub decoder_failures: usize,
    pub wall_s: f64,
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The row of a set of episodes of one scenario and controller; `line` is the start and goal
/// of a scenario whose episodes all walk the same line (path diversity).
pub(crate) fn row(episodes: &[EpisodeResult], line: Option<(DVec2, DVec2)>) -> Row {
    let people = || episodes.iter().flat_map(|e| e.agents.iter());
    let paths: Vec<&[[f64; 2]]> = episodes.iter().map(|e| e.pelvis_path.as_slice()).collect();
    let diversity = line.and_then(|(s, g)| path_diversity(&paths, s, g));
    Row {
        scenario: episodes
            .first()
            .map(|e| e.scenario.clone())
            .unwrap_or_default(),
        controller: episodes
            .first()
            .map(|e| e.controller.clone())
            .unwrap_or_default(),
        episodes: episodes.len(),
        people: people().count(),
        success_rate: mean(people().map(|a| f64::from(u8::from(a.reached)))).unwrap_or(0.0),
        final_distance_m: mean(people().map(|a| a.final_distance_m)).unwrap_or(f64::NAN),
        contact: mean(people().map(|a| a.contact)).unwrap_or(f64::NAN),
        obstacle_penetration_share: mean(people().filter_map(|a| a.obstacle_penetration_share)),
        human_penetration_share: mean(episodes.iter().filter_map(|e| e.human_penetration_share)),
        human_mesh_penetration_share: mean(
            episodes
                .iter()
                .filter_map(|e| e.human_mesh_penetration_share),
        ),
        human_mesh_vertices_inside_mean: mean(
            episodes
                .iter()
                .filter_map(|e| e.human_mesh_vertices_inside_mean),
        ),
        human_overlap_share: mean(episodes.iter().filter_map(|e| e.human_overlap_share)),
        path_std_m: diversity.map(|d| d.0),
        path_left_share: diversity.map(|d| d.1),
        path_location_std_m: line.and_then(|_| location_spread(&paths)),
        path_pooled_std_m: line.and_then(|_| pooled_location_std(&paths)),
        view_cos: mean(people().map(|a| a.view_cos)).unwrap_or(f64::NAN),
        pose_score: mean(people().map(|a| a.pose_score)).unwrap_or(f64::NAN),
        speed_successful_m_s: mean(people().filter(|a| a.reached).map(|a| a.speed_m_s)),
        fallen: people().filter(|a| a.fell).count(),
        decoder_failures: people().filter(|a| a.decoder_failure).count(),
        wall_s: episodes.iter().map(|e| e.wall_s).sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_location_spread_of_mirrored_walks_is_their_distance_apart_over_root_two() {
        // Two walks mirrored about the x axis, 1 m apart in y at every time: each time's
        // std is sqrt((0.5² + 0.5²) / 1) = 1/√2.
        let up: Vec<[f64; 2]> = (0..5).map(|t| [t as f64, 0.5]).collect();
        let down: Vec<[f64; 2]> = (0..5).map(|t| [t as f64, -0.5]).collect();
        let s = location_spread(&[&up, &down]).unwrap();
        assert!((s - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12, "{s}");
        // A walk that stops early stays where it stopped: the later times see it behind.
        let short: Vec<[f64; 2]> = (0..3).map(|t| [t as f64, 0.5]).collect();
        let same: Vec<[f64; 2]> = (0..5).map(|t| [t as f64, 0.5]).collect();
        let s = location_spread(&[&short, &same]).unwrap();
        // Times 3 and 4: 1 m and 2 m apart along x, std 1/√2 and 2/√2; the rest 0.
        let expected = (1.0 + 2.0) * std::f64::consts::FRAC_1_SQRT_2 / 5.0;
        assert!((s - expected).abs() < 1e-12, "{s} {expected}");
        assert_eq!(location_spread(&[&up]), None);
        // Pooled: one straight walk at an even pace, 0..=4 m in steps of 1 m: the sample std
        // of 0, 1, 2, 3, 4 is √2.5.
        let line: Vec<[f64; 2]> = (0..5).map(|t| [t as f64, 0.0]).collect();
        let pooled = pooled_location_std(&[&line]).unwrap();
        assert!((pooled - 2.5f64.sqrt()).abs() < 1e-12, "{pooled}");
        assert_eq!(location_spread(&[]), None);
    }
}
