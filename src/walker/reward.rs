//! The reward of one primitive (paper Tab. S2, as EgoGen's box environment computes it) and
//! what it says about the episode: success, penetration, and the per-primitive measures the
//! evaluation reports.
//!
//! Terms, each in `[0, 1]` or a distance decrease, weighted by [`RewardWeights`]:
//! - floor `exp(−mean_t |lowest foot marker − floor − 0.02|)` and skate
//!   `exp(−mean_t max(0, slowest foot-marker 3-D speed − 0.075))` (the two factors of Eq. 12);
//! - goal: decrease of the pelvis's horizontal distance to the goal over the primitive (m);
//!   with a walking-distance field ([`Situation::goal_field`], not EgoGen's), the decrease of
//!   the walking distance round walls instead, and orientation and attention face the way
//!   that distance falls;
//! - orientation `(b·u + 1)/2`, `b` the body's forward (z × hip line) at the last frame and `u`
//!   the unit direction from the pelvis to the goal; attention `(e·u + 1)/2` with `e` the floor
//!   projection of the CPF's viewing direction at the last frame;
//! - penetration: 0.05 while at most `penetration_cells` blocked map cells lie in the body's
//!   2D box (the bounding box of the 67 markers of the last two frames, in the new canonical
//!   frame: paper Eq. 7) — cells of that box inside a moving obstacle at the last frame count
//!   too — else 0; with [`Limits::people_every_frame`], also 0 when a body marker stands in
//!   another person's box in any new frame, with [`Limits::box_every_frame`] when one stands
//!   in a box scene's box;
//! - pose: 0.05 while the mean pose-prior score of the 20 frames is at most the prior's
//!   plausibility limit, else 0 (EgoGen: VPoser latent norm ≤ 11);
//! - success: 1 when the pelvis ends within `success_m` of the goal;
//! - beyond Tab. S2 (weights 0 by default): pace (`arrival`), looking away (`attention_gap`)
//!   and walking into the scene (`penetration_cost`: −1 for a primitive that penetrates).
//!
//! Distances are horizontal (EgoGen's code measures 3-D distance to a goal placed at the
//! start's pelvis height; the goal here lies on the floor plane).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::pose_prior::PosePrior;
use crate::body::joint;
use crate::math::Vec3;
use crate::motion::cvae::measure::contact_terms;
use crate::motion::cvae::DecodedPrimitive;
use crate::motion::primitive::{canonical_frame, PRIMITIVE_FRAMES, PRIMITIVE_RATE_HZ, SEED_FRAMES};
use crate::scene::{blocked_cells_in_box, MovingObstacle, Obstacle2, PathField, WalkableMap};

/// Weights of the reward terms (paper Tab. S2; penetration 1 in pretraining, 0.1 in
/// fine-tuning).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RewardWeights {
    pub floor: f64,
    pub skate: f64,
    pub goal: f64,
    pub orientation: f64,
    pub attention: f64,
    pub penetration: f64,
    pub pose: f64,
    pub success: f64,
    /// Pace (not in Tab. S2, 0 there): on success, this much more per primitive left before
    /// the timeout. Tab. S2's per-primitive terms pay about 0.85 for every primitive walked,
    /// so without it a body earns most by arriving at the last one.
    pub arrival: f64,
    /// Looking away (not in Tab. S2, 0 there): this much times `attention − 1` (0 looking at
    /// the goal, −1 looking away from it) every primitive. Tab. S2's attention term pays for
    /// every primitive walked, so weighting it more pays for walking slowly; this one costs
    /// for every primitive spent looking off the goal.
    pub attention_gap: f64,
    /// Walking into the scene (not in Tab. S2, 0 there): every primitive that penetrates
    /// costs this much. Tab. S2's penetration term pays 0.05 for every primitive clear of the
    /// scene, so weighting it more pays for every primitive walked — for loitering instead of
    /// arriving — where this one costs only the primitives that penetrate.
    pub penetration_cost: f64,
}

