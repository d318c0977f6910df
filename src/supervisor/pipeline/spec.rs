//! The rendering work of a take (step 4 of the main job): each camera on its wearer, the scene's
//! segmentation ids, ceiling, obstacles and held objects, their surfaces, the shard spec
//! Blender reads, and
//! the repair of what an interrupted run left.

use anyhow::Result;

use super::bodies::rendered_samples;
use super::RunMotion;
use crate::export::annotations::SegmentationId;
use crate::export::take::{moved_offset_at, moved_scene_objects};
use crate::plan::{RenderPlan, RunPlan};
use crate::render::lens_polynomial::{native_error, ERROR_GRID};
use crate::render::materials::{MaterialsMode, SurfaceFacts};
use crate::render::protocol::{
    MovedKey, ObstacleKey, PoseKey, ShardCeiling, ShardHeldObject, ShardMovedObject, ShardObstacle,
    CEILING_OBJECT,
};
use crate::render::render_camera::RenderCamera;
use crate::render::shard_plan::blender_fps;
use crate::render::{ShardBody, ShardRgb, ShardSpec};
use crate::scene::ceiling::ceiling_to_add;
use crate::scene::{Obstacle2, ObstacleSolid};
use crate::supervisor::staged::{CameraWork, Dataset, RenderedAgent};

/// The rig's cameras on every wearer (each camera set named after its wearer when there are
/// several), posed along the wearer's track with the headset's drawn offset on the head.
pub(super) fn camera_work(
    render: &RenderPlan,
    agents: &[RenderedAgent],
    wearers: &[usize],
    frames: &[u32],
) -> Vec<CameraWork> {
    let mut cameras = Vec::new();
    for &w in wearers {
        let track = &agents[w].track;
        let wear = render.headset_wear.map(|h| h.draw(w));
        let cpf_from_headset =
            wear.map_or(crate::math::Affine3::IDENTITY, |o| o.cpf_from_headset());
        for ((cam, rendered), noise) in render
            .cameras
            .iter()
            .zip(&render.render_cameras)
            .zip(&render.depth_noise)
        {
            let mut camera = cam.clone();
            if wearers.len() > 1 {
                camera.name = format!("{}_{}", agents[w].name, cam.name);
            }
            cameras.push(CameraWork {
                camera,
                render: *rendered,
                depth_noise: *noise,
                world_from_cam: track
                    .frames
                    .iter()
                    .map(|f| cam.world_from_cam(f.world_from_cpf * cpf_from_headset))
                    .collect(),
                headset_wear: wear,
                frames: frames.to_vec(),
                wearer: w,
            });
        }
    }
    cameras
}

/// What the renders hold besides the bodies: the scene's objects, a ceiling where the scene
/// has none and the plan asks for one, the `[[obstacles]]` boxes, the objects people pick up
/// (posed at the frames the renders of `frames` read); with their segmentation ids.
pub(super) struct SceneObjects {
    /// Every segmentation id but the agents': scene objects, ceiling, obstacles.
    pub(super) ids: Vec<(String, u32)>,
    ceiling: Option<ShardCeiling>,
    obstacles: Vec<ShardObstacle>,
    held_objects: Vec<ShardHeldObject>,
    moved_objects: Vec<ShardMovedObject>,
}

pub(super) fn scene_objects(
    plan: &RunPlan,
    render: &RenderPlan,
    scene: &crate::scene::SceneMesh,
    motion: &RunMotion,
    agents: &[RenderedAgent],
    frames: &[u32],
) -> SceneObjects {
    let mut ids: Vec<(String, u32)> = scene
        .objects
        .iter()
        .map(|o| (o.name.clone(), o.id.0))
        .collect();
    let next_id = |ids: &[(String, u32)]| ids.iter().map(|o| o.1).max().unwrap_or(0) + 1;
    let ceiling = plan.ceiling.then(|| ceiling_to_add(scene)).flatten();
    if let Some(c) = ceiling {
        eprintln!(
            "egogen-run: {} has no ceiling; closing its rooms with one at z = {:.2} m (scene.ceiling = false leaves it open)",
            plan.scene.display(),
            c.z_m
        );
        ids.push((CEILING_OBJECT.into(), next_id(&ids)));
    }
    let obstacles: Vec<ShardObstacle> = match motion {
        RunMotion::Agents {
            world, obstacles, ..
        } => {
            let rate = agents[0].motion.frame_rate_hz;
            let frames = agents[0].motion.len() as f64;
            obstacle_boxes(obstacles, &world.map, next_id(&ids), rate, frames)
        }
        RunMotion::Placed(_) => Vec::new(),
    };
    ids.extend(obstacles.iter().map(|o| (o.name.clone(), o.pass_index)));
    let held_objects = held_objects(render, agents, frames);
    ids.extend(held_objects.iter().map(|o| (o.name.clone(), o.pass_index)));
    SceneObjects {
        ids,
        ceiling: ceiling.map(|c| ShardCeiling {
            z_m: c.z_m,
            min_xy: c.min_xy,
            max_xy: c.max_xy,
        }),
        obstacles,
        held_objects,
        moved_objects: moved_objects(render, agents, frames),
    }
}

