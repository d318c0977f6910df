//! The take's people staged (steps 2 and 3 of the main job): the bodies rendered with their
//! tracks and who wears the rig, the take's `sequence/` folder, the Aria streams' output, and
//! Blender's body inputs (vertex caches, textures, skin maps, outfit regions, body parts).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::RunMotion;
use crate::body::parts::face_parts;
use crate::body::BodyModel;
use crate::export::aria::{AriaExport, AriaWearer};
use crate::export::gaze::GazeGoal;
use crate::plan::{RenderPlan, RunPlan};
use crate::render::outfit::regions::garment_fields;
use crate::render::outfit::{ShardOutfit, SLOTS};
use crate::render::passes::Pass;
use crate::render::protocol::ShardSkinRegion;
use crate::render::shard_plan::{AGENT_ID_BASE, HELD_OBJECT_ID_BASE};
use crate::render::skin_tone::SkinTextures;
use crate::render::ShardBody;
use crate::scene::walkable_map;
use crate::supervisor::staged::{RenderedAgent, RenderedMove, RenderedObject};
use crate::synth::body_cache::{body_cache_at, playback_keys, rendered_sample_indices};
use crate::synth::crowd_dir::write_crowd_dir;
use crate::synth::placement::place_motion;
use crate::synth::{pose_meshes, track_body, write_sequence_dir};
use crate::vertex_cache::{
    write_corner_uvs_npy, write_faces_npy, write_rest_vertices_npy, write_vertex_rows_npy,
};

/// The bodies the run renders, each with its track, and which of them wear the rig.
pub(super) fn rendered_agents(
    plan: &RunPlan,
    scene: &crate::scene::SceneMesh,
    motion: &RunMotion,
    model: &BodyModel,
) -> Result<(Vec<RenderedAgent>, Vec<usize>)> {
    match motion {
        RunMotion::Placed(m) => {
            let map = walkable_map(scene, &plan.scene, plan.walkable)?;
            if let Some(warning) = crate::scene::scene_frame_warning(scene, &map, &plan.scene) {
                eprintln!("{warning}");
            }
            let (placed, _) = place_motion(model, m, &map, plan.scene_seed)
                .with_context(|| format!("placing the motion in {}", plan.scene.display()))?;
            let track = track_body(model, &placed)?;
            let agent = RenderedAgent {
                name: "agent_0".into(),
                id: AGENT_ID_BASE,
                motion: placed,
                track,
                activities: None,
                held_objects: Vec::new(),
                moved_objects: Vec::new(),
            };
            Ok((vec![agent], vec![0]))
        }
        RunMotion::Agents { take, wearers, .. } => {
            // A take with activities labels every frame of every agent.
            let with_activities = take
                .agents
                .iter()
                .any(|a| !a.activity_segments.is_empty() || !a.skipped_activities.is_empty());
            let agents = take
                .agents
                .iter()
                .enumerate()
                .map(|(k, a)| {
                    let motion = a.motion_sequence(take.frame_rate_hz);
                    let track = track_body(model, &motion)?;
                    Ok(RenderedAgent {
                        name: a.name.clone(),
                        id: AGENT_ID_BASE + k as u32,
                        motion,
                        track,
                        activities: with_activities.then(|| a.activity_segments.clone()),
                        held_objects: Vec::new(),
                        moved_objects: a
                            .moved_objects
                            .iter()
                            .map(|m| moved_in_scene(scene, m))
                            .collect::<Result<_>>()?,
                    })
                })
                .collect::<Result<Vec<RenderedAgent>>>()?;
            // What they pick up: egogen's solids with segmentation ids in the take's order,
            // the scene's things with their own.
            let mut agents = agents;
            let mut id = HELD_OBJECT_ID_BASE;
            for (agent, a) in agents.iter_mut().zip(&take.agents) {
                for object in &a.held_objects {
                    let object_id = match &object.scene_object {
                        Some(name) => scene_object_id(scene, name)?,
                        None => {
                            id += 1;
                            id - 1
                        }
                    };
                    agent.held_objects.push(RenderedObject {
                        id: object_id,
                        object: object.clone(),
                    });
                }
            }
            Ok((agents, wearers.to_vec()))
        }
    }
}

