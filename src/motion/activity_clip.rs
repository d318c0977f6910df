//! Activity clips and the pose tools that play them on a body: the shipped mocap of sitting
//! down and standing up (three seat heights) and of bending to pick something up
//! (`assets/motion/activities/`, CMU, 40 Hz SMPL-X), a clip put on a body of any shape with
//! its feet on the floor, moved rigidly to a place, a blend from one pose to another, and
//! procedural idle motion (looking around, breathing) held on one pose. What an activity does
//! in a take — where, when, checked against the scene — is `synth::activity`'s.

use std::path::{Path, PathBuf};

use glam::DVec2;
use rand_chacha::ChaCha8Rng;

use super::amass::{MotionFileError, MotionSequence};
use super::cvae::BodyContext;
use super::primitive::PRIMITIVE_RATE_HZ;
use crate::body::{joint, BodyParams, PoseError};
use crate::math::random::uniform_in;
use crate::math::{axis_angle_to_matrix, matrix_to_axis_angle, Affine3, Mat3, Vec3};

/// What a clip shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum ClipKind {
    /// Stands, sits down, stands up again (split at its lowest pelvis).
    Sit,
    /// Stands, bends to pick something up from the floor, stands again.
    PickUp,
}

/// The shipped clips a take plays (`assets/motion/activities/<name>.npz`), by their CMU
/// take: 75_20 (low seat), 75_17 (medium), 75_18 (high), 64_28 (picking up a ball). The lifts
/// 74_07 and 74_08 start crouched, with no way down: not played.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum ClipId {
    /// CMU 75_20: sitting down on a low seat and standing up.
    Sit75_20,
    /// CMU 75_17: a medium seat.
    Sit75_17,
    /// CMU 75_18: a high seat (its first frame also stands a person looking around).
    Sit75_18,
    /// CMU 64_28: bending to pick a ball up from the floor.
    PickUp64_28,
}

impl ClipId {
    /// Every shipped clip, in the order they are loaded.
    pub(crate) const ALL: [ClipId; 4] = [
        ClipId::Sit75_20,
        ClipId::Sit75_17,
        ClipId::Sit75_18,
        ClipId::PickUp64_28,
    ];

    /// Its file's name (the CMU take, subject_trial), as records name it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ClipId::Sit75_20 => "75_20",
            ClipId::Sit75_17 => "75_17",
            ClipId::Sit75_18 => "75_18",
            ClipId::PickUp64_28 => "64_28",
        }
    }

    /// What it shows.
    pub(crate) fn kind(self) -> ClipKind {
        match self {
            ClipId::PickUp64_28 => ClipKind::PickUp,
            _ => ClipKind::Sit,
        }
    }
}

/// The folder the shipped clips are in.
pub(crate) fn activity_clip_dir() -> PathBuf {
    crate::paths::crate_root().join("assets/motion/activities")
}

/// SMPL-X joint spine3 (the chest), which breathes.
const SPINE3: usize = 9;

/// An activity clip as read: its frames at 40 Hz on the neutral body, feet on z = 0.
#[derive(Debug, Clone)]
pub(crate) struct ActivityClip {
    pub id: ClipId,
    pub name: String,
    pub kind: ClipKind,
    pub frames: Vec<BodyParams>,
}

/// What went wrong reading an activity clip.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ActivityClipError {
    #[error("activity clip {}: {source} (the shipped clips are rebuilt by `bash tools/build_training_clips.sh activities`)", path.display())]
    Read {
        path: PathBuf,
        source: MotionFileError,
    },
    #[error("activity clip {}: expected at least 8 frames at {PRIMITIVE_RATE_HZ} Hz, got {frames} at {rate} Hz (`egogen motion import --rate-hz 40`)", path.display())]
    Rate {
        path: PathBuf,
        frames: usize,
        rate: f64,
    },
}