/// Everything of a shard spec but its cameras; the lighting is drawn around the middle of the
/// first wearer's path.
pub(super) fn base_spec(
    plan: &RunPlan,
    render: &RenderPlan,
    scene: &crate::scene::SceneMesh,
    first_wearer: &RenderedAgent,
    bodies: Vec<ShardBody>,
    objects: &SceneObjects,
) -> Result<ShardSpec> {
    let (fps, fps_base) = blender_fps(first_wearer.motion.frame_rate_hz);
    let (lo, hi) = scene_bounds(scene);
    let track = &first_wearer.track;
    let mid = 0.5 * (track.frames[0].joints[0] + track.frames[track.frames.len() - 1].joints[0]);
    Ok(ShardSpec {
        scene_file: std::fs::canonicalize(&plan.scene)?,
        scene_up_axis: plan.scene_frame.up_for(&plan.scene).name().into(),
        scene_unit_m: plan.scene_frame.unit_m,
        object_ids: objects.ids.clone(),
        fps,
        fps_base,
        bodies,
        lighting: render
            .lighting
            .draw([mid.x, mid.y, lo.z + 0.85 * (hi.z - lo.z)]),
        materials: render.materials.draw(&surface_facts(plan, scene, objects)),
        rgb: render.passes.needs_colour_render().then_some(ShardRgb {
            samples: render.samples,
            adaptive_threshold: render.adaptive_threshold,
            denoise: render.denoise,
            shutter_frames: render.shutter_frames,
            seed: 0,
        }),
        ground_truth_passes: render
            .passes
            .ground_truth_render_passes()
            .into_iter()
            .map(String::from)
            .collect(),
        ground_truth_frame_step: render.every_n_frames as u32,
        device: render.device,
        cameras: Vec::new(),
        body_probe: None,
        ceiling: objects.ceiling,
        obstacles: objects.obstacles.clone(),
        held_objects: objects.held_objects.clone(),
        moved_objects: objects.moved_objects.clone(),
        scene_split: None,
    })
}

/// Repairs what an interrupted run left (damaged frames, missing records) and says how a
/// camera with Cycles' polynomial fisheye differs from its model.
pub(super) fn repair(dataset: &Dataset) -> Result<()> {
    for work in &dataset.cameras {
        if let RenderCamera::PolynomialFisheye(lens) = &work.render {
            let e = native_error(&work.camera.model, lens, ERROR_GRID);
            eprintln!(
                "egogen-run: {} renders with Cycles' polynomial fisheye (render.fisheye = \"native\"): off its Fisheye624 model by max {:.2} px, mean {:.2} px, 95% ≤ {:.2} px",
                work.camera.name, e.max_px, e.mean_px, e.p95_px
            );
        }
    }
    for (path, reason) in dataset.check_finished_frames()? {
        eprintln!(
            "egogen-run: {} is damaged ({reason}); rendering it again",
            path.display()
        );
    }
    Ok(())
}

/// The scene objects' segmentation ids (the added ceiling and obstacles among them), each with
/// its class where the scene file gives one.
pub(super) fn segmentation_ids(
    ids: &[(String, u32)],
    scene: &crate::scene::SceneMesh,
) -> Vec<SegmentationId> {
    let labels: std::collections::BTreeMap<u32, &String> = scene
        .objects
        .iter()
        .filter_map(|o| Some((o.id.0, o.label.as_ref()?)))
        .collect();
    ids.iter()
        .map(|(name, id)| SegmentationId {
            name: name.clone(),
            id: *id,
            label: labels.get(id).map(|l| l.to_string()),
        })
        .collect()
}

/// The `[[obstacles]]` as boxes standing on the map's floor under their centres (at its
/// keys, for a moving one), named `obstacle_NN` with ids
/// from `first_id`; a moving one keyed one frame before the take and one after its last frame
/// (`frames` at `rate_hz`), so that blur and motion vectors see it move at the ends too.
fn obstacle_boxes(
    solids: &[ObstacleSolid],
    map: &crate::scene::WalkableMap,
    first_id: u32,
    rate_hz: f64,
    frames: f64,
) -> Vec<ShardObstacle> {
    solids
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let (half, yaw_rad) = match s.motion.at_start {
                Obstacle2::Box {
                    half_extents,
                    yaw_rad,
                    ..
                } => (half_extents, yaw_rad),
                Obstacle2::Circle { radius_m, .. } => (glam::DVec2::splat(radius_m), 0.0),
            };
            let key = |frame: f64| {
                let c = s.motion.at(frame / rate_hz).centre();
                ObstacleKey {
                    frame,
                    centre: [c.x, c.y, map.floor_under(c) + 0.5 * s.height_m],
                }
            };
            let still = s.motion.velocity_m_per_s == glam::DVec2::ZERO;
            ShardObstacle {
                name: format!("obstacle_{k:02}"),
                pass_index: first_id + k as u32,
                size_m: [2.0 * half.x, 2.0 * half.y, s.height_m],
                yaw_rad,
                keys: if still {
                    vec![key(0.0)]
                } else {
                    vec![key(-1.0), key(frames)]
                },
            }
        })
        .collect()
}

