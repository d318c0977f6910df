//! Where a wearer looks: a plain, seeded model of fixations and saccades, written as MPS eye
//! gaze (`eye_gaze/general_eye_gaze.csv`, `mps.read_eyegaze`). It is a model, not a
//! measurement; each of its parts is a published regularity or a stated choice
//! (docs/ARIA.md, "Eye gaze"):
//!
//! - Targets, chosen at each fixation's start: while the wearer does an activity, what it acts
//!   on (the seat from the walk to it until seated, the spot on the floor picked from while
//!   bending; `synth::activity::LookAt`) with probability 0.7 when within 90° of the head's
//!   forward direction (a choice after Land & Hayhoe, Vision Research 2001: in everyday
//!   tasks the eyes fixate the object about to be acted on, ahead of the hands); else another
//!   person within 5 m and 40° of the head's
//!   forward direction (with probability 0.5; the nearest), the current goal when it is within
//!   4 m and 40° (probability 0.3), else the floor where the wearer's path will be 3–5 m on
//!   (walkers fixate the path ahead, the farther the flatter the ground: Matthis, Yates &
//!   Hayhoe, Current Biology 2018; indoor floors are flat); a wearer who stands looks 3 m
//!   ahead, within ±15°.
//! - Fixation durations log-normal, median 0.28 s, σ(ln) 0.45 (mean 0.31 s, near the 330 ms
//!   mean of scene viewing: Rayner, Psychological Bulletin 1998), at least 0.1 s. During a
//!   fixation the eyes stay on the target as the head moves (a person target is pursued).
//! - Saccades last `21 ms + 2.2 ms/° · amplitude` (the main sequence: Carpenter, Movements of
//!   the Eyes, 1988), with a minimum-jerk profile.
//! - The eyes stay within 30° of straight ahead (a choice inside the ±45–55° oculomotor
//!   range); a target beyond is looked at from the edge of that range.
//! - Depth: along the gaze ray to the first scene surface (`scene::mesh_distance::SceneRays`),
//!   or to the fixated person's eyes if nearer; the target's distance without a scene.
//!
//! Angles are in the device's CPF (x left, y up, z forward): `yaw = atan2(x, z)`,
//! `pitch = atan2(y, z)`, so projectaria-tools' `get_eyegaze_point_at_depth(yaw, pitch, depth)`
//! gives back the fixated point. The CSV is MPS's vergence layout: each eye's yaw towards that
//! point from eyes 63 mm apart, one pitch, the depth; projectaria-tools' reader combines the eyes'
//! yaws back into the yaw. The model has no uncertainty: low = high = the value.

use std::fmt::Write as _;

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use crate::math::pose_spline::PoseSpline;
use crate::math::random::{standard_normal, uniform_in, uniform_open01};
use crate::math::{Affine3, Real, Vec3};
use crate::scene::mesh_distance::SceneRays;
use crate::synth::activity::LookAt;

/// The model's figures (module docs).
const PERSON_RANGE_M: Real = 5.0;
const PERSON_PROBABILITY: Real = 0.5;
const GOAL_RANGE_M: Real = 4.0;
const ACTIVITY_PROBABILITY: Real = 0.7;
const ACTIVITY_ANGLE_DEG: Real = 90.0;
const GOAL_PROBABILITY: Real = 0.3;
const NOTICE_ANGLE_DEG: Real = 40.0;
const LOOK_AHEAD_M: [Real; 2] = [3.0, 5.0];
const FIXATION_MEDIAN_S: Real = 0.28;
const FIXATION_SIGMA_LN: Real = 0.45;
const FIXATION_MIN_S: Real = 0.1;
const SACCADE_BASE_S: Real = 0.021;
const SACCADE_S_PER_DEG: Real = 0.0022;
const EYE_RANGE_DEG: Real = 30.0;
/// Farthest a gaze ray is followed into the scene (m).
const MAX_DEPTH_M: Real = 50.0;