impl ActivityClip {
    /// Reads the clip `name` of `kind` from `dir`.
    pub(crate) fn load(dir: &Path, id: ClipId) -> Result<Self, ActivityClipError> {
        let (name, kind) = (id.name(), id.kind());
        let path = dir.join(format!("{name}.npz"));
        let seq = MotionSequence::read(&path).map_err(|source| ActivityClipError::Read {
            path: path.clone(),
            source,
        })?;
        if seq.frame_rate_hz != PRIMITIVE_RATE_HZ || seq.len() < 8 {
            return Err(ActivityClipError::Rate {
                path,
                frames: seq.len(),
                rate: seq.frame_rate_hz,
            });
        }
        let frames = (0..seq.len())
            .map(|f| {
                let mut p = seq.frame(f);
                p.betas.clear();
                p
            })
            .collect();
        Ok(Self {
            id,
            name: name.to_string(),
            kind,
            frames,
        })
    }

    /// Every shipped clip ([`ClipId::ALL`]) from `dir`.
    pub(crate) fn load_shipped(dir: &Path) -> Result<Vec<Self>, ActivityClipError> {
        ClipId::ALL.iter().map(|&id| Self::load(dir, id)).collect()
    }

    /// The clip on `body`: its shape's betas in every frame, lifted or lowered so that the
    /// body's lowest point in the first frame stands on z = 0.
    pub(crate) fn on_body(&self, body: &BodyContext) -> Result<ClipOnBody, PoseError> {
        let mut frames = self.frames.clone();
        for f in &mut frames {
            f.betas = body.betas.clone();
        }
        let all: Vec<u32> = (0..body.shaped.v_shaped.len() as u32).collect();
        let vertices = |f: &BodyParams| -> Result<Vec<Vec3>, PoseError> {
            let s = body.shaped.skeleton(&f.pose, f.transl)?;
            Ok(body.shaped.pose_vertices(&s, &f.pose, &all))
        };
        let lowest_z = vertices(&frames[0])?
            .iter()
            .map(|v| v.z)
            .fold(f64::INFINITY, f64::min);
        for f in &mut frames {
            f.transl.z -= lowest_z;
        }
        let pelvis: Vec<Vec3> = frames
            .iter()
            .map(|f| {
                body.shaped
                    .skeleton(&f.pose, f.transl)
                    .map(|s| s.joints[joint::PELVIS])
            })
            .collect::<Result<_, _>>()?;
        let lowest = (0..pelvis.len())
            .min_by(|&a, &b| pelvis[a].z.total_cmp(&pelvis[b].z))
            .unwrap_or(0);
        // What sits on the seat at the lowest frame: the lowest point of the buttocks and
        // thighs within 0.25 m of the pelvis, horizontally, and below it.
        let p = pelvis[lowest];
        let f = &frames[lowest];
        let s = body.shaped.skeleton(&f.pose, f.transl)?;
        let seat_contact_z = body
            .shaped
            .pose_vertices(&s, &f.pose, &sitting_vertices(body))
            .iter()
            .filter(|v| v.z < p.z && DVec2::new(v.x - p.x, v.y - p.y).length() < 0.25)
            .map(|v| v.z)
            .fold(f64::INFINITY, f64::min);
        let headings = frames
            .iter()
            .map(|f| {
                body.shaped
                    .skeleton(&f.pose, f.transl)
                    .map(|s| heading(&s.joints))
            })
            .collect::<Result<_, _>>()?;
        Ok(ClipOnBody {
            name: self.name.clone(),
            frames,
            pelvis,
            headings,
            lowest,
            seat_contact_z,
        })
    }
}

/// The vertices a body sits on: the buttocks and thighs, those moved most by the pelvis or a
/// hip.
pub(crate) fn sitting_vertices(body: &BodyContext) -> Vec<u32> {
    body.model
        .skin_weights
        .iter()
        .enumerate()
        .filter(|(_, w)| {
            let main = w
                .iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(u32::MAX, |&(j, _)| j) as usize;
            matches!(main, joint::PELVIS | joint::LEFT_HIP | joint::RIGHT_HIP)
        })
        .map(|(v, _)| v as u32)
        .collect()
}

