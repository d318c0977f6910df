//! Things people pick up and carry: a pick-up's object (a small object,
//! `scene::small_object`), standing on the floor under the reaching palm until the hand takes it at its lowest reach ([`Grasp`]), then carried rigidly with
//! that wrist to the end of the take. The kind is drawn among those whose top fits under the
//! palm there, close enough for the hand to close round it (a pick-up whose free hand stays
//! high takes nothing); the grip is shaped to its width
//! (`motion::hands::HandDoing::Holding`). Its pose on every frame is what the renders and the
//! annotations read.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::body::{joint, BodyParams, PoseError};
use crate::math::colour::hsv_linear;
use crate::math::random::uniform_in;
use crate::math::{Affine3, Vec3};
use crate::motion::cvae::BodyContext;
use crate::scene::small_object::{ObjectKind, ObjectShape};
use crate::synth::activity::ActivitySegment;

/// A hand.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Hand {
    Left,
    Right,
}

impl Hand {
    /// 0 for the left hand, 1 for the right (the order of `[left, right]` arrays).
    pub(crate) fn index(self) -> usize {
        self as usize
    }

    fn wrist_joint(self) -> usize {
        [joint::LEFT_WRIST, joint::RIGHT_WRIST][self.index()]
    }
}

/// Where a pick-up takes hold: the frame of its lowest reach and the hand that reaches lower.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Grasp {
    pub frame: usize,
    pub hand: Hand,
    /// The pick-up's first frame (its hold phase).
    pub from_frame: usize,
    /// The palm's centre at the grasp (world).
    pub palm: Vec3,
    /// From the wrist towards the fingers, horizontal, at the grasp.
    pub along: DVec2,
}

/// One object a person picked up.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeldObject {
    /// Unique in the take: `<person>_<kind>_<k>`.
    pub name: String,
    pub kind: ObjectKind,
    pub shape: ObjectShape,
    /// Full extents along its own x, y and up (m).
    pub size_m: [f64; 3],
    /// Linear RGB.
    pub colour_rgb: [f64; 3],
    pub hand: Hand,
    /// The frame the hand takes hold of it; it is carried from there to the take's end.
    pub grasp_frame: usize,
    /// How far the palm's centre was above the object's top when the hand took hold (m).
    pub palm_gap_m: f64,
    /// Deepest a fingertip of the holding hand went inside it while held (m).
    pub fingertip_depth_m: f64,
    /// Its pose on every frame of the take (object frame: centred, z up).
    #[serde(skip)]
    pub world_from_object: Vec<Affine3>,
}

impl HeldObject {
    /// Whether its hand holds it on frame `f`.
    pub(crate) fn held_at(&self, f: usize) -> bool {
        f >= self.grasp_frame
    }
}

/// Room left between the palm and the object's top when choosing a kind (m): skin and a
/// little air.
const PALM_CLEARANCE_M: f64 = 0.01;

/// The grasp of a pick-up (its hold phase `seg`) in `frames`: the frame where the wrist of a
/// hand that is `free` (`[left, right]`) comes lowest, with that hand; none with both hands
/// full.
pub(crate) fn grasp_in(
    seg: &ActivitySegment,
    frames: &[BodyParams],
    body: &BodyContext,
    free: [bool; 2],
) -> Result<Option<Grasp>, PoseError> {
    let end = seg.end_frame.min(frames.len());
    let mut lowest: Option<(f64, usize, Hand)> = None;
    for (f, frame) in frames.iter().enumerate().take(end).skip(seg.start_frame) {
        let s = body.shaped.skeleton(&frame.pose, frame.transl)?;
        for hand in [Hand::Left, Hand::Right] {
            let z = s.joints[hand.wrist_joint()].z;
            if free[hand.index()] && lowest.is_none_or(|l| z < l.0) {
                lowest = Some((z, f, hand));
            }
        }
    }
    let Some((_, frame, hand)) = lowest else {
        return Ok(None);
    };
    let s = body
        .shaped
        .skeleton(&frames[frame].pose, frames[frame].transl)?;
    let wrist = s.joints[hand.wrist_joint()];
    // The palm's centre: midway between the wrist and the middle finger's knuckle (as the
    // hand landmarks have it).
    let knuckle = s.joints[[28, 43][hand.index()]];
    let d = knuckle - wrist;
    Ok(Some(Grasp {
        frame,
        hand,
        from_frame: seg.start_frame,
        palm: (wrist + knuckle) * 0.5,
        along: DVec2::new(d.x, d.y).try_normalize().unwrap_or(DVec2::X),
    }))
}

