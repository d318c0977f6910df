//! Activities beyond walking in a take (docs/ACTIVITIES.md): what a person does when a walk
//! ends — walk on, stand and look around, sit down on a seat and stand up again, pick
//! something up from the floor (one of the scene's own things walked to, or egogen's own
//! object) — drawn from the take's seed and the `[activities]` weights;
//! the one schema of those settings; and the frames each activity is made of, on the body
//! that does it, at its place, checked against the scene: a transition from the walker's last
//! pose (a blend, turning at a bounded rate), the clip (`motion::activity_clip`) placed and
//! fitted to the seat, a hold with procedural idle motion, padded to whole primitives so that
//! the walker takes over where it ends. The crowd (`synth::crowd`) schedules them.
//!
//! Here: the schema and the records; `world` (the activity world every activity shares:
//! seats, the scene's small things, clips, the scene check, the transition), one file per activity (`stand`,
//! `pick_up`, `sit`), `refusal` (why one is skipped, typed).

use serde::{Deserialize, Serialize};

use crate::body::BodyParams;

mod pick_up;
mod refusal;
mod sit;
mod stand;
mod world;

pub(crate) use refusal::Refusal;
pub(crate) use world::ActivityWorld;

/// Relative weights of what a person does next when a walk ends (`[activities.weights]`: a
/// table by name; an array is refused, not read by position), one per [`Activity`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActivityWeights([f64; Activity::ALL.len()]);

impl Default for ActivityWeights {
    /// Walking only: `walk` 1, the others 0.
    fn default() -> Self {
        Self::named_only([(Activity::Walk, 1.0)])
    }
}

/// Written as a table by name, in [`Activity::ALL`]'s order.
impl Serialize for ActivityWeights {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for a in Activity::ALL {
            map.serialize_entry(a.name(), &self.weight(a))?;
        }
        map.end()
    }
}

/// `[activities.weights]`: a table of weights by name over the defaults (`walk` 1, the others
/// 0); unknown names and arrays are refused.
impl<'de> Deserialize<'de> for ActivityWeights {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let named = std::collections::BTreeMap::<String, f64>::deserialize(d)?;
        let mut w = ActivityWeights::default();
        for (name, v) in named {
            w.0[Activity::named(&name).map_err(D::Error::custom)? as usize] = v;
        }
        Ok(w)
    }
}

impl ActivityWeights {
    /// These weights, the others 0.
    fn named_only(named: impl IntoIterator<Item = (Activity, f64)>) -> Self {
        let mut w = Self([0.0; Activity::ALL.len()]);
        for (a, v) in named {
            w.0[a as usize] = v;
        }
        w
    }

    /// The weight of `activity`.
    pub(crate) fn weight(&self, activity: Activity) -> f64 {
        self.0[activity as usize]
    }

    /// The sum of the weights, added in [`Activity::ALL`]'s order.
    fn total(&self) -> f64 {
        self.0.iter().sum()
    }

    /// Draws what comes after a walk: each activity in proportion to its weight.
    pub(crate) fn draw(&self, rng: &mut rand_chacha::ChaCha8Rng) -> Activity {
        let mut x = crate::math::random::uniform_open01(rng) * self.total();
        for a in Activity::ALL.into_iter().filter(|&a| a != Activity::Walk) {
            let v = self.weight(a);
            if x < v {
                return a;
            }
            x -= v;
        }
        Activity::Walk
    }

    /// What is wrong with these weights, if anything: the activity whose weight it is
    /// (`None`: all of them) and what was expected. Each is finite and ≥ 0, and so is their
    /// sum, which is > 0.
    pub(crate) fn problem(&self) -> Option<(Option<Activity>, String)> {
        for a in Activity::ALL {
            let v = self.weight(a);
            if !(v.is_finite() && v >= 0.0) {
                return Some((Some(a), format!("expected a weight ≥ 0, got {v}")));
            }
        }
        let total = self.total();
        if !total.is_finite() {
            return Some((
                None,
                format!(
                    "expected weights whose sum is finite, got a sum of {total} (relative \
                     weights: 1, 2, 0.5 … say as much as 1e300 does)"
                ),
            ));
        }
        if total <= 0.0 {
            return Some((
                None,
                "expected at least one weight > 0 (walk = 1 walks only), got all zero".into(),
            ));
        }
        None
    }

