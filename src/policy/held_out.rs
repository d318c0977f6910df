//! Evaluation of a controller over a fixed set of held-out episodes: the first `episodes`
//! episodes of an environment whose `episode_base` training never uses, however many run in
//! parallel. Reported as EgoGen's box-scene table: success (pelvis within the success radius
//! of the goal), foot contact (3-D, Eq. 12), penetration (share of frames with a body marker
//! inside the obstacle), cos(view, goal direction) (over all primitives, and over those before
//! the arrival), walking speed over successful episodes and
//! the distribution of episode lengths; in a scene with a 3D SDF, scene penetration by paper
//! Eq. 11 (frames with at least 40 body vertices inside the scene); indoors, success by the
//! way round walls and by the detour it makes.

use serde::Serialize;

use super::env::{Ending, EnvError, EpisodeSummary, PolicyEnv, StepOutput};
use crate::math::Quantiles;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};

/// Episode base of held-out evaluation episodes (training bases are small integers).
pub(crate) const HELD_OUT_BASE: u64 = 0xE7A1_0000_0000;

/// Success among the episodes whose measure lies in `[from_m, to_m)` (the last bin's `to_m` is
/// infinite: `null` in the report's JSON).
#[derive(Debug, Clone, Serialize)]
pub(crate) struct SuccessBin {
    pub from_m: f64,
    pub to_m: f64,
    pub episodes: usize,
    pub success_rate: f64,
}

/// Bins of the way round (m): the evaluations' goals lie 2–7 m away in a straight line, and
/// 13 primitives of 0.45 s at a person's 1.2 m/s walk about 7 m.
const WAY_ROUND_EDGES_M: [f64; 6] = [0.0, 3.0, 5.0, 7.0, 9.0, f64::INFINITY];
/// Bins of the detour (m).
const DETOUR_EDGES_M: [f64; 5] = [0.0, 0.5, 2.0, 4.0, f64::INFINITY];

/// Success of the episodes with a measure (`None`: left out), binned by `edges`; empty when
/// no episode has one.
fn success_by(
    summaries: &[EpisodeSummary],
    measure: impl Fn(&EpisodeSummary) -> Option<f64>,
    edges: &[f64],
) -> Vec<SuccessBin> {
    let measured: Vec<(f64, bool)> = summaries
        .iter()
        .filter_map(|s| measure(s).map(|m| (m, s.ending == Ending::Success)))
        .collect();
    if measured.is_empty() {
        return Vec::new();
    }
    edges
        .windows(2)
        .map(|w| {
            let inside: Vec<bool> = measured
                .iter()
                .filter(|(m, _)| *m >= w[0] && *m < w[1])
                .map(|(_, ok)| *ok)
                .collect();
            SuccessBin {
                from_m: w[0],
                to_m: w[1],
                episodes: inside.len(),
                success_rate: inside.iter().filter(|ok| **ok).count() as f64
                    / inside.len().max(1) as f64,
            }
        })
        .collect()
}

/// The measures of a set of episodes.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct EvalReport {
    pub episodes: usize,
    pub success_rate: f64,
    pub timeout_rate: f64,
    pub penetration_end_rate: f64,
    pub failure_rate: f64,
    pub contact_mean: f64,
    pub penetration_share_mean: f64,
    pub view_cos_mean: f64,
    /// Mean over episodes of cos(view, goal direction) at the ends of the primitives before
    /// the arrival (those ending outside the success radius; episodes arriving in their first
    /// primitive left out).
    pub view_cos_walking_mean: f64,
    /// cos(view, goal direction) at the end of the first, second, … primitive, over the
    /// episodes that took it.
    pub view_cos_by_primitive: Vec<Quantiles>,
    /// Angle between the view and the direction of travel (degrees), over every primitive
    /// that travelled: how far the head looks off the way the body walks.
    pub view_off_travel_deg: Quantiles,
    /// Paper Eq. 11 (0 without a scene SDF): mean share of an episode's frames with at least
    /// 40 body vertices inside the scene, share of episodes with any such frame, and the most
    /// vertices inside in any frame of any episode.
    pub scene_penetration_share_mean: f64,
    pub scene_penetration_episode_rate: f64,
    pub scene_vertices_inside_max: usize,
    /// The pelvis over a wall: share of episodes in which its path passed over a cell that is
    /// not walkable (through a wall, furniture or a closed doorway; the controller as it is,
    /// without the redraws a take makes), and the mean share of their frames.
    pub pelvis_over_wall_episode_rate: f64,
    pub pelvis_over_wall_share_mean: f64,
    pub final_distance_m: Quantiles,
    /// The mean over episodes of their primitives' largest pose embedding norms (Table 3's
    /// ‖VP‖₂).
    pub pose_norm_max_mean: f64,
    pub speed_successful_m_s: Quantiles,
    pub primitives: Quantiles,
    pub reward_mean: f64,
    /// Success by the walking distance from start to goal round walls (indoor episodes whose
    /// way round was measured; empty otherwise): how far a goal lies on foot, against the
    /// time an episode has.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub success_by_way_round: Vec<SuccessBin>,
    /// Success by the detour: the way round less the straight start–goal distance (a goal in
    /// the open has none; one behind a wall, the way to and through its doorway).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub success_by_detour: Vec<SuccessBin>,
    /// Environment steps taken (all parallel episodes) and wall time (s).
    pub env_steps: usize,
    pub wall_s: f64,
}

