//! Sitting down on a seat from where the walk to it ended, staying seated for a drawn time,
//! standing up: a sit clip fitted to the seat.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;

use super::refusal::{Doing, Refusal};
use super::world::{record, rounded_hold, IDLE_STRIDE};
use super::{Activity, ActivityWorld, LookAt, Performance, Phase};
use crate::body::{joint, BodyParams, PoseError};
use crate::math::random::uniform_in;
use crate::motion::activity_clip::{
    idle_frames, keep_ankles, max_joint_speed, placed, sitting_vertices, ClipKind, ClipOnBody, Idle,
};
use crate::motion::cvae::BodyContext;
use crate::scene::{Seat, WalkableMap};

impl ActivityWorld {
    /// Sitting down on seat `s` from where `last` stands, staying seated for a drawn time,
    /// standing up: the sit clip nearest the seat's height, moved to the seat (its seated
    /// pelvis on the seat's place, facing the seat's way) and fitted to its height.
    #[allow(clippy::too_many_arguments)]
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
        let shift = (0..=6)
            .map(|i| 0.05 * i as f64)
            .take_while(|&x| x <= (seat.depth_m - 0.08).max(0.0))
            .find(|&x| {
                let seated = seat.pelvis() + facing * x;
                [0, n - 1]
                    .iter()
                    .all(|&k| map.is_walkable_at(standing_at(seated, k)))
            })
            .ok_or_else(|| Refusal::StandsOverFurniture {
                seat: seat.object_name.clone(),
                in_front_m: standing_at(DVec2::ZERO, 0).length(),
            })?;
        let seated_at = seat.pelvis() + facing * shift;
        let place = |dz: &dyn Fn(usize) -> f64| {
            placed(
                &clip.frames,
                body.shaped.rest_joints[joint::PELVIS],
                (clip.pelvis[l], clip.headings[l]),
                (seated_at, seat.facing_rad),
                dz,
            )
        };
        // Fitted to the seat's height, the legs bent to keep the feet where the clip has them.
        let grounded = place(&|_| floor_z);
        let mut played = place(&|k| floor_z + fit * drop(k));
        let mut foot_miss: f64 = 0.0;
        for (f, g) in played.iter_mut().zip(&grounded) {
            if f.transl == g.transl {
                continue;
            }
            let s = body.shaped.skeleton(&g.pose, g.transl)?;
            let ankles = [s.joints[joint::LEFT_ANKLE], s.joints[joint::RIGHT_ANKLE]];
            let (kept, miss) = keep_ankles(body, f, ankles)?;
            *f = kept;
            foot_miss = foot_miss.max(miss);
        }
        let (into, turn) = self.transition(body, last, &played[0])?;
        let [lo, hi] = self.settings.sit_s;
        let hold = rounded_hold(into.len() + n, uniform_in(rng, lo, hi), 0);
        let seated = idle_frames(&played[l], hold, Idle::SEATED, rng);
        let down = into.len() + l + 1;
        let mut frames = into;
        frames.extend_from_slice(&played[..=l]);
        frames.extend(seated);
        frames.extend_from_slice(&played[l + 1..]);
        let phases = vec![
            (Phase::Transition, down),
            (Phase::Hold, hold),
            (Phase::Transition, n - l - 1),
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
        r.seat_fit_m = Some(fit);
        r.foot_miss_m = Some(foot_miss);
        r.seat_penetration_m = Some(seat_penetration(body, &frames, &seat, map)?);
        r.look_at = Some(LookAt {
            point: [seated_at.x, seated_at.y, seat.surface_z_m],
            start_frame: 0,
            end_frame: down,
        });
        Ok(Performance {
            activity: Activity::Sit,
            record: r,
            frames,
            phases,
            seat: Some(s),
        })
    }
}

/// Deepest the buttocks and thighs (vertices moved most by the pelvis or a hip) go below the
/// seat's surface where they are over it, in `frames` (m).
fn seat_penetration(
    body: &BodyContext,
    frames: &[BodyParams],
    seat: &Seat,
    map: &WalkableMap,
) -> Result<f64, PoseError> {
    let cells: std::collections::HashSet<usize> = seat.cells.iter().copied().collect();
    let sitting = sitting_vertices(body);
    let mut deepest: f64 = 0.0;
    for f in frames.iter().step_by(2) {
        let s = body.shaped.skeleton(&f.pose, f.transl)?;
        // Only frames with the pelvis low enough to touch the seat.
        if s.joints[joint::PELVIS].z > seat.surface_z_m + 0.4 {
            continue;
        }
        for v in body.shaped.pose_vertices(&s, &f.pose, &sitting) {
            let on_seat = map
                .cell_of(DVec2::new(v.x, v.y))
                .is_some_and(|(i, j)| cells.contains(&(j * map.nx + i)));
            if on_seat {
                deepest = deepest.max(seat.surface_z_m - v.z);
            }
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
    use crate::scene::seats::test_scenes::room_with_chair;
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
    fn bodies_of_extreme_shape_sit_on_low_and_high_seats_and_too_high_a_seat_is_refused() {
        let model = BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap();
        let n = model.num_betas().min(2);
        for betas in [vec![], vec![-3.0; n], vec![3.0; n]] {
            let body = BodyContext::new(&model, &betas).unwrap();
            // Far from the origin too: a seat at the room's edge of a map placed far away.
            for (seat_h, x, y) in [(0.35, 0.0, 0.0), (0.45, 2.4, -2.7)] {
                let (mut acts, map) = world(sitting(), room_with_chair(seat_h, x, y, "chair"));
                assert_eq!(acts.seats.len(), 1, "seat at {seat_h} m");
                let last = arriving(&acts, &body, 0);
                let mut rng = ChaCha8Rng::seed_from_u64(1);
                let p = match acts.sit(&body, &map, &last, 0, 0.0, &mut rng) {
                    Ok(p) => p,
                    // A body of extreme shape may sit too low or high for every clip: refused
                    // by name, never sat badly (the shipped body always sits).
                    Err(e) if !betas.is_empty() && matches!(e, Refusal::NoClipFits { .. }) => {
                        continue
                    }
                    Err(e) => panic!("{betas:?} {seat_h}: {e}"),
                };
                let r = &p.record;
                assert!(r.seat_fit_m.unwrap().abs() <= 0.2);
                assert!(r.foot_miss_m.unwrap() < 0.02, "{r:?}");
                assert!(r.seat_penetration_m.unwrap() < 0.08, "{r:?}");
                assert!((r.turn_deg.abs() - 180.0).abs() < 30.0, "{r:?}");
                assert_eq!(p.frames.len() % NEW_FRAMES, 0);
                assert_eq!(p.phases.iter().map(|x| x.1).sum::<usize>(), p.frames.len());
                // Seated on the surface: the buttocks and thighs rest on it.
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
            }
            let (mut acts, map) = world(sitting(), room_with_chair(0.74, 0.0, 0.0, "chair"));
            let last = arriving(&acts, &body, 0);
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            let err = acts.sit(&body, &map, &last, 0, 0.0, &mut rng).unwrap_err();
            assert!(matches!(err, Refusal::NoClipFits { .. }), "{err}");
            assert!(err.to_string().contains("activities.seat_fit_m"), "{err}");
        }
    }

    #[test]
    fn a_sit_held_ten_minutes_keeps_the_body_on_its_seat() {
        let model = BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap();
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