    /// Weights given by name; those not named are 0 (unlike `[activities.weights]`, whose
    /// `walk` defaults to 1): what a campaign's `activity_weights` entries and
    /// `egogen-run --activity-weights` say. The message names the weight that is wrong.
    pub(crate) fn from_named<'a>(
        named: impl IntoIterator<Item = (&'a str, f64)>,
    ) -> Result<Self, String> {
        let mut w = Self::named_only([]);
        let mut given: Vec<Activity> = Vec::new();
        for (name, v) in named {
            let a = Activity::named(name)?;
            if given.contains(&a) {
                return Err(format!("`{name}` is given twice: give each weight once"));
            }
            given.push(a);
            w.0[a as usize] = v;
        }
        if let Some((a, what)) = w.problem() {
            return Err(match a {
                Some(a) => format!("`{}`: {what}", a.name()),
                None => what,
            });
        }
        Ok(w)
    }

    /// `walk=2,sit=1`: the weights above 0 by name (unnamed are 0).
    pub(crate) fn parse(text: &str) -> Result<Self, String> {
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
    pub(crate) fn flag(&self) -> String {
        Activity::ALL
            .into_iter()
            .filter(|&a| self.weight(a) > 0.0)
            .map(|a| format!("{}={}", a.name(), self.weight(a)))
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
    #[serde(deserialize_with = "min_max")]
    pub stand_s: [f64; 2],
    /// How long a person stays seated (s, drawn uniformly; default [4, 12]).
    #[serde(deserialize_with = "min_max")]
    pub sit_s: [f64; 2],
    /// Shortest transition from the walk into an activity (s; default 0.4): every joint
    /// blended from the last walking pose to the activity's first.
    pub blend_s: f64,
    /// Fastest turn in a transition (degrees per second; default 180): a person who arrives
    /// facing a seat turns round at this rate before sitting.
    pub turn_deg_per_s: f64,
    /// Farthest a sit clip's seated height is moved up or down to meet a seat (m; default
    /// 0.7: every seat of 0.35–0.75 m for the bodies the project draws): a seat no clip comes
    /// this close to is not sat on.
    pub seat_fit_m: f64,
}

/// `[MIN, MAX]`: exactly two numbers (a third is refused, not dropped).
fn min_max<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    use serde::de::Error;
    let v = Vec::<f64>::deserialize(d)?;
    <[f64; 2]>::try_from(v.as_slice()).map_err(|_| {
        D::Error::custom(format!(
            "expected [MIN, MAX]: two numbers, got {} ({v:?})",
            v.len()
        ))
    })
}

impl Default for ActivitySettings {
    fn default() -> Self {
        Self {
            weights: ActivityWeights::default(),
            stand_s: [3.0, 8.0],
            sit_s: [4.0, 12.0],
            blend_s: 0.4,
            turn_deg_per_s: 180.0,
            seat_fit_m: 0.7,
        }
    }
}

impl ActivitySettings {
    pub(crate) fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Whether people only walk (every weight but `walk` zero): takes exactly as without
    /// activities.
    pub(crate) fn walk_only(&self) -> bool {
        Activity::ALL
            .into_iter()
            .all(|a| a == Activity::Walk || self.weights.weight(a) == 0.0)
    }

    /// What is wrong with these settings, if anything: the key (under `activities.`) and
    /// what was expected.
    pub(crate) fn problem(&self) -> Option<(String, String)> {
        if let Some((a, what)) = self.weights.problem() {
            let key = match a {
                Some(a) => format!("weights.{}", a.name()),
                None => "weights".into(),
            };
            return Some((key, what));
        }
        for (key, [lo, hi]) in [("stand_s", self.stand_s), ("sit_s", self.sit_s)] {
            if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi && hi <= 3600.0) {
                return Some((
                    key.into(),
                    format!(
                        "expected [MIN, MAX] seconds with 0 < MIN ≤ MAX ≤ 3600, got [{lo}, {hi}]"
                    ),
                ));
            }
        }
        if !(self.blend_s.is_finite() && (0.05..=5.0).contains(&self.blend_s)) {
            return Some((
                "blend_s".into(),
                format!("expected 0.05–5 s, got {}", self.blend_s),
            ));
        }
        if !(self.turn_deg_per_s.is_finite() && self.turn_deg_per_s >= 10.0) {
            return Some((
                "turn_deg_per_s".into(),
                format!(
                    "expected at least 10 degrees per second, got {}",
                    self.turn_deg_per_s
                ),
            ));
        }
        if !(self.seat_fit_m.is_finite() && (0.0..=1.0).contains(&self.seat_fit_m)) {
            return Some((
                "seat_fit_m".into(),
                format!("expected 0–1 m, got {}", self.seat_fit_m),
            ));
        }
        None
    }
}

