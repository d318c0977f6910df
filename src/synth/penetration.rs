//! Human–human penetration of a take: how often, and how deep, one body's surface enters
//! another's volume. Every `every_n_frames`-th frame, for every agent, its posed vertices are
//! tested against the capsule volumes ([`CapsuleVolume`]) of every other agent whose pelvis is
//! within 1.5 m; a vertex inside a capsule is inside the other body (capsules lie inside the
//! skin, so the counts are lower bounds).

use rayon::prelude::*;
use serde::Serialize;

use super::crowd::AgentTrack;
use crate::body::{BodyModel, CapsuleVolume, PoseError};

/// Pelvis distance beyond which two bodies cannot touch (m).
const NEAR_M: f64 = 1.5;

/// The measure over a take.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HumanPenetration {
    pub every_n_frames: usize,
    /// (agent, frame) pairs checked.
    pub agent_frames: usize,
    /// Share of them with at least one vertex inside another body.
    pub penetrating_share: f64,
    /// Mean number of vertices inside other bodies, over all checked (agent, frame) pairs.
    pub vertices_inside_mean: f64,
    pub vertices_inside_max: usize,
}

/// Measures a take (see the module docs).
pub fn human_penetration(
    model: &BodyModel,
    agents: &[AgentTrack],
    every_n_frames: usize,
) -> Result<HumanPenetration, PoseError> {
    let every = every_n_frames.max(1);
    let frames = agents.iter().map(|a| a.frames.len()).min().unwrap_or(0);
    let shaped: Vec<_> = agents
        .iter()
        .map(|a| model.shape(&a.betas, &[]))
        .collect::<Result<_, _>>()?;
    let volumes: Vec<CapsuleVolume> = shaped
        .iter()
        .map(|s| CapsuleVolume::new(model, s))
        .collect();
    let per_frame: Vec<Vec<usize>> = (0..frames)
        .step_by(every)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|f| {
            let joints: Vec<Vec<crate::math::Vec3>> = agents
                .iter()
                .zip(&shaped)
                .map(|(a, s)| {
                    s.skeleton(&a.frames[f].pose, a.frames[f].transl)
                        .map(|k| k.joints.to_vec())
                })
                .collect::<Result<_, _>>()?;
            (0..agents.len())
                .map(|i| {
                    let near: Vec<usize> = (0..agents.len())
                        .filter(|&k| k != i && joints[k][0].distance(joints[i][0]) < NEAR_M)
                        .collect();
                    if near.is_empty() {
                        return Ok(0);
                    }
                    let a = &agents[i].frames[f];
                    let body = shaped[i].pose(&a.pose, a.transl)?;
                    let bounds: Vec<_> = near
                        .iter()
                        .map(|&k| volumes[k].bounds(&joints[k]))
                        .collect();
                    Ok(body
                        .vertices
                        .iter()
                        .filter(|v| {
                            near.iter().zip(&bounds).any(|(&k, (lo, hi))| {
                                v.cmpge(*lo).all()
                                    && v.cmple(*hi).all()
                                    && volumes[k].contains(&joints[k], **v)
                            })
                        })
                        .count())
                })
                .collect::<Result<Vec<usize>, PoseError>>()
        })
        .collect::<Result<_, _>>()?;
    let counts: Vec<usize> = per_frame.into_iter().flatten().collect();
    let n = counts.len().max(1) as f64;
    Ok(HumanPenetration {
        every_n_frames: every,
        agent_frames: counts.len(),
        penetrating_share: counts.iter().filter(|&&c| c > 0).count() as f64 / n,
        vertices_inside_mean: counts.iter().sum::<usize>() as f64 / n,
        vertices_inside_max: counts.iter().copied().max().unwrap_or(0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyParams;
    use crate::math::Vec3;
    use crate::synth::crowd::{AgentState, Steering};

    fn standing(name: &str, x: f64, frames: usize) -> AgentTrack {
        let f = BodyParams {
            // Zero pose: the model's own frame, y up, z forward; bodies one behind the other.
            transl: Vec3::new(0.0, 0.0, x),
            ..BodyParams::default()
        };
        AgentTrack {
            name: name.into(),
            betas: Vec::new(),
            steering: Steering::Sampling { k: 1 },
            frames: vec![f; frames],
            world_from_cpf: Vec::new(),
            markers: Vec::new(),
            pelvis_xy: Vec::new(),
            goals: Vec::new(),
            state: AgentState::Done,
            stopped_at_frame: None,
            primitives: 0,
            stuck_primitives: 0,
            contact: 0.0,
            penetration_share: 0.0,
            pelvis_off_floor_frames: 0,
            held_primitives: 0,
            speed_m_s: 0.0,
            view_cos: 0.0,
            pose_score: 0.0,
        }
    }

    #[test]
    fn bodies_apart_do_not_penetrate_and_bodies_overlapping_do() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let model = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
        let measure = |dx: f64| {
            human_penetration(&model, &[standing("a", 0.0, 8), standing("b", dx, 8)], 4).unwrap()
        };
        let apart = measure(1.0);
        assert_eq!(apart.agent_frames, 4);
        assert_eq!(apart.penetrating_share, 0.0);
        let brushing = measure(0.15);
        let inside = measure(0.0);
        assert_eq!(inside.penetrating_share, 1.0);
        // The same body in the same place: a large part of its surface is inside the other's
        // capsules, more than when they only overlap by a few centimetres.
        assert!(inside.vertices_inside_mean > 1000.0, "{inside:?}");
        assert!(
            brushing.vertices_inside_mean < inside.vertices_inside_mean,
            "{brushing:?}"
        );
    }
}
