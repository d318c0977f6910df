//! One person of a crowd: its plan, body, controller and walker, stepping one primitive a
//! round ([`Agent::choose`], [`Agent::take`]) and moving on from goal to goal; what it does
//! between walks is in `acting`.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::Rng;

use super::goals::sample_goal;
use super::track::{finish_motion, foot_points, AgentState, AgentTrack, GoalRecord};
use super::{
    AgentPlan, CrowdError, CrowdParts, CrowdSettings, CrowdWorld, NEW_FRAMES, STUCK_STEP_M,
};
use crate::body::joint;
use crate::motion::activity_clip::max_joint_speed;
use crate::motion::cvae::contact::contact_score;
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::tensor_body::RigGeometry;
use crate::motion::cvae::{BodyContext, DecodedPrimitive};
use crate::motion::hands::HandStyle;
use crate::motion::primitive::{PRIMITIVE_FRAMES, SEED_FRAMES};
use crate::scene::small_object::SceneThing;
use crate::scene::Obstacle2;
use crate::sensing::Sensor;
use crate::synth::activity::{
    Activity, ActivitySegment, ActivityWorld, Performance, Phase, Refusal, SkippedActivity,
};
use crate::walker::controller::{walker_rng, Controller, Sight};
use crate::walker::reward::{Judged, Limits, RewardWeights};
use crate::walker::state::{place_seed, SeedView, Surroundings, Walker};
use crate::walker::step::{walk_step, Judge, SceneCheck, StepContext};
use crate::walker::WalkerSettings;

/// What a person walks to: a seat to sit on, or a scene thing to pick up (indices into the
/// activity world's `seats` and `things`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Booked {
    Seat(usize),
    Thing(usize),
}

impl Booked {
    /// The activity the walk to it is the approach of.
    pub(super) fn activity(self) -> Activity {
        match self {
            Booked::Seat(_) => Activity::Sit,
            Booked::Thing(_) => Activity::PickUp,
        }
    }
}

pub(super) struct Agent<'m> {
    pub(super) plan: AgentPlan,
    /// What proposes its primitives (built from `plan.steering`).
    pub(super) controller: Box<dyn Controller + 'm>,
    pub(super) body: BodyContext<'m>,
    pub(super) foot_markers: Vec<usize>,
    pub(super) standing_head_m: f64,
    pub(super) walker: Walker,
    pub(super) goal: DVec2,
    pub(super) goal_steps: usize,
    pub(super) next_goal: usize,
    pub(super) rng: ChaCha8Rng,
    pub(super) track: AgentTrack,
    /// The activity being played and how many of its frames are taken.
    pub(super) acting: Option<(Performance, usize)>,
    /// The seat or scene thing being walked to (to sit on, or pick up, when reached) and
    /// the frame the walk began.
    pub(super) approaching: Option<(Booked, usize)>,
    /// The scene things it walked to and bent to take, in the order it did.
    pub(super) things: Vec<SceneThing>,
    /// Seats it walked to and did not reach: not tried again in this take.
    pub(super) unreached_seats: Vec<usize>,
    /// The seat being walked to is the sit's second: the first was not reached.
    pub(super) approach_retried: bool,
    /// Draws what comes after each walk: a stream of its own, so walking draws as without
    /// activities.
    pub(super) activity_rng: ChaCha8Rng,
    /// This person's hands (`motion::hands`), drawn from a stream of their own.
    pub(super) hands: HandStyle,
    /// Draws what its pick-ups take (`synth::held_object`): a stream of its own.
    pub(super) objects_rng: ChaCha8Rng,
}