/// A goal an agent walks to, and the frame it stops being the current one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GazeGoal {
    pub xy: [Real; 2],
    pub until_frame: usize,
}

/// What the wearer can look at.
pub(crate) struct GazeWorld<'a> {
    /// The device's CPF through the take (the headset spline).
    pub head: &'a PoseSpline,
    /// The other agents' eyes (`world_from_cpf` per frame, at the take's rate).
    pub others: Vec<&'a [Affine3]>,
    pub frame_rate_hz: Real,
    pub goals: &'a [GazeGoal],
    /// What its activities act on, in frame order (none where people only walk).
    pub looks: &'a [LookAt],
    /// The scene, for depths and the floor; `None`: depths to the targets, the floor 1.6 m
    /// below the eyes at the start.
    pub rays: Option<&'a SceneRays>,
}

/// What a fixation looks at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum GazeTarget {
    /// A fixed point (the floor ahead, a goal, a point in front of a standing wearer).
    Point(Vec3),
    /// Another agent's eyes, followed.
    Person(usize),
}

/// One fixation of the sequence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Fixation {
    pub start_s: Real,
    pub end_s: Real,
    pub target: GazeTarget,
    /// The saccade into it (none for the first): start time and amplitude (rad).
    pub saccade: Option<(Real, Real)>,
}

/// One gaze sample, in the device CPF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GazeSample {
    pub timestamp_us: i64,
    pub yaw_rad: Real,
    pub pitch_rad: Real,
    pub depth_m: Real,
    /// Angle between the gaze and the head's forward direction (rad).
    pub eccentricity_rad: Real,
}

impl GazeWorld<'_> {
    fn other_at(&self, k: usize, t: Real) -> Vec3 {
        let frames = self.others[k];
        let s = (t * self.frame_rate_hz).clamp(0.0, (frames.len() - 1) as Real);
        let i = (s.floor() as usize).min(frames.len().saturating_sub(2));
        let u = s - i as Real;
        let a = frames[i].translation;
        let b = frames[(i + 1).min(frames.len() - 1)].translation;
        a + (b - a) * u
    }

    fn target_at(&self, target: GazeTarget, t: Real) -> Vec3 {
        match target {
            GazeTarget::Point(p) => p,
            GazeTarget::Person(k) => self.other_at(k, t),
        }
    }

    /// The floor below a point (the first scene surface beneath it).
    fn floor_below(&self, p: Vec3, fallback_z: Real) -> Vec3 {
        let z = self
            .rays
            .and_then(|r| r.first_hit(p, Vec3::NEG_Z, 5.0))
            .map_or(fallback_z, |d| p.z - d);
        Vec3::new(p.x, p.y, z)
    }
}

/// A target's direction in the CPF at `head`, and its angle from straight ahead.
fn direction_in_cpf(head: &Affine3, p: Vec3) -> (Vec3, Real) {
    let d = head.matrix3.transpose() * (p - head.translation);
    let d = if d.length() > 1e-9 {
        d.normalize()
    } else {
        Vec3::Z
    };
    (d, d.z.clamp(-1.0, 1.0).acos())
}

/// `d` turned towards straight ahead (CPF z) until it is within the eyes' range.
fn within_eye_range(d: Vec3) -> Vec3 {
    let limit = EYE_RANGE_DEG.to_radians();
    let angle = d.z.clamp(-1.0, 1.0).acos();
    if angle <= limit {
        return d;
    }
    let side = Vec3::new(d.x, d.y, 0.0);
    let side = if side.length() > 1e-12 {
        side.normalize()
    } else {
        Vec3::Y
    };
    side * limit.sin() + Vec3::Z * limit.cos()
}

