//! Real renders: Blender (PyPI bpy 4.5) renders a walking body in the shipped apartment from a
//! shard spec written by Rust, seen by a pinhole and by a (tiny) Aria SLAM fisheye looking
//! down; the passes are read back with the `exr` crate and checked against geometry computed
//! in Rust: the vertex cache played back at whole and sub-frames, rays of every pixel, planar
//! depth, camera-frame normals of the floor, the body's segmentation, and optical flow of the
//! known camera motion.

use std::path::{Path, PathBuf};

use crate::body::BodyModel;
use crate::camera::{Camera, CameraModel, Pinhole, Pixel, Resolution};
use crate::inspect::ExrContents;
use crate::math::{Affine3, Mat3, Vec3};
use crate::motion::scripted::WalkCycle;
use crate::motion::MotionSequence;
use crate::render::frame_file::{assemble_frame, validate_frame};
use crate::render::lens_polynomial::native_error;
use crate::render::passes::{Pass, Passes};
use crate::render::protocol::{BodyProbe, PointLight, ShardSkinRegion};
use crate::render::render_camera::{FisheyeRendering, RenderCamera};
use crate::render::shard::worker_command;
use crate::render::shard_plan::{
    blender_fps, raw_frame_paths, shard_camera, RawRenders, AGENT_ID_BASE,
};
use crate::render::skin_tone::{RegionPaint, SkinPlan};
use crate::render::{BlenderRuntime, RenderDevice, ShardBody, ShardLighting, ShardRgb, ShardSpec};
use crate::rig::Rig;
use crate::scene::{load_scene, sample_start_goals, walkable_map, WalkableSettings};
use crate::synth::body_cache::{body_cache, body_cache_at, playback_keys, rendered_sample_indices};
use crate::vertex_cache::{
    write_corner_uvs_npy, write_faces_npy, write_rest_vertices_npy, PointCache,
};

/// Runs one shard through Blender directly (no pool): writes the spec, runs the worker to its
/// end and returns the EXR files it reported done, in order; a failure quotes Blender's
/// standard error.
fn render_shard(
    runtime: &BlenderRuntime,
    spec: &ShardSpec,
    spec_path: &Path,
) -> Result<Vec<PathBuf>, String> {
    std::fs::write(spec_path, serde_json::to_vec_pretty(spec).unwrap()).unwrap();
    let output = worker_command(runtime, spec_path)
        .output()
        .map_err(|e| e.to_string())?;
    let done: Vec<PathBuf> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|l| l.strip_prefix("EGOGEN_DONE "))
        .map(PathBuf::from)
        .collect();
    match output.status.success() && done.len() == spec.num_outputs() {
        true => Ok(done),
        false => Err(format!(
            "Blender {} after {} of {} frames:\n{}",
            output.status,
            done.len(),
            spec.num_outputs(),
            String::from_utf8_lossy(&output.stderr)
        )),
    }
}

const FRAMES: usize = 6;
const RATE_HZ: f64 = 40.0;
const SAMPLES_PER_FRAME: u32 = 4;
const CAMERA_HEIGHT_M: f64 = 2.3;
const CAMERA_STEP_M: f64 = 0.02;
const RENDERED: [u32; 2] = [2, 3];
/// Times the renders of `RENDERED` read the bodies at: shutter ends and centres, the flow's
/// neighbours, and sub-frames in between inside the shutter.
const PROBE_FRAMES: [f64; 8] = [1.0, 1.75, 1.875, 2.0, 2.25, 2.75, 3.125, 4.0];
/// The body's one skin region: green wherever its UV has u < 1/2 (a mask written here).
const GREEN_REGION: [f64; 3] = [0.05, 0.6, 0.05];

