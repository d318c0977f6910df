//! Activities beyond walking in a take (docs/ACTIVITIES.md): what a person does when a walk
//! ends — walk on, stand and look around, sit down on a seat and stand up again, pick
//! something up from the floor — drawn from the take's seed and the `[activities]` weights;
//! the one schema of those settings; and the frames each activity is made of, on the body
//! that does it, at its place, checked against the scene: a transition from the walker's last
//! pose (a blend, turning at a bounded rate), the clip (`motion::activity_clip`) placed and
//! fitted to the seat, a hold with procedural idle motion, padded to whole primitives so that
//! the walker takes over where it ends. The crowd (`synth::crowd`) schedules them.

use std::collections::HashMap;
use std::sync::Arc;

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::body::{joint, BodyParams};
use crate::math::random::{uniform_in, uniform_open01};
use crate::motion::activity_clip::{
    blend, heading, idle_frames, keep_ankles, max_joint_speed, placed, sitting_vertices,
    ActivityClip, ActivityClipError, ClipKind, ClipOnBody, Idle,
};
use crate::motion::cvae::BodyContext;
use crate::motion::primitive::{NEW_FRAMES, PRIMITIVE_RATE_HZ};
use crate::scene::mesh_distance::MeshDistance;
use crate::scene::{find_seats, SceneMesh, Seat, SeatSettings, WalkableMap};
use crate::walker::reward::path_leaves_floor;

/// Relative weights of what a person does next when a walk ends (`[activities.weights]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActivityWeights {
    /// Walk on to a new goal (default 1).
    pub walk: f64,
    /// Stand where the walk ended and look around (default 0).
    pub stand: f64,
    /// Walk to the nearest free seat, sit down, stay seated, stand up (default 0).
    pub sit: f64,
    /// Bend to pick something up from the floor where the walk ended (default 0).
    pub pick_up: f64,
}

impl Default for ActivityWeights {
    fn default() -> Self {
        Self {
            walk: 1.0,
            stand: 0.0,
            sit: 0.0,
            pick_up: 0.0,
        }
    }
}

impl ActivityWeights {
    /// The names a weight is given by.
    pub const NAMES: [&'static str; 4] = ["walk", "stand", "sit", "pick_up"];

    /// Weights given by name; those not named are 0 (unlike `[activities.weights]`, whose
    /// `walk` defaults to 1): what a campaign's `activity_weights` entries and
    /// `egogen-run --activity-weights` say. The message names the weight that is wrong.
    pub fn from_named<'a>(named: impl IntoIterator<Item = (&'a str, f64)>) -> Result<Self, String> {
        let mut w = Self {
            walk: 0.0,
            stand: 0.0,
            sit: 0.0,
            pick_up: 0.0,
        };
        for (name, v) in named {
            let slot = match name {
                "walk" => &mut w.walk,
                "stand" => &mut w.stand,
                "sit" => &mut w.sit,
                "pick_up" => &mut w.pick_up,
                other => {
                    return Err(format!(
                        "unknown activity `{other}` (expected {})",
                        Self::NAMES.join(", ")
                    ))
                }
            };
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("`{name}`: expected a weight ≥ 0, got {v}"));
            }
            *slot = v;
        }
        if w.walk + w.stand + w.sit + w.pick_up <= 0.0 {
            return Err("expected at least one weight > 0, got all zero".into());
        }
        Ok(w)
    }

    /// `walk=2,sit=1`: the weights above 0 by name (unnamed are 0).
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut named = Vec::new();
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (name, v) = part
                .split_once('=')
                .ok_or_else(|| format!("`{part}`: expected NAME=WEIGHT, e.g. walk=2,sit=1"))?;
            let v: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("`{part}`: expected a number after `=`"))?;
            named.push((name.trim(), v));
        }
        Self::from_named(named)
    }

    /// The weights above 0 as [`parse`](Self::parse) reads them.
    pub fn flag(&self) -> String {
        Self::NAMES
            .iter()
            .zip([self.walk, self.stand, self.sit, self.pick_up])
            .filter(|(_, v)| *v > 0.0)
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(",")
    }
}