/// The fixation sequence of a wearer over the take, drawn from `seed`.
pub(crate) fn fixations(world: &GazeWorld, seed: u64) -> Vec<Fixation> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let duration = world.head.duration_s();
    let start_eyes = world.head.sample(0.0).world_from_body.translation;
    let floor_z = world.floor_below(start_eyes, start_eyes.z - 1.6).z;
    let notice = NOTICE_ANGLE_DEG.to_radians();
    let mut out: Vec<Fixation> = Vec::new();
    let mut t = 0.0;
    while t <= duration {
        let head = world.head.sample(t).world_from_body;
        let eyes = head.translation;
        // Another person in view?
        let person = (0..world.others.len())
            .map(|k| (k, world.other_at(k, t)))
            .filter(|(_, p)| (*p - eyes).length() < PERSON_RANGE_M)
            .filter(|(_, p)| direction_in_cpf(&head, *p).1 < notice)
            .min_by(|a, b| (a.1 - eyes).length().total_cmp(&(b.1 - eyes).length()));
        let frame = (t * world.frame_rate_hz) as usize;
        let goal = world
            .goals
            .iter()
            .find(|g| g.until_frame >= frame)
            .map(|g| Vec3::new(g.xy[0], g.xy[1], floor_z))
            .filter(|g| {
                (Vec3::new(g.x, g.y, eyes.z) - eyes).length() < GOAL_RANGE_M
                    && direction_in_cpf(&head, *g).1 < notice
            });
        // Drawn only while an activity's target is in front: takes without one draw as before.
        let on_task = world
            .looks
            .iter()
            .find(|l| (l.start_frame..l.end_frame).contains(&frame))
            .map(|l| Vec3::from_array(l.point))
            .filter(|&p| direction_in_cpf(&head, p).1 < ACTIVITY_ANGLE_DEG.to_radians())
            .filter(|_| uniform_open01(&mut rng) < ACTIVITY_PROBABILITY);
        let roll = uniform_open01(&mut rng);
        let target = match (on_task, person, goal) {
            (Some(point), _, _) => GazeTarget::Point(point),
            (None, Some((k, _)), _) if roll < PERSON_PROBABILITY => GazeTarget::Person(k),
            (None, _, Some(g)) if uniform_open01(&mut rng) < GOAL_PROBABILITY => {
                GazeTarget::Point(g)
            }
            _ => {
                // The floor where the path will be 3–5 m on (within the next 6 s).
                let reach = uniform_in(&mut rng, LOOK_AHEAD_M[0], LOOK_AHEAD_M[1]);
                let flat = |v: Vec3| Vec3::new(v.x, v.y, 0.0);
                let later = (1..=60)
                    .map(|k| (t + 0.1 * k as Real).min(duration))
                    .map(|tk| world.head.sample(tk).world_from_body.translation)
                    .find(|p| (flat(*p) - flat(eyes)).length() >= reach);
                match later {
                    Some(p) => GazeTarget::Point(world.floor_below(p, floor_z)),
                    None => {
                        // Standing (or about to): somewhere 3 m ahead, within ±15°, at eye
                        // height or below.
                        let yaw = uniform_in(&mut rng, -15.0, 15.0).to_radians();
                        let pitch = uniform_in(&mut rng, -15.0, 0.0).to_radians();
                        let d = Vec3::new(
                            yaw.sin() * pitch.cos(),
                            pitch.sin(),
                            yaw.cos() * pitch.cos(),
                        );
                        GazeTarget::Point(head.transform_point3(d * 3.0))
                    }
                }
            }
        };
        let saccade = out.last().map(|prev| {
            let from = within_eye_range(direction_in_cpf(&head, world.target_at(prev.target, t)).0);
            let to = within_eye_range(direction_in_cpf(&head, world.target_at(target, t)).0);
            let amplitude = from.dot(to).clamp(-1.0, 1.0).acos();
            (t, amplitude)
        });
        if let Some((_, amplitude)) = saccade {
            t += SACCADE_BASE_S + SACCADE_S_PER_DEG * amplitude.to_degrees();
        }
        let length = (FIXATION_MEDIAN_S * (FIXATION_SIGMA_LN * standard_normal(&mut rng)).exp())
            .max(FIXATION_MIN_S);
        out.push(Fixation {
            start_s: t,
            end_s: t + length,
            target,
            saccade,
        });
        t += length;
    }
    out
}

