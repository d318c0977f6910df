//! Bending to pick something up from the floor: in front of where a walk ended, or over one
//! of the scene's small things walked to ([`ActivityWorld::pick_up_thing`]: the clip placed so
//! that the palm's lowest reach lands over its top).

use glam::DVec2;
use rand_chacha::ChaCha8Rng;

use super::refusal::{Doing, Refusal};
use super::world::{pelvis_and_heading, record, rounded_hold};
use super::{Activity, ActivityWorld, LookAt, Performance, Phase};
use crate::body::hand_landmarks::palm_centre;
use crate::body::{joint, BodyParams, PoseError};
use crate::motion::activity_clip::{idle_frames, max_joint_speed, ClipId, Idle};
use crate::motion::cvae::BodyContext;
use crate::scene::WalkableMap;

/// Where the pick-up clip brings a body's lowest palm (the palm of the hand whose wrist comes
/// lowest, where it does), from the clip's first pelvis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Reach {
    /// Ahead of the first pelvis (x) and to its left (y), in the frame of its first facing (m).
    pub offset: DVec2,
    /// How high over the floor (m).
    pub palm_over_floor_m: f64,
}

impl ActivityWorld {
    /// Bending to pick something up from the floor in front of where `last` stands.
    pub(crate) fn pick_up(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, Refusal> {
        let (played, pelvis) = self.where_standing(body, last, ClipId::PickUp64_28, floor_z)?;
        let spot = lowest_reach(body, &played, floor_z)?;
        self.bend(body, map, last, (played, pelvis), spot, floor_z, None, rng)
    }

    /// Where the pick-up clip brings `body`'s lowest palm.
    pub(crate) fn reach(&self, body: &BodyContext) -> Result<Reach, Refusal> {
        let frames = self.clip_placed(body, ClipId::PickUp64_28, (DVec2::ZERO, 0.0), 0.0)?;
        let (pelvis, _) = pelvis_and_heading(body, &frames[0])?;
        let palm = lowest_palm(body, &frames)?;
        Ok(Reach {
            offset: DVec2::new(palm.x, palm.y) - pelvis,
            palm_over_floor_m: palm.z,
        })
    }

    /// Bending to pick up scene thing `k` from where `last` stands near it: the clip turned
    /// and moved so that the palm's lowest reach lands over the middle of its top (the body
    /// may enter the thing itself while reaching for it).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn pick_up_thing(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        k: usize,
        reach: &Reach,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, Refusal> {
        let top = self.things[k].top_centre();
        let (from, _) = pelvis_and_heading(body, last)?;
        let c = top.truncate();
        let toward = (c - from).try_normalize().unwrap_or(DVec2::X);
        let facing = toward.to_angle() - reach.offset.to_angle();
        let pelvis = c - toward * reach.offset.length();
        let played = self.clip_placed(body, ClipId::PickUp64_28, (pelvis, facing), floor_z)?;
        let (first, _) = pelvis_and_heading(body, &played[0])?;
        self.bend(
            body,
            map,
            last,
            (played, first),
            top.to_array(),
            floor_z,
            Some(k),
            rng,
        )
    }

    /// The pick-up of `played` (the clip placed, its first pelvis) after `last`, looking at
    /// `spot`; of scene thing `thing` where one is taken.
    #[allow(clippy::too_many_arguments)]
    fn bend(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        (played, pelvis): (Vec<BodyParams>, DVec2),
        spot: [f64; 3],
        floor_z: f64,
        thing: Option<usize>,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, Refusal> {
        let clip_speed = max_joint_speed(&played);
        let (into, turn) = self.transition(body, last, &played[0])?;
        let end = played[played.len() - 1].clone();
        let pad = rounded_hold(into.len() + played.len(), 0.0, 0);
        let mut frames = into;
        let n_in = frames.len();
        frames.extend(played);
        frames.extend(idle_frames(&end, pad, Idle::SEATED, rng));
        let phases = vec![
            (Phase::Transition, n_in),
            (Phase::Hold, frames.len() - n_in),
        ];
        let name = thing.map(|k| self.things[k].name.clone());
        let doing = match &name {
            Some(n) => Doing::Taking(n.clone()),
            None => Doing::BendingThere,
        };
        self.fits_here(
            body,
            map,
            &frames,
            &phases,
            2,
            (floor_z, name.as_deref()),
            doing,
        )?;
        let mut r = record(Activity::PickUp, pelvis, turn);
        r.clip = Some(ClipId::PickUp64_28.name().into());
        r.clip_joint_speed_rad_s = Some(clip_speed);
        r.object = name;
        r.look_at = Some(LookAt {
            point: spot,
            start_frame: 0,
            end_frame: frames.len(),
        });
        Ok(Performance {
            activity: Activity::PickUp,
            record: r,
            frames,
            phases,
            seat: None,
            moved: None,
        })
    }
}

/// The spot on the floor below the hands where they reach lowest in `frames`.
fn lowest_reach(
    body: &BodyContext,
    frames: &[BodyParams],
    floor_z: f64,
) -> Result<[f64; 3], PoseError> {
    let mut best = [0.0, 0.0, f64::INFINITY];
    for f in frames {
        let s = body.shaped.skeleton(&f.pose, f.transl)?;
        let mid = (s.joints[joint::LEFT_WRIST] + s.joints[joint::RIGHT_WRIST]) * 0.5;
        if mid.z < best[2] {
            best = [mid.x, mid.y, mid.z];
        }
    }
    Ok([best[0], best[1], floor_z])
}

/// The palm's centre of the hand whose wrist comes lowest in `frames`, where it does (the
/// grasp a pick-up's object is taken at: `synth::held_object::grasp_in`).
fn lowest_palm(body: &BodyContext, frames: &[BodyParams]) -> Result<crate::math::Vec3, PoseError> {
    let mut best: Option<(f64, usize, usize)> = None;
    for (f, frame) in frames.iter().enumerate() {
        let s = body.shaped.skeleton(&frame.pose, frame.transl)?;
        for (h, j) in [joint::LEFT_WRIST, joint::RIGHT_WRIST]
            .into_iter()
            .enumerate()
        {
            let z = s.joints[j].z;
            if best.is_none_or(|b| z < b.0) {
                best = Some((z, f, h));
            }
        }
    }
    let (_, f, h) = best.unwrap_or((0.0, 0, 0));
    let s = body.shaped.skeleton(&frames[f].pose, frames[f].transl)?;
    Ok(palm_centre(&s, h))
}