/// What people do besides walking (`[activities]` of synth and run configs; docs/ACTIVITIES.md).
/// The default is walking only: takes as before.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActivitySettings {
    pub weights: ActivityWeights,
    /// How long a person stands and looks around (s, drawn uniformly; default [3, 8]).
    pub stand_s: [f64; 2],
    /// How long a person stays seated (s, drawn uniformly; default [4, 12]).
    pub sit_s: [f64; 2],
    /// Shortest transition from the walk into an activity (s; default 0.4): every joint
    /// blended from the last walking pose to the activity's first.
    pub blend_s: f64,
    /// Fastest turn in a transition (degrees per second; default 180): a person who arrives
    /// facing a seat turns round at this rate before sitting.
    pub turn_deg_per_s: f64,
    /// Farthest a sit clip's seated height is moved up or down to meet a seat (m; default
    /// 0.2): a seat no clip comes this close to is not sat on.
    pub seat_fit_m: f64,
}

impl Default for ActivitySettings {
    fn default() -> Self {
        Self {
            weights: ActivityWeights::default(),
            stand_s: [3.0, 8.0],
            sit_s: [4.0, 12.0],
            blend_s: 0.4,
            turn_deg_per_s: 180.0,
            seat_fit_m: 0.2,
        }
    }
}

impl ActivitySettings {
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Whether people only walk (every weight but `walk` zero): takes exactly as without
    /// activities.
    pub fn walk_only(&self) -> bool {
        let w = self.weights;
        w.stand == 0.0 && w.sit == 0.0 && w.pick_up == 0.0
    }

    /// What is wrong with these settings, if anything: the key (under `activities.`) and
    /// what was expected.
    pub fn problem(&self) -> Option<(&'static str, String)> {
        let w = self.weights;
        for (key, v) in [
            ("weights.walk", w.walk),
            ("weights.stand", w.stand),
            ("weights.sit", w.sit),
            ("weights.pick_up", w.pick_up),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Some((key, format!("expected a weight ≥ 0, got {v}")));
            }
        }
        if w.walk + w.stand + w.sit + w.pick_up <= 0.0 {
            return Some((
                "weights",
                "expected at least one weight > 0 (walk = 1 walks only), got all zero".into(),
            ));
        }
        for (key, [lo, hi]) in [("stand_s", self.stand_s), ("sit_s", self.sit_s)] {
            if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi && hi <= 3600.0) {
                return Some((
                    key,
                    format!(
                        "expected [MIN, MAX] seconds with 0 < MIN ≤ MAX ≤ 3600, got [{lo}, {hi}]"
                    ),
                ));
            }
        }
        if !(self.blend_s.is_finite() && (0.05..=5.0).contains(&self.blend_s)) {
            return Some((
                "blend_s",
                format!("expected 0.05–5 s, got {}", self.blend_s),
            ));
        }
        if !(self.turn_deg_per_s.is_finite() && self.turn_deg_per_s >= 10.0) {
            return Some((
                "turn_deg_per_s",
                format!(
                    "expected at least 10 degrees per second, got {}",
                    self.turn_deg_per_s
                ),
            ));
        }
        if !(self.seat_fit_m.is_finite() && (0.0..=0.5).contains(&self.seat_fit_m)) {
            return Some((
                "seat_fit_m",
                format!("expected 0–0.5 m, got {}", self.seat_fit_m),
            ));
        }
        None
    }
}

/// What a person does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Activity {
    Walk,
    Stand,
    Sit,
    PickUp,
}

impl Activity {
    /// Its name in configs and files (`walk`, `stand`, `sit`, `pick_up`).
    pub fn name(self) -> &'static str {
        match self {
            Activity::Walk => "walk",
            Activity::Stand => "stand",
            Activity::Sit => "sit",
            Activity::PickUp => "pick_up",
        }
    }
}

/// Where in an activity a frame is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Walking to the activity's place (a seat).
    Approach,
    /// Turning and blending into the activity, sitting down, standing up.
    Transition,
    /// The activity itself: standing and looking, seated, picking up.
    Hold,
}

impl Phase {
    /// Its name in files (`approach`, `transition`, `hold`).
    pub fn name(self) -> &'static str {
        match self {
            Phase::Approach => "approach",
            Phase::Transition => "transition",
            Phase::Hold => "hold",
        }
    }
}

/// Frames `start..end` of an agent's track spent in `activity`'s `phase` (frames in none: walking).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ActivitySegment {
    pub activity: Activity,
    pub phase: Phase,
    pub start_frame: usize,
    pub end_frame: usize,
}

