//! Standing where a walk ended and looking around for a drawn time.

use rand_chacha::ChaCha8Rng;

use super::refusal::{Doing, Refusal};
use super::world::{record, rounded_hold, IDLE_STRIDE};
use super::{Activity, ActivityWorld, Performance, Phase};
use crate::body::BodyParams;
use crate::math::random::uniform_in;
use crate::motion::activity_clip::{idle_frames, ClipId, Idle};
use crate::motion::cvae::BodyContext;
use crate::scene::WalkableMap;

impl ActivityWorld {
    /// Standing where `last` stands, looking around for a drawn time.
    pub(crate) fn stand(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, Refusal> {
        let (standing, pelvis) = self.where_standing(body, last, ClipId::Sit75_18, floor_z)?;
        let base = standing[0].clone();
        let [lo, hi] = self.settings.stand_s;
        let hold_s = uniform_in(rng, lo, hi);
        let (into, turn) = self.transition(body, last, &base)?;
        let hold = rounded_hold(into.len(), hold_s, 0);
        let mut frames = into;
        frames.extend(idle_frames(&base, hold, Idle::LOOK_AROUND, rng));
        let phases = vec![
            (Phase::Transition, frames.len() - hold),
            (Phase::Hold, hold),
        ];
        self.fits_here(
            body,
            map,
            &frames,
            &phases,
            IDLE_STRIDE,
            (floor_z, None),
            Doing::StandingThere,
        )?;
        Ok(Performance {
            activity: Activity::Stand,
            record: record(Activity::Stand, pelvis, turn),
            frames,
            phases,
            seat: None,
            moved: None,
        })
    }
}
