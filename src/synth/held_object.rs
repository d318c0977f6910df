//! Things people pick up and carry: a pick-up's object (a small object,
//! `scene::small_object`), standing on the floor under the reaching palm until the hand takes
//! it at its lowest reach ([`Grasp`]), then carried rigidly with that wrist to the end of the
//! take. The kind and its height are drawn among those whose top fits under the palm there,
//! close enough for the hand to close round it (a pick-up whose free hand stays high, or
//! reaches to the floor, takes nothing); the grip is shaped to its width
//! (`motion::hands::HandDoing::Holding`), and the object is lowered under the closed hand's
//! fingertips ([`fit_under_fingertips`]; one that cannot be is not taken). Or one of the
//! scene's own small things a person walked to ([`taken_thing`]): taken where the palm comes
//! over its top, not moved before. Its pose on every frame is what the renders and the
//! annotations read.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::body::hand_landmarks::palm_centre;
use crate::body::{joint, BodyParams, PoseError};
use crate::math::colour::hsv_linear;
use crate::math::random::uniform_in;
use crate::math::{Affine3, Vec3};
use crate::motion::cvae::BodyContext;
use crate::scene::small_object::{depth_under_surface, ObjectKind, ObjectShape, SceneThing};
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

/// One object a person picked up: a solid egogen adds (its `kind`, `shape` and colour), or
/// one of the scene's own things (`scene_object`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeldObject {
    /// Unique in the take: `<person>_<kind>_<k>`; a scene thing's: its name in the scene.
    pub name: String,
    /// The scene object it is, where it is one of the scene's own things.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene_object: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<ObjectKind>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shape: Option<ObjectShape>,
    /// Full extents along its own x, y and up (m): a scene thing's, its box's (its frame
    /// the world's axes at the box's centre).
    pub size_m: [f64; 3],
    /// Linear RGB.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub colour_rgb: Option<[f64; 3]>,
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
    /// A scene thing's triangles (object frame): what a fingertip may not go under.
    #[serde(skip)]
    pub triangles: Vec<[Vec3; 3]>,
}

impl HeldObject {
    /// Whether its hand holds it on frame `f`.
    pub(crate) fn held_at(&self, f: usize) -> bool {
        f >= self.grasp_frame
    }

    /// The width the hand closes round (m): a solid's kind's, a scene thing's box across the
    /// narrower way.
    pub(crate) fn grip_m(&self) -> f64 {
        match self.kind {
            Some(kind) => kind.grip_m(),
            None => self.size_m[0].min(self.size_m[1]),
        }
    }
}

/// Room left between the palm and the object's top when choosing a kind (m): skin and a
/// little air.
pub(crate) const PALM_CLEARANCE_M: f64 = 0.01;

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
    let palm = palm_centre(&s, hand.index());
    let d = palm - s.joints[hand.wrist_joint()];
    Ok(Some(Grasp {
        frame,
        hand,
        from_frame: seg.start_frame,
        palm,
        along: DVec2::new(d.x, d.y).try_normalize().unwrap_or(DVec2::X),
    }))
}

/// Farthest the palm's centre may be above the top of what it takes (m): the fingers close
/// round the top from up to this high.
pub(crate) const MAX_PALM_GAP_M: f64 = 0.08;

/// The heights (m) of `kind` whose top lies at most [`MAX_PALM_GAP_M`] under a palm with
/// `room` to the floor (and not in it); none where no height does.
fn heights_under(kind: ObjectKind, room: f64) -> Option<[f64; 2]> {
    let [lo, hi] = kind.heights_m();
    let (lo, hi) = (lo.max(room - MAX_PALM_GAP_M), hi.min(room));
    (lo <= hi).then_some([lo, hi])
}