/// A scene object a person moves, with its segmentation id: the take must name an object of
/// the scene it is rendered in.
fn moved_in_scene(
    scene: &crate::scene::SceneMesh,
    movement: &crate::synth::activity::ObjectMove,
) -> Result<RenderedMove> {
    Ok(RenderedMove {
        id: scene_object_id(scene, &movement.name)?,
        movement: movement.clone(),
    })
}

/// The segmentation id of the scene object `name` a take moves or picks up: the take must
/// name an object of the scene it is rendered in.
fn scene_object_id(scene: &crate::scene::SceneMesh, name: &str) -> Result<u32> {
    match scene.objects.iter().find(|o| o.name == name) {
        Some(object) => Ok(object.id.0),
        None => bail!(
            "the take moves the scene object `{name}`, which the scene has not got (was the take \
             made in another scene?)"
        ),
    }
}

/// Writes the dataset's `sequence/` folder: the take's folder, or a placed motion's.
pub(super) fn write_sequence(
    sequence: &Path,
    motion: &RunMotion,
    agents: &[RenderedAgent],
    model: &BodyModel,
    plan: &RunPlan,
) -> Result<()> {
    match motion {
        RunMotion::Placed(_) => {
            let a = &agents[0];
            let meshes = pose_meshes(model, &a.motion, plan.mesh_every_n_frames)?;
            write_sequence_dir(sequence, model, &a.motion, &a.track, &meshes).map(drop)
        }
        RunMotion::Agents {
            world, take, about, ..
        } => write_crowd_dir(sequence, world, model, take, None, about.clone()).map(drop),
    }
}

