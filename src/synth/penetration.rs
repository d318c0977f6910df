//! Human–human penetration of a take: how often, and how deep, one body's surface enters
//! another. Every `every_n_frames`-th frame, for every agent, its posed vertices are tested
//! against every other agent whose pelvis is within 1.5 m, twice: against the other's capsule
//! volume ([`CapsuleVolume`]: capsules lie inside the skin, so those counts are lower bounds),
//! and exactly, against the other's posed mesh ([`BodyOccupancy`]: a vertex is inside when the
//! mesh's winding number about it is not zero).

use rayon::prelude::*;
use serde::Serialize;

use super::crowd::AgentTrack;
use crate::body::{BodyModel, BodyOccupancy, CapsuleVolume, PoseError};
use crate::math::Vec3;

/// Pelvis distance beyond which two bodies cannot touch (m).
const NEAR_M: f64 = 1.5;

/// The measure over a take.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HumanPenetration {
    pub every_n_frames: usize,
    /// (agent, frame) pairs checked.
    pub agent_frames: usize,
    /// Share of them with at least one vertex inside another body's capsules.
    pub penetrating_share: f64,
    /// Mean number of vertices inside other bodies' capsules, over all checked pairs.
    pub vertices_inside_mean: f64,
    pub vertices_inside_max: usize,
    /// Share of them with at least one vertex inside another body's posed mesh (exact).
    pub mesh_penetrating_share: f64,
    /// Mean number of vertices inside other bodies' posed meshes, over all checked pairs.
    pub mesh_vertices_inside_mean: f64,
    pub mesh_vertices_inside_max: usize,
}

/// Vertices of one agent in one frame inside the others: (by capsules, by meshes).
type Counts = (usize, usize);

fn inside(lo: Vec3, hi: Vec3, v: Vec3) -> bool {
    v.cmpge(lo).all() && v.cmple(hi).all()
}

/// Measures a take (see the module docs).
pub(crate) fn human_penetration(
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
    let per_frame: Vec<Vec<Counts>> = (0..frames)
        .step_by(every)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|f| {
            let joints: Vec<Vec<Vec3>> = agents
                .iter()
                .zip(&shaped)
                .map(|(a, s)| {
                    s.skeleton(&a.frames[f].pose, a.frames[f].transl)
                        .map(|k| k.joints.to_vec())
                })
                .collect::<Result<_, _>>()?;
            let near: Vec<Vec<usize>> = (0..agents.len())
                .map(|i| {
                    (0..agents.len())
                        .filter(|&k| k != i && joints[k][0].distance(joints[i][0]) < NEAR_M)
                        .collect()
                })
                .collect();
            // Posed meshes of everyone near someone; a mesh's BVH only where a vertex of
            // another body falls inside its bounds.
            let bodies: Vec<Option<Vec<Vec3>>> = (0..agents.len())
                .map(|i| {
                    if near[i].is_empty() {
                        return Ok(None);
                    }
                    let a = &agents[i].frames[f];
                    Ok(Some(shaped[i].pose(&a.pose, a.transl)?.vertices))
                })
                .collect::<Result<_, PoseError>>()?;
            let occupancy: Vec<std::sync::OnceLock<BodyOccupancy>> =
                (0..agents.len()).map(|_| Default::default()).collect();
            let mesh_of = |k: usize| {
                occupancy[k].get_or_init(|| {
                    BodyOccupancy::new(bodies[k].as_deref().unwrap_or(&[]), &model.faces)
                })
            };
            let bounds: Vec<Option<(Vec3, Vec3)>> = bodies
                .iter()
                .map(|b| b.as_deref().and_then(crate::math::point_bounds))
                .collect();
            Ok((0..agents.len())
                .map(|i| {
                    let Some(vertices) = &bodies[i] else {
                        return (0, 0);
                    };
                    let capsule_bounds: Vec<_> = near[i]
                        .iter()
                        .map(|&k| volumes[k].bounds(&joints[k]))
                        .collect();
                    let by_capsules = vertices
                        .iter()
                        .filter(|&&v| {
                            near[i].iter().zip(&capsule_bounds).any(|(&k, &(lo, hi))| {
                                inside(lo, hi, v) && volumes[k].contains(&joints[k], v)
                            })
                        })
                        .count();
                    let by_meshes = vertices
                        .iter()
                        .filter(|&&v| {
                            near[i].iter().any(|&k| {
                                bounds[k].is_some_and(|(lo, hi)| inside(lo, hi, v))
                                    && mesh_of(k).contains(v)
                            })
                        })
                        .count();
                    (by_capsules, by_meshes)
                })
                .collect())
        })
        .collect::<Result<_, PoseError>>()?;
    let counts: Vec<Counts> = per_frame.into_iter().flatten().collect();
    let n = counts.len().max(1) as f64;
    let summary = |pick: fn(&Counts) -> usize| {
        let values = counts.iter().map(pick);
        (
            values.clone().filter(|&c| c > 0).count() as f64 / n,
            values.clone().sum::<usize>() as f64 / n,
            values.max().unwrap_or(0),
        )
    };
    let (penetrating_share, vertices_inside_mean, vertices_inside_max) = summary(|c| c.0);
    let (mesh_penetrating_share, mesh_vertices_inside_mean, mesh_vertices_inside_max) =
        summary(|c| c.1);
    Ok(HumanPenetration {
        every_n_frames: every,
        agent_frames: counts.len(),
        penetrating_share,
        vertices_inside_mean,
        vertices_inside_max,
        mesh_penetrating_share,
        mesh_vertices_inside_mean,
        mesh_vertices_inside_max,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyParams;
    use crate::math::Vec3;
    use crate::synth::crowd::AgentState;
    use crate::walker::ControllerSpec;

    fn standing(name: &str, x: f64, frames: usize) -> AgentTrack {
        let f = BodyParams {
            // Zero pose: the model's own frame, y up, z forward; bodies one behind the other.
            transl: Vec3::new(0.0, 0.0, x),
            ..BodyParams::default()
        };
        AgentTrack::new(
            name,
            Vec::new(),
            ControllerSpec::Sampling { k: 1 },
            AgentState::Done,
            vec![f; frames],
        )
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
        // The exact test sees what the capsules see and more: the capsules lie inside the skin.
        assert_eq!(apart.mesh_penetrating_share, 0.0);
        assert_eq!(brushing.mesh_penetrating_share, 1.0);
        assert_eq!(inside.mesh_penetrating_share, 1.0);
        assert!(brushing.mesh_vertices_inside_mean >= brushing.vertices_inside_mean);
        assert!(inside.mesh_vertices_inside_mean > inside.vertices_inside_mean);
    }
}