/// An activity clip on one body, its feet on z = 0 in the first frame.
#[derive(Debug, Clone)]
pub(crate) struct ClipOnBody {
    pub name: String,
    pub frames: Vec<BodyParams>,
    /// Pelvis joint per frame.
    pub pelvis: Vec<Vec3>,
    /// Facing per frame (rad from +x; [`heading`]).
    pub headings: Vec<f64>,
    /// Frame of the lowest pelvis (a sit clip's seated frame).
    pub lowest: usize,
    /// Height of what the body sits on at the lowest frame (m over the floor): the lowest point
    /// of its buttocks and thighs within 0.25 m of the pelvis and below it.
    pub seat_contact_z: f64,
}

/// Facing of a posed skeleton (rad from +x): the horizontal normal of its hip line, as a
/// motion primitive's canonical frame has it (forward = up × (right hip − left hip)).
pub(crate) fn heading(joints: &[Vec3]) -> f64 {
    let across = joints[joint::RIGHT_HIP] - joints[joint::LEFT_HIP];
    (across.x).atan2(-across.y)
}

/// `frames` moved rigidly so that the pose at `from` (pelvis position, facing) stands at `to`
/// (horizontal position, facing), heights unchanged but for `dz` (per frame: m added).
pub(crate) fn placed(
    frames: &[BodyParams],
    rest_pelvis: Vec3,
    from: (Vec3, f64),
    to: (DVec2, f64),
    dz: impl Fn(usize) -> f64,
) -> Vec<BodyParams> {
    let turn = Mat3::from_rotation_z(to.1 - from.1);
    let moved = turn * from.0;
    let world_from_clip = Affine3 {
        matrix3: turn,
        translation: Vec3::new(to.0.x - moved.x, to.0.y - moved.y, 0.0),
    };
    frames
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let mut p = f.moved_rigidly(world_from_clip, rest_pelvis);
            p.transl.z += dz(k);
            p
        })
        .collect()
}

/// `n` frames from pose `a` to pose `b`, neither included: every joint's rotation slerped and
/// the translation moved on a smooth step (zero velocity at both ends).
pub(crate) fn blend(a: &BodyParams, b: &BodyParams, n: usize) -> Vec<BodyParams> {
    (1..=n)
        .map(|k| {
            let t = k as f64 / (n + 1) as f64;
            let s = t * t * (3.0 - 2.0 * t);
            let mut f = a.clone();
            for j in 0..crate::body::skeleton::NUM_JOINTS {
                let qa = quat(a.joint_axis_angle(j));
                let qb = quat(b.joint_axis_angle(j));
                let q = qa.slerp(qb, s);
                let (axis, angle) = q.to_axis_angle();
                f.set_joint_axis_angle(j, axis * angle);
            }
            f.transl = a.transl.lerp(b.transl, s);
            f
        })
        .collect()
}

