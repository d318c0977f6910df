//! Sitting down on a seat from where the walk to it ended, staying seated for a drawn time,
//! standing up: a sit clip fitted to the seat — raised to its height, the legs bent by
//! inverse kinematics to keep the feet on the floor or the thighs on the seat, the body
//! resting on the surface (docs/ACTIVITIES.md "How an activity is made").

use glam::DVec2;
use rand_chacha::ChaCha8Rng;

use super::refusal::{Doing, Refusal};
use super::world::{record, rounded_hold, ENTER_TOLERANCE_M, IDLE_STRIDE};
use super::{Activity, ActivityWorld, LookAt, MovedObject, Performance, Phase};
use crate::body::{joint, BodyParams, PoseError};
use crate::math::random::uniform_in;
use crate::math::Vec3;
use crate::motion::activity_clip::{
    blend, idle_frames, keep_ankles, max_joint_speed, placed, sitting_vertices, ClipKind,
    ClipOnBody, Idle,
};
use crate::motion::cvae::BodyContext;
use crate::motion::primitive::PRIMITIVE_RATE_HZ;
use crate::scene::{Seat, WalkableMap};

impl ActivityWorld {
    /// Sitting down on seat `s` from where `last` stands, staying seated for a drawn time,
    /// standing up: the sit clip nearest the seat's height, moved to the seat (its seated
    /// pelvis on the seat's place, facing the seat's way) and fitted to its height.
    /// On a chair pulled out too little for this body ([`pulled_too_little`]), the same on the
    /// chair's longer pull ([`Seat::longer`]) where it has one.
    pub(crate) fn sit(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        s: usize,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, Refusal> {
        let seat = self.seats[s].clone();
        let done = self.sit_on(body, map, last, s, &seat, floor_z, rng);
        match (&done, seat.longer.as_deref()) {
            (Err(r), Some(longer)) if pulled_too_little(r) => {
                self.sit_on(body, map, last, s, longer, floor_z, rng)
            }
            _ => done,
        }
    }

    /// [`Self::sit`] on `seat`, place `s`'s (or its longer pull's).
    #[allow(clippy::too_many_arguments)]
    fn sit_on(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        s: usize,
        seat: &Seat,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, Refusal> {
        let seat_h = seat.surface_z_m - floor_z;
        let clips: Vec<ClipOnBody> = self
            .clips
            .iter()
            .filter(|c| c.kind == ClipKind::Sit)
            .map(|c| c.on_body(body))
            .collect::<Result<_, _>>()?;
        let clip = clips
            .iter()
            .min_by(|a, b| {
                (seat_h - a.seat_contact_z)
                    .abs()
                    .total_cmp(&(seat_h - b.seat_contact_z).abs())
            })
            .ok_or(Refusal::NoSitClip)?;
        let fit = seat_h - clip.seat_contact_z;
        if fit.abs() > self.settings.seat_fit_m {
            return Err(Refusal::NoClipFits {
                fit_m: self.settings.seat_fit_m,
                height_m: seat_h,
                seat: seat.object_name.clone(),
                nearest: clip.name.clone(),
                nearest_m: clip.seat_contact_z,
            });
        }
        let (seated_at, fitted) = fit_on_seat(body, clip, seat, map, floor_z, fit)?;
        let (l, n) = (clip.lowest, clip.frames.len());
        if fitted.lift_m.abs() > self.settings.seat_fit_m {
            return Err(Refusal::NoClipFits {
                fit_m: self.settings.seat_fit_m,
                height_m: seat_h,
                seat: seat.object_name.clone(),
                nearest: clip.name.clone(),
                nearest_m: seat_h - fitted.lift_m,
            });
        }
        let (played, foot_miss) = (fitted.frames, fitted.foot_miss_m);
        let (mut into, turn) = self.transition(body, last, &played[0])?;
        // A chair pulled out from its table slides out at most 0.5 m/s while the person steps
        // in (waiting where the walk ended if the step is quicker).
        if let Some(pull) = &seat.pull {
            let d = DVec2::from_array(pull.offset_m).length();
            let need = (d / PULL_SPEED_M_S * PRIMITIVE_RATE_HZ).ceil() as usize;
            if into.len() < need {
                let wait = vec![last.clone(); need - into.len()];
                into.splice(0..0, wait);
            }
        }
        // From a chair pulled out from its table, the person steps back out to where the walk
        // ended (walkable floor), for the walk to go on from there.
        let out = match &seat.pull {
            Some(_) => self.step_back(body, &played[n - 1], seat.stand())?,
            None => Vec::new(),
        };
        let [lo, hi] = self.settings.sit_s;
        let hold = rounded_hold(into.len() + n + out.len(), uniform_in(rng, lo, hi), 0);
        let seated = idle_frames(&played[l], hold, Idle::SEATED, rng);
        let down = into.len() + l + 1;
        let pulling = into.len();
        let mut frames = into;
        frames.extend_from_slice(&played[..=l]);
        frames.extend(seated);
        frames.extend_from_slice(&played[l + 1..]);
        frames.extend(out);
        let phases = vec![
            (Phase::Transition, down),
            (Phase::Hold, hold),
            (Phase::Transition, frames.len() - down - hold),
        ];
        if let Some((k, depth)) = self.first_entry(
            body,
            &frames,
            &phases,
            IDLE_STRIDE,
            Some(&seat.object_name),
            floor_z,
        ) {
            return Err(Refusal::EntersScene {
                doing: Doing::SittingOn(seat.object_name.clone()),
                depth_m: depth,
                frame: k,
            });
        }
        let mut r = record(Activity::Sit, seated_at, turn);
        r.clip = Some(clip.name.clone());
        r.clip_joint_speed_rad_s = Some(max_joint_speed(&clip.frames));
        r.seat = Some(seat.object_name.clone());
        r.seat_height_m = Some(seat_h);
        r.seat_fit_m = Some(fitted.lift_m);
        r.seat_gap_m = Some(fitted.gap_m);
        r.foot_miss_m = Some(foot_miss);
        // Standing in front of a seat as high as the buttocks (a bar stool, a tall body), the
        // clip's standing frames may lean into it: refused, never played.
        let (sink, frame) = seat_penetration(body, &frames, seat, map)?;
        if sink > ENTER_TOLERANCE_M {
            return Err(Refusal::EntersScene {
                doing: Doing::SittingOn(seat.object_name.clone()),
                depth_m: sink,
                frame,
            });
        }
        r.seat_penetration_m = Some(sink);
        r.chair_pulled_m = seat
            .pull
            .as_ref()
            .map(|p| DVec2::from_array(p.offset_m).length());
        r.look_at = Some(LookAt {
            point: [seated_at.x, seated_at.y, seat.surface_z_m],
            start_frame: 0,
            end_frame: down,
        });
        // The chair slides out while the person steps in, stays out, and slides back once they
        // have stepped out again.
        let moved = seat.pull.as_ref().map(|p| {
            let ramp = (pulling as f64).max(1.0);
            MovedObject {
                object: seat.object_name.clone(),
                offset_m: p.offset_m,
                out: (0..frames.len())
                    .map(|k| smooth_step((k + 1) as f64 / ramp))
                    .collect(),
                back_frames: (PUSH_BACK_S * PRIMITIVE_RATE_HZ).round() as usize,
            }
        });
        Ok(Performance {
            activity: Activity::Sit,
            record: r,
            frames,
            phases,
            seat: Some(s),
            moved,
        })
    }

    /// Frames stepping from the standing pose `from` to stand at `to` (the pelvis moved
    /// there, the pose kept): at most 0.6 m/s, at least `blend_s`.
    fn step_back(
        &self,
        body: &BodyContext,
        from: &BodyParams,
        to: DVec2,
    ) -> Result<Vec<BodyParams>, PoseError> {
        let s = body.shaped.skeleton(&from.pose, from.transl)?;
        let p = s.joints[joint::PELVIS];
        let d = to - DVec2::new(p.x, p.y);
        let mut there = from.clone();
        there.transl += Vec3::new(d.x, d.y, 0.0);
        let seconds = self.settings.blend_s.max(d.length() / 0.6);
        let n = (seconds * PRIMITIVE_RATE_HZ).round().max(1.0) as usize;
        let mut frames = blend(from, &there, n);
        frames.push(there);
        Ok(frames)
    }
}

/// Clip `clip` on the seat: where the seated pelvis goes and the clip fitted there
/// ([`fit_to_seat`]), `fit` being the seat's height less the clip's.
fn fit_on_seat(
    body: &BodyContext,
    clip: &ClipOnBody,
    seat: &Seat,
    map: &WalkableMap,
    floor_z: f64,
    fit: f64,
) -> Result<(DVec2, SeatFit), Refusal> {
    // The seated height moves in with the pelvis's descent, so standing frames stand on
    // the floor.
    let l = clip.lowest;
    let n = clip.frames.len();
    let drop = |k: usize| {
        let top = if k <= l {
            clip.pelvis[0].z
        } else {
            clip.pelvis[n - 1].z
        };
        let depth = top - clip.pelvis[l].z;
        if depth <= 1e-6 {
            1.0
        } else {
            ((top - clip.pelvis[k].z) / depth).clamp(0.0, 1.0)
        }
    };
    // Standing before sitting down and after standing up, the pelvis is in front of the
    // seat (0.3–0.45 m in the clips): on walkable floor, where the walk goes on. Where it
    // would not be, the seated pelvis moves towards the seat's front edge (keeping 8 cm
    // of seat behind the edge).
    let facing = DVec2::from_angle(seat.facing_rad);
    let clip_turn = DVec2::from_angle(seat.facing_rad - clip.headings[l]);
    let standing_at = |seated: DVec2, k: usize| {
        let d = clip.pelvis[k] - clip.pelvis[l];
        seated + clip_turn.rotate(DVec2::new(d.x, d.y))
    };
    // The first fit that need not raise the body more than 3 cm over the seat's height to
    // keep the thighs out of the seat: the feet kept where the clip has them if any place
    // on walkable floor allows it (the deepest first: on a high seat people sit nearer its
    // edge), else the feet a quarter of the way nearer the knees (the thighs kept as the
    // clip has them) … ; else the fit raised least.
    let shifts: Vec<f64> = (0..=6)
        .map(|i| 0.05 * i as f64)
        .take_while(|&x| x <= (seat.depth_m - 0.08).max(0.0))
        .filter(|&x| {
            let seated = seat.pelvis() + facing * x;
            [0, n - 1].iter().all(|&k| {
                let p = standing_at(seated, k);
                map.is_walkable_at(p) || seat.pull.as_ref().is_some_and(|pl| pl.frees(map, p))
            })
        })
        .collect();
    if shifts.is_empty() {
        return Err(Refusal::StandsOverFurniture {
            seat: seat.object_name.clone(),
            in_front_m: standing_at(DVec2::ZERO, 0).length(),
        });
    }
    let mut best: Option<(DVec2, SeatFit)> = None;
    'fit: for feet in [1.0, 0.75, 0.5, 0.25, 0.0] {
        for &shift in &shifts {
            let seated_at = seat.pelvis() + facing * shift;
            // Fitted to the seat's height (`fit_to_seat`), from the clip on the floor there.
            let grounded = placed(
                &clip.frames,
                body.shaped.rest_joints[joint::PELVIS],
                (clip.pelvis[l], clip.headings[l]),
                (seated_at, seat.facing_rad),
                |_| floor_z,
            );
            let fitted = fit_to_seat(body, clip, &grounded, &drop, fit, feet, seat, map)?;
            let raised = fitted.lift_m - fit;
            if best.as_ref().is_none_or(|b| raised < b.1.lift_m - fit) {
                best = Some((seated_at, fitted));
            }
            if raised <= 0.03 {
                break 'fit;
            }
        }
    }
    best.ok_or(Refusal::NoSitClip)
}

/// Whether a sit refused so might be done on the same chair pulled out farther: the body
/// would enter the scene sitting (the knees into the table) or stand over furniture in front
/// of the seat (the table).
fn pulled_too_little(refusal: &Refusal) -> bool {
    matches!(
        refusal,
        Refusal::EntersScene {
            doing: Doing::SittingOn(_),
            ..
        } | Refusal::StandsOverFurniture { .. }
    )
}

/// How long a chair pulled out from its table takes to slide back once the person has
/// stepped away (s).
const PUSH_BACK_S: f64 = 1.2;

/// Fastest a chair is pulled out on average (m/s).
const PULL_SPEED_M_S: f64 = 0.5;

/// 0 below 0, 1 above 1, smooth (zero slope at both ends) between.
fn smooth_step(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Deepest the thighs may rest below a seat's surface once seated (m): a cushion's give. A
/// fit that would sink them deeper is raised.
const SEAT_SINK_M: f64 = 0.01;

/// A sit clip fitted to a seat.
struct SeatFit {
    frames: Vec<BodyParams>,
    /// How far the seated pelvis was moved up (m; + up).
    lift_m: f64,
    /// Farthest an ankle moved from where the clip has it (m): drawn back under the hip where
    /// the leg does not reach, or hanging where even that is too far.
    foot_miss_m: f64,
    /// Where the buttocks and thighs rest when seated, over the seat's surface (m; − into it).
    gap_m: f64,
}

/// The placed clip `grounded` (feet on the floor) raised to the seat in step with the pelvis's
/// descent (`drop`: 0 standing, 1 seated), first by `lift` (the seat's height less the clip's),
/// then further while the thighs would sink more than [`SEAT_SINK_M`] into the seat at the
/// seated frame (the legs lifted straighter tilt the thighs down). Each lifted frame's legs
/// are bent at hip and knee to keep the ankles where the clip has them, or as near as the leg
/// reaches (`feet` 1), or to keep the thighs as the clip has them (`feet` 0), or a share of
/// the way between the two ([`ankle_targets`]).
#[allow(clippy::too_many_arguments)]
fn fit_to_seat(
    body: &BodyContext,
    clip: &ClipOnBody,
    grounded: &[BodyParams],
    drop: &dyn Fn(usize) -> f64,
    lift: f64,
    feet: f64,
    seat: &Seat,
    map: &WalkableMap,
) -> Result<SeatFit, PoseError> {
    let ankles: Vec<[Vec3; 2]> = grounded
        .iter()
        .map(|g| {
            let s = body.shaped.skeleton(&g.pose, g.transl)?;
            Ok([s.joints[joint::LEFT_ANKLE], s.joints[joint::RIGHT_ANKLE]])
        })
        .collect::<Result<_, PoseError>>()?;
    let sitting = sitting_vertices(body);
    // The clip raised by `lift_m` times its descent, and by `extra` frame by frame.
    let build = |lift_m: f64, extra: &[f64]| -> Result<(Vec<BodyParams>, f64), PoseError> {
        let mut frames = grounded.to_vec();
        let mut foot_miss_m: f64 = 0.0;
        for (k, f) in frames.iter_mut().enumerate() {
            let dz = lift_m * drop(k) + extra[k];
            if dz == 0.0 {
                continue;
            }
            f.transl.z += dz;
            let targets = ankle_targets(body, f, ankles[k], feet)?;
            let (kept, _) = keep_ankles(body, f, targets)?;
            *f = kept;
            let s = body.shaped.skeleton(&f.pose, f.transl)?;
            for (side, j) in [joint::LEFT_ANKLE, joint::RIGHT_ANKLE]
                .into_iter()
                .enumerate()
            {
                foot_miss_m = foot_miss_m.max((s.joints[j] - ankles[k][side]).length());
            }
        }
        Ok((frames, foot_miss_m))
    };
    // The seated frame first: the whole descent raised until it rests on the seat.
    let mut lift_m = lift;
    let mut extra = vec![0.0; grounded.len()];
    let (mut frames, mut foot_miss_m) = build(lift_m, &extra)?;
    for _ in 0..3 {
        let sink = seated_on(body, &frames[clip.lowest], &sitting, seat, map)?.0;
        if sink <= SEAT_SINK_M {
            break;
        }
        lift_m += sink - 0.5 * SEAT_SINK_M;
        (frames, foot_miss_m) = build(lift_m, &extra)?;
    }
    // Then the frames sitting down and standing up, raised where they would sink (the raise
    // spread over ±0.1 s: no frame raised less than it needs, none jumping).
    for _ in 0..4 {
        let need: Vec<f64> = frames
            .iter()
            .enumerate()
            .map(|(k, f)| {
                if drop(k) == 0.0 {
                    return Ok(0.0);
                }
                let sink = seated_on(body, f, &sitting, seat, map)?.0;
                Ok((sink - 0.5 * SEAT_SINK_M).max(0.0) * f64::from(sink > SEAT_SINK_M))
            })
            .collect::<Result<_, PoseError>>()?;
        if need.iter().all(|&x| x == 0.0) {
            break;
        }
        let spread = spread_raise(&need, 4);
        for (e, r) in extra.iter_mut().zip(spread) {
            *e += r;
        }
        (frames, foot_miss_m) = build(lift_m, &extra)?;
    }
    let gap_m = seated_on(body, &frames[clip.lowest], &sitting, seat, map)?.1;
    Ok(SeatFit {
        frames,
        lift_m,
        foot_miss_m,
        gap_m,
    })
}

/// `need` spread over ±`w` frames: the largest need within `w` frames, averaged over ±`w`
/// frames — at least the need at every frame (each frame of the average is the largest of a
/// window holding it), and no step steeper than the need over `w` frames.
fn spread_raise(need: &[f64], w: usize) -> Vec<f64> {
    let window = |k: usize| k.saturating_sub(w)..(k + w + 1).min(need.len());
    let widest: Vec<f64> = (0..need.len())
        .map(|k| need[window(k)].iter().copied().fold(0.0, f64::max))
        .collect();
    (0..need.len())
        .map(|k| {
            let r = window(k);
            let n = r.len() as f64;
            widest[r].iter().sum::<f64>() / n
        })
        .collect()
}

/// Where the ankles of `frame` (raised over the clip on the floor, whose ankles are
/// `ankles`) are put, per leg a share `feet` of the way from the target that keeps the thigh
/// (0) to the one that keeps the foot (1):
/// - keeping the foot: the clip's ankle, or where it is farther from the hip than the leg is
///   long (less 1 cm), moved horizontally towards below the hip at its height; where even
///   that is too far, below the hip (the foot hangs, as from a bar stool);
/// - keeping the thigh: the shin swung in the vertical plane through the knee and the clip's
///   ankle to put the ankle at the floor's height, or straight down from the knee where the
///   shin is too short for that.
fn ankle_targets(
    body: &BodyContext,
    frame: &BodyParams,
    ankles: [Vec3; 2],
    feet: f64,
) -> Result<[Vec3; 2], PoseError> {
    let s = body.shaped.skeleton(&frame.pose, frame.transl)?;
    let mut out = ankles;
    for (side, (hip, knee, ankle)) in [
        (joint::LEFT_HIP, joint::LEFT_KNEE, joint::LEFT_ANKLE),
        (joint::RIGHT_HIP, joint::RIGHT_KNEE, joint::RIGHT_ANKLE),
    ]
    .into_iter()
    .enumerate()
    {
        let (h, k, a) = (s.joints[hip], s.joints[knee], s.joints[ankle]);
        let (thigh, shin) = ((k - h).length(), (a - k).length());
        let t = ankles[side];
        let mut on_floor = t;
        let reach = thigh + shin - 0.01;
        if (t - h).length() > reach {
            let across = DVec2::new(t.x - h.x, t.y - h.y);
            let room = (reach * reach - (t.z - h.z).powi(2)).max(0.0).sqrt();
            let xy = DVec2::new(h.x, h.y) + across.normalize_or_zero() * room.min(across.length());
            on_floor = Vec3::new(xy.x, xy.y, t.z);
        }
        let fall = k.z - t.z;
        let under_knee = if fall >= shin {
            k - Vec3::Z * shin
        } else {
            let towards = DVec2::new(t.x - k.x, t.y - k.y).normalize_or_zero();
            let xy = DVec2::new(k.x, k.y) + towards * (shin * shin - fall * fall).sqrt();
            Vec3::new(xy.x, xy.y, t.z)
        };
        out[side] = under_knee.lerp(on_floor, feet);
    }
    Ok(out)
}

/// How a posed `frame` rests on `seat`: the deepest its buttocks and thighs (`sitting`) go
/// below the surface where over it (m, ≥ 0), and where the lowest of them over it within
/// 0.25 m of the pelvis lies over the surface (m; − below it; + the body hovering).
fn seated_on(
    body: &BodyContext,
    frame: &BodyParams,
    sitting: &[u32],
    seat: &Seat,
    map: &WalkableMap,
) -> Result<(f64, f64), PoseError> {
    let s = body.shaped.skeleton(&frame.pose, frame.transl)?;
    let p = s.joints[joint::PELVIS];
    let mut sink: f64 = 0.0;
    let mut lowest = f64::INFINITY;
    for v in body.shaped.pose_vertices(&s, &frame.pose, sitting) {
        let on_seat = map
            .cell_of(DVec2::new(v.x, v.y))
            .is_some_and(|(i, j)| seat.cells.binary_search(&(j * map.nx + i)).is_ok());
        if on_seat {
            sink = sink.max(seat.surface_z_m - v.z);
            if DVec2::new(v.x - p.x, v.y - p.y).length() < 0.25 {
                lowest = lowest.min(v.z);
            }
        }
    }
    Ok((sink, lowest - seat.surface_z_m))
}

/// Deepest the buttocks and thighs (vertices moved most by the pelvis or a hip) go below the
/// seat's surface where they are over it, in `frames` (m; every second frame whose pelvis is
/// low enough to touch the seat), and the frame.
fn seat_penetration(
    body: &BodyContext,
    frames: &[BodyParams],
    seat: &Seat,
    map: &WalkableMap,
) -> Result<(f64, usize), PoseError> {
    let sitting = sitting_vertices(body);
    let mut deepest = (0.0, 0);
    for (k, f) in frames.iter().enumerate().step_by(2) {
        let s = body.shaped.skeleton(&f.pose, f.transl)?;
        if s.joints[joint::PELVIS].z > seat.surface_z_m + 0.4 {
            continue;
        }
        let sink = seated_on(body, f, &sitting, seat, map)?.0;
        if sink > deepest.0 {
            deepest = (sink, k);
        }
    }
    Ok(deepest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyModel;
    use crate::motion::activity_clip::activity_clip_dir;
    use crate::motion::primitive::{NEW_FRAMES, PRIMITIVE_RATE_HZ};
    use crate::scene::seats::test_scenes::{chair_at_table, room_with_chair};
    use crate::scene::SceneMesh;
    use crate::scene::WalkableSettings;
    use crate::synth::activity::{ActivitySettings, ActivityWeights};
    use rand_core::SeedableRng;
    use std::sync::Arc;

    fn world(settings: ActivitySettings, mesh: SceneMesh) -> (ActivityWorld, WalkableMap) {
        let map = WalkableMap::build(&mesh, WalkableSettings::default()).unwrap();
        let acts =
            ActivityWorld::new(settings, Some(Arc::new(mesh)), &map, &activity_clip_dir()).unwrap();
        (acts, map)
    }

    fn sitting() -> ActivitySettings {
        ActivitySettings {
            weights: ActivityWeights::parse("walk=1,sit=1").unwrap(),
            ..Default::default()
        }
    }

    fn shipped_model() -> BodyModel {
        BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap()
    }

    /// A person standing at the seat's standing point, facing the seat (the way they walked).
    fn arriving(acts: &ActivityWorld, body: &BodyContext, s: usize) -> BodyParams {
        let seat = &acts.seats[s];
        let clip = acts
            .clip(crate::motion::activity_clip::ClipId::Sit75_18)
            .unwrap()
            .on_body(body)
            .unwrap();
        placed(
            &clip.frames[..1],
            body.shaped.rest_joints[joint::PELVIS],
            (clip.pelvis[0], clip.headings[0]),
            (seat.stand(), seat.facing_rad + std::f64::consts::PI),
            |_| 0.0,
        )
        .remove(0)
    }

    #[test]
    fn bodies_of_extreme_shape_sit_on_seats_of_any_height_and_a_tight_fit_refuses() {
        let model = shipped_model();
        let n = model.num_betas().min(2);
        let mut refused = 0;
        for betas in [vec![], vec![-3.0; n], vec![3.0; n]] {
            let body = BodyContext::new(&model, &betas).unwrap();
            // Far from the origin too: a seat at the room's edge of a map placed far away.
            for (seat_h, x, y) in [(0.35, 0.0, 0.0), (0.45, 2.4, -2.7), (0.75, 0.0, 0.0)] {
                let (mut acts, map) = world(sitting(), room_with_chair(seat_h, x, y, "chair"));
                assert_eq!(acts.seats.len(), 1, "seat at {seat_h} m");
                let last = arriving(&acts, &body, 0);
                let mut rng = ChaCha8Rng::seed_from_u64(1);
                let p = match acts.sit(&body, &map, &last, 0, 0.0, &mut rng) {
                    Ok(p) => p,
                    // The largest body standing in front of a seat as high as its buttocks
                    // leans into it: refused by name, never sat badly.
                    Err(Refusal::EntersScene { doing, .. })
                        if !betas.is_empty()
                            && seat_h > 0.7
                            && doing == Doing::SittingOn("chair".into()) =>
                    {
                        refused += 1;
                        continue;
                    }
                    Err(e) => panic!("{betas:?} {seat_h}: {e}"),
                };
                let r = &p.record;
                assert!(r.seat_fit_m.unwrap().abs() <= 0.7);
                // Resting on the seat, not in it, not over it (sitting down and standing up
                // into it no deeper than the scene check lets a body enter anything).
                assert!(r.seat_penetration_m.unwrap() <= ENTER_TOLERANCE_M, "{r:?}");
                assert!(r.seat_gap_m.unwrap().abs() <= 0.02, "{r:?}");
                // The feet move no farther than the seat is raised over the clip's.
                assert!(
                    r.foot_miss_m.unwrap() <= r.seat_fit_m.unwrap().abs() + 1e-3,
                    "{r:?}"
                );
                assert!((r.turn_deg.abs() - 180.0).abs() < 30.0, "{r:?}");
                assert_eq!(p.frames.len() % NEW_FRAMES, 0);
                assert_eq!(p.phases.iter().map(|x| x.1).sum::<usize>(), p.frames.len());
                // Seated on the surface, the feet never below the floor.
                let hold_start = p.phases[0].1;
                let f = &p.frames[hold_start];
                let s = body.shaped.skeleton(&f.pose, f.transl).unwrap();
                let p = s.joints[joint::PELVIS];
                let contact = body
                    .shaped
                    .pose_vertices(&s, &f.pose, &sitting_vertices(&body))
                    .iter()
                    .filter(|v| DVec2::new(v.x - p.x, v.y - p.y).length() < 0.15)
                    .map(|v| v.z)
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    (contact - seat_h).abs() < 0.03,
                    "{betas:?} {seat_h}: {contact}"
                );
                for ankle in [joint::LEFT_ANKLE, joint::RIGHT_ANKLE] {
                    assert!(s.joints[ankle].z > 0.0, "{betas:?} {seat_h}");
                }
            }
            // A fit held to 0.2 m refuses the 0.75 m seat, naming the key.
            let tight = ActivitySettings {
                seat_fit_m: 0.2,
                ..sitting()
            };
            let (mut acts, map) = world(tight, room_with_chair(0.75, 0.0, 0.0, "chair"));
            let last = arriving(&acts, &body, 0);
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            let err = acts.sit(&body, &map, &last, 0, 0.0, &mut rng).unwrap_err();
            assert!(matches!(err, Refusal::NoClipFits { .. }), "{err}");
            assert!(err.to_string().contains("activities.seat_fit_m"), "{err}");
        }
        // At most the one extreme body on the highest seat.
        assert!(refused <= 1, "{refused} refused");
    }

    #[test]
    fn a_chair_under_a_table_is_pulled_out_sat_on_and_pushed_back() {
        let model = shipped_model();
        let n = model.num_betas().min(2);
        for betas in [vec![], vec![-3.0; n], vec![3.0; n]] {
            let body = BodyContext::new(&model, &betas).unwrap();
            for under in [0.15, 0.44] {
                let mesh = chair_at_table(DVec2::new(0.3, -0.2), under);
                let (mut acts, map) = world(sitting(), mesh);
                assert_eq!(acts.seats.len(), 1, "{under}");
                let seat = acts.seats[0].clone();
                let pull = DVec2::from_array(seat.pull.as_ref().unwrap().offset_m);
                let last = arriving(&acts, &body, 0);
                let mut rng = ChaCha8Rng::seed_from_u64(3);
                let p = acts
                    .sit(&body, &map, &last, 0, 0.0, &mut rng)
                    .unwrap_or_else(|e| panic!("{betas:?} {under}: {e}"));
                let r = &p.record;
                assert!((r.chair_pulled_m.unwrap() - pull.length()).abs() < 1e-12);
                assert!(r.seat_gap_m.unwrap().abs() <= 0.02, "{r:?}");
                assert_eq!(p.frames.len() % NEW_FRAMES, 0);
                assert_eq!(p.phases.iter().map(|x| x.1).sum::<usize>(), p.frames.len());
                // The chair: out while seated, back after, moving smoothly.
                let m = p.moved.as_ref().expect("the chair moves");
                assert_eq!(m.object, seat.object_name);
                let moves = m.starting_at(100);
                let at = |f: usize| DVec2::from_array(moves.offset_at(f));
                let seated = 100 + p.phases[0].1 + p.phases[1].1 / 2;
                assert!(at(seated).distance(pull) < 1e-9);
                assert_eq!(at(99), DVec2::ZERO);
                assert_eq!(at(moves.end_frame), DVec2::ZERO);
                for f in 100..moves.end_frame {
                    assert!(at(f + 1).distance(at(f)) < 0.05, "{f}");
                }
                // Seated on the pulled chair, facing the table.
                let f = &p.frames[p.phases[0].1];
                let s = body.shaped.skeleton(&f.pose, f.transl).unwrap();
                let pelvis = s.joints[joint::PELVIS];
                assert!(DVec2::new(pelvis.x, pelvis.y).distance(seat.pelvis()) < 0.35);
                // The walk goes on from where it ended, on walkable floor.
                let end = p.frames.last().unwrap();
                let s = body.shaped.skeleton(&end.pose, end.transl).unwrap();
                let q = s.joints[joint::PELVIS];
                assert!(DVec2::new(q.x, q.y).distance(seat.stand()) < 1e-6);
                assert!(map.is_walkable_at(DVec2::new(q.x, q.y)));
            }
        }
    }

    /// A chair pulled out too little (its place 0.25 m nearer the table: the body would stand
    /// in the table) is sat on at its longer pull; without one, refused by name.
    #[test]
    fn a_chair_pulled_out_too_little_is_sat_on_at_its_longer_pull() {
        let model = shipped_model();
        let body = BodyContext::new(&model, &[]).unwrap();
        let (mut acts, map) = world(sitting(), chair_at_table(DVec2::new(0.3, -0.2), 0.15));
        let fits = acts.seats[0].clone();
        let mut near = fits.clone();
        near.pull.as_mut().unwrap().offset_m[1] += 0.25;
        near.pelvis_xy[1] += 0.25;
        let last = arriving(&acts, &body, 0);
        let mut sit = |longer: Option<Seat>| {
            acts.seats[0] = Seat {
                longer: longer.map(Box::new),
                ..near.clone()
            };
            acts.sit(
                &body,
                &map,
                &last,
                0,
                0.0,
                &mut ChaCha8Rng::seed_from_u64(3),
            )
        };
        let fits_m = DVec2::from_array(fits.pull.as_ref().unwrap().offset_m).length();
        let pulled = sit(Some(fits)).unwrap().record.chair_pulled_m.unwrap();
        assert!((pulled - fits_m).abs() < 1e-12);
        let refused = sit(None).unwrap_err();
        assert!(pulled_too_little(&refused), "{refused}");
    }

    #[test]
    fn a_sit_held_ten_minutes_keeps_the_body_on_its_seat() {
        let model = shipped_model();
        let body = BodyContext::new(&model, &[]).unwrap();
        let settings = ActivitySettings {
            sit_s: [600.0, 600.0],
            ..sitting()
        };
        let (mut acts, map) = world(settings, room_with_chair(0.45, 0.0, 0.0, "chair"));
        let last = arriving(&acts, &body, 0);
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let p = acts.sit(&body, &map, &last, 0, 0.0, &mut rng).unwrap();
        let (down, hold) = (p.phases[0].1, p.phases[1].1);
        assert!(
            (hold as f64 / PRIMITIVE_RATE_HZ - 600.0).abs() < 1.0,
            "{hold}"
        );
        let seated = &p.frames[down..down + hold];
        assert!(seated.iter().all(|f| f.transl == seated[0].transl
            && f.joint_axis_angle(0) == seated[0].joint_axis_angle(0)
            && f.pose.iter().all(|x| x.is_finite())));
        // Still on the seat at the end, and standing up after.
        let end = &p.frames[p.frames.len() - 1];
        let s = body.shaped.skeleton(&end.pose, end.transl).unwrap();
        assert!(s.joints[joint::PELVIS].z > 0.8);
    }
}