impl ActivityWorld {
    /// Plays `activity` where the walk that `last` ends has ended, in its own file's way
    /// (`stand.rs`, `pick_up.rs`): its frames, or why not. Walking on and sitting (which walks
    /// to a seat first, `sit.rs`) are the crowd's to start.
    pub(crate) fn play_here(
        &mut self,
        activity: Activity,
        body: &crate::motion::cvae::BodyContext,
        map: &crate::scene::WalkableMap,
        last: &BodyParams,
        floor_z: f64,
        rng: &mut rand_chacha::ChaCha8Rng,
    ) -> Result<Performance, Refusal> {
        match activity {
            Activity::Stand => self.stand(body, map, last, floor_z, rng),
            Activity::PickUp => self.pick_up(body, map, last, floor_z, rng),
            Activity::Walk | Activity::Sit => Err(Refusal::NotHere(activity.name())),
        }
    }
}

/// What a person does. A new activity is a variant here (with its name, and its arm in
/// [`ActivityWorld::play_here`]) and a file of its own beside `stand.rs`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Activity {
    Walk,
    Stand,
    Sit,
    PickUp,
}

impl Activity {
    /// Every activity, in the order weights are drawn and written.
    pub(crate) const ALL: [Activity; 4] = [
        Activity::Walk,
        Activity::Stand,
        Activity::Sit,
        Activity::PickUp,
    ];

    /// Its name in configs and files (`walk`, `stand`, `sit`, `pick_up`).
    pub(crate) fn name(self) -> &'static str {
        match self {
            Activity::Walk => "walk",
            Activity::Stand => "stand",
            Activity::Sit => "sit",
            Activity::PickUp => "pick_up",
        }
    }

    /// The activity of a name, or an error listing the names.
    pub(crate) fn named(name: &str) -> Result<Activity, String> {
        Activity::ALL
            .into_iter()
            .find(|a| a.name() == name)
            .ok_or_else(|| {
                let names: Vec<_> = Activity::ALL.into_iter().map(Activity::name).collect();
                format!("unknown activity `{name}` (expected {})", names.join(", "))
            })
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
    pub(crate) fn name(self) -> &'static str {
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
    pub(crate) fn at(segments: &[ActivitySegment], f: usize) -> (Activity, Option<Phase>) {
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
    /// Where the buttocks and thighs rest once seated, over the seat's surface (m; − into
    /// it): the lowest of them within 0.25 m of the pelvis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seat_gap_m: Option<f64>,
    /// Farthest an ankle moved from where the clip put it once the clip was fitted to the
    /// seat (m): drawn back under the hip on a seat too high for the leg to reach the clip's
    /// foot, hanging where even that is too far.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub foot_miss_m: Option<f64>,
    /// How far a chair at a table or desk was pulled out to sit on (m).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chair_pulled_m: Option<f64>,
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
    /// The scene thing a pick-up bent to take (whether the hand took it: the person's
    /// `held_objects`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub object: Option<String>,
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

/// An activity's frames, ready to be taken [`crate::motion::primitive::NEW_FRAMES`] at a time.
#[derive(Debug, Clone)]
pub(crate) struct Performance {
    pub activity: Activity,
    pub frames: Vec<BodyParams>,
    /// Phases in order with their frame counts (summing to `frames.len()`).
    pub phases: Vec<(Phase, usize)>,
    pub record: ActivityRecord,
    /// The seat booked for it, given back when it ends.
    pub seat: Option<usize>,
    /// A scene object it moves (a chair pulled out from its table).
    pub moved: Option<MovedObject>,
}

/// A scene object an activity moves: a chair pulled out from its table, sat on and pushed
/// back.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MovedObject {
    /// The scene object's name.
    pub object: String,
    /// Where it is moved to from where the scene has it (horizontal, m).
    pub offset_m: [f64; 2],
    /// Share of `offset_m` it is moved by at each frame of the activity.
    pub out: Vec<f64>,
    /// Frames it takes to slide back (smoothly) after the activity.
    pub back_frames: usize,
}

/// A scene object a person moved in a take, as `summary.json` lists it: which, over which
/// frames, how far at most; where at each frame is in `moved_objects.npy`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct ObjectMove {
    /// The scene object's name.
    pub name: String,
    /// From this frame it moves…
    pub start_frame: usize,
    /// … and from this one it stands where the scene has it again.
    pub end_frame: usize,
    /// Where it is moved to, at most (horizontal, m).
    pub offset_m: [f64; 2],
    /// Share of `offset_m` at each frame from `start_frame`.
    #[serde(skip)]
    pub shares: Vec<f64>,
}