impl Default for RewardWeights {
    fn default() -> Self {
        Self {
            floor: 0.1,
            skate: 0.3,
            goal: 1.0,
            orientation: 0.1,
            attention: 0.3,
            penetration: 1.0,
            pose: 0.1,
            success: 0.5,
            arrival: 0.0,
            attention_gap: 0.0,
            penetration_cost: 0.0,
        }
    }
}

/// Changes to [`RewardWeights`] for some of the episodes (the environment's box scenes, or its
/// indoor ones): each weight given replaces the base one, the others stay as the base has
/// them.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WeightChanges {
    pub floor: Option<f64>,
    pub skate: Option<f64>,
    pub goal: Option<f64>,
    pub orientation: Option<f64>,
    pub attention: Option<f64>,
    pub penetration: Option<f64>,
    pub pose: Option<f64>,
    pub success: Option<f64>,
    pub arrival: Option<f64>,
    pub attention_gap: Option<f64>,
    pub penetration_cost: Option<f64>,
}

impl WeightChanges {
    /// `base` with these changes.
    pub(crate) fn applied_to(&self, base: RewardWeights) -> RewardWeights {
        RewardWeights {
            floor: self.floor.unwrap_or(base.floor),
            skate: self.skate.unwrap_or(base.skate),
            goal: self.goal.unwrap_or(base.goal),
            orientation: self.orientation.unwrap_or(base.orientation),
            attention: self.attention.unwrap_or(base.attention),
            penetration: self.penetration.unwrap_or(base.penetration),
            pose: self.pose.unwrap_or(base.pose),
            success: self.success.unwrap_or(base.success),
            arrival: self.arrival.unwrap_or(base.arrival),
            attention_gap: self.attention_gap.unwrap_or(base.attention_gap),
            penetration_cost: self.penetration_cost.unwrap_or(base.penetration_cost),
        }
    }
}

/// Value of the penetration and pose terms when they hold (EgoGen's 0.05).
pub(crate) const BINARY_TERM: f64 = 0.05;

/// The reward terms of one primitive, unweighted.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct RewardTerms {
    pub floor: f64,
    pub skate: f64,
    pub goal: f64,
    pub orientation: f64,
    pub attention: f64,
    pub penetration: f64,
    pub pose: f64,
    pub success: f64,
}

impl RewardTerms {
    /// The weighted sum.
    pub(crate) fn total(&self, w: &RewardWeights) -> f64 {
        w.floor * self.floor
            + w.skate * self.skate
            + w.goal * self.goal
            + w.orientation * self.orientation
            + w.attention * self.attention
            + w.penetration * self.penetration
            + w.pose * self.pose
            + w.success * self.success
            + w.attention_gap * (self.attention - 1.0)
            + w.penetration_cost * (self.penetration / BINARY_TERM - 1.0)
    }

    /// The weighted sum, with the pace bonus for a success with `primitives_left` primitives
    /// before the timeout.
    pub(crate) fn total_with_arrival(&self, w: &RewardWeights, primitives_left: usize) -> f64 {
        self.total(w) + w.arrival * self.success * primitives_left as f64
    }
}

/// Where the episode stands before the primitive.
#[derive(Debug, Clone, Copy)]
pub struct Situation<'a> {
    pub map: &'a WalkableMap,
    pub obstacle: Option<&'a Obstacle2>,
    /// Obstacles that move (other people as 2D boxes), and the time of the primitive's first
    /// frame on their clock (s).
    pub moving: &'a [MovingObstacle],
    pub t0_s: f64,
    pub goal: DVec2,
    /// Horizontal pelvis–goal distance at the end of the previous primitive (m).
    pub distance_m: f64,
    /// The walking distance to the goal round walls, where the goal term should pay progress
    /// along it (and orientation and attention face the way it leads) instead of straight at
    /// the goal (`EnvSettings::goal_by_path`); `None`: straight, as EgoGen.
    pub goal_field: Option<&'a PathField>,
}

