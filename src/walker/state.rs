//! One walking body as a controller sees it: the two seed frames of its next primitive (with
//! their markers, eye frames and pelvis), the pelvis–goal distance, and running totals. The
//! same state serves an episode of the training environment and an agent of a crowd; what
//! differs is what surrounds it ([`Surroundings`]) and whose clock moves obstacles.
//!
//! Observation (EgoGen's layout, [`ObsLayout`]): for each of the two seed frames the 67
//! markers in the seed's canonical frame and the unit vectors from each marker to the goal
//! (2 × 67 × 6); the sensing of both seed frames (the paper's 32-ray scan, 2 × 32,
//! −1 + 2·hit/7 m, or another [`crate::sensing::SensingSpec`]); `1/(1 + d)` of the horizontal
//! pelvis–goal distance; the share of the episode's time left. [`ObsLayout`] says where each
//! part lies.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::reward::{Judged, Situation};
use crate::body::{joint, BodyParams, NUM_MARKERS};
use crate::math::{Affine3, Mat3, Vec3};
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::{BodyContext, DecodedPrimitive, PrimitiveSeed};
use crate::motion::primitive::{canonical_frame, PRIMITIVE_FRAMES, PRIMITIVE_RATE_HZ, SEED_FRAMES};
use crate::scene::{MovingObstacle, Obstacle2, SeenMap, WalkableMap};
use crate::sensing::{EgoPose2, EgoSensor, RayScan, SensingWorld, Sensor};

/// The rays a walker remembers what it saw with ([`Walker::look`]): the policy's own ray fan,
/// or the paper's 32 rays where it senses otherwise.
pub(crate) fn memory_scan(sensor: &Sensor) -> RayScan {
    match sensor {
        Sensor::Rays(scan) => scan.clone(),
        _ => RayScan::default(),
    }
}

/// Values per seed frame of the marker state: 67 canonical positions and 67 goal directions.
pub(crate) const STATE_FRAME_DIM: usize = NUM_MARKERS * 6;
/// Where the parts of an observation lie, for sensing that writes `sensing_per_frame` values
/// per seed frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObsLayout {
    pub sensing_per_frame: usize,
}

impl ObsLayout {
    /// The paper's layout: 32 rays per seed frame.
    pub const PAPER: Self = Self {
        sensing_per_frame: 32,
    };

    /// The layout for a policy's sensing.
    pub(crate) fn of(sensing: &crate::sensing::SensingSpec) -> Self {
        Self {
            sensing_per_frame: sensing.dim(),
        }
    }

    /// Observation length.
    pub const fn dim(&self) -> usize {
        SEED_FRAMES * (STATE_FRAME_DIM + self.sensing_per_frame) + 2
    }

    /// Offset of the sensing of the first seed frame (the second follows it).
    pub(crate) const fn sensing_offset(&self) -> usize {
        SEED_FRAMES * STATE_FRAME_DIM
    }

    /// Offset of `1/(1 + d)`; the time left follows it.
    pub(crate) const fn dist_offset(&self) -> usize {
        self.sensing_offset() + SEED_FRAMES * self.sensing_per_frame
    }
}

/// Time (s) of frame `f` of the primitive taken at step `steps` of a clock that starts with
/// frame 0 of the first seed at 0.
pub(crate) fn frame_time_s(steps: usize, f: usize) -> f64 {
    (steps * (PRIMITIVE_FRAMES - SEED_FRAMES) + f) as f64 / PRIMITIVE_RATE_HZ
}

/// Length of one primitive's new motion (s).
pub(crate) const PRIMITIVE_S: f64 = (PRIMITIVE_FRAMES - SEED_FRAMES) as f64 / PRIMITIVE_RATE_HZ;

/// Obstacles as a walker sees them ahead: each standing where it will be when the primitive
/// taken at `t0_s` ends (how the crowd stepping shows the other people, and the training
/// environment with the walker setting [`anticipate_people`]).
///
/// [`anticipate_people`]: super::WalkerSettings::anticipate_people
pub(crate) fn seen_ahead<'a, I: IntoIterator<Item = &'a MovingObstacle>>(
    moving: I,
    t0_s: f64,
) -> impl Iterator<Item = MovingObstacle> + use<'a, I> {
    moving.into_iter().map(move |m| MovingObstacle {
        at_start: m.at(t0_s + PRIMITIVE_S),
        velocity_m_per_s: DVec2::ZERO,
    })
}

