//! How an episode ended and what it measured.

use super::*;

/// How an episode ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    Success,
    Penetration,
    Timeout,
    /// The decoder produced a non-finite primitive.
    Failure,
}

/// A finished episode.
#[derive(Debug, Clone, Serialize)]
pub struct EpisodeSummary {
    pub id: u64,
    pub ending: Ending,
    pub primitives: usize,
    pub start_distance_m: f64,
    pub final_distance_m: f64,
    /// Sum of rewards.
    pub reward: f64,
    /// Mean foot contact (3-D, Eq. 12) over the primitives.
    pub contact: f64,
    /// Mean cos(view, goal direction) at primitive ends.
    pub view_cos: f64,
    /// cos(view, goal direction) at the end of each primitive, in order.
    pub view_cos_each: Vec<f64>,
    /// Their mean without the arrival (an episode's last primitive when it succeeds), where
    /// the pelvis stands centimetres from the goal and the direction to it is noise; NaN when
    /// the first primitive arrives.
    pub view_cos_walking: f64,
    /// Angle between the view and the direction of travel, each primitive that travelled
    /// (degrees; [`crate::walker::reward::Judged::view_off_travel_rad`]).
    pub view_off_travel_deg: Vec<f64>,
    /// Share of the new frames in which a body marker stood inside the obstacle.
    pub penetration_share: f64,
    /// Horizontal pelvis path length over time (m/s).
    pub speed_m_s: f64,
    /// Share of the new frames penetrating the scene by paper Eq. 11, and the most body
    /// vertices inside it in a frame (0 where the scene has no 3D SDF).
    pub scene_penetration_share: f64,
    pub scene_vertices_inside_max: usize,
    /// New frames whose pelvis path passed over a cell that is not walkable: through a wall,
    /// furniture or a closed doorway ([`crate::walker::reward::path_leaves_floor`]).
    pub pelvis_off_floor_frames: usize,
    /// The pelvis's floor position at the end (m, world).
    pub end_xy: [f64; 2],
    /// The walking distance from the start to the goal round what blocks walking on the
    /// course's map (m; `scene::PathField`: 8-connected 0.1 m cells, a lower bound on a walk
    /// that keeps a body's width off the walls). Indoor courses, when the environment measures
    /// it ([`PolicyEnv::measuring_way_round`]); `None` otherwise or where the goal cannot be
    /// reached on the map.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub way_round_m: Option<f64>,
    /// The mean over its primitives of each one's largest pose embedding norm (EgoGen's
    /// ‖VP‖₂ role, [`crate::walker::PosePrior::embedding_norms`]; comparable with mocap primitives').
    pub pose_norm_max: f64,
}

impl EpisodeSummary {
    /// The summary of a walk that ended.
    pub(crate) fn of(id: u64, ending: Ending, w: &Walker) -> Self {
        let n = w.steps.max(1) as f64;
        Self {
            id,
            ending,
            primitives: w.steps,
            start_distance_m: w.start_distance_m,
            final_distance_m: w.distance_m,
            reward: w.totals.reward,
            contact: w.totals.contact / n,
            view_cos: w.totals.view_cos / n,
            view_cos_each: w.totals.view_cos_each.clone(),
            view_cos_walking: mean_before_arrival(&w.totals.view_cos_each, ending),
            view_off_travel_deg: w
                .totals
                .view_off_travel_rad
                .iter()
                .map(|a| a.to_degrees())
                .collect(),
            penetration_share: w.totals.frames_in_obstacle as f64 / w.totals.frames.max(1) as f64,
            speed_m_s: w.speed_m_s(),
            scene_penetration_share: w.totals.scene_penetrating_frames as f64
                / w.totals.frames.max(1) as f64,
            scene_vertices_inside_max: w.totals.scene_vertices_inside_max,
            pelvis_off_floor_frames: w.totals.pelvis_off_floor_frames,
            end_xy: w.view.pelvis.to_array(),
            pose_norm_max: w.totals.pose_norm_max_sum / n,
            way_round_m: None,
        }
    }
}

/// Mean of a measure taken at each primitive's end, without the arrival (the last primitive
/// of an episode that succeeded); NaN when nothing is left.
pub(crate) fn mean_before_arrival(each: &[f64], ending: Ending) -> f64 {
    let walking = match ending {
        Ending::Success => &each[..each.len().saturating_sub(1)],
        _ => each,
    };
    match walking.len() {
        0 => f64::NAN,
        k => walking.iter().sum::<f64>() / k as f64,
    }
}
