//! The per-camera annotation file (`cameras/<camera>/annotations.json`) as types: what a
//! dataset promises its users, written (`annotate`) and read back by the same structs. The schema, with
//! units, is in docs/ANNOTATIONS.md; [`ANNOTATIONS_VERSION`] changes when it does.

use serde::{Deserialize, Serialize};

use crate::synth::activity::{Activity, Phase};

/// Version of the annotation schema (`egogen_annotations` in the file).
pub(crate) const ANNOTATIONS_VERSION: u32 = 1;

/// One camera's annotations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraAnnotations {
    pub egogen_annotations: u32,
    pub conventions: Conventions,
    /// The camera as in a rig file (model, parameters, resolution, pose on the CPF).
    pub camera: serde_json::Value,
    /// The lens the images were rendered with (`kind`: `exact` or
    /// `cycles_polynomial_fisheye` with its error against `camera`).
    pub image_model: serde_json::Value,
    /// The noisy depth channel's model and seed, when the camera has one.
    pub depth_noise: Option<serde_json::Value>,
    /// Name of the agent wearing the camera.
    pub wearer: String,
    /// The rig's offset on the wearer's head (`[render.headset_wear]`); `t_world_cam` of
    /// every frame includes it. Absent: the rig as its file places it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub headset_wear: Option<crate::rig::wear::WearOffset>,
    /// The lights egogen added (world light, lamps), as rendered.
    pub lighting: crate::render::ShardLighting,
    /// The scene objects whose materials egogen drew (`[render.materials]`), as rendered;
    /// absent: every object has the scene's own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<crate::render::ShardMaterial>,
    /// Each agent's skin material, as rendered (absent in files written before skins).
    #[serde(default)]
    pub skins: Vec<AgentSkin>,
    /// Each person's outfit, as rendered (`[render.outfits]`); absent with outfits off.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) outfits: Vec<AgentOutfit>,
    pub frame_rate_hz: f64,
    pub segmentation_ids: Vec<SegmentationId>,
    pub frames: Vec<FrameAnnotation>,
}

/// The conventions, spelled out in every file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Conventions {
    pub world: String,
    pub camera_frame: String,
    pub pixels: String,
    #[serde(rename = "T_world_cam")]
    pub t_world_cam: String,
    pub depth: String,
    pub joint_visibility: String,
    pub bbox_xyxy: String,
    /// What the frame file's `segmentation.part` values are (absent in files written before).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub segmentation_part: String,
    /// What the frame file's `segmentation.garment` values are (absent without outfits).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub segmentation_garment: String,
}

/// A segmentation id and what carries it (a scene object, the added ceiling, an agent).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentationId {
    pub name: String,
    pub id: u32,
    /// The object's class where the scene file says (a Replica scan's `info_semantic.json`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
}

/// One rendered frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameAnnotation {
    pub frame: u32,
    pub time_s: f64,
    /// The frame's EXR file, next to the annotations.
    pub file: String,
    /// Row-major 4×4 mapping camera-frame points (OpenCV) to the world (m).
    #[serde(rename = "T_world_cam")]
    pub t_world_cam: [[f64; 4]; 4],
    /// The automatic exposure of the frame's colour: the factor by which the COLMAP image
    /// multiplies the EXR's linear colour before encoding (absent without the colour pass).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour_exposure: Option<f32>,
    /// Every agent of the run, in view or not.
    pub agents: Vec<AgentAnnotation>,
    /// The objects people pick up, in view or not: standing where they are found until a
    /// hand takes them, then carried (absent in a take where nobody picks anything up).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectAnnotation>,
    /// The scene objects people move (chairs pulled out from their tables), in view or not
    /// (absent in a take where nobody moves one).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) moved_scene_objects: Vec<MovedSceneObject>,
}

/// A scene object people move, in one frame: where it is against where the scene file
/// places it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct MovedSceneObject {
    /// Its name in the scene (and in `segmentation_ids`).
    pub(crate) name: String,
    /// Its segmentation id.
    pub(crate) id: u32,
    /// Added to where the scene file places it in this frame (world, m; horizontal): the
    /// object's pose is the scene's, translated by it.
    pub(crate) offset_m: [f64; 3],
    /// The person moving it or keeping it moved in this frame (from its first frame out until
    /// it stands where the scene has it again); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) moved_by: Option<String>,
    /// Tight box of its segmentation pixels, inclusive pixel indices; `None` when not in view
    /// (or the run rendered no segmentation).
    pub(crate) bbox_xyxy: Option<[usize; 4]>,
}

/// An object people pick up ([`crate::synth::held_object`]), in one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectAnnotation {
    pub name: String,
    /// Its segmentation id.
    pub id: u32,
    /// The scene object it is, where a person picked up one of the scene's own things (its
    /// frame: the world's axes at its box's centre).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_object: Option<String>,
    /// What egogen's own solid it is (a scene thing has none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<crate::scene::small_object::ObjectKind>,
    /// Row-major 4×4 mapping the object's frame (centred, z up; its `size_m` along x, y,
    /// z) to the world (m).
    #[serde(rename = "T_world_object")]
    pub t_world_object: [[f64; 4]; 4],
    pub size_m: [f64; 3],
    /// The person holding it in this frame; absent while it stands where it was found.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_by: Option<ObjectHolder>,
    /// Its centre's pixel; `None` outside the valid field of view.
    pub centre_2d: Option<[f64; 2]>,
    /// Its centre's visibility, as a joint's.
    pub centre_visibility: JointVisibility,
    /// Tight box of its segmentation pixels, inclusive pixel indices; `None` when not in view
    /// (or the run rendered no segmentation).
    pub bbox_xyxy: Option<[usize; 4]>,
}