/// A canonical mocap seed (facing +y, its floor at `floor` in its frame) placed with its
/// pelvis over `start`, turned to face `facing_rad` (world yaw of the walking direction,
/// from +x), its floor on world height `floor_z`.
pub fn place_seed(
    frames: &[BodyParams; SEED_FRAMES],
    floor: f64,
    start: DVec2,
    facing_rad: f64,
    floor_z: f64,
    rest_pelvis: Vec3,
) -> PrimitiveSeed {
    let world_from_canon = Affine3 {
        matrix3: Mat3::from_rotation_z(facing_rad - std::f64::consts::FRAC_PI_2),
        translation: Vec3::new(start.x, start.y, floor_z - floor),
    };
    PrimitiveSeed {
        frames: std::array::from_fn(|k| frames[k].moved_rigidly(world_from_canon, rest_pelvis)),
        floor_z,
    }
}

/// What surrounds a walker: the floor map, a static obstacle that is not in the map (a box
/// scene's box), and obstacles that move on a clock (other people as 2D boxes).
#[derive(Debug, Clone, Copy)]
pub struct Surroundings<'a> {
    pub map: &'a WalkableMap,
    pub obstacle: Option<&'a Obstacle2>,
    pub moving: &'a [MovingObstacle],
}

/// What the seed frames of the next primitive look like to the observation.
#[derive(Debug, Clone)]
pub struct SeedView {
    pub seed: PrimitiveSeed,
    pub markers: [Vec<Vec3>; SEED_FRAMES],
    pub world_from_cpf: [Affine3; SEED_FRAMES],
    /// Horizontal pelvis position of the first seed frame.
    pub pelvis: DVec2,
}

impl SeedView {
    /// Poses the seed frames of `seed` with `body`.
    pub fn new(body: &BodyContext, seed: PrimitiveSeed) -> Result<Self, DecodeError> {
        let mut markers: [Vec<Vec3>; SEED_FRAMES] = Default::default();
        let mut cpf = [Affine3::IDENTITY; SEED_FRAMES];
        let mut pelvis = DVec2::ZERO;
        for (k, f) in seed.frames.iter().enumerate() {
            let mf = body
                .shaped
                .marker_frame(&f.pose, f.transl, &body.marker_ids)?;
            cpf[k] = body.cpf.world_from_cpf(&mf.skeleton);
            if k == 0 {
                let p = mf.skeleton.joints[joint::PELVIS];
                pelvis = DVec2::new(p.x, p.y);
            }
            markers[k] = mf.markers;
        }
        Ok(Self {
            seed,
            markers,
            world_from_cpf: cpf,
            pelvis,
        })
    }

    /// The seed of the primitive after `p`, from its last frames.
    pub(crate) fn after(p: &DecodedPrimitive) -> Self {
        let n = p.joints.len();
        let p0 = p.joints[n - SEED_FRAMES][joint::PELVIS];
        Self {
            seed: p.next_seed(),
            markers: std::array::from_fn(|k| p.markers[p.markers.len() - SEED_FRAMES + k].clone()),
            world_from_cpf: std::array::from_fn(|k| {
                p.world_from_cpf[p.world_from_cpf.len() - SEED_FRAMES + k]
            }),
            pelvis: DVec2::new(p0.x, p0.y),
        }
    }

    /// The body's 2D box as others see it: [`footprint`] of both seed frames' markers.
    pub(crate) fn footprint(&self) -> Obstacle2 {
        footprint(
            self.markers.iter().flatten(),
            &self.world_from_cpf[SEED_FRAMES - 1],
            self.pelvis,
        )
    }
}

/// A body's 2D box: the bounding box of its markers in its own horizontal frame (x along the
/// hip line, y the facing of the eye frame `world_from_cpf` on the floor) — the box the
/// penetration test of Eq. 7 lays over a body. Without finite markers, a point at `pelvis`.
pub(crate) fn footprint<'a>(
    markers: impl Iterator<Item = &'a Vec3>,
    world_from_cpf: &Affine3,
    pelvis: DVec2,
) -> Obstacle2 {
    let fwd = world_from_cpf.matrix3.z_axis;
    let fwd = DVec2::new(fwd.x, fwd.y).normalize_or(DVec2::Y);
    let x = -fwd.perp();
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for v in markers {
        let d = v.truncate();
        let local = DVec2::new(x.dot(d), x.perp().dot(d));
        lo = lo.min(local);
        hi = hi.max(local);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return Obstacle2::Circle {
            centre: pelvis,
            radius_m: 0.0,
        };
    }
    let c = (lo + hi) * 0.5;
    Obstacle2::Box {
        centre: x * c.x + x.perp() * c.y,
        half_extents: (hi - lo) * 0.5,
        yaw_rad: x.y.atan2(x.x),
    }
}

