//! A person's activities between walks: what comes after a walk (walk on, stand, pick up
//! here, walk to one of the scene's small things and pick it up, or walk to a seat and sit),
//! and an activity's frames taken a round at a time
//! ([`crate::synth::activity`] makes them).

use glam::DVec2;

use super::{CrowdError, CrowdSettings, CrowdWorld, NEW_FRAMES};
use crate::body::joint;
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::PrimitiveSeed;
use crate::synth::activity::{
    Activity, ActivitySegment, ActivityWorld, Performance, Phase, Refusal, SkippedActivity,
};
use crate::synth::held_object::{MAX_PALM_GAP_M, PALM_CLEARANCE_M};
use crate::walker::state::SeedView;

use super::person::{Agent, Booked};

impl Agent<'_> {
    /// After a walk: sits down or picks up if it was the walk to a seat or a thing, else
    /// draws what comes next from `acts`; whether an activity (or the walk to one) began —
    /// `false`: walk on.
    pub(super) fn after_walk(&mut self, acts: &mut ActivityWorld, world: &CrowdWorld) -> bool {
        let frame = self.track.frames.len();
        if let Some((booked, began)) = self.approaching.take() {
            self.track.activity_segments.push(ActivitySegment {
                activity: booked.activity(),
                phase: Phase::Approach,
                start_frame: began,
                end_frame: frame,
            });
            let reached = self.track.goals.last().is_some_and(|g| g.reached);
            match booked {
                Booked::Seat(s) => {
                    if self.arrive_at_seat(acts, world, s, reached) {
                        return true;
                    }
                }
                Booked::Thing(k) => return self.arrive_at_thing(acts, world, k, reached),
            }
        }
        let activity = acts.draw(&mut self.activity_rng);
        let floor_z = self.walker.view.seed.floor_z;
        let last = self.track.frames[frame - 1].clone();
        let done = match activity {
            Activity::Walk => return false,
            Activity::Sit if self.approach_seat(acts, world, frame) => {
                self.approach_retried = false;
                return true;
            }
            Activity::Sit => Err(if acts.seats.is_empty() {
                Refusal::NoSeat
            } else if self.unreached_seats.iter().any(|&s| !acts.taken[s]) {
                Refusal::SeatsUnreached
            } else {
                Refusal::SeatsTaken
            }),
            Activity::PickUp if self.approach_thing(acts, world, frame) => return true,
            here => acts.play_here(
                here,
                &self.body,
                &world.map,
                &last,
                floor_z,
                &mut self.activity_rng,
            ),
        };
        self.performed(activity, frame, done)
    }

    /// Plays `done`, or records why `activity` was skipped at `frame`; whether it is played.
    fn performed(
        &mut self,
        activity: Activity,
        frame: usize,
        done: Result<Performance, Refusal>,
    ) -> bool {
        match done {
            Ok(p) => {
                self.perform(p);
                true
            }
            Err(reason) => {
                self.skip(activity, frame, reason);
                false
            }
        }
    }

    /// At the end of the walk to seat `s` (`reached`: its place was): sits down, or walks to
    /// another free seat once; whether that began.
    fn arrive_at_seat(
        &mut self,
        acts: &mut ActivityWorld,
        world: &CrowdWorld,
        s: usize,
        reached: bool,
    ) -> bool {
        let frame = self.track.frames.len();
        let floor_z = self.walker.view.seed.floor_z;
        let last = self.track.frames[frame - 1].clone();
        let sat = if reached {
            acts.sit(
                &self.body,
                &world.map,
                &last,
                s,
                floor_z,
                &mut self.activity_rng,
            )
        } else {
            self.unreached_seats.push(s);
            acts.taken[s] = false;
            // Another free seat, once: a person who cannot get through to one takes another.
            if !self.approach_retried && self.approach_seat(acts, world, frame) {
                self.approach_retried = true;
                return true;
            }
            Err(Refusal::SeatNotReached {
                seat: acts.seats[s].object_name.clone(),
            })
        };
        if sat.is_err() {
            acts.taken[s] = false;
        }
        self.performed(Activity::Sit, frame, sat)
    }

    /// At the end of the walk to scene thing `k` (`reached`: the place beside it was): bends
    /// to take it; whether that began. One not reached, or not taken, is free again.
    fn arrive_at_thing(
        &mut self,
        acts: &mut ActivityWorld,
        world: &CrowdWorld,
        k: usize,
        reached: bool,
    ) -> bool {
        let frame = self.track.frames.len();
        let floor_z = self.walker.view.seed.floor_z;
        let last = self.track.frames[frame - 1].clone();
        let bent = match reached {
            true => acts.reach(&self.body).and_then(|reach| {
                acts.pick_up_thing(
                    &self.body,
                    &world.map,
                    &last,
                    k,
                    &reach,
                    floor_z,
                    &mut self.activity_rng,
                )
            }),
            false => Err(Refusal::ThingNotReached {
                thing: acts.things[k].name.clone(),
            }),
        };
        match &bent {
            Ok(_) => self.things.push(acts.things[k].clone()),
            Err(_) => acts.thing_taken[k] = false,
        }
        self.performed(Activity::PickUp, frame, bent)
    }

    /// On a person's first pick-up (both hands free), books the free scene thing nearest on
    /// foot whose top lies where this body's palm closes round it
    /// ([`crate::synth::held_object::MAX_PALM_GAP_M`] at most under the palm's lowest reach,
    /// and not in it) and walks to where the palm's reach lands over it from `frame`;
    /// whether there was one.
    fn approach_thing(
        &mut self,
        acts: &mut ActivityWorld,
        world: &CrowdWorld,
        frame: usize,
    ) -> bool {
        let picked_before = self
            .track
            .activities
            .iter()
            .any(|r| r.activity == Activity::PickUp);
        if picked_before || acts.things.is_empty() {
            return false;
        }
        let Ok(reach) = acts.reach(&self.body) else {
            return false;
        };
        let palm = reach.palm_over_floor_m;
        let within = [palm - MAX_PALM_GAP_M, palm - PALM_CLEARANCE_M];
        let floor_z = self.walker.view.seed.floor_z;
        let pelvis = self.walker.view.pelvis;
        let Some((k, stand)) =
            acts.nearest_free_thing(&world.map, pelvis, floor_z, within, reach.offset.length())
        else {
            return false;
        };
        acts.thing_taken[k] = true;
        self.approaching = Some((Booked::Thing(k), frame));
        self.goal = stand;
        self.goal_steps = 0;
        self.walker.retarget(self.goal);
        true
    }

    /// Books the free seat nearest on foot (none walked to before and not reached) and walks
    /// to the place in front of it from `frame`; whether there was one.
    fn approach_seat(
        &mut self,
        acts: &mut ActivityWorld,
        world: &CrowdWorld,
        frame: usize,
    ) -> bool {
        let Some(s) =
            acts.nearest_free_seat(&world.map, self.walker.view.pelvis, &self.unreached_seats)
        else {
            return false;
        };
        acts.taken[s] = true;
        self.approaching = Some((Booked::Seat(s), frame));
        self.goal = acts.seats[s].stand();
        self.goal_steps = 0;
        self.walker.retarget(self.goal);
        true
    }

    pub(super) fn skip(&mut self, activity: Activity, frame: usize, reason: Refusal) {
        self.track.skipped_activities.push(SkippedActivity {
            activity,
            frame,
            reason: reason.to_string(),
        });
    }

    /// Begins playing `p` from the next frame.
    pub(super) fn perform(&mut self, mut p: Performance) {
        let start = self.track.frames.len();
        if let Some(look) = p.record.look_at.as_mut() {
            look.start_frame += start;
            look.end_frame += start;
            // A seat is looked at from the walk to it on.
            if let Some(walk) = self.track.activity_segments.last().filter(|s| {
                p.activity == Activity::Sit && s.phase == Phase::Approach && s.end_frame == start
            }) {
                look.start_frame = walk.start_frame;
            }
        }
        let mut k = start;
        for &(phase, n) in &p.phases {
            self.track.activity_segments.push(ActivitySegment {
                activity: p.activity,
                phase,
                start_frame: k,
                end_frame: k + n,
            });
            k += n;
        }
        p.record.start_frame = start;
        p.record.end_frame = k;
        if let Some(m) = &p.moved {
            self.track.moved_objects.push(m.starting_at(start));
        }
        self.track.activities.push(p.record.clone());
        self.acting = Some((p, 0));
    }

    /// Takes the next [`NEW_FRAMES`] frames of the activity being played; when it ends,
    /// gives its seat back and walks on to the next goal.
    pub(super) fn act(
        &mut self,
        acts: &mut ActivityWorld,
        world: &CrowdWorld,
        settings: &CrowdSettings,
    ) -> Result<(), CrowdError> {
        let Some((p, taken)) = self.acting.as_mut() else {
            return Ok(());
        };
        let end = (*taken + NEW_FRAMES).min(p.frames.len());
        if *taken == 0 {
            self.track.joins.push(self.track.frames.len());
        }
        let frames = p.frames[*taken..end].to_vec();
        *taken = end;
        let over = end == p.frames.len();
        for f in frames {
            let mf = self
                .body
                .shaped
                .marker_frame(&f.pose, f.transl, &self.body.marker_ids)
                .map_err(DecodeError::from)?;
            let q = mf.skeleton.joints[joint::PELVIS];
            self.track
                .world_from_cpf
                .push(self.body.cpf.world_from_cpf(&mf.skeleton));
            self.track.markers.push(mf.markers);
            self.track.pelvis_xy.push(DVec2::new(q.x, q.y));
            self.track.frames.push(f);
        }
        let n = self.track.frames.len();
        let seed = PrimitiveSeed {
            frames: [
                self.track.frames[n - 2].clone(),
                self.track.frames[n - 1].clone(),
            ],
            floor_z: self.walker.view.seed.floor_z,
        };
        self.walker.view = SeedView::new(&self.body, seed)?;
        if over {
            if let Some((p, _)) = self.acting.take() {
                if let Some(s) = p.seat {
                    acts.taken[s] = false;
                }
            }
            // A walk comes between two activities.
            self.next_goal(world, settings);
        }
        Ok(())
    }
}