/// `frame` with each leg bent at hip and knee (two-bone inverse kinematics in the leg's own
/// plane, the foot keeping its world orientation) so that its ankles reach `ankles` (left,
/// right; world) — how a clip lifted or lowered to fit a seat keeps its feet where they
/// were. Returns the frame and the farthest an ankle stays from its target (m: a leg too
/// short to reach stays straight towards it).
pub(crate) fn keep_ankles(
    body: &BodyContext,
    frame: &BodyParams,
    ankles: [Vec3; 2],
) -> Result<(BodyParams, f64), PoseError> {
    use super::retarget::rotation_between;
    let mut out = frame.clone();
    for (side, target) in ankles.into_iter().enumerate() {
        let (hip, knee, ankle) = [
            (joint::LEFT_HIP, joint::LEFT_KNEE, joint::LEFT_ANKLE),
            (joint::RIGHT_HIP, joint::RIGHT_KNEE, joint::RIGHT_ANKLE),
        ][side];
        let s = body.shaped.skeleton(&out.pose, out.transl)?;
        let (h, k, a) = (s.joints[hip], s.joints[knee], s.joints[ankle]);
        let rot = |j: usize| s.world_from_joint[j].matrix3;
        let (l1, l2) = ((k - h).length(), (a - k).length());
        let d = (target - h)
            .length()
            .clamp((l1 - l2).abs() + 1e-6, l1 + l2 - 1e-6);
        // The knee's interior angle for reach `d`, about the leg plane's normal.
        let (u, v) = (h - k, a - k);
        let normal = u.cross(v);
        let axis = if normal.length() > 1e-9 {
            normal.normalize()
        } else {
            rot(hip) * Vec3::X
        };
        let now = u.angle_between(v);
        let want = ((l1 * l1 + l2 * l2 - d * d) / (2.0 * l1 * l2))
            .clamp(-1.0, 1.0)
            .acos();
        let bend = axis_angle_to_matrix(axis * (want - now));
        let a_bent = k + bend * v;
        // Then the whole leg swung about the hip onto the target.
        let swing = rotation_between(a_bent - h, target - h);
        let hip_world = swing * rot(hip);
        let knee_world = swing * bend * rot(knee);
        let parent = rot(joint::PELVIS);
        out.set_joint_axis_angle(hip, matrix_to_axis_angle(parent.transpose() * hip_world));
        out.set_joint_axis_angle(
            knee,
            matrix_to_axis_angle(hip_world.transpose() * knee_world),
        );
        out.set_joint_axis_angle(
            ankle,
            matrix_to_axis_angle(knee_world.transpose() * rot(ankle)),
        );
    }
    let s = body.shaped.skeleton(&out.pose, out.transl)?;
    let miss = (s.joints[joint::LEFT_ANKLE] - ankles[0])
        .length()
        .max((s.joints[joint::RIGHT_ANKLE] - ankles[1]).length());
    Ok((out, miss))
}

/// The fastest any of the 22 body joints (the root's orientation among them) turns from one
/// frame to the next in `frames` at 40 Hz (rad/s).
pub(crate) fn max_joint_speed(frames: &[BodyParams]) -> f64 {
    frames
        .windows(2)
        .flat_map(|w| {
            (0..22).map(move |j| {
                quat(w[0].joint_axis_angle(j)).angle_between(quat(w[1].joint_axis_angle(j)))
            })
        })
        .fold(0.0, f64::max)
        * PRIMITIVE_RATE_HZ
}

fn quat(aa: Vec3) -> glam::DQuat {
    glam::DQuat::from_mat3(&axis_angle_to_matrix(aa))
}

/// How idle motion moves a held pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Idle {
    /// Largest turn of the head to either side (rad), shared by neck (40 %) and head (60 %).
    pub look_rad: f64,
    /// Largest nod up or down (rad).
    pub nod_rad: f64,
    /// Seconds between new directions looked in (each drawn in 0.6–1.4 × this).
    pub look_every_s: f64,
}

impl Idle {
    /// Standing and looking around.
    pub(crate) const LOOK_AROUND: Idle = Idle {
        look_rad: 1.0,
        nod_rad: 0.25,
        look_every_s: 1.5,
    };
    /// Seated: glancing about.
    pub(crate) const SEATED: Idle = Idle {
        look_rad: 0.6,
        nod_rad: 0.2,
        look_every_s: 2.5,
    };
}