/// Limits the terms are judged by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    pub success_m: f64,
    pub penetration_cells: usize,
    /// Whether a body marker inside another person's box (a moving obstacle) in any new frame
    /// penetrates too, beside Eq. 7's cells at the primitive's end (which miss a person
    /// passed through within the primitive).
    pub people_every_frame: bool,
    /// Whether a body marker inside a box scene's box in any new frame penetrates too (the
    /// cells at the primitive's end miss an arm or a shoulder brushing it on the way).
    pub box_every_frame: bool,
    /// Whether the scene is tested at every new frame, not only at the primitive's end: the
    /// body's box on more than `penetration_cells` blocked cells in any frame
    /// ([`Judged::blocked_cells_swept_max`]), or the pelvis's path passing over a cell that is
    /// not walkable ([`Judged::pelvis_off_floor_frames`]), penetrates. A 0.5 s primitive at
    /// 1.2 m/s covers 0.6 m: the end alone lets a step pass through a wall.
    pub scene_every_frame: bool,
}

/// Blocked cells in the body's 2D box beyond which a primitive penetrates (paper Eq. 7: more
/// than 3).
pub(crate) const EQ7_PENETRATION_CELLS: usize = 3;

impl Limits {
    /// EgoGen's test: success within `success_m`, penetration by Eq. 7's cells at the
    /// primitive's end alone.
    pub fn eq7(success_m: f64) -> Limits {
        Limits {
            success_m,
            penetration_cells: EQ7_PENETRATION_CELLS,
            people_every_frame: false,
            box_every_frame: false,
            scene_every_frame: false,
        }
    }

    /// [`Limits::eq7`] with the scene tested at every frame ([`Limits::scene_every_frame`]):
    /// how agents of a take are judged, so that no primitive steps through a wall.
    pub fn swept(success_m: f64) -> Limits {
        Limits {
            scene_every_frame: true,
            ..Limits::eq7(success_m)
        }
    }
}

/// One primitive judged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Judged {
    pub terms: RewardTerms,
    /// Horizontal pelvis–goal distance at the primitive's end (m).
    pub distance_m: f64,
    pub success: bool,
    /// Blocked cells in the body's 2D box at the end (Eq. 7), moving obstacles' included.
    pub blocked_cells: usize,
    /// The most blocked cells of the walkable map in the body's 2D box (Eq. 7's box of each
    /// frame, laid over that frame's markers along its hip line) in any new frame; 0 unless
    /// [`Limits::scene_every_frame`].
    pub blocked_cells_swept_max: usize,
    /// New frames whose pelvis path from the frame before passes over a cell that is not
    /// walkable (a wall, furniture, a closed doorway): the pelvis crossing solid geometry
    /// (measured whatever the limits; it penetrates with [`Limits::scene_every_frame`]).
    pub pelvis_off_floor_frames: usize,
    pub penetrated: bool,
    /// Foot contact (3-D, Eq. 12) = floor · skate.
    pub contact: f64,
    /// Mean pose-prior score of the frames.
    pub pose_nll: f64,
    /// The largest pose embedding norm among them ([`PosePrior::embedding_norms`]).
    pub pose_norm_max: f64,
    /// New frames (after the seed) in which a body marker stands inside the obstacle's
    /// footprint.
    pub frames_in_obstacle: usize,
    /// cos(angle) between the viewing direction and the direction to the goal, last frame.
    pub view_cos: f64,
    /// Angle between the viewing direction in the last frame and the pelvis's horizontal
    /// direction of travel over the primitive (last seed frame to last frame; rad, 0 to π);
    /// NaN when the pelvis moved less than [`TRAVEL_MIN_M`].
    pub view_off_travel_rad: f64,
    /// Scene penetration (paper Eq. 11), where the scene has a 3D SDF: new frames in which at
    /// least [`EQ11_VERTICES`] body vertices lie inside the scene, and the most vertices inside
    /// in any new frame (both 0 without an SDF).
    pub scene_penetrating_frames: usize,
    pub scene_vertices_inside_max: usize,
}

