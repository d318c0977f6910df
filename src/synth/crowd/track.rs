//! What a person of a crowd did: every frame of its body, its goals and how it ended
//! ([`AgentTrack`]), and its motion finished as written (joins smoothed, head steadied, what its
//! pick-ups take carried in its hands, the fingers moved with what the hands do).

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::CrowdError;
use crate::body::hand_landmarks::{hand_landmarks, HandTips};
use crate::body::{joint, BodyParams};
use crate::math::{Affine3, Vec3};
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::BodyContext;
use crate::motion::hands::{move_fingers, HandAxes, HandDoing, HandStyle};
use crate::motion::head_stabilise::{stabilise_head, HeadStabiliser};
use crate::motion::joins::{smooth_joins, JoinWindow};
use crate::motion::primitive::PRIMITIVE_RATE_HZ;
use crate::scene::small_object::SceneThing;
use crate::scene::WalkableMap;
use crate::synth::activity::{
    Activity, ActivityRecord, ActivitySegment, ObjectMove, Phase, SkippedActivity,
};
use crate::synth::held_object::{
    fit_under_fingertips, grasp_in, placed_object, taken_thing, Grasp, HeldObject,
};
use crate::walker::reward::path_leaves_floor;
use crate::walker::{ControllerSpec, WalkerSettings};

/// Why an agent stopped before the take ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AgentState {
    /// Still walking when the take ended.
    Walking,
    /// No goals left (all reached or missed).
    Done,
    /// The head came below half the standing head height.
    Fell,
    /// The decoder produced a non-finite primitive.
    DecoderFailure,
}

/// One goal an agent walked to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GoalRecord {
    pub goal: [f64; 2],
    pub reached: bool,
    /// Primitives spent on it.
    pub primitives: usize,
    /// Frame at which it was reached or given up.
    pub end_frame: usize,
    pub final_distance_m: f64,
}

/// What an agent did: every frame of its body at 40 Hz, eye frames and markers, goals.
#[derive(Debug, Clone, Serialize)]
pub struct AgentTrack {
    pub name: String,
    pub betas: Vec<f64>,
    pub steering: ControllerSpec,
    #[serde(skip)]
    pub frames: Vec<BodyParams>,
    #[serde(skip)]
    pub world_from_cpf: Vec<Affine3>,
    #[serde(skip)]
    pub markers: Vec<Vec<Vec3>>,
    /// Horizontal pelvis position per frame.
    #[serde(skip)]
    pub pelvis_xy: Vec<DVec2>,
    /// First frame of each primitive walked (its 18 new frames follow its two seed frames).
    #[serde(skip)]
    pub primitive_starts: Vec<usize>,
    /// Frames where what the body does hands over to what comes next: each primitive's
    /// first frame, an activity's, the held pose's after a stop ([`crate::motion::joins`]).
    #[serde(skip)]
    pub joins: Vec<usize>,
    pub goals: Vec<GoalRecord>,
    pub state: AgentState,
    /// First frame of the held pose, when the agent stopped before the take ended.
    pub stopped_at_frame: Option<usize>,
    /// Primitives taken.
    pub primitives: usize,
    /// Primitives in which the pelvis moved less than [`super::STUCK_STEP_M`] with the goal not
    /// reached: time spent stuck.
    pub stuck_primitives: usize,
    /// Mean foot contact (3-D, Eq. 12) over the primitives walked, as written (joins
    /// smoothed, head steadied).
    pub contact: f64,
    /// Share of new frames with a body marker inside a static obstacle, a moving obstacle or
    /// another agent's 2D box.
    pub penetration_share: f64,
    /// Frames of the take whose pelvis path from the frame before passes over a cell of the
    /// walkable map that is not walkable (a wall, furniture, a closed doorway), measured on
    /// the track as written ([`crate::walker::reward::path_leaves_floor`]); frames sitting
    /// down, seated or standing up (over the seat) not counted.
    pub pelvis_off_floor_frames: usize,
    /// Those frames, in order (absent where there are none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pelvis_off_floor_at: Vec<usize>,
    /// Primitives in which the body held its pose because every draw would have taken its
    /// pelvis over a wall ([`WalkerSettings::scene_every_frame`]).
    pub held_primitives: usize,
    /// Horizontal walking speed over the primitives taken (m/s).
    pub speed_m_s: f64,
    /// Mean cos(angle) between the viewing direction and the direction to the goal at the
    /// primitives' ends.
    pub view_cos: f64,
    /// Mean pose-prior score (−ln p / 63) over the primitives.
    pub pose_score: f64,
    /// Activities done besides walking ([`crate::synth::activity`]), in order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub activities: Vec<ActivityRecord>,
    /// Which frames each activity's phases span (frames in none: walking).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub activity_segments: Vec<ActivitySegment>,
    /// Activities drawn but not done, with why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub skipped_activities: Vec<SkippedActivity>,
    /// What its pick-ups took and carry to the take's end, with a pose per frame.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub held_objects: Vec<HeldObject>,
    /// Scene objects it moved (chairs pulled out from their tables to sit on), in order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(crate) moved_objects: Vec<ObjectMove>,
}

