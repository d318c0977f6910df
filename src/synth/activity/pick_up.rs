//! Bending to pick something up from the floor in front of where a walk ended.

use rand_chacha::ChaCha8Rng;

use super::refusal::{Doing, Refusal};
use super::world::{record, rounded_hold};
use super::{Activity, ActivityWorld, LookAt, Performance, Phase};
use crate::body::{joint, BodyParams, PoseError};
use crate::motion::activity_clip::{idle_frames, max_joint_speed, ClipId, Idle};
use crate::motion::cvae::BodyContext;
use crate::scene::WalkableMap;

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
        let clip_speed = max_joint_speed(&played);
        let spot = lowest_reach(body, &played, floor_z)?;
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
        self.fits_here(body, map, &frames, &phases, 2, floor_z, Doing::BendingThere)?;
        let mut r = record(Activity::PickUp, pelvis, turn);
        r.clip = Some(ClipId::PickUp64_28.name().into());
        r.clip_joint_speed_rad_s = Some(clip_speed);
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