/// Running totals of a walk, for its summary.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Totals {
    pub reward: f64,
    pub contact: f64,
    pub view_cos: f64,
    /// cos(view, goal direction) at the end of each primitive, in order.
    #[serde(default)]
    pub view_cos_each: Vec<f64>,
    /// The angle between view and travel of each primitive that travelled (rad).
    #[serde(default)]
    pub view_off_travel_rad: Vec<f64>,
    pub frames: usize,
    pub frames_in_obstacle: usize,
    pub path_m: f64,
    /// Sum of the primitives' mean pose-prior scores.
    #[serde(default)]
    pub pose_score: f64,
    /// Sum of the primitives' largest pose embedding norms
    /// ([`super::PosePrior::embedding_norms`]).
    #[serde(default)]
    pub pose_norm_max_sum: f64,
    /// Frames penetrating the scene by paper Eq. 11, and the most body vertices inside it in
    /// a frame (0 where the scene has no 3D SDF).
    #[serde(default)]
    pub scene_penetrating_frames: usize,
    #[serde(default)]
    pub scene_vertices_inside_max: usize,
    /// Frames whose pelvis path passed over a cell that is not walkable
    /// ([`super::reward::Judged::pelvis_off_floor_frames`]).
    #[serde(default)]
    pub pelvis_off_floor_frames: usize,
}

/// A body walking to a goal, one primitive at a time.
#[derive(Debug, Clone)]
pub struct Walker {
    pub view: SeedView,
    /// Primitives taken.
    pub steps: usize,
    /// Horizontal pelvis–goal distance now and at the start (m).
    pub distance_m: f64,
    pub start_distance_m: f64,
    pub totals: Totals,
}

impl Walker {
    /// A walker at its seed, `goal` ahead.
    pub fn new(view: SeedView, goal: DVec2) -> Self {
        let distance_m = view.pelvis.distance(goal);
        Self {
            view,
            steps: 0,
            distance_m,
            start_distance_m: distance_m,
            totals: Totals::default(),
        }
    }

    /// Writes the observation (`sensor`'s [`ObsLayout`]) for a walk to `goal`; `t0_s` is the time
    /// of the first seed frame on the obstacles' clock, `time_left` the share of the walk's
    /// primitives left (EgoGen's `1 − t/T`).
    #[allow(clippy::too_many_arguments)]
    pub fn observe_into(
        &self,
        body: &BodyContext,
        sensor: &Sensor,
        goal: DVec2,
        around: &Surroundings,
        t0_s: f64,
        time_left: f64,
        out: &mut [f32],
    ) {
        let v = &self.view;
        let layout = ObsLayout {
            sensing_per_frame: sensor.dim(),
        };
        debug_assert_eq!(out.len(), layout.dim());
        let goal = Vec3::new(goal.x, goal.y, 0.0);
        // The canonical frame of the seed; with hips vertical (never in a walking seed) the
        // world frame at the pelvis stands in.
        let world_from_canon = body
            .shaped
            .skeleton(&v.seed.frames[0].pose, v.seed.frames[0].transl)
            .ok()
            .and_then(|s| canonical_frame(&s.joints).ok())
            .unwrap_or(Affine3::from_translation(Vec3::new(
                v.pelvis.x, v.pelvis.y, 0.0,
            )));
        let canon_from_world = world_from_canon.inverse();
        for (k, markers) in v.markers.iter().enumerate() {
            let o = &mut out[k * STATE_FRAME_DIM..(k + 1) * STATE_FRAME_DIM];
            for (i, m) in markers.iter().enumerate() {
                let c = canon_from_world.transform_point3(*m);
                let g = goal.with_z(m.z);
                let d = canon_from_world.transform_vector3((g - *m).normalize_or_zero());
                o[3 * i..3 * i + 3].copy_from_slice(&[c.x as f32, c.y as f32, c.z as f32]);
                let j = 3 * NUM_MARKERS + 3 * i;
                o[j..j + 3].copy_from_slice(&[d.x as f32, d.y as f32, d.z as f32]);
            }
        }
        let mut obstacles: Vec<Obstacle2> = Vec::with_capacity(around.moving.len() + 1);
        for (k, cpf) in v.world_from_cpf.iter().enumerate() {
            let t = t0_s + k as f64 / PRIMITIVE_RATE_HZ;
            obstacles.clear();
            obstacles.extend(around.obstacle.copied());
            obstacles.extend(around.moving.iter().map(|m| m.at(t)));
            let world = SensingWorld {
                map: around.map,
                obstacles: &obstacles,
            };
            let at = layout.sensing_offset() + k * layout.sensing_per_frame;
            sensor.observe_into(
                &world,
                EgoPose2::from_world_from_cpf(cpf),
                &mut out[at..at + layout.sensing_per_frame],
            );
        }
        out[layout.dist_offset()] = (1.0 / (1.0 + self.distance_m)) as f32;
        out[layout.dist_offset() + 1] = time_left as f32;
    }