/// Shortest pelvis travel over a primitive that gives [`Judged::view_off_travel_rad`] a
/// direction (m).
pub(crate) const TRAVEL_MIN_M: f64 = 0.1;

/// Body vertices with negative scene SDF that make a frame penetrate (paper Eq. 11: 40).
pub(crate) const EQ11_VERTICES: usize = 40;

/// Paper Eq. 11 on a primitive: every vertex of the posed body in each new frame looked up in
/// the scene's SDF; `(frames with ≥ EQ11_VERTICES inside, most inside in a frame)`.
pub(crate) fn scene_penetration(
    body: &crate::motion::cvae::BodyContext,
    p: &DecodedPrimitive,
    sdf: &crate::scene::SceneSdf,
) -> Result<(usize, usize), crate::body::PoseError> {
    let (mut frames, mut most) = (0, 0);
    for f in &p.world[SEED_FRAMES..] {
        let posed = body.shaped.pose(&f.pose, f.transl)?;
        let inside = crate::scene::sdf_penetration(sdf, &posed.vertices).count;
        frames += usize::from(inside >= EQ11_VERTICES);
        most = most.max(inside);
    }
    Ok((frames, most))
}

/// Paper Eq. 11 as training tests it, on a fixed subset of the body's vertices: `count` ids by
/// farthest-point sampling of the rest template (spread over the whole surface,
/// [`crate::body::farthest_point_markers`]), and the threshold of [`EQ11_VERTICES`] of all
/// vertices scaled to the subset's share (at least 1). Only the subset is posed, so a test
/// costs a small part of [`scene_penetration`]'s.
#[derive(Debug, Clone)]
pub(crate) struct SceneTest {
    ids: Vec<u32>,
    threshold: usize,
}

impl SceneTest {
    pub(crate) fn new(model: &crate::body::BodyModel, count: usize) -> Self {
        let ids = crate::body::farthest_point_markers(model, count);
        let share = ids.len() as f64 / model.num_vertices().max(1) as f64;
        let threshold = ((EQ11_VERTICES as f64 * share).round() as usize).max(1);
        Self { ids, threshold }
    }

    /// Vertices of the subset.
    #[cfg(test)]
    pub(crate) fn vertices(&self) -> usize {
        self.ids.len()
    }

    /// Subset vertices inside the scene that make a frame penetrate.
    #[cfg(test)]
    pub(crate) fn threshold(&self) -> usize {
        self.threshold
    }

    /// Whether any new frame of `p` has at least [`Self::threshold`] subset vertices inside
    /// the scene.
    pub(crate) fn penetrates(
        &self,
        body: &crate::motion::cvae::BodyContext,
        p: &DecodedPrimitive,
        sdf: &crate::scene::SceneSdf,
    ) -> Result<bool, crate::body::PoseError> {
        let mut skeleton = crate::body::PosedSkeleton::default();
        for f in &p.world[SEED_FRAMES..] {
            body.shaped
                .skeleton_into(&f.pose, f.transl, &mut skeleton)?;
            let vertices = body.shaped.pose_vertices(&skeleton, &f.pose, &self.ids);
            if crate::scene::sdf_penetration(sdf, &vertices).count >= self.threshold {
                return Ok(true);
            }
        }
        Ok(false)
    }
}

impl Judged {
    /// Judges penetration by another test (Eq. 11 where a scene has a 3D SDF): the
    /// termination and the penetration reward term follow it.
    pub(crate) fn set_penetrated(&mut self, penetrated: bool) {
        self.penetrated = penetrated;
        self.terms.penetration = if penetrated { 0.0 } else { BINARY_TERM };
    }
}

