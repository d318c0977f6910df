//! The activity world of a take: its seats and who sits on them, the scene's small things on
//! the floor and who took them, the clips, the scene each activity's frames are checked against; what every activity shares (placing a clip where
//! the walk ended, the transition into it, the checks).

use std::collections::HashMap;
use std::sync::Arc;

use glam::DVec2;
use rand_chacha::ChaCha8Rng;

use super::refusal::{Doing, Refusal};
use super::{Activity, ActivityRecord, ActivitySettings, Phase};
use crate::body::{joint, BodyParams, PoseError};
use crate::motion::activity_clip::{
    blend, heading, placed, ActivityClip, ActivityClipError, ClipId,
};
use crate::motion::cvae::BodyContext;
use crate::motion::primitive::{NEW_FRAMES, PRIMITIVE_RATE_HZ};
use crate::scene::mesh_distance::MeshDistance;
use crate::scene::path_plan::PathField;
use crate::scene::small_object::{things_on_floor, SceneThing};
use crate::scene::{find_seats, SceneMesh, Seat, SeatSettings, WalkableMap};
use crate::walker::reward::path_leaves_floor;

/// Markers this close above the floor (m) are not tested against the scene: feet on a floor
/// modelled as a slab (walking is not tested there either).
pub(super) const FLOOR_BAND_M: f64 = 0.05;

/// Farthest a scene thing's bottom may lie from the floor a person stands on for it to be
/// picked up from that floor (m).
const THING_ON_FLOOR_M: f64 = 0.03;

/// Farthest a person walks to pick up one of the scene's things (m on foot): a thing in
/// another room far off is left where it is.
pub(crate) const THING_WALK_M: f64 = 6.0;

/// Every how many frames an idle hold (only the head and chest moving) is tested against the
/// scene; transitions and clips every second frame.
pub(super) const IDLE_STRIDE: usize = 20;

/// Markers more than this far inside scene geometry (m) count as entering it (markers lie
/// on the skin; cushions and mesh noise give a little).
pub(crate) const ENTER_TOLERANCE_M: f64 = 0.03;

/// What activities need of a take's world: its seats and who sits on them, the clips, the
/// scene for the 3D check of every frame an activity plays. Built once per take, and only
/// when the take asks for more than walking.
pub(crate) struct ActivityWorld {
    pub settings: ActivitySettings,
    pub seats: Vec<Seat>,
    /// Booked by someone walking to it or sitting on it.
    pub taken: Vec<bool>,
    /// The scene's small things a pick-up may take (found only where pick-ups are drawn).
    pub things: Vec<SceneThing>,
    /// Booked by someone walking to it, or taken.
    pub thing_taken: Vec<bool>,
    pub(super) clips: Vec<ActivityClip>,
    mesh: Option<Arc<SceneMesh>>,
    /// The scene without the objects of one name (the seat sat on: its parts, a chair's
    /// backrest among them; `None`: the whole scene), for distances.
    distances: HashMap<Option<String>, Option<MeshDistance>>,
}

impl ActivityWorld {
    /// The activity world of a scene (`None`: open floor, no seats) and its map.
    pub(crate) fn new(
        settings: ActivitySettings,
        mesh: Option<Arc<SceneMesh>>,
        map: &WalkableMap,
        clip_dir: &std::path::Path,
    ) -> Result<Self, ActivityClipError> {
        let seats = match (&mesh, settings.weights.weight(Activity::Sit) > 0.0) {
            (Some(m), true) => find_seats(m, map, &SeatSettings::default())
                .into_iter()
                .filter(|s| map.is_walkable_at(s.stand()))
                .collect(),
            _ => Vec::new(),
        };
        let things = match (&mesh, settings.weights.weight(Activity::PickUp) > 0.0) {
            (Some(m), true) => things_on_floor(m),
            _ => Vec::new(),
        };
        Ok(Self {
            settings,
            taken: vec![false; seats.len()],
            seats,
            thing_taken: vec![false; things.len()],
            things,
            clips: ActivityClip::load_shipped(clip_dir)?,
            mesh,
            distances: HashMap::new(),
        })
    }