impl ActivitySegment {
    /// What frame `f` of an agent with these segments does: the segment's activity and phase,
    /// or walking (no phase).
    pub fn at(segments: &[ActivitySegment], f: usize) -> (Activity, Option<Phase>) {
        segments
            .iter()
            .find(|s| (s.start_frame..s.end_frame).contains(&f))
            .map_or((Activity::Walk, None), |s| (s.activity, Some(s.phase)))
    }
}

/// One activity done, and how well it fitted its place.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ActivityRecord {
    pub activity: Activity,
    pub start_frame: usize,
    pub end_frame: usize,
    /// Where (the seated pelvis for a sit, else where the person stood).
    pub place: [f64; 2],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clip: Option<String>,
    /// The seat's object and surface height (m over the floor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seat: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seat_height_m: Option<f64>,
    /// How far the clip's seated height was moved to meet the seat (m, + up).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seat_fit_m: Option<f64>,
    /// Farthest an ankle stayed from where the clip put it once the clip was fitted to the
    /// seat (m: legs too short to reach a lower seat's floor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub foot_miss_m: Option<f64>,
    /// Deepest the buttocks and thighs went below the seat's surface where over it, sitting
    /// down, seated or standing up (m).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seat_penetration_m: Option<f64>,
    /// The turn in the transition into it (degrees).
    pub turn_deg: f64,
    /// Foot contact over its frames (paper Eq. 12 over 20-frame windows, as a walking
    /// primitive's).
    pub contact: f64,
    /// The fastest joint turn (rad/s) within 0.1 s of where it joins the walk before and
    /// after it, beside the same in the clip itself (`clip_joint_speed_rad_s`).
    pub join_joint_speed_rad_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clip_joint_speed_rad_s: Option<f64>,
    /// What the person looks at while doing it (the Aria gaze model fixates it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look_at: Option<LookAt>,
}

/// A point a person looks at over frames `start_frame..end_frame` of its track: the seat
/// from the walk to it until seated, the spot on the floor picked from while bending.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LookAt {
    /// World (m).
    pub point: [f64; 3],
    pub start_frame: usize,
    pub end_frame: usize,
}

/// An activity drawn but not done, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkippedActivity {
    pub activity: Activity,
    pub frame: usize,
    pub reason: String,
}

/// An activity's frames, ready to be taken [`NEW_FRAMES`] at a time.
#[derive(Debug, Clone)]
pub struct Performance {
    pub activity: Activity,
    pub frames: Vec<BodyParams>,
    /// Phases in order with their frame counts (summing to `frames.len()`).
    pub phases: Vec<(Phase, usize)>,
    pub record: ActivityRecord,
    /// The seat booked for it, given back when it ends.
    pub seat: Option<usize>,
}

/// Markers this close above the floor (m) are not tested against the scene: feet on a floor
/// modelled as a slab (walking is not tested there either).
const FLOOR_BAND_M: f64 = 0.05;

/// Every how many frames an idle hold (only the head and chest moving) is tested against the
/// scene; transitions and clips every second frame.
const IDLE_STRIDE: usize = 20;

/// Markers more than this far inside scene geometry (m) count as entering it (markers lie
/// on the skin; cushions and mesh noise give a little).
pub const ENTER_TOLERANCE_M: f64 = 0.03;

/// What activities need of a take's world: its seats and who sits on them, the clips, the
/// scene for the 3D check of every frame an activity plays. Built once per take, and only
/// when the take asks for more than walking.
pub struct ActivityWorld {
    pub settings: ActivitySettings,
    pub seats: Vec<Seat>,
    /// Booked by someone walking to it or sitting on it.
    pub taken: Vec<bool>,
    clips: Vec<ActivityClip>,
    mesh: Option<Arc<SceneMesh>>,
    /// The scene without the objects of one name (the seat sat on: its parts, a chair's
    /// backrest among them; `None`: the whole scene), for distances.
    distances: HashMap<Option<String>, Option<MeshDistance>>,
}

impl ActivityWorld {
    /// The activity world of a scene (`None`: open floor, no seats) and its map.
    pub fn new(
        settings: ActivitySettings,
        mesh: Option<Arc<SceneMesh>>,
        map: &WalkableMap,
        clip_dir: &std::path::Path,
    ) -> Result<Self, ActivityClipError> {
        let seats = match (&mesh, settings.weights.sit > 0.0) {
            (Some(m), true) => find_seats(m, map, &SeatSettings::default())
                .into_iter()
                .filter(|s| map.is_walkable_at(s.stand()))
                .collect(),
            _ => Vec::new(),
        };
        Ok(Self {
            settings,
            taken: vec![false; seats.len()],
            seats,
            clips: ActivityClip::load_shipped(clip_dir)?,
            mesh,
            distances: HashMap::new(),
        })
    }