/// Cells of a `cell_m` grid laid over an oriented box (centre, half extents, yaw) whose centres
/// lie inside any of `obstacles`: Eq. 7's blocked-cell count for obstacles that are not in the
/// walkable map.
pub(crate) fn cells_in_obstacles(
    obstacles: &[Obstacle2],
    centre: DVec2,
    half: DVec2,
    yaw_rad: f64,
    cell_m: f64,
) -> usize {
    if obstacles.is_empty() || !(half.is_finite() && cell_m > 0.0) {
        return 0;
    }
    let (nx, ny) = (
        ((2.0 * half.x / cell_m).ceil() as usize).clamp(1, 1000),
        ((2.0 * half.y / cell_m).ceil() as usize).clamp(1, 1000),
    );
    let rot = DVec2::from_angle(yaw_rad);
    let mut n = 0;
    for j in 0..ny {
        for i in 0..nx {
            let local = DVec2::new(
                -half.x + (i as f64 + 0.5) * 2.0 * half.x / nx as f64,
                -half.y + (j as f64 + 0.5) * 2.0 * half.y / ny as f64,
            );
            let p = centre + rot.rotate(local);
            if obstacles.iter().any(|o| o.contains(p)) {
                n += 1;
            }
        }
    }
    n
}

fn unit_xy(v: Vec3) -> DVec2 {
    DVec2::new(v.x, v.y).normalize_or_zero()
}

/// A body's 2D box (Eq. 7): the bounding box of `markers` in the horizontal canonical frame of
/// a frame's `joints` (x along the hip line, origin at the pelvis), as its centre, half
/// extents and yaw; `None` when the hips stand vertical.
fn body_box<'a>(
    joints: &[Vec3],
    markers: impl Iterator<Item = &'a Vec3>,
) -> Option<(DVec2, DVec2, f64)> {
    let frame = canonical_frame(joints).ok()?;
    let x = DVec2::new(frame.matrix3.x_axis.x, frame.matrix3.x_axis.y);
    let o = DVec2::new(frame.translation.x, frame.translation.y);
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for m in markers {
        let d = DVec2::new(m.x, m.y) - o;
        let local = DVec2::new(x.dot(d), x.perp().dot(d));
        lo = lo.min(local);
        hi = hi.max(local);
    }
    let c = (lo + hi) * 0.5;
    let centre = o + x * c.x + x.perp() * c.y;
    Some((centre, (hi - lo) * 0.5, x.y.atan2(x.x)))
}

/// Whether the straight path from `from` to `to` passes over a cell of `map` that is not
/// walkable (touching its edge or corner counts; cells outside the grid are not walkable).
pub(crate) fn path_leaves_floor(map: &WalkableMap, from: DVec2, to: DVec2) -> bool {
    let d = to - from;
    let length = d.length();
    if !(from.is_finite() && length.is_finite()) {
        return true;
    }
    if length == 0.0 {
        return !map.is_walkable_at(from);
    }
    crate::sensing::ray::grid::hit_grid(
        map,
        crate::sensing::Ray2 {
            origin: from,
            dir: d / length,
        },
        length,
    )
    .is_some()
}