impl<'m> Agent<'m> {
    /// `neutral`: the mocap seeds' body (zero betas), shared by all agents.
    pub(super) fn new(
        parts: &CrowdParts<'m>,
        neutral: &BodyContext,
        world: &CrowdWorld,
        plan: &AgentPlan,
        index: usize,
        settings: &CrowdSettings,
    ) -> Result<Self, CrowdError> {
        let err = |message: String| CrowdError::Agent {
            agent: plan.name.clone(),
            message,
        };
        if parts.bank.seeds.is_empty() {
            return Err(err("the seed bank is empty".into()));
        }
        let controller = plan
            .steering
            .build(parts.policy.map(|p| p as &dyn crate::walker::Policy))
            .ok_or_else(|| err("steered by the policy, but no policy was loaded".into()))?;
        let body = BodyContext::new(parts.body_model, &plan.betas)
            .map_err(|e| err(format!("betas: {e}")))?;
        let foot_markers = RigGeometry::new(body.model, &body.betas)
            .map_err(|e| err(format!("body: {e}")))?
            .foot_markers;
        let mut rng = walker_rng(settings.seed, index);
        let mut goals = plan.goals.iter().copied();
        let goal = match goals.next() {
            Some(g) => g,
            None => sample_goal(
                &world.map,
                world.region.as_deref(),
                plan.start,
                settings.wander_distance_m,
                settings.clearance_m,
                &mut rng,
            )
            .ok_or_else(|| {
                err(format!(
                    "no goal given and none could be drawn around the start: no walkable cell \
                     {}–{} m away (`[motion] wander_distance_m`) with {} m of free space \
                     (`clearance_m`) on the start's floor; shorten the distances or give goals",
                    settings.wander_distance_m.0,
                    settings.wander_distance_m.1,
                    settings.clearance_m
                ))
            })?,
        };
        let (frames, floor) =
            &parts.bank.seeds[(rng.next_u64() % parts.bank.seeds.len() as u64) as usize];
        let to_goal = goal - plan.start;
        let facing = plan
            .facing_rad
            .unwrap_or_else(|| to_goal.y.atan2(to_goal.x));
        let rest_pelvis = body.shaped.rest_joints[joint::PELVIS];
        let map = &*world.map;
        let mut seed = place_seed(
            frames,
            *floor,
            plan.start,
            facing,
            map.floor_z_m,
            rest_pelvis,
        );
        // The bank's floor is the mocap body's; a body of another shape stands its lowest foot
        // marker at the same height over the floor.
        let lowest = |b: &BodyContext, s: &crate::motion::cvae::PrimitiveSeed| {
            s.frames
                .iter()
                .map(|f| {
                    b.shaped
                        .marker_frame(&f.pose, f.transl, &b.marker_ids)
                        .map(|m| m.markers.iter().map(|v| v.z).fold(f64::INFINITY, f64::min))
                })
                .try_fold(f64::INFINITY, |acc, z| z.map(|z| acc.min(z)))
        };
        let neutral_seed = place_seed(
            frames,
            *floor,
            plan.start,
            facing,
            map.floor_z_m,
            neutral.shaped.rest_joints[joint::PELVIS],
        );
        let dz = lowest(neutral, &neutral_seed).map_err(DecodeError::from)?
            - lowest(&body, &seed).map_err(DecodeError::from)?;
        for f in &mut seed.frames {
            f.transl.z += dz;
        }
        let view = SeedView::new(&body, seed)?;
        let f0 = &view.seed.frames[0];
        let standing_head_m = body
            .shaped
            .skeleton(&f0.pose, f0.transl)
            .map_err(DecodeError::from)?
            .joints[joint::HEAD]
            .z
            - map.floor_z_m;
        let walker = Walker::new(view.clone(), goal);
        let mut track = AgentTrack {
            world_from_cpf: view.world_from_cpf.to_vec(),
            markers: view.markers.to_vec(),
            pelvis_xy: vec![view.pelvis; SEED_FRAMES],
            ..AgentTrack::new(
                &plan.name,
                plan.betas.clone(),
                plan.steering,
                AgentState::Walking,
                view.seed.frames.to_vec(),
            )
        };
        track
            .frames
            .iter_mut()
            .for_each(|f| f.betas = plan.betas.clone());
        Ok(Self {
            plan: plan.clone(),
            controller,
            body,
            foot_markers,
            standing_head_m,
            walker,
            goal,
            goal_steps: 0,
            next_goal: 1,
            rng,
            track,
            acting: None,
            approaching: None,
            things: Vec::new(),
            unreached_seats: Vec::new(),
            approach_retried: false,
            activity_rng: walker_rng(settings.seed ^ 0xAC71_7117, index),
            hands: HandStyle::draw(&mut walker_rng(settings.seed ^ 0x4A4D_5EED, index)),
            objects_rng: walker_rng(settings.seed ^ 0x0B1E_C75E, index),
        })
    }

    pub(super) fn active(&self) -> bool {
        self.track.state == AgentState::Walking
    }

    pub(super) fn head_height_m(&self, p: &DecodedPrimitive) -> f64 {
        let last = &p.joints[p.joints.len() - 1];
        last[joint::HEAD].z - p.floor_z
    }