/// The gaze at each `k / rate_hz` (whole microseconds) through `fixations`.
pub(crate) fn gaze_samples(
    world: &GazeWorld,
    fixations: &[Fixation],
    rate_hz: Real,
) -> Vec<GazeSample> {
    let times = super::imu::sample_times_ns(rate_hz, world.head.duration_s());
    let mut k = 0;
    times
        .into_iter()
        .map(|ns| {
            let us = (ns + 500) / 1000;
            let t = us as Real * 1e-6;
            while k + 1 < fixations.len()
                && fixations[k + 1]
                    .saccade
                    .map_or(fixations[k + 1].start_s, |s| s.0)
                    <= t
            {
                k += 1;
            }
            let head = world.head.sample(t).world_from_body;
            let fix = &fixations[k];
            let look = |target: GazeTarget| {
                within_eye_range(direction_in_cpf(&head, world.target_at(target, t)).0)
            };
            let mut d = look(fix.target);
            if let Some((start, _)) = fix.saccade {
                if t < fix.start_s && k > 0 {
                    // Mid-saccade: minimum-jerk from the last target to this one.
                    let tau = ((t - start) / (fix.start_s - start).max(1e-9)).clamp(0.0, 1.0);
                    let s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
                    let from = look(fixations[k - 1].target);
                    d = (from * (1.0 - s) + d * s).normalize();
                }
            }
            let world_dir = head.matrix3 * d;
            let target_depth = (world.target_at(fix.target, t) - head.translation).length();
            let scene_depth = world
                .rays
                .and_then(|r| r.first_hit(head.translation, world_dir, MAX_DEPTH_M));
            let depth_m = match (fix.target, scene_depth) {
                (GazeTarget::Person(_), Some(s)) => s.min(target_depth),
                (GazeTarget::Person(_), None) => target_depth,
                (_, Some(s)) => s,
                (_, None) => target_depth,
            };
            GazeSample {
                timestamp_us: us,
                yaw_rad: d.x.atan2(d.z),
                pitch_rad: d.y.atan2(d.z),
                depth_m,
                eccentricity_rad: d.z.clamp(-1.0, 1.0).acos(),
            }
        })
        .collect()
}

/// Half the distance between the eyes (m): the eye origins written in the CSV, left at +x
/// (CPF's x points left), as in Meta's published sample (`tx_left_eye_cpf` 0.0315).
pub(crate) const HALF_IPD_M: Real = 0.0315;

/// The MPS eye-gaze header of the vergence layout (projectaria-tools reads it first, by name).
pub(crate) const EYE_GAZE_HEADER: &str =
    "tracking_timestamp_us,left_yaw_rads_cpf,right_yaw_rads_cpf,pitch_rads_cpf,depth_m,\
left_yaw_low_rads_cpf,right_yaw_low_rads_cpf,pitch_low_rads_cpf,\
left_yaw_high_rads_cpf,right_yaw_high_rads_cpf,pitch_high_rads_cpf,\
tx_left_eye_cpf,ty_left_eye_cpf,tz_left_eye_cpf,tx_right_eye_cpf,ty_right_eye_cpf,tz_right_eye_cpf,\
session_uid";

/// Each eye's yaw towards the fixated point: the point at `depth_m` along (tan yaw, tan pitch,
/// 1), seen from the eyes at x = ±[`HALF_IPD_M`]. The reader's combined yaw, atan of the rays'
/// crossing x/z, is the sample's yaw for any eye distance; `depth_m` is written as it is.
fn eye_yaws(s: &GazeSample) -> (Real, Real) {
    let (tx, ty) = (s.yaw_rad.tan(), s.pitch_rad.tan());
    let z = s.depth_m / (tx * tx + ty * ty + 1.0).sqrt();
    let x = tx * z;
    (((x - HALF_IPD_M) / z).atan(), ((x + HALF_IPD_M) / z).atan())
}