    /// Draws what comes after a walk ([`super::ActivityWeights::draw`]).
    pub(crate) fn draw(&self, rng: &mut ChaCha8Rng) -> Activity {
        self.settings.weights.draw(rng)
    }

    /// The free seat nearest to walk to from `from` (walking distance over the walkable map,
    /// round walls and furniture; straight distance where `from` is off the map), among those
    /// whose standing point lies on `from`'s floor region, but those on an object of which a
    /// seat is in `passed` (seats the person could not reach: the object's other places are
    /// reached the same way).
    pub(crate) fn nearest_free_seat(
        &self,
        map: &WalkableMap,
        from: DVec2,
        passed: &[usize],
    ) -> Option<usize> {
        let region = |p: DVec2| map.cell_of(p).map(|(i, j)| map.component[j * map.nx + i]);
        let here = region(from);
        let walk = PathField::to_goal(map, from);
        let distance = |s: usize| {
            let stand = self.seats[s].stand();
            match &walk {
                Some(field) => field.at(stand).unwrap_or(f64::INFINITY),
                None => stand.distance(from),
            }
        };
        let unreached = |s: usize| {
            passed
                .iter()
                .any(|&p| self.seats[p].object_name == self.seats[s].object_name)
        };
        (0..self.seats.len())
            .filter(|&s| !self.taken[s] && !unreached(s) && region(self.seats[s].stand()) == here)
            .map(|s| (s, distance(s)))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
            .map(|(s, _)| s)
    }