/// `n` frames of `base` held with idle motion (procedural, not mocap): the head turns and nods
/// towards directions drawn every [`Idle::look_every_s`] (eased from one to the next), the
/// chest breathes (0.25 Hz, 1.5°). The first and last frames are `base`'s own head and
/// chest, so the hold joins what comes before and after it without a jump.
pub(crate) fn idle_frames(
    base: &BodyParams,
    n: usize,
    idle: Idle,
    rng: &mut ChaCha8Rng,
) -> Vec<BodyParams> {
    let rate = PRIMITIVE_RATE_HZ;
    // Key frames: (frame, yaw, pitch); the first and last at rest.
    let mut keys = vec![(0usize, 0.0, 0.0)];
    let mut f = 0.0;
    loop {
        f += idle.look_every_s * uniform_in(rng, 0.6, 1.4) * rate;
        if f >= n as f64 - 0.5 * idle.look_every_s * rate {
            break;
        }
        keys.push((
            f as usize,
            uniform_in(rng, -idle.look_rad, idle.look_rad),
            uniform_in(rng, -idle.nod_rad, idle.nod_rad),
        ));
    }
    keys.push((n.saturating_sub(1), 0.0, 0.0));
    let eased = |k: usize| -> (f64, f64) {
        let i = keys.iter().rposition(|key| key.0 <= k).unwrap_or(0);
        let (a, b) = (keys[i], keys[(i + 1).min(keys.len() - 1)]);
        if b.0 <= a.0 {
            return (a.1, a.2);
        }
        let t = (k - a.0) as f64 / (b.0 - a.0) as f64;
        let s = 0.5 - 0.5 * (std::f64::consts::PI * t).cos();
        (a.1 + (b.1 - a.1) * s, a.2 + (b.2 - a.2) * s)
    };
    (0..n)
        .map(|k| {
            let (yaw, pitch) = eased(k);
            let breath = 0.026
                * (std::f64::consts::TAU * 0.25 * k as f64 / rate).sin()
                * (k.min(n - 1 - k) as f64 / rate).min(1.0);
            let mut p = base.clone();
            // Local frames are the model's (y up, x to the body's left): a turn about y, a
            // nod about x, in the parent's frame.
            let turn = |p: &mut BodyParams, j: usize, yaw: f64, pitch: f64| {
                let r = Mat3::from_rotation_y(yaw)
                    * Mat3::from_rotation_x(pitch)
                    * axis_angle_to_matrix(p.joint_axis_angle(j));
                p.set_joint_axis_angle(j, matrix_to_axis_angle(r));
            };
            turn(&mut p, joint::NECK, 0.4 * yaw, 0.4 * pitch);
            turn(&mut p, joint::HEAD, 0.6 * yaw, 0.6 * pitch);
            turn(&mut p, SPINE3, 0.0, breath);
            p
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyModel;
    use rand_core::SeedableRng;

    fn model() -> BodyModel {
        BodyModel::load(crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap()
    }

    #[test]
    fn shipped_sit_clips_sit_lower_in_order_and_stand_on_the_floor() {
        let model = model();
        let clips = ActivityClip::load_shipped(&activity_clip_dir()).unwrap();
        for betas in [vec![], vec![2.0, -1.5, 1.0]] {
            let body = BodyContext::new(&model, &betas).unwrap();
            let on: Vec<ClipOnBody> = clips.iter().map(|c| c.on_body(&body).unwrap()).collect();
            // Low, medium, high: seated heights rise, all between the floor and a chair.
            let seats: Vec<f64> = on[..3].iter().map(|c| c.seat_contact_z).collect();
            assert!(seats[0] < seats[1] && seats[1] < seats[2], "{seats:?}");
            assert!(seats[0] > 0.0 && seats[2] < 0.6, "{seats:?}");
            for c in &on {
                // Standing at both ends, lowest inside.
                assert!(c.lowest > 0 && c.lowest < c.frames.len() - 1, "{}", c.name);
                assert!(c.pelvis[0].z > 0.8 && c.pelvis[c.frames.len() - 1].z > 0.8);
            }
        }
    }

    #[test]
    fn placing_moves_the_chosen_pose_to_the_place_and_facing() {
        let model = model();
        let body = BodyContext::new(&model, &[0.5]).unwrap();
        let clip = ActivityClip::load(&activity_clip_dir(), ClipId::Sit75_18)
            .unwrap()
            .on_body(&body)
            .unwrap();
        let l = clip.lowest;
        for (x, y, facing) in [
            (1e4, -3.0, 0.0),
            (2.0, 5.0, std::f64::consts::PI),
            (-7.5, 0.1, -3.1),
        ] {
            let to = (DVec2::new(x, y), facing);
            let frames = placed(
                &clip.frames,
                body.shaped.rest_joints[joint::PELVIS],
                (clip.pelvis[l], clip.headings[l]),
                to,
                |_| 0.25,
            );
            let s = body
                .shaped
                .skeleton(&frames[l].pose, frames[l].transl)
                .unwrap();
            let p = s.joints[joint::PELVIS];
            assert!((DVec2::new(p.x, p.y) - to.0).length() < 1e-6 * (1.0 + x.abs()));
            assert!((p.z - clip.pelvis[l].z - 0.25).abs() < 1e-9);
            let d = heading(&s.joints) - facing;
            assert!(d.sin().abs() < 1e-9 && d.cos() > 0.0, "{d}");
        }
    }

    #[test]
    fn lifted_legs_keep_their_ankles_and_feet() {
        let model = model();
        for betas in [vec![], vec![-2.0, 2.0]] {
            let body = BodyContext::new(&model, &betas).unwrap();
            let clip = ActivityClip::load(&activity_clip_dir(), ClipId::Sit75_18)
                .unwrap()
                .on_body(&body)
                .unwrap();
            for k in [0, clip.lowest / 2, clip.lowest] {
                let f = &clip.frames[k];
                let s = body.shaped.skeleton(&f.pose, f.transl).unwrap();
                let targets = [s.joints[joint::LEFT_ANKLE], s.joints[joint::RIGHT_ANKLE]];
                for dz in [-0.1, 0.0, 0.12] {
                    let mut lifted = f.clone();
                    lifted.transl.z += dz;
                    let (kept, miss) = keep_ankles(&body, &lifted, targets).unwrap();
                    if k == 0 && dz > 0.0 {
                        // Standing legs are straight: lifted, they cannot reach, and point
                        // straight at their ankles' places.
                        assert!(miss <= dz + 1e-6, "{miss}");
                        continue;
                    }
                    assert!(miss < 1e-6, "frame {k}, {dz} m: {miss}");
                    let t = body.shaped.skeleton(&kept.pose, kept.transl).unwrap();
                    // The pelvis stays lifted; each foot keeps its world orientation.
                    assert!((t.joints[joint::PELVIS] - s.joints[joint::PELVIS]).z - dz < 1e-9);
                    for a in [joint::LEFT_ANKLE, joint::RIGHT_ANKLE] {
                        let r = t.world_from_joint[a].matrix3.transpose()
                            * s.world_from_joint[a].matrix3;
                        assert!(matrix_to_axis_angle(r).length() < 1e-6);
                    }
                }
            }
        }
    }

    #[test]
    fn a_blend_and_an_idle_hold_join_their_ends_without_a_jump() {
        let model = model();
        let body = BodyContext::new(&model, &[]).unwrap();
        let clip = ActivityClip::load(&activity_clip_dir(), ClipId::Sit75_17)
            .unwrap()
            .on_body(&body)
            .unwrap();
        let (a, b) = (&clip.frames[0], &clip.frames[clip.lowest]);
        let frames = blend(a, b, 10);
        assert_eq!(frames.len(), 10);
        let step = |x: &BodyParams, y: &BodyParams| {
            (0..crate::body::skeleton::NUM_JOINTS)
                .map(|j| {
                    let (qa, qb) = (quat(x.joint_axis_angle(j)), quat(y.joint_axis_angle(j)));
                    qa.angle_between(qb)
                })
                .fold(0.0, f64::max)
        };
        let whole = step(a, b);
        let mut path = vec![a.clone()];
        path.extend(frames);
        path.push(b.clone());
        for w in path.windows(2) {
            assert!(
                step(&w[0], &w[1]) <= 0.25 * whole,
                "{} of {whole}",
                step(&w[0], &w[1])
            );
        }
        // Held 10 s: starts and ends on the base pose; the pelvis never moves.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let held = idle_frames(b, 400, Idle::SEATED, &mut rng);
        assert_eq!(held.len(), 400);
        assert!(step(&held[0], b) < 1e-6 && step(&held[399], b) < 1e-6);
        assert!(held
            .iter()
            .all(|f| f.transl == b.transl && f.joint_axis_angle(0) == b.joint_axis_angle(0)));
        for w in held.windows(2) {
            assert!(step(&w[0], &w[1]) < 0.05);
        }
        assert!(held.iter().any(|f| step(f, b) > 0.1), "it looks around");
    }
}