struct Rendered {
    spec: ShardSpec,
    _dir: tempfile::TempDir,
    raw_dir: PathBuf,
    motion: MotionSequence,
    model: BodyModel,
    cache: PointCache,
    probe: PathBuf,
    floor_id: u32,
    cameras: Vec<(String, Camera, RenderCamera)>,
    poses: Vec<Affine3>,
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Looking straight down (OpenCV: z_cam = −z, x_cam = +x, y_cam = −y), moving along (½, 1, 0).
fn camera_poses(spot: Vec3) -> Vec<Affine3> {
    (0..FRAMES)
        .map(|i| Affine3 {
            matrix3: Mat3::from_cols(Vec3::X, -Vec3::Y, -Vec3::Z),
            translation: spot
                + Vec3::new(
                    0.5 * CAMERA_STEP_M * i as f64,
                    CAMERA_STEP_M * i as f64,
                    CAMERA_HEIGHT_M,
                ),
        })
        .collect()
}

/// The body model and a scripted walk of `FRAMES` frames near `spot`.
fn walking_body(spot: Vec3) -> (BodyModel, MotionSequence) {
    let model = BodyModel::load(repo().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let shaped = model.shape(&[], &[]).unwrap();
    let sole_y = shaped
        .v_shaped
        .iter()
        .map(|v| v.y)
        .fold(f64::INFINITY, f64::min);
    let mut motion = WalkCycle::default().sequence(
        FRAMES as f64 / RATE_HZ,
        RATE_HZ,
        &[],
        shaped.rest_joints[0],
        sole_y,
    );
    for t in &mut motion.trans {
        *t += spot - Vec3::new(0.1, 0.0, 0.0);
    }
    (model, motion)
}

/// A 64×48 pinhole and a 64×48 Aria SLAM fisheye traced exactly, natively and as an
/// equidistant source.
fn test_cameras() -> Vec<(String, Camera, RenderCamera)> {
    let pinhole = Camera::Pinhole(
        Pinhole::new(
            48.0,
            48.0,
            31.5,
            23.5,
            Resolution {
                width_px: 64,
                height_px: 48,
            },
        )
        .unwrap(),
    );
    let rig = Rig::load(&repo().join("camera_rigs/aria_gen1.json")).unwrap();
    let Camera::Fisheye624(slam) = &rig.camera("camera-slam-left").unwrap().model else {
        panic!("slam camera is Fisheye624")
    };
    let tiny_slam = slam
        .rescaled(
            Resolution {
                width_px: 64,
                height_px: 48,
            },
            0.1,
            Pixel::ZERO,
        )
        .unwrap();
    [
        ("pinhole", pinhole, FisheyeRendering::Exact),
        (
            "slam",
            Camera::Fisheye624(tiny_slam),
            FisheyeRendering::Exact,
        ),
        (
            "slam_native",
            Camera::Fisheye624(tiny_slam),
            FisheyeRendering::Native,
        ),
        (
            "slam_equidistant",
            Camera::Fisheye624(tiny_slam),
            FisheyeRendering::Equidistant,
        ),
    ]
    .into_iter()
    .map(|(n, c, mode)| {
        let r = RenderCamera::for_camera(&c, 1.0, mode).unwrap();
        (n.to_string(), c, r)
    })
    .collect()
}

fn render_scene() -> Rendered {
    let glb = repo().join("assets/scenes/apartment.glb");
    let mesh = load_scene(&glb, Default::default()).unwrap();
    let map = walkable_map(&mesh, &glb, WalkableSettings::default()).unwrap();
    let s = sample_start_goals(&map, 7, 1, 0.8, 0.0)[0].start;
    let spot = Vec3::new(s.x, s.y, 0.0);
    let floor_id = mesh
        .objects
        .iter()
        .find(|o| o.name == "floor")
        .unwrap()
        .id
        .0;

    let (model, motion) = walking_body(spot);

    let dir = tempfile::tempdir().unwrap();
    // Blender gets the times the renders read only (as egogen-run writes it); the full cache
    // is the reference it must play back the same as.
    let cache = body_cache(&model, &motion, SAMPLES_PER_FRAME).unwrap();
    let read = rendered_sample_indices(&RENDERED, 1, 0.5, SAMPLES_PER_FRAME, FRAMES);
    let sparse = body_cache_at(&model, &motion, SAMPLES_PER_FRAME, Some(&read)).unwrap();
    assert!(sparse.samples.len() < cache.samples.len() / 2);
    let pc2 = dir.path().join("body.pc2");
    let faces = dir.path().join("faces.npy");
    let vertices = dir.path().join("vertices.npy");
    sparse.write(&pc2).unwrap();
    write_faces_npy(&faces, &model.faces).unwrap();
    write_rest_vertices_npy(&vertices, &sparse).unwrap();
    let uvs = dir.path().join("uvs.npy");
    write_corner_uvs_npy(&uvs, &model.uvs.as_ref().unwrap().per_corner()).unwrap();
    let mask = dir.path().join("u_below_half.png");
    write_left_half_mask(&mask, 64);

    let cameras = test_cameras();
    let poses = camera_poses(spot);
    let raw_dir = dir.path().join("raw");
    let (fps, fps_base) = blender_fps(RATE_HZ);
    let probe = dir.path().join("probe.json");
    let spec = ShardSpec {
        scene_file: glb,
        scene_up_axis: "y".into(),
        scene_unit_m: 1.0,
        object_ids: mesh
            .objects
            .iter()
            .map(|o| (o.name.clone(), o.id.0))
            .collect(),
        fps,
        fps_base,
        bodies: vec![ShardBody {
            name: "agent_0".into(),
            pass_index: AGENT_ID_BASE,
            faces_npy: faces,
            vertices_npy: vertices,
            pc2,
            samples_per_frame: SAMPLES_PER_FRAME,
            cache_keys: playback_keys(&read, SAMPLES_PER_FRAME),
            motion_steps: crate::render::shard_plan::deform_motion_steps(0.5, SAMPLES_PER_FRAME),
            skin: SkinPlan::default().draw(0),
            uvs_npy: Some(uvs),
            skin_regions: vec![ShardSkinRegion {
                paint: RegionPaint {
                    region: "u_below_half".into(),
                    mask: "u_below_half.png".into(),
                    rgb: GREEN_REGION,
                    roughness: 0.45,
                },
                mask,
            }],
            // The shipped detail map scales every colour alike: the region and the skin keep
            // their hues (`skin_regions_follow_the_body_uvs`).
            skin_detail: Some(repo().join("assets/body/textures/egogen_skin_detail.jpg")),
            outfit: None,
            parts_npy: None,
        }],
        lighting: ShardLighting {
            world_rgb: [0.3, 0.3, 0.3],
            world_hdri: None,
            point_lights: vec![PointLight {
                position: (spot + Vec3::new(0.5, 0.5, 2.2)).to_array(),
                watts: 200.0,
            }],
        },
        materials: Vec::new(),
        rgb: Some(ShardRgb {
            samples: 4,
            adaptive_threshold: 0.0,
            denoise: None,
            shutter_frames: 0.5,
            seed: 0,
        }),
        // `z`, Cycles' own depth, only to cross-check the planar depth made from `position`.
        ground_truth_passes: ["position", "normal", "object_index", "vector", "z"]
            .map(String::from)
            .to_vec(),
        ground_truth_frame_step: 1,
        device: RenderDevice::Cpu,
        cameras: cameras
            .iter()
            .map(|(n, _, r)| {
                shard_camera(
                    n,
                    r,
                    &poses,
                    &RENDERED,
                    SAMPLES_PER_FRAME,
                    1,
                    &raw_dir,
                    BOTH,
                )
            })
            .collect(),
        body_probe: Some(BodyProbe {
            frames: PROBE_FRAMES.to_vec(),
            output_json: probe.clone(),
        }),
        ceiling: None,
        obstacles: Vec::new(),
        held_objects: Vec::new(),
        moved_objects: Vec::new(),
        scene_split: None,
    };
    let runtime = BlenderRuntime::resolve(None).expect("Blender 4.5 (managed PyPI bpy)");
    let done = render_shard(&runtime, &spec, &dir.path().join("shard.json")).unwrap();
    assert_eq!(done.len(), spec.num_outputs());
    Rendered {
        spec,
        raw_dir,
        _dir: dir,
        motion,
        model,
        cache,
        probe,
        floor_id,
        cameras,
        poses,
    }
}

/// A grey `size`² PNG, white where u < 1/2 (the left half), black elsewhere.
fn write_left_half_mask(path: &std::path::Path, size: u32) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, size, size);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let pixels: Vec<u8> = (0..size * size)
        .map(|i| if i % size < size / 2 { 255 } else { 0 })
        .collect();
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&pixels).unwrap();
}