/// Farthest the palm's centre may be above the top of what it takes (m): the fingers close
/// round the top from up to this high.
pub(crate) const MAX_PALM_GAP_M: f64 = 0.08;

/// The object `grasp` takes: a kind drawn among those whose top lies at most
/// [`MAX_PALM_GAP_M`] under the palm (and not in it), standing on the floor at `floor_z` under
/// the palm, turned to the hand; named `<person>_<kind>_<k>`. None where no kind fits (a hand
/// that stayed high). Its poses are set by [`carry`].
pub(crate) fn placed_object(
    person: &str,
    k: usize,
    grasp: &Grasp,
    floor_z: f64,
    rng: &mut ChaCha8Rng,
) -> Option<HeldObject> {
    let room = grasp.palm.z - floor_z - PALM_CLEARANCE_M;
    let fits: Vec<ObjectKind> = ObjectKind::ALL
        .into_iter()
        .filter(|kind| (room - MAX_PALM_GAP_M..=room).contains(&kind.size_m()[2]))
        .collect();
    let draw = uniform_in(rng, 0.0, 1.0);
    let colour_rgb = hsv_linear(
        uniform_in(rng, 0.0, 360.0),
        uniform_in(rng, 0.3, 0.85),
        uniform_in(rng, 0.35, 0.9),
    );
    let kind = *fits.get(((draw * fits.len() as f64) as usize).min(fits.len().max(1) - 1))?;
    let size_m = kind.size_m();
    let centre = Vec3::new(grasp.palm.x, grasp.palm.y, floor_z + 0.5 * size_m[2]);
    let resting = Affine3::from_rotation_translation(
        glam::DQuat::from_rotation_z(grasp.along.to_angle()),
        centre,
    );
    Some(HeldObject {
        name: format!("{person}_{}_{k}", kind.name()),
        kind,
        shape: kind.shape(),
        size_m,
        colour_rgb,
        hand: grasp.hand,
        grasp_frame: grasp.frame,
        palm_gap_m: grasp.palm.z - (floor_z + size_m[2]),
        fingertip_depth_m: 0.0,
        world_from_object: vec![resting],
    })
}

/// Every frame's pose of `object` from the take's wrists (`world_from_wrist[f][hand]`): where
/// it stands until its grasp, then moved with the wrist that took it.
pub(crate) fn carry(object: &mut HeldObject, world_from_wrist: &[[Affine3; 2]]) {
    let resting = object.world_from_object[0];
    let h = object.hand.index();
    let g = object
        .grasp_frame
        .min(world_from_wrist.len().saturating_sub(1));
    let wrist_from_object = world_from_wrist[g][h].inverse() * resting;
    object.world_from_object = world_from_wrist
        .iter()
        .enumerate()
        .map(|(f, w)| {
            if f < object.grasp_frame {
                resting
            } else {
                w[h] * wrist_from_object
            }
        })
        .collect();
}

/// How deep `point` (world) lies inside `object` on frame `f` (m to its nearest face; 0
/// outside).
pub(crate) fn depth_inside(object: &HeldObject, f: usize, point: Vec3) -> f64 {
    let p = object.world_from_object[f]
        .inverse()
        .transform_point3(point);
    let [x, y, z] = object.size_m.map(|v| 0.5 * v);
    let across = match object.shape {
        ObjectShape::Cylinder => x - DVec2::new(p.x, p.y).length(),
        ObjectShape::Box => (x - p.x.abs()).min(y - p.y.abs()),
    };
    across.min(z - p.z.abs()).max(0.0)
}