impl EvalReport {
    pub(crate) fn of(summaries: &[EpisodeSummary], env_steps: usize, wall_s: f64) -> Self {
        let n = summaries.len().max(1) as f64;
        let rate = |e: Ending| summaries.iter().filter(|s| s.ending == e).count() as f64 / n;
        let mean = |f: fn(&EpisodeSummary) -> f64| summaries.iter().map(f).sum::<f64>() / n;
        Self {
            episodes: summaries.len(),
            success_rate: rate(Ending::Success),
            timeout_rate: rate(Ending::Timeout),
            penetration_end_rate: rate(Ending::Penetration),
            failure_rate: rate(Ending::Failure),
            contact_mean: mean(|s| s.contact),
            penetration_share_mean: mean(|s| s.penetration_share),
            view_cos_mean: mean(|s| s.view_cos),
            view_cos_walking_mean: {
                let walking: Vec<f64> = summaries
                    .iter()
                    .map(|s| s.view_cos_walking)
                    .filter(|v| !v.is_nan())
                    .collect();
                walking.iter().sum::<f64>() / walking.len().max(1) as f64
            },
            view_cos_by_primitive: (0..summaries
                .iter()
                .map(|s| s.view_cos_each.len())
                .max()
                .unwrap_or(0))
                .map(|k| {
                    Quantiles::of(
                        summaries
                            .iter()
                            .filter_map(|s| s.view_cos_each.get(k).copied()),
                    )
                })
                .collect(),
            view_off_travel_deg: Quantiles::of(
                summaries
                    .iter()
                    .flat_map(|s| s.view_off_travel_deg.iter().copied()),
            ),
            scene_penetration_share_mean: mean(|s| s.scene_penetration_share),
            scene_penetration_episode_rate: summaries
                .iter()
                .filter(|s| s.scene_penetration_share > 0.0)
                .count() as f64
                / n,
            scene_vertices_inside_max: summaries
                .iter()
                .map(|s| s.scene_vertices_inside_max)
                .max()
                .unwrap_or(0),
            pelvis_over_wall_episode_rate: summaries
                .iter()
                .filter(|s| s.pelvis_off_floor_frames > 0)
                .count() as f64
                / n,
            pelvis_over_wall_share_mean: mean(|s| {
                s.pelvis_off_floor_frames as f64
                    / (s.primitives * (PRIMITIVE_FRAMES - SEED_FRAMES)).max(1) as f64
            }),
            final_distance_m: Quantiles::of(summaries.iter().map(|s| s.final_distance_m)),
            pose_norm_max_mean: mean(|s| s.pose_norm_max),
            speed_successful_m_s: Quantiles::of(
                summaries
                    .iter()
                    .filter(|s| s.ending == Ending::Success)
                    .map(|s| s.speed_m_s),
            ),
            primitives: Quantiles::of(summaries.iter().map(|s| s.primitives as f64)),
            reward_mean: mean(|s| s.reward),
            success_by_way_round: success_by(summaries, |s| s.way_round_m, &WAY_ROUND_EDGES_M),
            success_by_detour: success_by(
                summaries,
                |s| s.way_round_m.map(|w| (w - s.start_distance_m).max(0.0)),
                &DETOUR_EDGES_M,
            ),
            env_steps,
            wall_s,
        }
    }
}