impl AgentTrack {
    /// A person's track before anything is walked or done: `frames`, its first poses, in
    /// `state`.
    pub(crate) fn new(
        name: &str,
        betas: Vec<f64>,
        steering: ControllerSpec,
        state: AgentState,
        frames: Vec<BodyParams>,
    ) -> Self {
        AgentTrack {
            name: name.into(),
            betas,
            steering,
            frames,
            world_from_cpf: Vec::new(),
            markers: Vec::new(),
            pelvis_xy: Vec::new(),
            primitive_starts: Vec::new(),
            joins: Vec::new(),
            goals: Vec::new(),
            state,
            stopped_at_frame: None,
            primitives: 0,
            stuck_primitives: 0,
            contact: 0.0,
            penetration_share: 0.0,
            pelvis_off_floor_frames: 0,
            pelvis_off_floor_at: Vec::new(),
            held_primitives: 0,
            speed_m_s: 0.0,
            view_cos: 0.0,
            pose_score: 0.0,
            activities: Vec::new(),
            activity_segments: Vec::new(),
            skipped_activities: Vec::new(),
            held_objects: Vec::new(),
            moved_objects: Vec::new(),
        }
    }

    /// Lifts a track walked on the flat floor at the map's `floor_z_m` onto its stepped
    /// floors ([`crate::scene::WalkableSettings::floor_steps_m`]), rigidly, frame by frame:
    /// at least to the floor under the pelvis ([`WalkableMap::floor_under`]), and high
    /// enough that no marker stands lower under the floor of its own cell than it stood under
    /// the flat floor (a foot over a step up lifts the body onto it); that lift is the
    /// largest within ±[`FLOOR_FOLLOW_FRAMES`] of each frame, averaged over as many, so the
    /// body rises or sinks over 0.2 s and never puts a foot into a step. The motion model
    /// walks a flat floor, so the body is lifted onto a step up to 0.1 s before its foot
    /// lands there, and the other foot lifts off the floor below. Nothing changes on a flat
    /// floor.
    pub(crate) fn follow_floor(&mut self, map: &WalkableMap) {
        if map.is_flat() || self.frames.is_empty() {
            return;
        }
        let z0 = map.floor_z_m;
        let need: Vec<f64> = (0..self.frames.len())
            .map(|f| {
                self.markers[f]
                    .iter()
                    .filter_map(|m| {
                        let under = map.cell_floor_at(DVec2::new(m.x, m.y))?;
                        Some(under - z0 - (m.z - z0).max(0.0))
                    })
                    .fold(map.floor_under(self.pelvis_xy[f]) - z0, f64::max)
            })
            .collect();
        let last = need.len() - 1;
        let window = |f: usize| {
            (
                f.saturating_sub(FLOOR_FOLLOW_FRAMES),
                (f + FLOOR_FOLLOW_FRAMES).min(last),
            )
        };
        let most: Vec<f64> = (0..need.len())
            .map(|f| {
                let (a, b) = window(f);
                need[a..=b]
                    .iter()
                    .copied()
                    .fold(f64::NEG_INFINITY, f64::max)
            })
            .collect();
        let lift: Vec<f64> = (0..self.frames.len())
            .map(|f| {
                let (a, b) = window(f);
                most[a..=b].iter().sum::<f64>() / (b - a + 1) as f64
            })
            .collect();
        for (f, &dz) in lift.iter().enumerate() {
            self.frames[f].transl.z += dz;
            self.world_from_cpf[f].translation.z += dz;
            for m in &mut self.markers[f] {
                m.z += dz;
            }
        }
        // A held object rises with the hand; before its grasp it stands where the hand finds
        // it, lifted as the body is there.
        for o in &mut self.held_objects {
            for (f, pose) in o.world_from_object.iter_mut().enumerate() {
                pose.translation.z += lift[f.max(o.grasp_frame).min(lift.len() - 1)];
            }
        }
    }