/// The samples as `general_eye_gaze.csv`.
pub(crate) fn eye_gaze_csv(samples: &[GazeSample], session: &str) -> String {
    let mut text = String::with_capacity(samples.len() * 280 + 400);
    text.push_str(EYE_GAZE_HEADER);
    text.push('\n');
    let h = HALF_IPD_M;
    for s in samples {
        let (left, right) = eye_yaws(s);
        let p = s.pitch_rad;
        let _ = writeln!(
            text,
            "{},{left},{right},{p},{},{left},{right},{p},{left},{right},{p},{h},0,0,{},0,0,{session}",
            s.timestamp_us, s.depth_m, -h,
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// projectaria-tools' `computeDepthAndCombinedGazeDirection` (EyeGazeFormat.h): the crossing
    /// of the eyes' rays from x = ±half_ipd, its distance and combined yaw.
    fn reader_combines(left: Real, right: Real, pitch: Real, half_ipd: Real) -> (Real, Real) {
        let (tl, tr) = (left.tan(), right.tan());
        let x = half_ipd * (tl + tr) / (tr - tl);
        let z = 2.0 * half_ipd / (tr - tl);
        let y = z * pitch.tan();
        ((x * x + y * y + z * z).sqrt(), (x / z).atan())
    }

    #[test]
    fn the_eyes_yaws_combine_back_into_the_gaze_at_its_depth() {
        for (yaw_deg, pitch_deg, depth_m) in [
            (0.0, 0.0, 1.0),
            (29.9, -29.9, 0.12),
            (-20.0, 10.0, 19.5),
            (5.0, -25.0, 2.5),
            (-29.9, 29.9, 60.0),
        ] {
            let s = GazeSample {
                timestamp_us: 0,
                yaw_rad: (yaw_deg as Real).to_radians(),
                pitch_rad: (pitch_deg as Real).to_radians(),
                depth_m,
                eccentricity_rad: 0.0,
            };
            let (left, right) = eye_yaws(&s);
            assert!(
                left < right,
                "the left eye (+x) turns further right: {left} {right}"
            );
            let (depth, yaw) = reader_combines(left, right, s.pitch_rad, HALF_IPD_M);
            assert!(
                (yaw - s.yaw_rad).abs() < 1e-9 * depth_m.max(1.0),
                "{yaw} {}",
                s.yaw_rad
            );
            assert!(
                (depth - depth_m).abs() < 1e-9 * depth_m,
                "{depth} {depth_m}"
            );
            // Another eye distance in the reader: the yaw is the same.
            let (_, yaw) = reader_combines(left, right, s.pitch_rad, 0.032);
            assert!((yaw - s.yaw_rad).abs() < 1e-9 * depth_m.max(1.0));
        }
        let row = eye_gaze_csv(
            &[GazeSample {
                timestamp_us: 33_333,
                yaw_rad: 0.1,
                pitch_rad: -0.2,
                depth_m: 1.5,
                eccentricity_rad: 0.2,
            }],
            "agent_0",
        );
        let lines: Vec<&str> = row.lines().collect();
        assert_eq!(lines.len(), 2);
        let header: Vec<&str> = lines[0].split(',').collect();
        let values: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(header.len(), 18);
        assert_eq!(values.len(), 18);
        let at = |name: &str| values[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!(at("tracking_timestamp_us"), "33333");
        assert_eq!(at("depth_m"), "1.5");
        assert_eq!(at("pitch_rads_cpf"), "-0.2");
        assert_eq!(at("tx_left_eye_cpf"), "0.0315");
        assert_eq!(at("tx_right_eye_cpf"), "-0.0315");
        assert_eq!(at("session_uid"), "agent_0");
    }
}