    /// Adds to `seen` what `scan` shows from the eyes of both seed frames of the still scene:
    /// the map and the obstacles that stand (`still`; people who move are left out: the policy
    /// sees them itself).
    pub(crate) fn look(
        &self,
        scan: &RayScan,
        map: &WalkableMap,
        still: &[Obstacle2],
        seen: &mut SeenMap,
    ) {
        let world = SensingWorld {
            map,
            obstacles: still,
        };
        let range = scan.settings.max_range_m;
        for cpf in &self.view.world_from_cpf {
            let pose = EgoPose2::from_world_from_cpf(cpf);
            for (k, t) in scan.distances(&world, pose).into_iter().enumerate() {
                let hit = (t < range).then_some(t);
                seen.record_ray(pose.position, scan.beam_dir(pose, k), hit, range);
            }
        }
    }

    /// Where the walker stands before its next primitive, for [`super::reward::judge`].
    pub fn situation<'a>(
        &self,
        around: &Surroundings<'a>,
        goal: DVec2,
        t0_s: f64,
    ) -> Situation<'a> {
        Situation {
            map: around.map,
            obstacle: around.obstacle,
            moving: around.moving,
            t0_s,
            goal,
            distance_m: self.distance_m,
            goal_field: None,
        }
    }

    /// Takes a judged primitive: totals, distance, and the next seed.
    pub(crate) fn advance(&mut self, p: &DecodedPrimitive, j: &Judged, reward: f64) {
        self.steps += 1;
        self.totals.reward += reward;
        let first = p.joints[SEED_FRAMES - 1][joint::PELVIS];
        let mut prev = DVec2::new(first.x, first.y);
        for f in &p.joints[SEED_FRAMES..] {
            let q = DVec2::new(f[joint::PELVIS].x, f[joint::PELVIS].y);
            self.totals.path_m += q.distance(prev);
            prev = q;
        }
        self.totals.contact += j.contact;
        self.totals.view_cos += j.view_cos;
        self.totals.view_cos_each.push(j.view_cos);
        if !j.view_off_travel_rad.is_nan() {
            self.totals.view_off_travel_rad.push(j.view_off_travel_rad);
        }
        self.totals.pose_score += j.pose_nll;
        self.totals.pose_norm_max_sum += j.pose_norm_max;
        self.totals.frames += p.joints.len() - SEED_FRAMES;
        self.totals.frames_in_obstacle += j.frames_in_obstacle;
        self.totals.scene_penetrating_frames += j.scene_penetrating_frames;
        self.totals.pelvis_off_floor_frames += j.pelvis_off_floor_frames;
        self.totals.scene_vertices_inside_max = self
            .totals
            .scene_vertices_inside_max
            .max(j.scene_vertices_inside_max);
        self.distance_m = j.distance_m;
        self.view = SeedView::after(p);
    }

    /// Counts a step that produced no primitive (the decoder's output was not finite).
    pub(crate) fn fail(&mut self, reward: f64) {
        self.steps += 1;
        self.totals.reward += reward;
    }

    /// Aims the walker at a new goal (the totals go on).
    pub(crate) fn retarget(&mut self, goal: DVec2) {
        self.distance_m = self.view.pelvis.distance(goal);
        self.start_distance_m = self.distance_m;
    }

    /// Horizontal walking speed over the primitives taken (m/s).
    pub(crate) fn speed_m_s(&self) -> f64 {
        self.totals.path_m / (self.totals.frames.max(1) as f64 / PRIMITIVE_RATE_HZ)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_times_follow_the_primitive_clock() {
        assert_eq!(frame_time_s(0, 0), 0.0);
        // Each primitive adds 18 new frames at 40 Hz.
        assert!((frame_time_s(1, 0) - 18.0 / 40.0).abs() < 1e-12);
        assert!((frame_time_s(2, 1) - 37.0 / 40.0).abs() < 1e-12);
    }
}