    /// The agent's frames as a motion sequence (neutral gender; the body model's).
    pub(crate) fn motion_sequence(&self, frame_rate_hz: f64) -> crate::motion::MotionSequence {
        crate::motion::MotionSequence {
            frame_rate_hz,
            betas: self.betas.clone(),
            gender: "neutral".into(),
            poses: self.frames.iter().map(|f| f.pose).collect(),
            trans: self.frames.iter().map(|f| f.transl).collect(),
        }
    }
}

/// The foot markers' positions over `frames`, as the foot-contact score reads them.
pub(super) fn foot_points(
    markers: &[Vec<Vec3>],
    foot_markers: &[usize],
    frames: std::ops::Range<usize>,
) -> Vec<Vec<[f64; 3]>> {
    frames
        .map(|f| {
            foot_markers
                .iter()
                .map(|&k| markers[f][k].to_array())
                .collect()
        })
        .collect()
}

/// The frames with each join's velocity jump spread ([`smooth_joins`]), but for the joins
/// where the spreading would take the pelvis path over a cell of `map` that is not walkable
/// where the frames as drawn did not (the primitives were drawn to keep it on the floor; a
/// spread shifts it by centimetres, now and then over a wall's or a piece's edge): each frame
/// the smoothing takes off the floor leaves the join nearest to it unsmoothed, until none does.
/// The pelvis joint moves with the translation, so the smoothed pelvis path is the drawn one
/// shifted by the change of translation.
fn smoothed_on_floor(t: &AgentTrack, map: &WalkableMap) -> Vec<BodyParams> {
    let window = JoinWindow::at_rate(PRIMITIVE_RATE_HZ);
    let n = t.frames.len().min(t.pelvis_xy.len());
    let drawn_leaves: Vec<bool> = (1..n)
        .map(|f| path_leaves_floor(map, t.pelvis_xy[f - 1], t.pelvis_xy[f]))
        .collect();
    let mut joins = t.joins.clone();
    loop {
        let mut frames = t.frames.clone();
        smooth_joins(&mut frames, &joins, &window);
        let at = |f: usize| {
            let d = frames[f].transl - t.frames[f].transl;
            t.pelvis_xy[f] + DVec2::new(d.x, d.y)
        };
        let off: Vec<usize> = (1..n)
            .filter(|&f| !drawn_leaves[f - 1] && path_leaves_floor(map, at(f - 1), at(f)))
            .collect();
        if off.is_empty() || joins.is_empty() {
            return frames;
        }
        for f in off {
            if let Some(k) = (0..joins.len()).min_by_key(|&k| joins[k].abs_diff(f)) {
                joins.remove(k);
            }
        }
    }
}