/// Runs `step` on `env` until its first `episodes` episodes have ended; their summaries in id
/// order and the number of environment steps taken. `progress` is told of each finished one.
pub(crate) fn run_episodes(
    env: &mut PolicyEnv,
    episodes: usize,
    mut step: impl FnMut(&mut PolicyEnv) -> Result<StepOutput, EnvError>,
    mut progress: impl FnMut(&EpisodeSummary),
) -> Result<(Vec<EpisodeSummary>, usize), EnvError> {
    let mut done: Vec<EpisodeSummary> = Vec::with_capacity(episodes);
    let mut steps = 0;
    while done.len() < episodes {
        let out = step(env)?;
        steps += out.reward.len();
        for s in out.finished {
            if (s.id as usize) < episodes {
                progress(&s);
                done.push(s);
            }
        }
    }
    done.sort_by_key(|s| s.id);
    Ok((done, steps))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::env::summary::mean_before_arrival;

    fn summary(id: u64, ending: Ending, view_cos_each: Vec<f64>) -> EpisodeSummary {
        let n = view_cos_each.len();
        EpisodeSummary {
            id,
            ending,
            primitives: n,
            start_distance_m: 3.0,
            final_distance_m: 0.1,
            reward: 1.0,
            contact: 1.0,
            view_cos: view_cos_each.iter().sum::<f64>() / n.max(1) as f64,
            view_cos_walking: mean_before_arrival(&view_cos_each, ending),
            view_cos_each,
            view_off_travel_deg: vec![10.0, 30.0],
            penetration_share: 0.0,
            speed_m_s: 1.0,
            scene_penetration_share: 0.0,
            scene_vertices_inside_max: 0,
            pelvis_off_floor_frames: 0,
            end_xy: [0.0, 0.0],
            pose_norm_max: 1.0,
            way_round_m: None,
        }
    }

    #[test]
    fn success_is_binned_by_the_way_round_and_the_detour_of_measured_episodes_only() {
        let with_way = |id, ending, way: Option<f64>| EpisodeSummary {
            way_round_m: way,
            ..summary(id, ending, vec![1.0])
        };
        // Straight distance 3 m: ways of 3.2 (no detour), 6 (3 m detour), 10 m (7 m).
        let summaries = [
            with_way(0, Ending::Success, Some(3.2)),
            with_way(1, Ending::Timeout, Some(6.0)),
            with_way(2, Ending::Success, Some(6.5)),
            with_way(3, Ending::Timeout, Some(10.0)),
            with_way(4, Ending::Timeout, None),
        ];
        let r = EvalReport::of(&summaries, 5, 1.0);
        let bins: Vec<(f64, usize, f64)> = r
            .success_by_way_round
            .iter()
            .map(|b| (b.from_m, b.episodes, b.success_rate))
            .collect();
        assert_eq!(
            bins,
            [
                (0.0, 0, 0.0),
                (3.0, 1, 1.0),
                (5.0, 2, 0.5),
                (7.0, 0, 0.0),
                (9.0, 1, 0.0)
            ]
        );
        let detours: Vec<(f64, usize)> = r
            .success_by_detour
            .iter()
            .map(|b| (b.from_m, b.episodes))
            .collect();
        assert_eq!(detours, [(0.0, 1), (0.5, 0), (2.0, 2), (4.0, 1)]);
        let unmeasured = EvalReport::of(&summaries[4..], 1, 1.0);
        assert!(unmeasured.success_by_way_round.is_empty());
        assert!(unmeasured.success_by_detour.is_empty());
    }

    #[test]
    fn the_view_is_reported_with_and_without_the_arrival_and_by_primitive() {
        let summaries = [
            // Arrives in its third primitive standing on the goal, looking past it.
            summary(0, Ending::Success, vec![0.9, 0.7, -0.5]),
            // Times out: every primitive counts.
            summary(1, Ending::Timeout, vec![0.5, 0.9, 1.0, 0.6]),
            // Arrives in its first: nothing before the arrival.
            summary(2, Ending::Success, vec![0.2]),
        ];
        let r = EvalReport::of(&summaries, 8, 1.0);
        let all = (1.1 / 3.0 + 3.0 / 4.0 + 0.2) / 3.0;
        assert!((r.view_cos_mean - all).abs() < 1e-12);
        // (0.9 + 0.7) / 2 and the timeout's 0.75; the third episode left out.
        assert!((r.view_cos_walking_mean - (0.8 + 0.75) / 2.0).abs() < 1e-12);
        // Pooled over every primitive that travelled (two per episode here).
        assert_eq!(r.view_off_travel_deg.count, 6);
        assert!((r.view_off_travel_deg.mean - 20.0).abs() < 1e-12);
        let by: Vec<(usize, f64)> = r
            .view_cos_by_primitive
            .iter()
            .map(|q| (q.count, q.mean))
            .collect();
        let want = [(3, 1.6 / 3.0), (2, 0.8), (2, 0.25), (1, 0.6)];
        assert_eq!(by.len(), want.len());
        for ((n, m), (wn, wm)) in by.iter().zip(want) {
            assert_eq!(*n, wn);
            assert!((m - wm).abs() < 1e-12, "{m} against {wm}");
        }
    }
}
