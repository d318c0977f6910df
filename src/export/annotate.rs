//! Computing and writing the annotations: each finished frame's annotation from its pixels
//! while they are in memory ([`annotate_frame`]: agents in view, 2D joints and their
//! visibility, boxes, the objects people pick up and the hands holding them, the scene
//! objects people move, the colour's exposure), and the output writing
//! `cameras/<camera>/annotations.json` of a finished take ([`Annotations`]). The file's types
//! are `annotations`.

use anyhow::{Context, Result};
use serde_json::json;

use super::annotations::{
    ActivityLabel, AgentAnnotation, AgentOutfit, AgentSkin, CameraAnnotations, Conventions,
    FrameAnnotation, HandAnnotation, JointVisibility, MovedSceneObject, ObjectAnnotation,
    ObjectHolder, SegmentationId, SmplxParams, ANNOTATIONS_VERSION,
};
use super::take::{moved_offset_at, CameraWork, FinishedTake, RenderedAgent, TakeExport};
use crate::body::parts::BodyPart;
use crate::camera::CameraModel;
use crate::exr_file::ExrContents;
use crate::render::lens_polynomial::{native_error, ERROR_GRID};
use crate::render::render_camera::RenderCamera;
use crate::rig::{Rig, RigCamera};
use crate::synth::activity::ActivitySegment;

/// A joint is occluded when the rendered surface at its pixel is nearer than this (m): joints
/// lie inside the body, up to about this deep under its surface.
pub(crate) const JOINT_OCCLUSION_TOLERANCE_M: f64 = 0.10;

/// How much nearer than a hand landmark another part of its own person must be at its pixel
/// for the landmark to count as hidden by the body (m): the landmarks lie up to about 1.5 cm
/// under the hand's skin.
pub(crate) const SELF_OCCLUSION_TOLERANCE_M: f64 = 0.03;

/// `cameras/<camera>/annotations.json` for every camera (OpenCV conventions), from the
/// frames' records.
pub(crate) struct Annotations;

impl TakeExport for Annotations {
    fn name(&self) -> &'static str {
        "annotations"
    }

    fn finish(&self, take: &FinishedTake) -> Result<()> {
        write_annotations(take)
    }
}