/// The Aria streams' output of the take (`[render.aria]`), written when it is finished: each
/// wearer with its goals and headset offset (and its hands' landmarks when the hands are
/// asked), and the scene's rays when the gaze is asked. Settings the rig cannot serve fail
/// here, before anything renders.
pub(super) fn aria_export(
    render: &RenderPlan,
    wearers: &[usize],
    motion: &RunMotion,
    agents: &[RenderedAgent],
    model: &BodyModel,
    scene: &crate::scene::SceneMesh,
) -> Result<Option<AriaExport>> {
    let Some(settings) = &render.aria else {
        return Ok(None);
    };
    if let Some(p) = settings.problem(&render.rig) {
        bail!("aria streams: {p}");
    }
    let hands = |w: usize| -> Result<Option<Vec<_>>> {
        if !settings.streams.hands {
            return Ok(None);
        }
        if let Some(hands) = &agents[w].track.hands {
            return Ok(Some(hands.clone()));
        }
        let m = &agents[w].motion;
        crate::body::hand_landmarks::hand_track(model, &m.betas, &m.poses, &m.trans)
            .map(Some)
            .map_err(|e| anyhow::anyhow!("the hands of {}: {e}", agents[w].name))
    };
    let wearers = wearers
        .iter()
        .map(|&w| -> Result<AriaWearer> {
            Ok(AriaWearer {
                agent: w,
                goals: match motion {
                    RunMotion::Agents { take, .. } => take.agents[w]
                        .goals
                        .iter()
                        .map(|g| GazeGoal {
                            xy: g.goal,
                            until_frame: g.end_frame,
                        })
                        .collect(),
                    RunMotion::Placed(_) => Vec::new(),
                },
                looks: match motion {
                    RunMotion::Agents { take, .. } => take.agents[w]
                        .activities
                        .iter()
                        .filter_map(|a| a.look_at)
                        .collect(),
                    RunMotion::Placed(_) => Vec::new(),
                },
                cpf_from_headset: render
                    .headset_wear
                    .map_or(crate::math::Affine3::IDENTITY, |h| {
                        h.draw(w).cpf_from_headset()
                    }),
                hands: hands(w)?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Some(AriaExport {
        settings: settings.clone(),
        wearers,
        rays: settings
            .streams
            .gaze
            .then(|| crate::scene::mesh_distance::SceneRays::new(scene))
            .flatten(),
    }))
}

/// What the renders of `frames` read of a motion of `len` frames, on a grid of
/// `samples_per_frame`: the shutter around each rendered frame and the neighbours the flow
/// reads (with the colour pass off, no shutter) ([`rendered_sample_indices`]).
pub(super) fn rendered_samples(
    render: &RenderPlan,
    frames: &[u32],
    samples_per_frame: u32,
    len: usize,
) -> Vec<usize> {
    let shutter = if render.passes.needs_colour_render() {
        render.shutter_frames
    } else {
        0.0
    };
    rendered_sample_indices(
        frames,
        render.every_n_frames as u32,
        shutter,
        samples_per_frame,
        len,
    )
}

/// Writes what Blender reads of each body into `work` (a PC2 cache of the times the renders
/// of `frames` read, faces, rest vertices), rewritten identically on every (re)start; returns
/// the bodies as shard specs name them and the files written (scratch, removed when the
/// dataset is finished).
pub(super) fn write_body_inputs(
    work: &Path,
    agents: &[RenderedAgent],
    model: &BodyModel,
    render: &RenderPlan,
    frames: &[u32],
) -> Result<(Vec<ShardBody>, Vec<PathBuf>)> {
    std::fs::create_dir_all(work).with_context(|| format!("creating {}", work.display()))?;
    let textures = SkinTextures::of(model)?;
    let mut scratch = Vec::new();
    // One UV file for every agent: they share the model's layout.
    let uvs_npy = match (&model.uvs, textures.need_uvs()) {
        (Some(uvs), true) => {
            let path = work.join("body_uvs.npy");
            write_corner_uvs_npy(&path, &uvs.per_corner())?;
            scratch.push(path.clone());
            Some(std::fs::canonicalize(&path)?)
        }
        _ => None,
    };
    // One part per face for every agent (they share the model's skinning), where the
    // segmentation tells the hands and forearms apart.
    let parts_npy = if render.passes.has(Pass::Segmentation) {
        let path = work.join("body_parts.npy");
        let parts: Vec<[f32; 1]> = face_parts(model)
            .into_iter()
            .map(|p| [p as u8 as f32])
            .collect();
        write_vertex_rows_npy(&path, &parts)?;
        scratch.push(path.clone());
        Some(std::fs::canonicalize(&path)?)
    } else {
        None
    };
    let mut bodies = Vec::with_capacity(agents.len());
    for (k, a) in agents.iter().enumerate() {
        let pc2 = work.join(format!("agent_{k}.pc2"));
        let faces = work.join(format!("agent_{k}_faces.npy"));
        let vertices = work.join(format!("agent_{k}_vertices.npy"));
        let indices = rendered_samples(
            render,
            frames,
            render.cache_samples_per_frame,
            a.motion.len(),
        );
        let cache = body_cache_at(
            model,
            &a.motion,
            render.cache_samples_per_frame,
            Some(&indices),
        )?;
        cache.write(&pc2)?;
        write_faces_npy(&faces, &model.faces)?;
        write_rest_vertices_npy(&vertices, &cache)?;
        drop(cache);
        let skin = render.skin.draw(k);
        let skin_regions = ShardSkinRegion::painted(&textures, &skin);
        let outfit = match render.outfits.draw(k) {
            None => None,
            Some(outfit) => {
                let path = work.join(format!("agent_{k}_outfit.npy"));
                let fields = garment_fields(model, &a.motion.betas, &outfit)
                    .with_context(|| format!("measuring {}'s outfit on its body", a.name))?;
                write_vertex_rows_npy(&path, &fields)?;
                scratch.push(path.clone());
                Some(ShardOutfit {
                    fields_npy: std::fs::canonicalize(&path)?,
                    slots: SLOTS.iter().map(|s| s.to_string()).collect(),
                    outfit,
                })
            }
        };
        bodies.push(ShardBody {
            name: a.name.clone(),
            pass_index: a.id,
            faces_npy: std::fs::canonicalize(&faces)?,
            vertices_npy: std::fs::canonicalize(&vertices)?,
            pc2: std::fs::canonicalize(&pc2)?,
            samples_per_frame: render.cache_samples_per_frame,
            cache_keys: playback_keys(&indices, render.cache_samples_per_frame),
            motion_steps: crate::render::shard_plan::deform_motion_steps(
                render.shutter_frames,
                render.cache_samples_per_frame,
            ),
            skin,
            uvs_npy: uvs_npy.clone(),
            skin_regions,
            skin_detail: textures.detail.clone(),
            outfit,
            parts_npy: parts_npy.clone(),
        });
        scratch.extend([pc2, faces, vertices]);
    }
    Ok((bodies, scratch))
}