/// Who holds an object, with which hand.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectHolder {
    pub agent: String,
    pub hand: crate::synth::held_object::Hand,
}

/// An agent's skin ([`crate::render::skin_tone`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AgentSkin {
    pub name: String,
    pub skin: crate::render::skin_tone::Skin,
    /// The regions painted through the body model's masks (empty: none; absent in files
    /// written before regions).
    #[serde(default)]
    pub regions: Vec<crate::render::skin_tone::RegionPaint>,
    /// The skin detail map's file name (in the body model's `textures/`), when one was used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detail: Option<String>,
}

/// A person's outfit ([`crate::render::outfit`]): its garments (lowest layer first), whether
/// the top is tucked in, and the cut (where each garment ends, in shares of the person's own
/// lengths).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct AgentOutfit {
    pub(crate) name: String,
    pub(crate) outfit: crate::render::outfit::Outfit,
}

/// Where a joint is in the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointVisibility {
    Visible,
    /// The joint's pixel shows another object or agent nearer than the joint.
    Occluded,
    /// A hand landmark's pixel shows another part of its own person nearer than it (the body
    /// or the other hand before it); only where the frame has the body parts.
    OccludedByBody,
    /// Not in the camera's valid field of view.
    Outside,
    /// In the valid field of view; whether it is occluded is not known (the run rendered no
    /// depth or no segmentation).
    InView,
}

/// One agent in one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AgentAnnotation {
    pub name: String,
    /// Its segmentation id.
    pub id: u32,
    /// Whether it wears this camera.
    pub wearer: bool,
    /// Whether its segmentation shows in the image.
    pub in_view: bool,
    pub smplx: SmplxParams,
    /// The 55 SMPL-X joints in the world (m).
    pub joints_3d: Vec<[f64; 3]>,
    /// Their pixels; `None` outside the valid field of view.
    pub joints_2d: Vec<Option<[f64; 2]>>,
    pub joint_visibility: Vec<JointVisibility>,
    /// Tight box of its segmentation pixels, inclusive pixel indices; `None` when not in view.
    pub bbox_xyxy: Option<[usize; 4]>,
    /// Pelvis distance to the nearest other agent (m); `None` for a single agent.
    pub interaction_distance_m: Option<f64>,
    /// What it does in this frame, in a take with activities (docs/ACTIVITIES.md); absent
    /// in a take where people only walk.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub activity: Option<ActivityLabel>,
    /// Its hands, left then right: each one's 21 landmarks in MPS order (docs/HANDS.md);
    /// absent for a body whose hand pose is all zeros (the rest hand throughout).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hands: Option<Vec<HandAnnotation>>,
}

/// One hand in one frame: its landmarks as the joints are annotated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HandAnnotation {
    /// `left` or `right`.
    pub side: String,
    /// The 21 landmarks in the world (m), in MPS order (`body::hand_landmarks::HAND_LANDMARKS`).
    pub landmarks_3d: Vec<[f64; 3]>,
    /// Their pixels; `None` outside the valid field of view.
    pub landmarks_2d: Vec<Option<[f64; 2]>>,
    /// Each one's visibility, as the joints' (`joint_visibility`).
    pub landmark_visibility: Vec<JointVisibility>,
    /// The box of its landmarks in view (x0, y0, x1, y1 in pixels); `None` when none is.
    pub bbox_xyxy: Option<[f64; 4]>,
    /// Tight box of its own pixels (the segmentation's `part` of this person), inclusive pixel
    /// indices; absent when none is in view or the run rendered no segmentation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mask_bbox_xyxy: Option<[usize; 4]>,
    /// The segmentation id of the object it holds in this frame (`objects`); absent: it
    /// holds nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<u32>,
}

/// What an agent does in a frame: `walk` (no phase), or an activity and its phase
/// (`approach`, `transition`, `hold`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ActivityLabel {
    pub activity: Activity,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phase: Option<Phase>,
}

/// SMPL-X parameters as the `smplx` package takes them (axis-angle, radians; m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SmplxParams {
    pub betas: Vec<f64>,
    pub global_orient: [f64; 3],
    pub body_pose: Vec<f64>,
    pub jaw_pose: [f64; 3],
    pub leye_pose: [f64; 3],
    pub reye_pose: [f64; 3],
    pub left_hand_pose: Vec<f64>,
    pub right_hand_pose: Vec<f64>,
    pub transl: [f64; 3],
}

impl SmplxParams {
    /// Splits a full SMPL-X pose (55 × axis-angle) into the `smplx` package's groups.
    pub(crate) fn new(
        betas: &[f64],
        pose: &[f64; crate::body::POSE_DIM],
        transl: [f64; 3],
    ) -> Self {
        let three = |k: usize| [pose[k], pose[k + 1], pose[k + 2]];
        Self {
            betas: betas.to_vec(),
            global_orient: three(0),
            body_pose: pose[3..66].to_vec(),
            jaw_pose: three(66),
            leye_pose: three(69),
            reye_pose: three(72),
            left_hand_pose: pose[75..120].to_vec(),
            right_hand_pose: pose[120..165].to_vec(),
            transl,
        }
    }
}