fn write_annotations(take: &FinishedTake) -> Result<()> {
    let agents = take.agents;
    for (work, records) in take.cameras.iter().zip(take.records) {
        let model_json = camera_json(take.rig, &work.camera)?;
        let frames = records.iter().map(|r| r.annotation.clone()).collect();
        let mut segmentation_ids: Vec<SegmentationId> = take.scene_ids.to_vec();
        segmentation_ids.extend(agents.iter().map(|a| SegmentationId {
            name: a.name.clone(),
            id: a.id,
            label: None,
        }));
        let doc = CameraAnnotations {
            egogen_annotations: ANNOTATIONS_VERSION,
            conventions: Conventions {
                world: "metres, z up".into(),
                camera_frame: "OpenCV: x right, y down, z forward".into(),
                pixels: "centre of the top-left pixel at (0, 0)".into(),
                t_world_cam: "row-major 4x4 mapping camera-frame points to the world".into(),
                depth: "planar: z of the surface point in the camera frame (m); 0 = no surface".into(),
                joint_visibility: format!("visible | occluded (the pixel shows another object or agent, > {JOINT_OCCLUSION_TOLERANCE_M} m nearer than the joint) | occluded_by_body (hand landmarks: the pixel shows another part of the same person, > {SELF_OCCLUSION_TOLERANCE_M} m nearer) | outside (not in the valid field of view) | in_view (inside it; occlusion not known: the run rendered no depth or no segmentation)"),
                bbox_xyxy: "tight box of the agent's segmentation pixels, inclusive pixel indices; null without the segmentation pass".into(),
                segmentation_part: "a person's body part at the pixel, beside its segmentation.id: 1 left hand, 2 right hand, 3 left forearm, 4 right forearm, 0 the rest of a person and every other pixel (a vertex belongs to the joint that carries most of its skin weight: the wrist's and fingers' make the hand, the elbow's the forearm)".into(),
                segmentation_garment: match take.spec.dresses_people() {
                    true => "the garment on top at a person's pixel, beside its segmentation.id (with the segmentation pass): 1 top, 2 bottom, 3 socks, 4 shoes, 5 hair, 0 the skin and every other pixel (a dress is a top and a bottom of one fabric; the edge where the outfit's colour changes)".into(),
                    false => String::new(),
                },
            },
            camera: model_json,
            image_model: image_model(work),
            depth_noise: work.depth_noise.map(|(model, seed)| json!({
                "channel": "depth_noisy.Z",
                "model": "sigma = a + b (z - c)^2 + d theta^2 / (sqrt(z) (pi/2 - theta)^2), Nguyen et al. 2012; 0 = no measurement",
                "parameters": model,
                "seed": seed,
            })),
            wearer: agents[work.wearer].name.clone(),
            headset_wear: work.headset_wear,
            lighting: take.spec.lighting.clone(),
            materials: take.spec.materials.clone(),
            skins: take
                .spec
                .bodies
                .iter()
                .map(|b| AgentSkin {
                    name: b.name.clone(),
                    skin: b.skin,
                    regions: b.skin_regions.iter().map(|r| r.paint.clone()).collect(),
                    detail: b.skin_detail.as_ref().and_then(|p| {
                        p.file_name().map(|n| n.to_string_lossy().into_owned())
                    }),
                })
                .collect(),
            outfits: take
                .spec
                .bodies
                .iter()
                .filter_map(|b| {
                    b.outfit.as_ref().map(|o| AgentOutfit {
                        name: b.name.clone(),
                        outfit: o.outfit.clone(),
                    })
                })
                .collect(),
            frame_rate_hz: agents[0].motion.frame_rate_hz,
            segmentation_ids,
            frames,
        };
        let path = take
            .folder
            .join("cameras")
            .join(&work.camera.name)
            .join("annotations.json");
        crate::atomic_file::write_atomically(&path, serde_json::to_string_pretty(&doc)?.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// What lens the image was rendered with: `exact` (the camera model itself), or Cycles'
/// polynomial fisheye standing in for it, with its pixel error against the camera model.
fn image_model(work: &CameraWork) -> serde_json::Value {
    match &work.render {
        RenderCamera::PolynomialFisheye(lens) => json!({
            "kind": "cycles_polynomial_fisheye",
            "note": "rendered by this radially symmetric lens instead of `camera`: pixel channels (depth, normals, position, segmentation, flow) follow the image; 2D joints follow `camera`, off the image by `error_vs_camera_px`",
            "centre_px": [lens.centre_px.x, lens.centre_px.y],
            "theta_rad_of_radius_px": lens.theta_coeffs,
            "max_radius_px": lens.max_radius_px,
            "error_vs_camera_px": native_error(&work.camera.model, lens, ERROR_GRID),
        }),
        _ => json!({"kind": "exact"}),
    }
}

fn camera_json(rig: &Rig, camera: &RigCamera) -> Result<serde_json::Value> {
    let one = Rig {
        cameras: vec![camera.clone()],
        ..rig.clone()
    };
    let mut value: serde_json::Value = serde_json::from_str(&one.to_json())?;
    Ok(value["cameras"][0].take())
}

/// A frame file's colour: `rgb`, or `gray` of a monochrome camera.
pub(crate) fn colour_pass(contents: &ExrContents) -> Option<&crate::exr_file::ExrPass> {
    contents
        .passes
        .iter()
        .find(|p| p.name == "rgb" || p.name == "gray")
}

/// A finished frame's annotation, from its validated `contents` (the frame file's channels):
/// the camera's pose, the agents' bodies and, where the frame holds them, its depth and
/// segmentation planes (joint visibility, boxes) and its colour (the exposure).
pub(crate) fn annotate_frame(
    work: &CameraWork,
    frame: u32,
    agents: &[RenderedAgent],
    contents: &ExrContents,
) -> FrameAnnotation {
    let plane = |name: &str| contents.channel(name).map(|c| c.values.as_slice());
    let mut annotation = frame_annotation(
        work,
        frame,
        agents,
        plane("depth.Z"),
        plane("segmentation.id"),
        plane("segmentation.part"),
    );
    annotation.colour_exposure =
        colour_pass(contents).map(|p| crate::inspect::preview::auto_exposure(contents, p));
    annotation
}

/// A frame's annotation from the camera's pose, the agents' bodies and, where the frame holds
/// them, its depth and segmentation planes (joint visibility, boxes). `colour_exposure` is
/// left for the caller.
fn frame_annotation(
    work: &CameraWork,
    f: u32,
    agents: &[RenderedAgent],
    depth: Option<&[f32]>,
    ids: Option<&[f32]>,
    parts: Option<&[f32]>,
) -> FrameAnnotation {
    let i = f as usize;
    let res = work.camera.model.resolution();
    let w = res.width_px as usize;
    let world_from_cam = work.world_from_cam[i];
    let cam_from_world = world_from_cam.inverse();
    let pelvis = |a: &RenderedAgent| a.track.frames[i].joints[0];
    let listed = agents
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let joints = &a.track.frames[i].joints;
            let seen = |points: &[crate::math::Vec3]| {
                project_points(work, cam_from_world, depth, ids, a.id, points)
            };
            let (joints_2d, visibility) = seen(joints);
            let bbox = ids.and_then(|ids| bbox_of(ids, w, a.id));
            let hands = a.track.hands.as_ref().map(|hands| {
                hands[i]
                    .iter()
                    .zip(["left", "right"])
                    .enumerate()
                    .map(|(h, (hand, side))| {
                        let (landmarks_2d, landmark_visibility) = project_part_points(
                            work,
                            cam_from_world,
                            depth,
                            ids,
                            parts.map(|p| (p, BodyPart::hand(h))),
                            a.id,
                            &hand.points,
                        );
                        HandAnnotation {
                            side: side.into(),
                            landmarks_3d: hand.points.iter().map(|p| p.to_array()).collect(),
                            bbox_xyxy: box_of(&landmarks_2d),
                            landmarks_2d,
                            landmark_visibility,
                            // Its pixels lie in its person's box: only those rows are read.
                            mask_bbox_xyxy: ids.zip(parts).zip(bbox).and_then(
                                |((ids, parts), [_, y0, _, y1])| {
                                    let part = BodyPart::hand(h) as u8 as f32;
                                    box_where(y0 * w..(y1 + 1) * w, w, |i| {
                                        parts[i] == part && ids[i] as u32 == a.id
                                    })
                                },
                            ),
                            contact: a
                                .held_objects
                                .iter()
                                .find(|o| o.object.hand.index() == h && o.object.held_at(i))
                                .map(|o| o.id),
                        }
                    })
                    .collect()
            });
            // With segmentation: its pixels are in the image; without: a joint is.
            let in_view = match ids {
                Some(_) => bbox.is_some(),
                None => joints_2d.iter().any(Option::is_some),
            };
            // Distance to the nearest other agent (pelvis to pelvis); none alone.
            let nearest = agents
                .iter()
                .enumerate()
                .filter(|(o, _)| *o != k)
                .map(|(_, o)| pelvis(o).distance(pelvis(a)))
                .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.min(d))));
            AgentAnnotation {
                name: a.name.clone(),
                id: a.id,
                wearer: k == work.wearer,
                in_view,
                smplx: SmplxParams::new(
                    &a.motion.betas,
                    &a.motion.poses[i],
                    a.motion.trans[i].to_array(),
                ),
                joints_3d: joints.iter().map(|j| j.to_array()).collect(),
                joints_2d,
                joint_visibility: visibility,
                bbox_xyxy: bbox,
                interaction_distance_m: nearest,
                activity: a.activities.as_ref().map(|segments| {
                    let (activity, phase) = ActivitySegment::at(segments, f as usize);
                    ActivityLabel { activity, phase }
                }),
                hands,
            }
        })
        .collect();
    let objects = agents
        .iter()
        .flat_map(|a| a.held_objects.iter().map(move |o| (a, o)))
        .map(|(a, o)| {
            let h = &o.object;
            let pose = h.world_from_object[i.min(h.world_from_object.len() - 1)];
            let (centre, seen) =
                project_points(work, cam_from_world, depth, ids, o.id, &[pose.translation]);
            ObjectAnnotation {
                name: h.name.clone(),
                id: o.id,
                scene_object: h.scene_object.clone(),
                kind: h.kind,
                t_world_object: crate::math::row_major(pose),
                size_m: h.size_m,
                held_by: h.held_at(i).then(|| ObjectHolder {
                    agent: a.name.clone(),
                    hand: h.hand,
                }),
                centre_2d: centre[0],
                centre_visibility: seen[0],
                bbox_xyxy: ids.and_then(|ids| bbox_of(ids, w, o.id)),
            }
        })
        .collect();
    FrameAnnotation {
        frame: f,
        time_s: f as f64 / agents[0].motion.frame_rate_hz,
        file: format!("frame_{f:05}.exr"),
        t_world_cam: crate::math::row_major(world_from_cam),
        colour_exposure: None,
        agents: listed,
        objects,
        moved_scene_objects: moved_scene_objects(agents, i, ids.map(|ids| (ids, w))),
    }
}