    /// Draws what comes after a walk.
    pub fn draw(&self, rng: &mut ChaCha8Rng) -> Activity {
        let w = self.settings.weights;
        let total = w.walk + w.stand + w.sit + w.pick_up;
        let mut x = uniform_open01(rng) * total;
        for (a, v) in [
            (Activity::Stand, w.stand),
            (Activity::Sit, w.sit),
            (Activity::PickUp, w.pick_up),
        ] {
            if x < v {
                return a;
            }
            x -= v;
        }
        Activity::Walk
    }

    /// The nearest free seat whose standing point lies on `from`'s floor region, if any.
    pub fn nearest_free_seat(&self, map: &WalkableMap, from: DVec2) -> Option<usize> {
        let region = |p: DVec2| map.cell_of(p).map(|(i, j)| map.component[j * map.nx + i]);
        let here = region(from);
        (0..self.seats.len())
            .filter(|&s| !self.taken[s] && region(self.seats[s].stand()) == here)
            .min_by(|&a, &b| {
                let d = |s: usize| self.seats[s].stand().distance(from);
                d(a).total_cmp(&d(b)).then(a.cmp(&b))
            })
    }

    fn clip(&self, name: &str) -> &ActivityClip {
        self.clips
            .iter()
            .find(|c| c.name == name)
            .expect("shipped clips are loaded together")
    }

    /// The scene's distance field without the objects named `without` (cached).
    fn distance(&mut self, without: Option<&str>) -> Option<&MeshDistance> {
        let mesh = self.mesh.clone()?;
        self.distances
            .entry(without.map(str::to_string))
            .or_insert_with(|| match without {
                None => MeshDistance::new(&mesh),
                Some(name) => {
                    // The same vertices, the triangles of every other object.
                    let kept: Vec<usize> = (0..mesh.triangles.len())
                        .filter(|&t| {
                            let o = mesh.triangle_object[t].0 as usize;
                            mesh.objects
                                .get(o.wrapping_sub(1))
                                .is_none_or(|o| o.name != name)
                        })
                        .collect();
                    let rest = SceneMesh {
                        vertices: mesh.vertices.clone(),
                        triangles: kept.iter().map(|&t| mesh.triangles[t]).collect(),
                        triangle_object: kept.iter().map(|&t| mesh.triangle_object[t]).collect(),
                        objects: mesh.objects.clone(),
                        file_face_objects: None,
                    };
                    MeshDistance::new(&rest)
                }
            })
            .as_ref()
    }

    /// The first frame of `frames` (in `phases`: every second frame of a transition, every
    /// `hold_stride`-th of a hold, and the last) whose body markers above the floor's band
    /// ([`FLOOR_BAND_M`] over `floor_z`) enter the scene (but the objects named `without`)
    /// deeper than [`ENTER_TOLERANCE_M`], and how
    /// deep.
    fn first_entry(
        &mut self,
        body: &BodyContext,
        frames: &[BodyParams],
        phases: &[(Phase, usize)],
        hold_stride: usize,
        without: Option<&str>,
        floor_z: f64,
    ) -> Option<(usize, f64)> {
        let distance = self.distance(without)?;
        let mut checked = Vec::new();
        let mut start = 0;
        for &(phase, n) in phases {
            let stride = if phase == Phase::Hold { hold_stride } else { 2 };
            checked.extend((start..start + n).step_by(stride));
            start += n;
        }
        checked.push(frames.len().saturating_sub(1));
        checked
            .into_iter()
            .filter(|&k| k < frames.len())
            .find_map(|k| {
                let f = &frames[k];
                let mf = body
                    .shaped
                    .marker_frame(&f.pose, f.transl, &body.marker_ids)
                    .ok()?;
                let deepest = mf
                    .markers
                    .iter()
                    .filter(|m| m.z > floor_z + FLOOR_BAND_M)
                    .map(|m| distance.signed_distance(*m))
                    .fold(f64::INFINITY, f64::min);
                (deepest < -ENTER_TOLERANCE_M).then_some((k, -deepest))
            })
    }