fn rendered() -> &'static Rendered {
    static ONCE: std::sync::OnceLock<Rendered> = std::sync::OnceLock::new();
    ONCE.get_or_init(render_scene)
}

const BOTH: RawRenders = RawRenders {
    colour: true,
    ground_truth: true,
};

fn raw(r: &Rendered, camera: &str, frame: u32) -> (PathBuf, PathBuf) {
    let (rgb, gt) = raw_frame_paths(&r.raw_dir, camera, frame, BOTH);
    (rgb.unwrap(), gt.unwrap())
}

fn plane<'a>(exr: &'a ExrContents, name: &str) -> &'a [f32] {
    &exr.channel(name)
        .unwrap_or_else(|| panic!("{name} missing"))
        .values
}

/// Assembles and validates the dataset frame of a camera; returns its contents.
fn frame(r: &Rendered, cam: usize, frame: u32) -> ExrContents {
    let (name, target, render) = &r.cameras[cam];
    let (rgb, gt) = raw(r, name, frame);
    let image = assemble_frame(
        Some(&rgb),
        Some(&gt),
        render,
        target,
        r.poses[frame as usize],
    )
    .unwrap();
    let out = r.raw_dir.join(format!("{name}_{frame}.exr"));
    image.write(&out).unwrap();
    let res = target.resolution();
    let channels = Passes::default().frame_channels(false, false, false);
    validate_frame(&out, res.width_px, res.height_px, &channels).unwrap()
}

mod checks;