/// The scene objects the agents move, at take frame `i`, by name (each once, whoever moves
/// it: where the renders place it), with their boxes in the segmentation plane `ids` (`width`
/// pixels a row) where there is one.
fn moved_scene_objects(
    agents: &[RenderedAgent],
    i: usize,
    ids: Option<(&[f32], usize)>,
) -> Vec<MovedSceneObject> {
    super::take::moved_scene_objects(agents)
        .into_iter()
        .map(|(name, id)| {
            let [x, y] = moved_offset_at(agents, name, i);
            let moving = |a: &&RenderedAgent| {
                a.moved_objects.iter().any(|m| {
                    m.movement.name == name
                        && (m.movement.start_frame..m.movement.end_frame).contains(&i)
                })
            };
            MovedSceneObject {
                name: name.to_string(),
                id,
                offset_m: [x, y, 0.0],
                moved_by: agents.iter().find(moving).map(|a| a.name.clone()),
                bbox_xyxy: ids.and_then(|(ids, w)| bbox_of(ids, w, id)),
            }
        })
        .collect()
}

/// Each of `points` (world) in the camera's image: its pixel (`None` outside the valid field of
/// view) and its visibility — occluded where the pixel shows something else than the agent
/// `id`, nearer than the point by more than [`JOINT_OCCLUSION_TOLERANCE_M`] (the agent's own
/// surface over a point is the point seen), `InView` without depth or segmentation.
fn project_points(
    work: &CameraWork,
    cam_from_world: crate::math::Affine3,
    depth: Option<&[f32]>,
    ids: Option<&[f32]>,
    id: u32,
    points: &[crate::math::Vec3],
) -> (Vec<Option<[f64; 2]>>, Vec<JointVisibility>) {
    project_part_points(work, cam_from_world, depth, ids, None, id, points)
}