impl ObjectMove {
    /// Its horizontal offset from where the scene has it at take frame `f` (m).
    pub(crate) fn offset_at(&self, f: usize) -> [f64; 2] {
        let share = f
            .checked_sub(self.start_frame)
            .and_then(|k| self.shares.get(k))
            .copied()
            .unwrap_or(0.0);
        self.offset_m.map(|x| x * share)
    }
}

impl MovedObject {
    /// The move from take frame `start`, the activity's first.
    pub(crate) fn starting_at(&self, start: usize) -> ObjectMove {
        let shares = self.shares();
        ObjectMove {
            name: self.object.clone(),
            start_frame: start,
            end_frame: start + shares.len(),
            offset_m: self.offset_m,
            shares,
        }
    }

    /// Share of the offset at each frame from the activity's first to the end of the slide
    /// back.
    fn shares(&self) -> Vec<f64> {
        let last = self.out.last().copied().unwrap_or(0.0);
        let back = (1..=self.back_frames).map(|k| {
            let t = k as f64 / self.back_frames as f64;
            last * (1.0 - t * t * (3.0 - 2.0 * t))
        });
        self.out.iter().copied().chain(back).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_given_by_name_read_back_from_their_flag_and_bad_ones_are_named() {
        let w = ActivityWeights::parse("walk=2, sit=0.5").unwrap();
        let by_name = [
            Activity::Walk,
            Activity::Stand,
            Activity::Sit,
            Activity::PickUp,
        ];
        assert_eq!(by_name.map(|a| w.weight(a)), [2.0, 0.0, 0.5, 0.0]);
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
            ("walk=1,walk=0,sit=1", "`walk` is given twice"),
            ("walk=1e308,sit=1e308", "sum is finite"),
        ] {
            let e = ActivityWeights::parse(text).unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
        }
    }

    #[test]
    fn activity_settings_refuse_arrays_for_tables_extra_numbers_and_weights_that_overflow() {
        let read = |text: &str| toml::from_str::<ActivitySettings>(text);
        let ok = read("weights = { walk = 1.0, sit = 2.0 }\nsit_s = [1.0, 2.0]").unwrap();
        let w = ok.weights;
        assert_eq!(
            (w.weight(Activity::Walk), w.weight(Activity::Sit)),
            (1.0, 2.0)
        );
        assert_eq!(ok.sit_s, [1.0, 2.0]);
        // Not read by position.
        let e = read("weights = [1.0, 2.0]").unwrap_err().to_string();
        assert!(e.contains("expected a map"), "{e}");
        // Not the first two of three.
        let e = read("sit_s = [1.0, 2.0, 3.0]").unwrap_err().to_string();
        assert!(e.contains("two numbers, got 3"), "{e}");
        let e = read("weights = { run = 1.0 }").unwrap_err().to_string();
        assert!(e.contains("unknown activity `run`"), "{e}");
        // Each weight finite, their sum infinite: refused by key, not walked as the first.
        let huge = read("weights = { walk = 1e308, sit = 1e308 }").unwrap();
        let (key, what) = huge.problem().unwrap();
        assert_eq!(key, "weights");
        assert!(what.contains("sum is finite"), "{what}");
        // As before: a JSON record of the weights reads back.
        let w = ActivityWeights::parse("walk=2,sit=1").unwrap();
        let back: ActivityWeights =
            serde_json::from_str(&serde_json::to_string(&w).unwrap()).unwrap();
        assert_eq!(back, w);
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
}