/// The motion as written: each join's velocity jump spread ([`WalkerSettings::smooth_joins`]:
/// where that would take the pelvis over a cell of `map` the primitives as drawn kept it off,
/// not at that join, [`smoothed_on_floor`]),
/// the head steadied against the torso's sway ([`WalkerSettings::steady_head`]), the objects
/// its pick-ups take placed (standing on the floor at `floor_z`, kinds and colours drawn from
/// `objects_rng`: [`crate::synth::held_object`]), the fingers moved with what the hands do
/// ([`WalkerSettings::finger_motion`], `hands`: the person's, closing round what they hold);
/// the eye frame, markers and pelvis positions posed again from the frames where any changed
/// them, and the held objects carried with their wrists, each lowered under its hand's
/// fingertips (one that cannot be is left on the floor); a pick-up that bent over one of
/// `things` (the scene's, walked to) takes that, where the palm comes over it.
pub(super) fn finish_motion(
    t: &mut AgentTrack,
    body: &BodyContext,
    settings: &WalkerSettings,
    hands: &HandStyle,
    (floor_z, map): (f64, &WalkableMap),
    things: &[SceneThing],
    objects_rng: &mut ChaCha8Rng,
) -> Result<(), CrowdError> {
    let picks_up = t
        .activity_segments
        .iter()
        .any(|s| s.activity == Activity::PickUp);
    if !settings.smooth_joins && !settings.steady_head && !settings.finger_motion && !picks_up {
        return Ok(());
    }
    if settings.smooth_joins {
        t.frames = smoothed_on_floor(t, map);
    }
    if settings.steady_head {
        stabilise_head(
            &mut t.frames,
            &body.shaped,
            &body.cpf,
            PRIMITIVE_RATE_HZ,
            &HeadStabiliser::default(),
        )
        .map_err(DecodeError::from)?;
    }
    // Each pick-up takes something with a free hand that reaches low enough; it holds it to
    // the take's end.
    let mut holds: Vec<Grasp> = Vec::new();
    for seg in &t.activity_segments {
        if seg.activity != Activity::PickUp || seg.phase != Phase::Hold {
            continue;
        }
        let free = [0, 1].map(|h| holds.iter().all(|g| g.hand.index() != h));
        let Some(g) = grasp_in(seg, &t.frames, body, free).map_err(DecodeError::from)? else {
            continue;
        };
        // A pick-up that bent over a scene thing takes that or nothing.
        let bent_over = t
            .activities
            .iter()
            .find(|r| r.start_frame <= seg.start_frame && seg.start_frame < r.end_frame)
            .and_then(|r| r.object.as_deref())
            .and_then(|name| things.iter().find(|t| t.name == name));
        let taken = match bent_over {
            Some(thing) => taken_thing(thing, &g),
            None => placed_object(&t.name, holds.len(), &g, floor_z, objects_rng),
        };
        if let Some(o) = taken {
            holds.push(g);
            t.held_objects.push(o);
        }
    }
    // The hands close round what they hold, each object lowered under its hand's fingertips;
    // one no height of its kind clears is left on the floor, and the hands posed again
    // without it.
    loop {
        if settings.finger_motion {
            let doing = hands_doing(t, &holds);
            let axes = HandAxes::from_rest(&body.shaped.rest_joints);
            move_fingers(&mut t.frames, &doing, &axes, hands, PRIMITIVE_RATE_HZ);
        }
        let (wrists, fingertips) = pose_again(t, body)?;
        let fits: Vec<bool> = t
            .held_objects
            .iter_mut()
            .map(|o| {
                let tips: Vec<[Vec3; 5]> = fingertips.iter().map(|f| f[o.hand.index()]).collect();
                fit_under_fingertips(o, &tips, &wrists)
            })
            .collect();
        if fits.iter().all(|&f| f) {
            return Ok(());
        }
        for k in (0..fits.len()).rev().filter(|&k| !fits[k]) {
            holds.remove(k);
            t.held_objects.remove(k);
        }
    }
}