/// The object `grasp` takes: a kind drawn among those that come in a height whose top lies
/// at most [`MAX_PALM_GAP_M`] under the palm (and not in it), its height drawn among those,
/// standing on the floor at `floor_z` under the palm, turned to the hand; named
/// `<person>_<kind>_<k>`. None where no kind fits (a hand that stayed high, or reached to the
/// floor). Its poses are set by [`fit_under_fingertips`].
pub(crate) fn placed_object(
    person: &str,
    k: usize,
    grasp: &Grasp,
    floor_z: f64,
    rng: &mut ChaCha8Rng,
) -> Option<HeldObject> {
    let room = grasp.palm.z - floor_z - PALM_CLEARANCE_M;
    let fits: Vec<(ObjectKind, [f64; 2])> = ObjectKind::ALL
        .into_iter()
        .filter_map(|kind| Some((kind, heights_under(kind, room)?)))
        .collect();
    let draw = uniform_in(rng, 0.0, 1.0);
    let colour_rgb = hsv_linear(
        uniform_in(rng, 0.0, 360.0),
        uniform_in(rng, 0.3, 0.85),
        uniform_in(rng, 0.35, 0.9),
    );
    let height = uniform_in(rng, 0.0, 1.0);
    let (kind, [lo, hi]) =
        *fits.get(((draw * fits.len() as f64) as usize).min(fits.len().max(1) - 1))?;
    let [x, y] = kind.footprint_m();
    let size_m = [x, y, lo + height * (hi - lo)];
    let centre = Vec3::new(grasp.palm.x, grasp.palm.y, floor_z + 0.5 * size_m[2]);
    let resting = Affine3::from_rotation_translation(
        glam::DQuat::from_rotation_z(grasp.along.to_angle()),
        centre,
    );
    Some(HeldObject {
        name: format!("{person}_{}_{k}", kind.name()),
        scene_object: None,
        kind: Some(kind),
        shape: Some(kind.shape()),
        size_m,
        colour_rgb: Some(colour_rgb),
        hand: grasp.hand,
        grasp_frame: grasp.frame,
        palm_gap_m: grasp.palm.z - (floor_z + size_m[2]),
        fingertip_depth_m: 0.0,
        world_from_object: vec![resting],
        triangles: Vec::new(),
    })
}

/// Deepest a fingertip of the holding hand may go under a scene thing's upper surface (m):
/// skin gives a little, and the thing cannot be made lower.
const THING_FINGERTIP_DEPTH_M: f64 = 0.01;

/// Farthest the palm's centre may lie outside a scene thing's footprint, horizontally, where
/// the hand takes it (m).
const THING_PALM_MISS_M: f64 = 0.03;