/// [`project_points`] of points of one body part (`part`: the frame's `segmentation.part`
/// plane and the part's value): a point whose pixel shows another part of the same person,
/// nearer than the point by more than [`SELF_OCCLUSION_TOLERANCE_M`], is
/// [`JointVisibility::OccludedByBody`] (a hand behind its own body or the other hand).
fn project_part_points(
    work: &CameraWork,
    cam_from_world: crate::math::Affine3,
    depth: Option<&[f32]>,
    ids: Option<&[f32]>,
    part: Option<(&[f32], BodyPart)>,
    id: u32,
    points: &[crate::math::Vec3],
) -> (Vec<Option<[f64; 2]>>, Vec<JointVisibility>) {
    let res = work.camera.model.resolution();
    let w = res.width_px as usize;
    let mut pixels = Vec::with_capacity(points.len());
    let mut visibility = Vec::with_capacity(points.len());
    for j in points {
        let p = cam_from_world.transform_point3(*j);
        match work.camera.model.project(p) {
            Some(px) => {
                let (x, y) = (px.x.round() as usize, px.y.round() as usize);
                let at = y.min(res.height_px as usize - 1) * w + x.min(w - 1);
                pixels.push(Some([px.x, px.y]));
                visibility.push(match (depth, ids) {
                    (Some(depth), Some(ids)) => {
                        let d = depth[at] as f64;
                        let own_other_part = part.is_some_and(|(parts, part)| {
                            parts[at] as u32 != part as u32
                                && d > 0.0
                                && d < p.z - SELF_OCCLUSION_TOLERANCE_M
                        });
                        if ids[at] as u32 != id && d > 0.0 && d < p.z - JOINT_OCCLUSION_TOLERANCE_M
                        {
                            JointVisibility::Occluded
                        } else if ids[at] as u32 == id && own_other_part {
                            JointVisibility::OccludedByBody
                        } else {
                            JointVisibility::Visible
                        }
                    }
                    _ => JointVisibility::InView,
                });
            }
            None => {
                pixels.push(None);
                visibility.push(JointVisibility::Outside);
            }
        }
    }
    (pixels, visibility)
}