/// The scene objects the agents move, by name (one key list per object, whoever moves it:
/// the offsets added), and the scene things they pick up (each key the world motion from
/// where the scene has it), keyed at every motion frame the renders of `frames` read.
fn moved_objects(
    render: &RenderPlan,
    agents: &[RenderedAgent],
    frames: &[u32],
) -> Vec<ShardMovedObject> {
    let Some(n) = agents.iter().map(|a| a.motion.len()).max() else {
        return Vec::new();
    };
    let keyed = rendered_samples(render, frames, 1, n);
    let moved = moved_scene_objects(agents)
        .into_iter()
        .map(|(name, _)| ShardMovedObject {
            name: name.to_string(),
            keys: keyed
                .iter()
                .map(|&f| {
                    let [x, y] = moved_offset_at(agents, name, f);
                    MovedKey {
                        frame: f as f64,
                        centre: [x, y, 0.0],
                        rotation_wxyz: None,
                    }
                })
                .collect(),
        });
    let taken = agents
        .iter()
        .flat_map(|a| a.held_objects.iter())
        .filter(|o| o.object.scene_object.is_some())
        .map(|o| {
            let h = &o.object;
            let from_scene = h.world_from_object[0].inverse();
            // Each key's quaternion on the side of the one before: Blender interpolates them
            // component by component.
            let mut before = glam::DQuat::IDENTITY;
            ShardMovedObject {
                name: h.name.clone(),
                keys: keyed
                    .iter()
                    .map(|&f| {
                        let pose = h.world_from_object[f.min(h.world_from_object.len() - 1)];
                        let moved = pose * from_scene;
                        let mut q = glam::DQuat::from_mat3(&moved.matrix3);
                        if q.dot(before) < 0.0 {
                            q = -q;
                        }
                        before = q;
                        MovedKey {
                            frame: f as f64,
                            centre: moved.translation.to_array(),
                            rotation_wxyz: Some([q.w, q.x, q.y, q.z]),
                        }
                    })
                    .collect(),
            }
        });
    moved.chain(taken).collect()
}

/// The objects the agents pick up, keyed at every motion frame the renders of `frames` read
/// (linear in between: a shutter's blur and the flow's neighbours).
fn held_objects(
    render: &RenderPlan,
    agents: &[RenderedAgent],
    frames: &[u32],
) -> Vec<ShardHeldObject> {
    agents
        .iter()
        .flat_map(|a| {
            let keyed = rendered_samples(render, frames, 1, a.motion.len());
            a.held_objects.iter().filter_map(move |o| {
                let h = &o.object;
                Some(ShardHeldObject {
                    name: h.name.clone(),
                    pass_index: o.id,
                    shape: h.shape?,
                    size_m: h.size_m,
                    colour_rgb: h.colour_rgb?,
                    keys: keyed
                        .iter()
                        .map(|&f| {
                            let pose = h.world_from_object[f];
                            let q = glam::DQuat::from_mat3(&pose.matrix3);
                            PoseKey {
                                frame: f as f64,
                                location: pose.translation.to_array(),
                                rotation_wxyz: [q.w, q.x, q.y, q.z],
                            }
                        })
                        .collect(),
                })
            })
        })
        .collect()
}

/// What `[render.materials]` classes each scene object by (the added ceiling among them): its
/// name, label, own texture and how its surfaces face above the walked floor.
fn surface_facts(
    plan: &RunPlan,
    scene: &crate::scene::SceneMesh,
    objects: &SceneObjects,
) -> Vec<SurfaceFacts> {
    if plan
        .render
        .as_ref()
        .is_none_or(|r| r.materials.mode == MaterialsMode::Keep)
    {
        return Vec::new();
    }
    let floor_z = plan
        .walkable
        .floor_z_m
        .or_else(|| crate::scene::floor::detect_floor_z(scene))
        .unwrap_or(0.0);
    let mut facts: Vec<SurfaceFacts> = scene
        .objects
        .iter()
        .zip(scene.object_orientations())
        .map(|(o, f)| SurfaceFacts {
            name: o.name.clone(),
            label: o.label.clone(),
            textured: o.textured,
            see_through: o.see_through,
            area_up: f.area_up,
            area_down: f.area_down,
            area_side: f.area_side,
            z_min_m: f.z_min - floor_z,
            z_max_m: f.z_max - floor_z,
        })
        .collect();
    if let Some(c) = objects.ceiling {
        facts.push(SurfaceFacts {
            name: CEILING_OBJECT.into(),
            label: None,
            textured: false,
            see_through: false,
            area_up: 0.0,
            area_down: 1.0,
            area_side: 0.0,
            z_min_m: c.z_m - floor_z,
            z_max_m: c.z_m - floor_z,
        });
    }
    facts
}

fn scene_bounds(scene: &crate::scene::SceneMesh) -> (crate::math::Vec3, crate::math::Vec3) {
    scene.vertices.iter().fold(
        (
            crate::math::Vec3::splat(f64::INFINITY),
            crate::math::Vec3::splat(f64::NEG_INFINITY),
        ),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    )
}