    /// Chooses, decodes and judges the next primitive: sensing `around`, judged against
    /// `judged` (the same map, the others as [`WalkerSettings::anticipate_people`] says);
    /// `standing`: the world's obstacles that do not move, which the guide plans round.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn choose(
        &mut self,
        parts: &CrowdParts,
        sensor: &Sensor,
        around: &Surroundings,
        judged: &Surroundings,
        standing: &[Obstacle2],
        t0_s: f64,
        settings: &CrowdSettings,
    ) -> Result<Option<(DecodedPrimitive, Judged, f64)>, CrowdError> {
        let time_left =
            1.0 - self.goal_steps as f64 / settings.walker.max_primitives_per_goal as f64;
        let sight = Sight {
            walker: &self.walker,
            body: &self.body,
            sensor,
            around,
            standing,
            goal: self.goal,
            t0_s,
            time_left: time_left.max(0.0),
            settings: &settings.walker,
            latent_dim: parts.model.latent_dim(),
        };
        let judge = Judge {
            limits: match settings.walker.scene_every_frame {
                true => Limits::swept(settings.walker.success_m),
                false => Limits::eq7(settings.walker.success_m),
            },
            weights: RewardWeights::default(),
            primitives_left: settings
                .walker
                .max_primitives_per_goal
                .saturating_sub(self.goal_steps + 1),
            foot_markers: &self.foot_markers,
            prior: parts.prior,
            scene: SceneCheck::Cells,
            no_progress_through_walls: false,
        };
        let situation = self.walker.situation(judged, self.goal, t0_s);
        let ctx = StepContext {
            model: parts.model,
            body: &self.body,
            seed: &self.walker.view.seed,
            judge: &judge,
            situation: &situation,
            pelvis: self.walker.view.pelvis,
        };
        let chosen = walk_step(
            self.controller.as_mut(),
            &sight,
            &ctx,
            settings.walker.penetration_redraws,
            &mut self.rng,
        )?;
        if chosen.as_ref().is_some_and(|c| c.held) {
            self.track.held_primitives += 1;
        }
        Ok(chosen.map(|c| (c.primitive, c.judged, c.reward)))
    }

    /// Takes the chosen primitive and, when this goal is over, moves on: to what `acts`
    /// draws (where the take asks for activities), else to the next goal.
    pub(super) fn take(
        &mut self,
        p: DecodedPrimitive,
        j: Judged,
        reward: f64,
        world: &CrowdWorld,
        settings: &CrowdSettings,
        acts: Option<&mut ActivityWorld>,
    ) {
        let before = self.walker.view.pelvis;
        self.walker.advance(&p, &j, reward);
        self.goal_steps += 1;
        self.track.primitives += 1;
        // Stuck: hardly moving with the goal still ahead.
        if self.walker.view.pelvis.distance(before) < STUCK_STEP_M
            && j.distance_m >= settings.walker.success_m
        {
            self.track.stuck_primitives += 1;
        }
        let start = self.track.frames.len();
        self.track.primitive_starts.push(start);
        self.track.joins.push(start);
        for k in SEED_FRAMES..p.world.len() {
            let mut f = p.world[k].clone();
            f.betas = self.plan.betas.clone();
            self.track.frames.push(f);
            self.track.world_from_cpf.push(p.world_from_cpf[k]);
            self.track.markers.push(p.markers[k].clone());
            let q = p.joints[k][joint::PELVIS];
            self.track.pelvis_xy.push(DVec2::new(q.x, q.y));
        }
        let frame = self.track.frames.len() - 1;
        if self.head_height_m(&p) < 0.5 * self.standing_head_m {
            self.stop(AgentState::Fell);
            return;
        }
        let reached = j.distance_m < settings.walker.success_m;
        let arrived = settings.arrival_m.map_or(reached, |r| j.distance_m < r);
        if !arrived && self.goal_steps < settings.walker.max_primitives_per_goal {
            return;
        }
        self.track.goals.push(GoalRecord {
            goal: self.goal.to_array(),
            reached,
            primitives: self.goal_steps,
            end_frame: frame,
            final_distance_m: j.distance_m,
        });
        if let Some(acts) = acts {
            if self.after_walk(acts, world) {
                return;
            }
        }
        self.next_goal(world, settings);
    }

    /// Walks on to the next goal given, or drawn when wandering, or stops: no goals left.
    pub(super) fn next_goal(&mut self, world: &CrowdWorld, settings: &CrowdSettings) {
        let next = match self.plan.goals.get(self.next_goal) {
            Some(&g) => Some(g),
            None if self.plan.wander => sample_goal(
                &world.map,
                world.region.as_deref(),
                self.walker.view.pelvis,
                settings.wander_distance_m,
                settings.clearance_m,
                &mut self.rng,
            ),
            None => None,
        };
        self.next_goal += 1;
        match next {
            Some(g) => {
                self.goal = g;
                self.goal_steps = 0;
                self.walker.retarget(g);
            }
            None => self.stop(AgentState::Done),
        }
    }
}

