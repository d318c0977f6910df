//! Evaluation of a controller over a fixed set of held-out episodes: the first `episodes`
//! episodes of an environment whose `episode_base` training never uses, however many run in
//! parallel. Reported as EgoGen's box-scene table: success (pelvis within the success radius
//! of the goal), foot contact (3-D, Eq. 12), penetration (share of frames with a body marker
//! inside the obstacle), cos(view, goal direction), walking speed over successful episodes and
//! the distribution of episode lengths; in a scene with a 3D SDF, scene penetration by paper
//! Eq. 11 (frames with at least 40 body vertices inside the scene).

use serde::Serialize;

use super::env::{Ending, EnvError, EpisodeSummary, PolicyEnv, StepOutput};
use crate::motion::cvae::pace::Quantiles;

/// Episode base of held-out evaluation episodes (training bases are small integers).
pub const HELD_OUT_BASE: u64 = 0xE7A1_0000_0000;

/// The measures of a set of episodes.
#[derive(Debug, Clone, Serialize)]
pub struct EvalReport {
    pub episodes: usize,
    pub success_rate: f64,
    pub timeout_rate: f64,
    pub penetration_end_rate: f64,
    pub failure_rate: f64,
    pub contact_mean: f64,
    pub penetration_share_mean: f64,
    pub view_cos_mean: f64,
    /// Paper Eq. 11 (0 without a scene SDF): mean share of an episode's frames with at least
    /// 40 body vertices inside the scene, share of episodes with any such frame, and the most
    /// vertices inside in any frame of any episode.
    pub scene_penetration_share_mean: f64,
    pub scene_penetration_episode_rate: f64,
    pub scene_vertices_inside_max: usize,
    pub final_distance_m: Quantiles,
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
            final_distance_m: Quantiles::of(summaries.iter().map(|s| s.final_distance_m)),
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
pub fn run_episodes(
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