/// Judges a decoded primitive in a situation.
pub fn judge(
    p: &DecodedPrimitive,
    s: &Situation,
    foot_markers: &[usize],
    prior: &PosePrior,
    limits: &Limits,
) -> Judged {
    let feet: Vec<Vec<[f64; 3]>> = p
        .markers
        .iter()
        .map(|m| foot_markers.iter().map(|&k| m[k].to_array()).collect())
        .collect();
    let (floor, skate) = contact_terms(&feet, p.floor_z);
    let (pose_nll, pose_norm_max) = prior.mean_nll_and_max_norm(&p.world);
    let last = PRIMITIVE_FRAMES - 1;
    let joints = &p.joints[last];
    let pelvis = DVec2::new(joints[joint::PELVIS].x, joints[joint::PELVIS].y);
    let from = {
        let q = p.joints[SEED_FRAMES - 1][joint::PELVIS];
        DVec2::new(q.x, q.y)
    };
    // Along the walking distance where one is given and tells both ends, else straight.
    let along = s
        .goal_field
        .and_then(|f| Some((f.at(from)? - f.at(pelvis)?, f.way_at(pelvis))));
    let to_goal = match along {
        Some((_, Some(way))) => way,
        _ => (s.goal - pelvis).normalize_or_zero(),
    };
    let forward = unit_xy(Vec3::Z.cross(joints[joint::RIGHT_HIP] - joints[joint::LEFT_HIP]));
    let view = unit_xy(p.world_from_cpf[last].matrix3.z_axis);
    let distance_m = pelvis.distance(s.goal);
    let travel = pelvis - from;
    let view_off_travel_rad = match travel.length() >= TRAVEL_MIN_M {
        true => view.dot(travel.normalize()).clamp(-1.0, 1.0).acos(),
        false => f64::NAN,
    };
    // The body's 2D box: markers of the last two frames in the new canonical frame.
    let blocked_cells = match body_box(
        &p.joints[last + 1 - SEED_FRAMES],
        p.markers[last + 1 - SEED_FRAMES..].iter().flatten(),
    ) {
        Some((centre, half, yaw)) => {
            let t_end = s.t0_s + last as f64 / PRIMITIVE_RATE_HZ;
            let moving: Vec<Obstacle2> = s.moving.iter().map(|m| m.at(t_end)).collect();
            blocked_cells_in_box(s.map, centre, half, yaw)
                + cells_in_obstacles(&moving, centre, half, yaw, s.map.cell_m)
        }
        None => usize::MAX,
    };
    // The pelvis's path, measured always (18 short grid traversals: evaluations report it);
    // the body's box at every frame where the limits ask for the swept test.
    let pelvis_off_floor_frames = (SEED_FRAMES..PRIMITIVE_FRAMES)
        .filter(|&k| {
            let xy = |f: usize| {
                let q = p.joints[f][joint::PELVIS];
                DVec2::new(q.x, q.y)
            };
            path_leaves_floor(s.map, xy(k - 1), xy(k))
        })
        .count();
    let blocked_cells_swept_max = match limits.scene_every_frame {
        true => (SEED_FRAMES..PRIMITIVE_FRAMES)
            .map(|k| match body_box(&p.joints[k], p.markers[k].iter()) {
                Some((centre, half, yaw)) => blocked_cells_in_box(s.map, centre, half, yaw),
                None => usize::MAX,
            })
            .max()
            .unwrap_or(0),
        false => 0,
    };
    let (mut frames_in_obstacle, mut frames_in_people, mut frames_in_box) = (0, 0, 0);
    for (k, f) in p.markers[SEED_FRAMES..].iter().enumerate() {
        let t = s.t0_s + (SEED_FRAMES + k) as f64 / PRIMITIVE_RATE_HZ;
        let inside = |o: &Obstacle2| f.iter().any(|m| o.contains(DVec2::new(m.x, m.y)));
        let in_people = s.moving.iter().any(|o| inside(&o.at(t)));
        let in_box = s.obstacle.is_some_and(inside);
        frames_in_people += usize::from(in_people);
        frames_in_box += usize::from(in_box);
        frames_in_obstacle += usize::from(in_people || in_box);
    }
    let penetrated = blocked_cells > limits.penetration_cells
        || (limits.people_every_frame && frames_in_people > 0)
        || (limits.box_every_frame && frames_in_box > 0)
        || (limits.scene_every_frame
            && (blocked_cells_swept_max > limits.penetration_cells || pelvis_off_floor_frames > 0));
    let success = distance_m < limits.success_m;
    let terms = RewardTerms {
        floor,
        skate,
        goal: match along {
            Some((progress, _)) => progress,
            None => s.distance_m - distance_m,
        },
        orientation: (forward.dot(to_goal) + 1.0) / 2.0,
        attention: (view.dot(to_goal) + 1.0) / 2.0,
        penetration: if penetrated { 0.0 } else { BINARY_TERM },
        pose: if pose_nll <= prior.plausible_max_nll {
            BINARY_TERM
        } else {
            0.0
        },
        success: if success { 1.0 } else { 0.0 },
    };
    Judged {
        terms,
        distance_m,
        success,
        blocked_cells,
        blocked_cells_swept_max,
        pelvis_off_floor_frames,
        penetrated,
        contact: floor * skate,
        pose_nll,
        pose_norm_max,
        frames_in_obstacle,
        view_cos: view.dot(to_goal),
        view_off_travel_rad,
        scene_penetrating_frames: 0,
        scene_vertices_inside_max: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weight_changes_replace_only_the_weights_given() {
        let base = RewardWeights {
            penetration: 0.1,
            attention_gap: 3.0,
            ..RewardWeights::default()
        };
        assert_eq!(WeightChanges::default().applied_to(base), base);
        let changed = WeightChanges {
            attention_gap: Some(0.5),
            arrival: Some(1.5),
            ..WeightChanges::default()
        }
        .applied_to(base);
        assert_eq!(
            changed,
            RewardWeights {
                attention_gap: 0.5,
                arrival: 1.5,
                ..base
            }
        );
        // In a config: unknown names are refused, the others default to no change.
        let parsed: WeightChanges = toml::from_str("arrival = 1.5").unwrap();
        assert_eq!(parsed.arrival, Some(1.5));
        assert_eq!(parsed.applied_to(base).skate, base.skate);
        assert!(toml::from_str::<WeightChanges>("arival = 1.5").is_err());
        // Weights not given stay not given through JSON and TOML.
        let json = serde_json::to_string(&parsed).unwrap();
        assert_eq!(
            serde_json::from_str::<WeightChanges>(&json).unwrap(),
            parsed
        );
        let text = toml::to_string(&parsed).unwrap();
        assert_eq!(text.trim(), "arrival = 1.5");
        assert_eq!(toml::from_str::<WeightChanges>(&text).unwrap(), parsed);
    }

    #[test]
    fn cells_of_the_body_box_inside_a_moving_obstacle_are_counted() {
        let person = Obstacle2::Box {
            centre: DVec2::new(1.0, 0.0),
            half_extents: DVec2::new(0.3, 0.2),
            yaw_rad: 0.0,
        };
        let body = |x: f64| {
            cells_in_obstacles(
                &[person],
                DVec2::new(x, 0.0),
                DVec2::new(0.3, 0.2),
                0.3,
                0.1,
            )
        };
        // Apart, touching a little, overlapping fully.
        assert_eq!(body(-1.0), 0);
        assert!((1..=8).contains(&body(0.45)), "{}", body(0.45));
        assert!(body(1.0) >= 20, "{}", body(1.0));
        assert_eq!(
            cells_in_obstacles(&[], DVec2::ZERO, DVec2::ONE, 0.0, 0.1),
            0
        );
    }

    #[test]
    fn the_pace_bonus_pays_a_success_for_the_primitives_left_and_nothing_else() {
        let terms = |success: f64| RewardTerms {
            floor: 1.0,
            skate: 1.0,
            goal: 0.2,
            orientation: 1.0,
            attention: 1.0,
            penetration: BINARY_TERM,
            pose: BINARY_TERM,
            success,
        };
        let tab_s2 = RewardWeights::default();
        let pace = RewardWeights {
            arrival: 1.0,
            ..tab_s2
        };
        // Tab. S2 (arrival 0): the bonus is nothing, early or late.
        assert_eq!(
            terms(1.0).total_with_arrival(&tab_s2, 5),
            terms(1.0).total(&tab_s2)
        );
        // With the bonus: one per primitive left, only on success.
        let early = terms(1.0).total_with_arrival(&pace, 5);
        assert!(
            (early - terms(1.0).total(&pace) - 5.0).abs() < 1e-12,
            "{early}"
        );
        assert_eq!(
            terms(0.0).total_with_arrival(&pace, 5),
            terms(0.0).total(&pace)
        );
        assert_eq!(
            terms(1.0).total_with_arrival(&pace, 0),
            terms(1.0).total(&pace)
        );
    }

    #[test]
    fn looking_away_costs_its_weight_times_the_attention_gap_and_nothing_on_the_goal() {
        let terms = |attention: f64| RewardTerms {
            attention,
            goal: 0.3,
            skate: 0.9,
            ..RewardTerms::default()
        };
        let tab_s2 = RewardWeights::default();
        let gap = RewardWeights {
            attention_gap: 2.0,
            ..tab_s2
        };
        // Looking at the goal: no cost; at right angles (attention 0.5): half the weight;
        // away from it: the whole weight.
        for (attention, cost) in [(1.0, 0.0), (0.5, 1.0), (0.0, 2.0)] {
            let d = terms(attention).total(&tab_s2) - terms(attention).total(&gap);
            assert!((d - cost).abs() < 1e-12, "{attention}: {d}");
        }
    }

    #[test]
    fn walking_into_the_scene_costs_its_weight_and_a_clear_primitive_nothing() {
        let terms = |penetration: f64| RewardTerms {
            penetration,
            goal: 0.4,
            skate: 0.9,
            ..RewardTerms::default()
        };
        let tab_s2 = RewardWeights::default();
        let cost = RewardWeights {
            penetration_cost: 2.0,
            ..tab_s2
        };
        // Clear (the term holds): no cost; penetrating: the whole weight, beside Tab. S2's
        // term, which pays nothing then.
        for (penetration, c) in [(BINARY_TERM, 0.0), (0.0, 2.0)] {
            let d = terms(penetration).total(&tab_s2) - terms(penetration).total(&cost);
            assert!((d - c).abs() < 1e-12, "{penetration}: {d}");
        }
    }

    #[test]
    fn a_pelvis_path_over_a_wall_leaves_the_floor_and_one_beside_it_does_not() {
        // A 4 × 4 m floor of 0.1 m cells with a one-cell wall along x = 0.0..0.1.
        let n = 40;
        let origin = DVec2::splat(-2.0);
        let walkable = (0..n * n).map(|k| k % n != 20).collect();
        let map = WalkableMap::from_walkable(origin, 0.1, n, n, walkable);
        let at = |x: f64, y: f64| DVec2::new(x, y);
        // Straight through, and a 3 cm step whose two ends lie on either side.
        assert!(path_leaves_floor(&map, at(-0.5, 0.0), at(0.5, 0.3)));
        assert!(path_leaves_floor(&map, at(-0.001, 0.0), at(0.101, 0.0)));
        // Into the wall and standing in it.
        assert!(path_leaves_floor(&map, at(-0.2, 0.0), at(0.05, 0.0)));
        assert!(path_leaves_floor(&map, at(0.05, 0.5), at(0.05, 0.5)));
        // Along it, beside it, and standing still beside it.
        assert!(!path_leaves_floor(&map, at(-0.02, -1.0), at(-0.02, 1.0)));
        assert!(!path_leaves_floor(&map, at(0.12, 1.0), at(0.9, -1.5)));
        assert!(!path_leaves_floor(&map, at(-0.5, 0.5), at(-0.5, 0.5)));
        // Off the grid, and not a number.
        assert!(path_leaves_floor(&map, at(1.5, 0.0), at(2.5, 0.0)));
        assert!(path_leaves_floor(&map, at(f64::NAN, 0.0), at(0.5, 0.0)));
    }
}