    /// Whether an activity played where the walk ended fits there: no frame enters the
    /// scene ([`Self::first_entry`]) and the pelvis stays on the walkable floor (the walker
    /// takes over where it ends); else why not.
    #[allow(clippy::too_many_arguments)]
    fn fits_here(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        frames: &[BodyParams],
        phases: &[(Phase, usize)],
        hold_stride: usize,
        floor_z: f64,
    ) -> Result<(), String> {
        if let Some((k, depth)) = self.first_entry(body, frames, phases, hold_stride, None, floor_z)
        {
            return Err(format!(
                "the body would enter the scene {depth:.2} m at its frame {k}"
            ));
        }
        match off_floor(body, map, frames)? {
            Some(k) => Err(format!(
                "the pelvis would leave the walkable floor at its frame {k}"
            )),
            None => Ok(()),
        }
    }

    /// The clip `name` on `body`, its first frame standing where `last` stands and facing its
    /// way, on the floor at `floor_z`; and where that is.
    fn where_standing(
        &self,
        body: &BodyContext,
        last: &BodyParams,
        name: &str,
        floor_z: f64,
    ) -> Result<(Vec<BodyParams>, DVec2), String> {
        let clip = self.clip(name).on_body(body).map_err(|e| e.to_string())?;
        let (pelvis, facing) = pelvis_and_heading(body, last)?;
        let frames = placed(
            &clip.frames,
            body.shaped.rest_joints[joint::PELVIS],
            (clip.pelvis[0], clip.headings[0]),
            (pelvis, facing),
            |_| floor_z,
        );
        Ok((frames, pelvis))
    }

    /// Standing where `last` stands, looking around for a drawn time.
    pub fn stand(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, String> {
        let (standing, pelvis) = self.where_standing(body, last, "75_18", floor_z)?;
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
        self.fits_here(body, map, &frames, &phases, IDLE_STRIDE, floor_z)
            .map_err(|why| format!("standing there, {why}"))?;
        Ok(Performance {
            activity: Activity::Stand,
            record: record(Activity::Stand, pelvis, turn),
            frames,
            phases,
            seat: None,
        })
    }

    /// Bending to pick something up from the floor in front of where `last` stands.
    pub fn pick_up(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, String> {
        let (played, pelvis) = self.where_standing(body, last, "64_28", floor_z)?;
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
        self.fits_here(body, map, &frames, &phases, 2, floor_z)
            .map_err(|why| format!("bending there, {why}"))?;
        let mut r = record(Activity::PickUp, pelvis, turn);
        r.clip = Some("64_28".into());
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
        })
    }