/// Scene thing `thing` as `grasp` takes it: where the palm's centre comes over its top
/// (within [`THING_PALM_MISS_M`] of its footprint) with at most [`MAX_PALM_GAP_M`] between
/// them and not into it; none where it does not. Its pose is its box's centre, the world's
/// axes; set per frame by [`fit_under_fingertips`].
pub(crate) fn taken_thing(thing: &SceneThing, grasp: &Grasp) -> Option<HeldObject> {
    let size = thing.max - thing.min;
    let centre = thing.centre();
    let gap = grasp.palm.z - thing.max.z;
    let off = (DVec2::new(grasp.palm.x - centre.x, grasp.palm.y - centre.y).abs()
        - DVec2::new(size.x, size.y) * 0.5)
        .max(DVec2::ZERO)
        .length();
    ((0.0..=MAX_PALM_GAP_M + PALM_CLEARANCE_M).contains(&gap) && off <= THING_PALM_MISS_M).then(
        || HeldObject {
            name: thing.name.clone(),
            scene_object: Some(thing.name.clone()),
            kind: None,
            shape: None,
            size_m: size.to_array(),
            colour_rgb: None,
            hand: grasp.hand,
            grasp_frame: grasp.frame,
            palm_gap_m: gap,
            fingertip_depth_m: 0.0,
            world_from_object: vec![Affine3::from_translation(centre)],
            triangles: thing
                .triangles
                .iter()
                .map(|t| t.map(|v| v - centre))
                .collect(),
        },
    )
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

/// Room left between a fingertip and the top of what the hand holds, where the object is
/// lowered under the fingertips (m).
const FINGERTIP_CLEARANCE_M: f64 = 0.002;

/// The deepest any of its hand's `fingertips` (per frame, world) lies inside `object` from its
/// grasp on (m; 0: none inside).
fn deepest_fingertip(object: &HeldObject, fingertips: &[[Vec3; 5]]) -> f64 {
    (object.grasp_frame..fingertips.len().min(object.world_from_object.len()))
        .flat_map(|f| fingertips[f].map(|p| depth_inside(object, f, p)))
        .fold(0.0, f64::max)
}

/// Carries `object` with `world_from_wrist` ([`carry`]), lowered (its top, standing where it
/// stood) until no fingertip of its hand (`fingertips`, per frame) enters it, at a height its
/// kind comes in; sets its palm gap and fingertip depth. False where even its lowest height
/// leaves a fingertip inside: the hand cannot close round it.
pub(crate) fn fit_under_fingertips(
    object: &mut HeldObject,
    fingertips: &[[Vec3; 5]],
    world_from_wrist: &[[Affine3; 2]],
) -> bool {
    carry(object, world_from_wrist);
    // Each pass clears the faces the fingertips entered; one entering a side may need
    // another.
    for _ in 0..8 {
        let depth = deepest_fingertip(object, fingertips);
        object.fingertip_depth_m = depth;
        if depth <= 0.0 {
            return true;
        }
        let lower = depth + FINGERTIP_CLEARANCE_M;
        let Some(kind) = object.kind else {
            // A scene thing keeps its height: the fingertips may enter it this deep.
            return depth <= THING_FINGERTIP_DEPTH_M;
        };
        if object.size_m[2] - lower < kind.heights_m()[0] {
            return false;
        }
        object.size_m[2] -= lower;
        object.palm_gap_m += lower;
        // Before its grasp it stands still: its first pose is where it stands.
        let mut resting = object.world_from_object[0];
        resting.translation.z -= 0.5 * lower;
        object.world_from_object = vec![resting];
        carry(object, world_from_wrist);
    }
    false
}

/// How deep `point` (world) lies inside `object` on frame `f` (m to its nearest face; 0
/// outside); inside a scene thing, how far under its upper surface.
pub(crate) fn depth_inside(object: &HeldObject, f: usize, point: Vec3) -> f64 {
    let p = object.world_from_object[f]
        .inverse()
        .transform_point3(point);
    let [radius, _, z] = object.size_m.map(|v| 0.5 * v);
    let across = match object.shape {
        Some(ObjectShape::Cylinder) => radius - DVec2::new(p.x, p.y).length(),
        None if p.z < -z => return 0.0,
        None => return depth_under_surface(&object.triangles, p),
    };
    across.min(z - p.z.abs()).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand_core::SeedableRng;

    fn grasp_at(palm: Vec3, frame: usize) -> Grasp {
        Grasp {
            frame,
            hand: Hand::Right,
            from_frame: 0,
            palm,
            along: DVec2::new(0.6, 0.8),
        }
    }

    /// A wrist pose from an axis-angle (any angle, π included) and a position.
    fn wrist(axis: [f64; 3], angle: f64, at: [f64; 3]) -> Affine3 {
        let axis = Vec3::from_array(axis).try_normalize().unwrap_or(Vec3::Z);
        Affine3::from_rotation_translation(glam::DQuat::from_axis_angle(axis, angle), at.into())
    }

    proptest! {
        /// Whatever the palm's height, the object taken never reaches into the palm and its
        /// top lies within [`MAX_PALM_GAP_M`] below it, its height one its kind comes in;
        /// a palm too low for the lowest object or too high over the tallest takes nothing,
        /// any palm between takes something (no height is left without an object). Far from
        /// the origin too.
        #[test]
        fn the_object_taken_fits_under_the_palm(
            height in 0.0f64..0.6,
            floor in -50.0f64..50.0,
            xy in prop::array::uniform2(-1.0e4f64..1.0e4),
            seed in 0u64..1000,
        ) {
            let palm = Vec3::new(xy[0], xy[1], floor + height);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let taken = placed_object("p", 0, &grasp_at(palm, 7), floor, &mut rng);
            let room = palm.z - floor - PALM_CLEARANCE_M;
            let lowest = ObjectKind::ALL.iter().map(|k| k.heights_m()[0]).fold(f64::INFINITY, f64::min);
            let tallest = ObjectKind::ALL.iter().map(|k| k.heights_m()[1]).fold(0.0, f64::max);
            let fits = (lowest..=tallest + MAX_PALM_GAP_M).contains(&room);
            prop_assert_eq!(taken.is_some(), fits, "room {}", room);
            if let Some(o) = taken {
                let kind = o.kind.unwrap();
                let [lo, hi] = kind.heights_m();
                prop_assert!((lo - 1e-12..=hi + 1e-12).contains(&o.size_m[2]));
                prop_assert_eq!(&o.size_m[..2], &kind.footprint_m()[..]);
                let top = floor + o.size_m[2];
                prop_assert!(top <= palm.z - PALM_CLEARANCE_M + 1e-9);
                prop_assert!(o.palm_gap_m <= MAX_PALM_GAP_M + PALM_CLEARANCE_M + 1e-9);
                let bottom = o.world_from_object[0].transform_point3(Vec3::new(0.0, 0.0, -0.5 * o.size_m[2]));
                prop_assert!((bottom.z - floor).abs() < 1e-6 * (1.0 + floor.abs()));
                prop_assert!((bottom.x - palm.x).abs() < 1e-6 && (bottom.y - palm.y).abs() < 1e-6);
            }
        }

        /// Carried, the object keeps its pose in the wrist's frame on every frame (rotations
        /// near 0 and π, far from the origin), and stands still before the grasp.
        #[test]
        fn a_carried_object_stays_put_in_the_hand(
            axes in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 6),
            angles in prop::collection::vec(prop_oneof![0.0f64..1e-6, (std::f64::consts::PI - 1e-6)..std::f64::consts::PI, 0.0f64..std::f64::consts::PI], 6),
            at in prop::collection::vec(prop::array::uniform3(-1.0e3f64..1.0e3), 6),
            grasp in 0usize..6,
        ) {
            let wrists: Vec<[Affine3; 2]> = (0..6)
                .map(|f| { let w = wrist(axes[f], angles[f], at[f]); [w, w] })
                .collect();
            let palm = wrists[grasp][1].translation + Vec3::new(0.0, 0.0, -0.02);
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            // A palm 0.15 m over the floor takes something.
            let floor = palm.z - 0.15;
            let mut o = placed_object("p", 0, &grasp_at(palm, grasp), floor, &mut rng).unwrap();
            let resting = o.world_from_object[0];
            carry(&mut o, &wrists);
            prop_assert_eq!(o.world_from_object.len(), 6);
            let held = wrists[grasp][1].inverse() * o.world_from_object[grasp];
            for f in 0..6 {
                if f < grasp {
                    prop_assert_eq!(o.world_from_object[f], resting);
                } else {
                    let d = wrists[f][1].inverse() * o.world_from_object[f];
                    let off = d.to_cols_array().iter().zip(held.to_cols_array()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                    prop_assert!(off < 1e-9 * 1.0e3, "frame {}: {}", f, off);
                }
                prop_assert_eq!(o.held_at(f), f >= grasp);
            }
            prop_assert!((o.world_from_object[grasp].translation - resting.translation).length() < 1e-9 * 1.0e3);
        }
    }

    /// A fingertip inside the top of what is held lowers it under the fingertip, a clearance
    /// over, its bottom still on the floor and its palm gap grown as much; a fingertip near
    /// its bottom, which no height of its kind clears, leaves it untaken.
    #[test]
    fn an_object_is_lowered_under_the_fingertips() {
        let palm = Vec3::new(3.0, -2.0, 0.30);
        let take = || {
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            placed_object("p", 0, &grasp_at(palm, 2), 0.0, &mut rng).unwrap()
        };
        let wrists = vec![[wrist([0.0, 0.0, 1.0], 0.3, [3.0, -2.0, 0.35]); 2]; 5];
        let mut o = take();
        assert_eq!(o.kind, Some(ObjectKind::Bottle));
        let (height, gap) = (o.size_m[2], o.palm_gap_m);
        let inside = Vec3::new(3.0, -2.0, height - 0.01);
        let tips = vec![[inside, palm, palm, palm, palm]; 5];
        assert!(fit_under_fingertips(&mut o, &tips, &wrists));
        let lowered = 0.01 + FINGERTIP_CLEARANCE_M;
        assert!((o.size_m[2] - (height - lowered)).abs() < 1e-9);
        assert!((o.palm_gap_m - (gap + lowered)).abs() < 1e-9);
        assert_eq!(o.fingertip_depth_m, 0.0);
        for pose in &o.world_from_object {
            let bottom = pose.transform_point3(Vec3::new(0.0, 0.0, -0.5 * o.size_m[2]));
            assert!(bottom.z.abs() < 1e-9, "{bottom}");
        }
        let mut o = take();
        let near_bottom = Vec3::new(3.0, -2.0, 0.005);
        let tips = vec![[near_bottom, palm, palm, palm, palm]; 5];
        assert!(!fit_under_fingertips(&mut o, &tips, &wrists));
    }

    /// A point's depth inside each solid: at its centre half its smallest extent, 0 on and
    /// outside its faces; the cylinder's corners are outside it.
    #[test]
    fn depth_inside_measures_to_the_nearest_face() {
        for kind in ObjectKind::ALL {
            let [x, y] = kind.footprint_m();
            let size_m = [x, y, kind.heights_m()[0]];
            let o = HeldObject {
                name: "o".into(),
                scene_object: None,
                kind: Some(kind),
                shape: Some(kind.shape()),
                size_m,
                colour_rgb: Some([0.5; 3]),
                hand: Hand::Left,
                grasp_frame: 0,
                palm_gap_m: 0.0,
                fingertip_depth_m: 0.0,
                world_from_object: vec![wrist([0.3, 0.2, 1.0], 2.0, [100.0, -40.0, 3.0])],
                triangles: Vec::new(),
            };
            let world = |p: Vec3| o.world_from_object[0].transform_point3(p);
            let half = size_m.map(|v| 0.5 * v);
            let centre = depth_inside(&o, 0, world(Vec3::ZERO));
            assert!(
                (centre - half.iter().cloned().fold(f64::INFINITY, f64::min)).abs() < 1e-9,
                "{kind:?}"
            );
            for p in [
                Vec3::new(half[0] + 1e-6, 0.0, 0.0),
                Vec3::new(0.0, 0.0, -half[2] - 1e-6),
                Vec3::new(0.0, half[1], 0.0),
            ] {
                assert!(depth_inside(&o, 0, world(p)) < 1e-6, "{kind:?} {p}");
            }
            let corner = Vec3::new(0.95 * half[0], 0.95 * half[1], 0.0);
            let d = depth_inside(&o, 0, world(corner));
            match kind.shape() {
                ObjectShape::Cylinder => assert_eq!(d, 0.0, "{kind:?}"),
            }
        }
    }
}