/// Poses `t`'s frames again where the finishing passes changed them: the eye frame, markers
/// and pelvis positions; returns each frame's wrists (`[left, right]`) and, where the person
/// holds something, both hands' fingertips (thumb first).
#[allow(clippy::type_complexity)]
fn pose_again(
    t: &mut AgentTrack,
    body: &BodyContext,
) -> Result<(Vec<[Affine3; 2]>, Vec<[[Vec3; 5]; 2]>), CrowdError> {
    let tips = match t.held_objects.is_empty() {
        true => None,
        false => Some(HandTips::of(body.model).map_err(DecodeError::from)?),
    };
    let mut wrists = Vec::with_capacity(t.frames.len());
    let mut fingertips = Vec::new();
    for (f, frame) in t.frames.iter().enumerate() {
        let mf = body
            .shaped
            .marker_frame(&frame.pose, frame.transl, &body.marker_ids)
            .map_err(DecodeError::from)?;
        let q = mf.skeleton.joints[joint::PELVIS];
        t.world_from_cpf[f] = body.cpf.world_from_cpf(&mf.skeleton);
        t.pelvis_xy[f] = DVec2::new(q.x, q.y);
        wrists
            .push([joint::LEFT_WRIST, joint::RIGHT_WRIST].map(|j| mf.skeleton.world_from_joint[j]));
        if let Some(tips) = &tips {
            let hands = hand_landmarks(&body.shaped, &mf.skeleton, &frame.pose, tips);
            fingertips.push(hands.map(|h| [0, 1, 2, 3, 4].map(|k| h.points[k])));
        }
        t.markers[f] = mf.markers;
    }
    Ok((wrists, fingertips))
}

/// How long before the lowest reach of a pick-up the reaching hand opens (s).
const REACH_OPENS_S: f64 = 0.8;

/// What each hand does on each frame of `t` (`[left, right]`): walking outside activities,
/// standing in a stand and after the walk ends, seated from sitting down to standing up; in a
/// pick-up that takes an object (`holds[k]` took `t.held_objects[k]`) the hand that takes it
/// opens before its lowest reach and holds it, shaped to its width, to the take's end.
fn hands_doing(t: &AgentTrack, holds: &[Grasp]) -> Vec<[HandDoing; 2]> {
    let n = t.frames.len();
    let still_from = t.stopped_at_frame.unwrap_or(n);
    let mut doing: Vec<[HandDoing; 2]> = (0..n)
        .map(|f| {
            let one = match ActivitySegment::at(&t.activity_segments, f) {
                (Activity::Sit, Some(Phase::Transition | Phase::Hold)) => HandDoing::Seated,
                (Activity::Stand | Activity::PickUp, Some(_)) => HandDoing::Standing,
                _ if f >= still_from => HandDoing::Standing,
                _ => HandDoing::Walking,
            };
            [one; 2]
        })
        .collect();
    for (g, held) in holds.iter().zip(&t.held_objects) {
        let holding = HandDoing::Holding {
            grip_mm: (held.grip_m() * 1000.0).round().min(u16::MAX as f64) as u16,
        };
        let opens = g
            .frame
            .saturating_sub((REACH_OPENS_S * PRIMITIVE_RATE_HZ) as usize)
            .max(g.from_frame);
        for (f, d) in doing.iter_mut().enumerate().skip(opens) {
            d[g.hand.index()] = if f < g.frame {
                HandDoing::Reaching
            } else {
                holding
            };
        }
    }
    doing
}

/// Frames either side over which [`AgentTrack::follow_floor`] takes the largest lift a frame
/// needs and averages it (0.1 s at 40 Hz).
pub(crate) const FLOOR_FOLLOW_FRAMES: usize = 4;