/// The box (x0, y0, x1, y1) of the pixels given, `None` when there are none.
fn box_of(pixels: &[Option<[f64; 2]>]) -> Option<[f64; 4]> {
    pixels.iter().flatten().fold(None, |b, p| {
        Some(
            b.map_or([p[0], p[1], p[0], p[1]], |[x0, y0, x1, y1]: [f64; 4]| {
                [x0.min(p[0]), y0.min(p[1]), x1.max(p[0]), y1.max(p[1])]
            }),
        )
    })
}

/// Inclusive pixel box of the pixels labelled `id`, if any.
fn bbox_of(ids: &[f32], width: usize, id: u32) -> Option<[usize; 4]> {
    box_where(0..ids.len(), width, |i| ids[i] as u32 == id)
}

/// Tight box (inclusive pixel indices) of the pixels `i` in `pixels` (row-major indices of a
/// `width`-wide image) where `inside(i)`.
fn box_where(
    pixels: std::ops::Range<usize>,
    width: usize,
    inside: impl Fn(usize) -> bool,
) -> Option<[usize; 4]> {
    let mut b: Option<[usize; 4]> = None;
    for i in pixels.filter(|&i| inside(i)) {
        let (x, y) = (i % width, i / width);
        b = Some(match b {
            None => [x, y, x, y],
            Some([x0, y0, x1, y1]) => [x0.min(x), y0.min(y), x1.max(x), y1.max(y)],
        });
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pixel;
    use crate::math::{Affine3, Vec3};
    use proptest::prelude::*;

    /// The Aria rig's cameras (two SLAM fisheyes cut by their sensors, the RGB fisheye), as a
    /// take renders them.
    fn aria_cameras() -> Vec<CameraWork> {
        let rig = Rig::load(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("camera_rigs/aria_gen1.json"),
        )
        .unwrap();
        rig.cameras
            .into_iter()
            .map(|camera| CameraWork {
                render: RenderCamera::equidistant(&camera.model, 1.0),
                camera,
                depth_noise: None,
                world_from_cam: Vec::new(),
                headset_wear: None,
                frames: Vec::new(),
                wearer: 0,
            })
            .collect()
    }

    /// Where the valid field of view ends along the image ray from the principal point at
    /// `angle` (px from it): bisected on `unproject`, to 1e-9 px.
    fn edge_px(model: &crate::camera::Camera, angle: f64) -> f64 {
        let c = model.principal_point();
        let at = |s: f64| c + s * Pixel::new(angle.cos(), angle.sin());
        let (mut inside, mut outside) = (0.0, 4096.0);
        while outside - inside > 1e-9 {
            let mid = 0.5 * (inside + outside);
            match model.unproject(at(mid)) {
                Some(_) => inside = mid,
                None => outside = mid,
            }
        }
        inside
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// A hand at the fisheye's edge — where the valid circle or the sensor ends — is
        /// annotated where its landmarks are: each landmark within the field of view gets its
        /// own pixel back (1e-6 px; 1e-6 to 2 px inside the edge) and is visible, one beyond the largest angle or behind the
        /// camera is outside; a head turned near 0 or π, 10 km from the origin. Another part of
        /// the person nearer hides the landmarks (`occluded_by_body`), another object too.
        #[test]
        fn a_hand_at_the_fisheyes_edge_is_annotated_where_it_is(
            camera in 0usize..3,
            angles in prop::collection::vec(0.0f64..std::f64::consts::TAU, 21),
            inward_px in prop::collection::vec(prop_oneof![1e-6f64..2e-6, 1e-6f64..2.0], 21),
            distance_m in 0.05f64..3.0,
            axis in prop::array::uniform3(-1.0f64..1.0),
            turn in prop_oneof![0.0f64..1e-6, (std::f64::consts::PI - 1e-6)..std::f64::consts::PI],
            at in prop::array::uniform3(-1.0e4f64..1.0e4),
        ) {
            let works = aria_cameras();
            let work = &works[camera];
            let model = &work.camera.model;
            let axis = Vec3::from_array(axis).try_normalize().unwrap_or(Vec3::Z);
            let world_from_cam = Affine3::from_rotation_translation(
                glam::DQuat::from_axis_angle(axis, turn),
                Vec3::from_array(at),
            );
            let c = model.principal_point();
            let mut pixels = Vec::new();
            let (mut points, mut z) = (Vec::new(), Vec::new());
            for (&a, &d) in angles.iter().zip(&inward_px) {
                let px = c + (edge_px(model, a) - d) * Pixel::new(a.cos(), a.sin());
                let ray = model.unproject(px).unwrap();
                pixels.push(px);
                points.push(world_from_cam.transform_point3(ray * distance_m));
                z.push(ray.z * distance_m);
            }
            // Beyond the largest angle, and behind the camera: outside.
            let beyond = model.max_theta_rad() + 1e-6;
            points.push(world_from_cam.transform_point3(Vec3::new(beyond.sin(), 0.0, beyond.cos())));
            points.push(world_from_cam.transform_point3(Vec3::new(0.0, 0.0, -distance_m)));
            let res = model.resolution();
            let n = (res.width_px * res.height_px) as usize;
            let (far, id) = (vec![100.0f32; n], 1000u32);
            let own = vec![id as f32; n];
            let hand = BodyPart::hand(1);
            let hands = vec![hand as u8 as f32; n];
            let cam_from_world = world_from_cam.inverse();
            let (got, seen) = project_part_points(
                work, cam_from_world, Some(&far), Some(&own), Some((&hands, hand)), id, &points,
            );
            for k in 0..21 {
                let g = got[k].unwrap();
                let miss = (Pixel::new(g[0], g[1]) - pixels[k]).length();
                prop_assert!(miss < 1e-6, "landmark {}: {} px from its pixel", k, miss);
                prop_assert_eq!(seen[k], JointVisibility::Visible);
            }
            for k in 21..23 {
                prop_assert!(got[k].is_none());
                prop_assert_eq!(seen[k], JointVisibility::Outside);
            }
            let b = box_of(&got).unwrap();
            prop_assert!(b[0] >= -0.5 && b[1] >= -0.5);
            prop_assert!(b[2] <= res.width_px as f64 - 0.5 && b[3] <= res.height_px as f64 - 0.5);
            // The forearm in front of the hand, then another object.
            let near = vec![0.04f32; n];
            let forearm = vec![BodyPart::LeftForearm as u8 as f32; n];
            let (_, behind_body) = project_part_points(
                work, cam_from_world, Some(&near), Some(&own), Some((&forearm, hand)), id, &points[..21],
            );
            let other = vec![7.0f32; n];
            let (_, behind_other) = project_part_points(
                work, cam_from_world, Some(&near), Some(&other), Some((&hands, hand)), id, &points[..21],
            );
            // Planar depth: a landmark's z, small at the edge of a wide lens.
            for k in 0..21 {
                let hidden = 0.04 < z[k] - SELF_OCCLUSION_TOLERANCE_M;
                prop_assert!(seen_as(behind_body[k], hidden, JointVisibility::OccludedByBody));
                let hidden = 0.04 < z[k] - JOINT_OCCLUSION_TOLERANCE_M;
                prop_assert!(seen_as(behind_other[k], hidden, JointVisibility::Occluded));
            }
        }
    }

    /// `v` is `hidden_as` where `hidden`, else visible.
    fn seen_as(v: JointVisibility, hidden: bool, hidden_as: JointVisibility) -> bool {
        v == if hidden {
            hidden_as
        } else {
            JointVisibility::Visible
        }
    }
}
