//! Evaluation of a controller over a fixed set of held-out episodes: the first `episodes`
//! episodes of an environment whose `episode_base` training never uses, however many run in
//! parallel. Reported as EgoGen's box-scene table: success (pelvis within the success radius
//! of the goal), foot contact (3-D, Eq. 12), penetration (share of frames with a body marker
//! inside the obstacle), cos(view, goal direction) (over all primitives, and over those before
//! the arrival), walking speed over successful episodes and
//! the distribution of episode lengths; in a scene with a 3D SDF, scene penetration by paper
//! Eq. 11 (frames with at least 40 body vertices inside the scene).

use serde::Serialize;

use super::env::{Ending, EnvError, EpisodeSummary, PolicyEnv, StepOutput};
use crate::motion::cvae::pace::Quantiles;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};

/// Episode base of held-out evaluation episodes (training bases are small integers).
pub(crate) const HELD_OUT_BASE: u64 = 0xE7A1_0000_0000;

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
    /// Environment steps taken (all parallel episodes) and wall time (s).
    pub env_steps: usize,
    pub wall_s: f64,
}

impl EvalReport {
    pub fn of(summaries: &[EpisodeSummary], env_steps: usize, wall_s: f64) -> Self {
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
    use crate::policy::env::mean_before_arrival;

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
        }
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