    /// The free scene thing nearest to walk to from `from` (as [`Self::nearest_free_seat`],
    /// at most [`THING_WALK_M`] on foot) that stands on the floor at `floor_z` with its top
    /// `within` (m over that floor), and the place to walk to: `reach` from the thing, on
    /// the line from `from`, walkable.
    pub(crate) fn nearest_free_thing(
        &self,
        map: &WalkableMap,
        from: DVec2,
        floor_z: f64,
        within: [f64; 2],
        reach: f64,
    ) -> Option<(usize, DVec2)> {
        let region = |p: DVec2| map.cell_of(p).map(|(i, j)| map.component[j * map.nx + i]);
        let here = region(from);
        let walk = PathField::to_goal(map, from);
        (0..self.things.len())
            .filter(|&k| !self.thing_taken[k])
            .filter_map(|k| {
                let t = &self.things[k];
                let top = t.max.z - floor_z;
                let on_floor = (t.min.z - floor_z).abs() <= THING_ON_FLOOR_M;
                let c = t.top_centre().truncate();
                let stand = c - (c - from).try_normalize()? * reach;
                (on_floor
                    && (within[0]..=within[1]).contains(&top)
                    && map.is_walkable_at(stand)
                    && region(stand) == here)
                    .then(|| {
                        let d = match &walk {
                            Some(field) => field.at(stand).unwrap_or(f64::INFINITY),
                            None => stand.distance(from),
                        };
                        (k, stand, d)
                    })
            })
            .filter(|&(_, _, d)| d <= THING_WALK_M)
            .min_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)))
            .map(|(k, stand, _)| (k, stand))
    }

    pub(super) fn clip(&self, id: ClipId) -> Result<&ActivityClip, Refusal> {
        self.clips
            .iter()
            .find(|c| c.id == id)
            .ok_or(Refusal::NoClip(id.name()))
    }

    /// The scene's distance field without the objects named `without` (cached).
    pub(super) fn distance(&mut self, without: Option<&str>) -> Option<&MeshDistance> {
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
    pub(super) fn first_entry(
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
    /// scene ([`Self::first_entry`]; but the object named `without`) and the pelvis stays on the walkable floor (the walker
    /// takes over where it ends); else why not, the body `doing` what it did.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn fits_here(
        &mut self,
        body: &BodyContext,
        map: &WalkableMap,
        frames: &[BodyParams],
        phases: &[(Phase, usize)],
        hold_stride: usize,
        (floor_z, without): (f64, Option<&str>),
        doing: Doing,
    ) -> Result<(), Refusal> {
        if let Some((frame, depth_m)) =
            self.first_entry(body, frames, phases, hold_stride, without, floor_z)
        {
            return Err(Refusal::EntersScene {
                doing,
                depth_m,
                frame,
            });
        }
        match off_floor(body, map, frames)? {
            Some(frame) => Err(Refusal::LeavesFloor { doing, frame }),
            None => Ok(()),
        }
    }

    /// The clip `name` on `body`, its first frame standing where `last` stands and facing its
    /// way, on the floor at `floor_z`; and where that is.
    pub(super) fn where_standing(
        &self,
        body: &BodyContext,
        last: &BodyParams,
        id: ClipId,
        floor_z: f64,
    ) -> Result<(Vec<BodyParams>, DVec2), Refusal> {
        let (pelvis, facing) = pelvis_and_heading(body, last)?;
        Ok((
            self.clip_placed(body, id, (pelvis, facing), floor_z)?,
            pelvis,
        ))
    }

    /// The clip `id` on `body`, its first frame's pelvis at `at.0` facing `at.1` (rad), on the
    /// floor at `floor_z`.
    pub(super) fn clip_placed(
        &self,
        body: &BodyContext,
        id: ClipId,
        at: (DVec2, f64),
        floor_z: f64,
    ) -> Result<Vec<BodyParams>, Refusal> {
        let clip = self.clip(id)?.on_body(body)?;
        Ok(placed(
            &clip.frames,
            body.shaped.rest_joints[joint::PELVIS],
            (clip.pelvis[0], clip.headings[0]),
            at,
            |_| floor_z,
        ))
    }

    /// The frames from `last` into `first` (neither included): a blend of at least
    /// `blend_s`, longer where the body must turn faster than `turn_deg_per_s` or move its
    /// pelvis faster than 0.6 m/s; and the turn (degrees).
    pub(super) fn transition(
        &self,
        body: &BodyContext,
        last: &BodyParams,
        first: &BodyParams,
    ) -> Result<(Vec<BodyParams>, f64), Refusal> {
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

pub(super) fn record(activity: Activity, place: DVec2, turn_deg: f64) -> ActivityRecord {
    ActivityRecord {
        activity,
        start_frame: 0,
        end_frame: 0,
        place: place.to_array(),
        clip: None,
        seat: None,
        seat_height_m: None,
        seat_fit_m: None,
        seat_gap_m: None,
        chair_pulled_m: None,
        foot_miss_m: None,
        seat_penetration_m: None,
        turn_deg,
        contact: f64::NAN,
        join_joint_speed_rad_s: f64::NAN,
        clip_joint_speed_rad_s: None,
        object: None,
        look_at: None,
    }
}

/// Frames of a hold of about `seconds` after `before` frames and before `after`, such that
/// the whole is a whole number of primitives' new frames (at least one frame more).
pub(super) fn rounded_hold(before: usize, seconds: f64, after: usize) -> usize {
    let per = NEW_FRAMES;
    let want = before + ((seconds * PRIMITIVE_RATE_HZ).round() as usize).max(1) + after;
    want.div_ceil(per) * per - before - after
}

/// A pose's pelvis (horizontal) and facing.
pub(super) fn pelvis_and_heading(
    body: &BodyContext,
    p: &BodyParams,
) -> Result<(DVec2, f64), PoseError> {
    let s = body.shaped.skeleton(&p.pose, p.transl)?;
    let q = s.joints[joint::PELVIS];
    Ok((DVec2::new(q.x, q.y), heading(&s.joints)))
}

/// The first frame of `frames` whose pelvis path from the frame before passes over a cell of
/// the walkable map that is not walkable (the walk's own test: the walker takes over where an
/// activity ends).
pub(super) fn off_floor(
    body: &BodyContext,
    map: &WalkableMap,
    frames: &[BodyParams],
) -> Result<Option<usize>, PoseError> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::seats::SeatNaming;
    use crate::scene::ObjectId;

    fn seat(object: &str, stand: [f64; 2]) -> Seat {
        Seat {
            pelvis_xy: stand,
            facing_rad: 0.0,
            height_m: 0.45,
            surface_z_m: 0.45,
            stand_xy: stand,
            depth_m: 0.2,
            backed: true,
            object: ObjectId(1),
            object_name: object.into(),
            naming: SeatNaming::Shape,
            cells: Vec::new(),
            pull: None,
            longer: None,
        }
    }

    /// A floor `nx` cells of 0.1 m long and 6 m wide, a wall at y = 3 m from x = 0 to 8 m (its
    /// way round at x > 8 m).
    fn walled_floor(nx: usize) -> WalkableMap {
        let ny = 60;
        let walkable = (0..nx * ny)
            .map(|k| !(k / nx == 30 && k % nx < 80))
            .collect();
        WalkableMap::from_walkable(DVec2::ZERO, 0.1, nx, ny, walkable)
    }

    /// An activity world of `seats` and `things`, none taken, with no clips and no scene.
    fn world_of(seats: Vec<Seat>, things: Vec<SceneThing>) -> ActivityWorld {
        ActivityWorld {
            settings: ActivitySettings::default(),
            taken: vec![false; seats.len()],
            seats,
            thing_taken: vec![false; things.len()],
            things,
            clips: Vec::new(),
            mesh: None,
            distances: HashMap::new(),
        }
    }

    /// A small scene thing at `(x, y)`, its bottom at `z0`, `h` high.
    fn thing(name: &str, x: f64, y: f64, z0: f64, h: f64) -> SceneThing {
        SceneThing {
            name: name.into(),
            min: crate::math::Vec3::new(x - 0.03, y - 0.03, z0),
            max: crate::math::Vec3::new(x + 0.03, y + 0.03, z0 + h),
            triangles: Vec::new(),
        }
    }

    /// The thing chosen is the free one nearest on foot whose top lies in the palm's band and
    /// whose bottom is on the person's floor, at most [`THING_WALK_M`] away; the place to walk
    /// to lies the reach short of it on the line from the person.
    #[test]
    fn the_thing_nearest_on_foot_in_reach_is_chosen() {
        let map = walled_floor(200);
        let from = DVec2::new(2.0, 2.5);
        let mut world = world_of(
            Vec::new(),
            vec![
                thing("behind_the_wall", 2.0, 3.6, 0.0, 0.09),
                thing("too_tall", 3.0, 2.5, 0.0, 0.2),
                thing("on_a_table", 3.0, 2.0, 0.7, 0.09),
                thing("toy", 5.0, 2.5, 0.0, 0.09),
                thing("far", 12.0, 1.0, 0.0, 0.09),
            ],
        );
        let band = [0.05, 0.12];
        let (k, stand) = world
            .nearest_free_thing(&map, from, 0.0, band, 0.5)
            .unwrap();
        assert_eq!(world.things[k].name, "toy");
        assert!(stand.distance(DVec2::new(4.5, 2.5)) < 1e-9, "{stand}");
        world.thing_taken[k] = true;
        // Behind the wall is 1.1 m as the crow flies, over 6 m on foot round it.
        assert_eq!(world.nearest_free_thing(&map, from, 0.0, band, 0.5), None);
        let near = DVec2::new(9.0, 1.0);
        let (k, _) = world
            .nearest_free_thing(&map, near, 0.0, band, 0.5)
            .unwrap();
        assert_eq!(world.things[k].name, "far");
    }

    /// The seat chosen is the nearest on foot: one 1 m away behind a wall loses to one 3 m
    /// away in the open; a seat on an object walked to before and not reached is passed over
    /// with every other place on that object.
    #[test]
    fn the_seat_nearest_on_foot_is_chosen_and_unreached_objects_are_passed() {
        let map = walled_floor(100);
        let from = DVec2::new(2.0, 2.5);
        let mut world = world_of(
            vec![
                seat("behind_the_wall", [2.0, 3.55]),
                seat("sofa", [5.0, 2.0]),
                seat("sofa", [5.6, 2.0]),
                seat("armchair", [7.0, 1.0]),
            ],
            Vec::new(),
        );
        assert!(world.seats[0].stand().distance(from) < world.seats[1].stand().distance(from));
        assert_eq!(world.nearest_free_seat(&map, from, &[]), Some(1));
        world.taken[1] = true;
        assert_eq!(world.nearest_free_seat(&map, from, &[]), Some(2));
        // Place 1 of the sofa was not reached: its place 2 is passed over too.
        world.taken[1] = false;
        assert_eq!(world.nearest_free_seat(&map, from, &[1]), Some(3));
        assert_eq!(world.nearest_free_seat(&map, from, &[1, 3]), Some(0));
    }
}