    /// Sitting down on seat `s` from where `last` stands, staying seated for a drawn time,
    /// standing up: the sit clip nearest the seat's height, moved to the seat (its seated
    /// pelvis on the seat's place, facing the seat's way) and fitted to its height.
    #[allow(clippy::too_many_arguments)]
    pub fn sit(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        last: &BodyParams,
        s: usize,
        floor_z: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Performance, String> {
        let seat = self.seats[s].clone();
        let seat_h = seat.surface_z_m - floor_z;
        let clips: Vec<ClipOnBody> = self
            .clips
            .iter()
            .filter(|c| c.kind == ClipKind::Sit)
            .map(|c| c.on_body(body))
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?;
        let clip = clips
            .iter()
            .min_by(|a, b| {
                (seat_h - a.seat_contact_z)
                    .abs()
                    .total_cmp(&(seat_h - b.seat_contact_z).abs())
            })
            .ok_or("no sit clip")?;
        let fit = seat_h - clip.seat_contact_z;
        if fit.abs() > self.settings.seat_fit_m {
            return Err(format!(
                "no sit clip comes within activities.seat_fit_m = {} m of the {:.2} m seat of {} (nearest: {} at {:.2} m)",
                self.settings.seat_fit_m, seat_h, seat.object_name, clip.name, clip.seat_contact_z
            ));
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
            .ok_or_else(|| {
                format!(
                    "standing in front of the seat of {}, the body would stand over furniture \
                     (the clip stands {:.2} m in front of where it sits)",
                    seat.object_name,
                    standing_at(DVec2::ZERO, 0).length()
                )
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
            let s = body
                .shaped
                .skeleton(&g.pose, g.transl)
                .map_err(|e| e.to_string())?;
            let ankles = [s.joints[joint::LEFT_ANKLE], s.joints[joint::RIGHT_ANKLE]];
            let (kept, miss) = keep_ankles(body, f, ankles).map_err(|e| e.to_string())?;
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
            return Err(format!(
                "sitting on {}, the body would enter the scene {depth:.2} m at its frame {k}",
                seat.object_name
            ));
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

    /// The frames from `last` into `first` (neither included): a blend of at least
    /// `blend_s`, longer where the body must turn faster than `turn_deg_per_s` or move its
    /// pelvis faster than 0.6 m/s; and the turn (degrees).
    fn transition(
        &self,
        body: &BodyContext,
        last: &BodyParams,
        first: &BodyParams,
    ) -> Result<(Vec<BodyParams>, f64), String> {
        let (pa, ha) = pelvis_and_heading(body, last)?;
        let (pb, hb) = pelvis_and_heading(body, first)?;
        let turn = (hb - ha + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        let s = self.settings;
        let seconds = s
            .blend_s
            .max(turn.abs().to_degrees() / s.turn_deg_per_s)
            .max(pa.distance(pb) / 0.6);
        let n = (seconds * PRIMITIVE_RATE_HZ).round().max(1.0) as usize;
        Ok((blend(last, first, n), turn.to_degrees()))
    }
}

fn record(activity: Activity, place: DVec2, turn_deg: f64) -> ActivityRecord {
    ActivityRecord {
        activity,
        start_frame: 0,
        end_frame: 0,
        place: place.to_array(),
        clip: None,
        seat: None,
        seat_height_m: None,
        seat_fit_m: None,
        foot_miss_m: None,
        seat_penetration_m: None,
        turn_deg,
        contact: f64::NAN,
        join_joint_speed_rad_s: f64::NAN,
        clip_joint_speed_rad_s: None,
        look_at: None,
    }
}

/// Frames of a hold of about `seconds` after `before` frames and before `after`, such that
/// the whole is a whole number of primitives' new frames (at least one frame more).
fn rounded_hold(before: usize, seconds: f64, after: usize) -> usize {
    let per = NEW_FRAMES;
    let want = before + ((seconds * PRIMITIVE_RATE_HZ).round() as usize).max(1) + after;
    want.div_ceil(per) * per - before - after
}

/// The spot on the floor below the hands where they reach lowest in `frames`.
fn lowest_reach(
    body: &BodyContext,
    frames: &[BodyParams],
    floor_z: f64,
) -> Result<[f64; 3], String> {
    let mut best = [0.0, 0.0, f64::INFINITY];
    for f in frames {
        let s = body
            .shaped
            .skeleton(&f.pose, f.transl)
            .map_err(|e| e.to_string())?;
        let mid = (s.joints[joint::LEFT_WRIST] + s.joints[joint::RIGHT_WRIST]) * 0.5;
        if mid.z < best[2] {
            best = [mid.x, mid.y, mid.z];
        }
    }
    Ok([best[0], best[1], floor_z])
}

/// A pose's pelvis (horizontal) and facing.
fn pelvis_and_heading(body: &BodyContext, p: &BodyParams) -> Result<(DVec2, f64), String> {
    let s = body
        .shaped
        .skeleton(&p.pose, p.transl)
        .map_err(|e| e.to_string())?;
    let q = s.joints[joint::PELVIS];
    Ok((DVec2::new(q.x, q.y), heading(&s.joints)))
}

/// The first frame of `frames` whose pelvis path from the frame before passes over a cell of
/// the walkable map that is not walkable (the walk's own test: the walker takes over where an
/// activity ends).
fn off_floor(
    body: &BodyContext,
    map: &WalkableMap,
    frames: &[BodyParams],
) -> Result<Option<usize>, String> {
    let mut before: Option<DVec2> = None;
    for (k, f) in frames.iter().enumerate() {
        let (p, _) = pelvis_and_heading(body, f)?;
        if path_leaves_floor(map, before.unwrap_or(p), p) {
            return Ok(Some(k));
        }
        before = Some(p);
    }
    Ok(None)
}

/// Deepest the buttocks and thighs (vertices moved most by the pelvis or a hip) go below the
/// seat's surface where they are over it, in `frames` (m).
fn seat_penetration(
    body: &BodyContext,
    frames: &[BodyParams],
    seat: &Seat,
    map: &WalkableMap,
) -> Result<f64, String> {
    let cells: std::collections::HashSet<usize> = seat.cells.iter().copied().collect();
    let sitting = sitting_vertices(body);
    let mut deepest: f64 = 0.0;
    for f in frames.iter().step_by(2) {
        let s = body
            .shaped
            .skeleton(&f.pose, f.transl)
            .map_err(|e| e.to_string())?;
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
    use crate::scene::seats::test_scenes::room_with_chair;
    use crate::scene::WalkableSettings;
    use rand_core::SeedableRng;

    fn world(settings: ActivitySettings, mesh: SceneMesh) -> (ActivityWorld, WalkableMap) {
        let map = WalkableMap::build(&mesh, WalkableSettings::default()).unwrap();
        let acts =
            ActivityWorld::new(settings, Some(Arc::new(mesh)), &map, &activity_clip_dir()).unwrap();
        (acts, map)
    }

    fn sitting() -> ActivitySettings {
        ActivitySettings {
            weights: ActivityWeights {
                walk: 1.0,
                stand: 0.0,
                sit: 1.0,
                pick_up: 0.0,
            },
            ..Default::default()
        }
    }

    /// A person standing at the seat's standing point, facing the seat (the way they walked).
    fn arriving(acts: &ActivityWorld, body: &BodyContext, s: usize) -> BodyParams {
        let seat = &acts.seats[s];
        let clip = acts.clip("75_18").on_body(body).unwrap();
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
                    Err(e) if !betas.is_empty() && e.contains("activities.seat_fit_m") => continue,
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
            assert!(err.contains("activities.seat_fit_m"), "{err}");
        }
    }

    #[test]
    fn weights_given_by_name_read_back_from_their_flag_and_bad_ones_are_named() {
        let w = ActivityWeights::parse("walk=2, sit=0.5").unwrap();
        assert_eq!((w.walk, w.stand, w.sit, w.pick_up), (2.0, 0.0, 0.5, 0.0));
        assert_eq!(w.flag(), "walk=2,sit=0.5");
        assert_eq!(ActivityWeights::parse(&w.flag()).unwrap(), w);
        let tiny = ActivityWeights::from_named([("pick_up", 1e-300)]).unwrap();
        assert_eq!(ActivityWeights::parse(&tiny.flag()).unwrap(), tiny);
        for (text, says) in [
            ("run=1", "unknown activity `run`"),
            ("sit=-1", "`sit`: expected a weight ≥ 0, got -1"),
            ("sit=NaN", "`sit`: expected a weight ≥ 0"),
            ("sit", "expected NAME=WEIGHT"),
            ("sit=x", "expected a number"),
            ("walk=0", "all zero"),
            ("", "all zero"),
        ] {
            let e = ActivityWeights::parse(text).unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
        }
    }

    #[test]
    fn a_frame_is_labelled_by_the_segment_holding_it_or_walking() {
        let seg = |activity, phase, start_frame, end_frame| ActivitySegment {
            activity,
            phase,
            start_frame,
            end_frame,
        };
        let segments = [
            seg(Activity::Sit, Phase::Approach, 10, 20),
            seg(Activity::Sit, Phase::Transition, 20, 30),
            seg(Activity::Stand, Phase::Hold, 40, 41),
        ];
        let at = |f| ActivitySegment::at(&segments, f);
        assert_eq!(at(9), (Activity::Walk, None));
        assert_eq!(at(10), (Activity::Sit, Some(Phase::Approach)));
        assert_eq!(at(20), (Activity::Sit, Some(Phase::Transition)));
        assert_eq!(at(30), (Activity::Walk, None));
        assert_eq!(at(40), (Activity::Stand, Some(Phase::Hold)));
        assert_eq!(at(41), (Activity::Walk, None));
        assert_eq!(ActivitySegment::at(&[], 5), (Activity::Walk, None));
        // Names as files spell them.
        for a in [
            Activity::Walk,
            Activity::Stand,
            Activity::Sit,
            Activity::PickUp,
        ] {
            assert_eq!(
                serde_json::to_string(&a).unwrap(),
                format!("\"{}\"", a.name())
            );
        }
        for p in [Phase::Approach, Phase::Transition, Phase::Hold] {
            assert_eq!(
                serde_json::to_string(&p).unwrap(),
                format!("\"{}\"", p.name())
            );
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