impl Agent<'_> {
    pub(super) fn stop(&mut self, state: AgentState) {
        self.track.state = state;
        self.track.stopped_at_frame = Some(self.track.frames.len());
    }

    /// Holds the last pose until the take has `frames` frames, smooths the joins and steadies
    /// the head ([`finish_motion`]); closes the summary.
    pub(super) fn finish(
        mut self,
        frames: usize,
        settings: &WalkerSettings,
        map: &crate::scene::WalkableMap,
    ) -> Result<AgentTrack, CrowdError> {
        let t = &mut self.track;
        for seg in &mut t.activity_segments {
            seg.end_frame = seg.end_frame.min(frames);
        }
        if let Some((booked, began)) = self.approaching {
            t.activity_segments.push(ActivitySegment {
                activity: booked.activity(),
                phase: Phase::Approach,
                start_frame: began,
                end_frame: frames,
            });
        }
        t.activity_segments
            .retain(|seg| seg.start_frame < seg.end_frame);
        // An activity drawn as the take ended was never played: skipped, not done.
        let (played, unplayed): (Vec<_>, Vec<_>) = std::mem::take(&mut t.activities)
            .into_iter()
            .partition(|r| r.start_frame < frames);
        t.activities = played;
        t.skipped_activities
            .extend(unplayed.into_iter().map(|r| SkippedActivity {
                activity: r.activity,
                frame: r.start_frame.min(frames),
                reason: Refusal::TakeEnded.to_string(),
            }));
        for r in &mut t.activities {
            r.end_frame = r.end_frame.min(frames);
            if let Some(look) = r.look_at.as_mut() {
                look.end_frame = look.end_frame.min(frames);
            }
        }
        if t.frames.len() < frames {
            t.joins.push(t.frames.len());
        }
        while t.frames.len() < frames {
            t.frames.push(t.frames[t.frames.len() - 1].clone());
            t.world_from_cpf
                .push(t.world_from_cpf[t.world_from_cpf.len() - 1]);
            t.markers.push(t.markers[t.markers.len() - 1].clone());
            t.pelvis_xy.push(t.pelvis_xy[t.pelvis_xy.len() - 1]);
        }
        let floor_z = self.walker.view.seed.floor_z;
        finish_motion(
            t,
            &self.body,
            settings,
            &self.hands,
            (floor_z, map),
            &self.things,
            &mut self.objects_rng,
        )?;
        // How each activity moved: foot contact over its frames, the fastest joint turn where
        // it joins the walk.
        for r in &mut t.activities {
            let (a, b) = (r.start_frame, r.end_frame.min(t.frames.len()));
            let feet = foot_points(&t.markers, &self.foot_markers, a..b);
            let scores: Vec<f64> = (0..feet.len().saturating_sub(PRIMITIVE_FRAMES - 1))
                .step_by(NEW_FRAMES)
                .map(|s| contact_score(&feet[s..s + PRIMITIVE_FRAMES], floor_z))
                .collect();
            r.contact = scores.iter().sum::<f64>() / scores.len().max(1) as f64;
            let join = |f: usize| {
                max_joint_speed(&t.frames[f.saturating_sub(4)..(f + 4).min(t.frames.len())])
            };
            r.join_joint_speed_rad_s = join(a).max(join(b));
        }
        let w = &self.walker;
        let n = w.steps.max(1) as f64;
        let walked: Vec<f64> = t
            .primitive_starts
            .iter()
            .filter(|&&s| s + NEW_FRAMES <= t.frames.len())
            .map(|&s| {
                let feet = foot_points(
                    &t.markers,
                    &self.foot_markers,
                    s - SEED_FRAMES..s + NEW_FRAMES,
                );
                contact_score(&feet, floor_z)
            })
            .collect();
        t.contact = walked.iter().sum::<f64>() / walked.len().max(1) as f64;
        t.penetration_share = w.totals.frames_in_obstacle as f64 / w.totals.frames.max(1) as f64;
        t.speed_m_s = w.speed_m_s();
        t.view_cos = w.totals.view_cos / n;
        t.pose_score = w.totals.pose_score / n;
        Ok(self.track)
    }
}
