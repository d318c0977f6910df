//! Where each garment of an [`Outfit`] lies on one body: a signed distance per vertex and
//! garment (metres, positive on the garment), measured on the person's shaped rest body (the
//! T-pose, y up, +x the body's left, +z forward) from its own joints, so a sleeve ends at a
//! share of that person's arm whatever the shape, and the region moves with the skin as the
//! body is posed. Blender interpolates the distances over each triangle and paints where they
//! are positive: hems are sharp lines across triangles, not a triangle's jagged edge.
//!
//! The measures: a vertex's distance along its arm (shoulder → elbow → wrist → fingertips) and
//! along its leg (hip → knee → ankle → toes), negative towards the torso, taken only where the
//! limb's joints carry most of its skin weight; its height; the neck's opening; and, on the
//! head, the hairline's height at the vertex's bearing round the head (front, side, back).

use super::{Neckline, Outfit, SLOTS};
use crate::body::{joint, BodyModel, PoseError};
use crate::math::{Real, Vec3};

/// Columns per vertex in [`garment_fields`]: one distance per slot of [`SLOTS`], then the
/// vertex's rest position (the fabrics' pattern coordinates, metres).
pub(crate) const FIELD_COLUMNS: usize = SLOTS.len() + 3;

/// The body's own lengths and landmarks the cuts are shares of.
struct Frame {
    joints: [Vec3; crate::body::NUM_JOINTS],
    /// Neck joint to pelvis joint (m).
    torso: Real,
    /// Eyes to the crown (m).
    head: Real,
    eye_y: Real,
    /// The neck's radius at the neck joint (m).
    neck_radius: Real,
}

/// Each vertex's garment distances and rest position, `FIELD_COLUMNS` values a vertex, for
/// the body of `betas` wearing `outfit`.
pub(crate) fn garment_fields(
    model: &BodyModel,
    betas: &[Real],
    outfit: &Outfit,
) -> Result<Vec<[f32; FIELD_COLUMNS]>, PoseError> {
    let shaped = model.shape(betas, &[])?;
    let v = &shaped.v_shaped;
    let j = shaped.rest_joints;
    let limb_weight = |vertex: usize, joints: &[usize]| -> Real {
        model.skin_weights[vertex]
            .iter()
            .filter(|(k, _)| joints.contains(&(*k as usize)))
            .map(|(_, w)| w)
            .sum()
    };
    let eye_y = 0.5 * (j[joint::LEFT_EYE].y + j[joint::RIGHT_EYE].y);
    let crown = v.iter().map(|p| p.y).fold(Real::NEG_INFINITY, Real::max);
    let neck = j[joint::NECK];
    // The neck's radius: the median horizontal distance from the neck joint of the vertices
    // within 1 cm of its height that the neck and head joints move most.
    let mut radii: Vec<Real> = v
        .iter()
        .enumerate()
        .filter(|(k, p)| {
            (p.y - neck.y).abs() < 0.01 && limb_weight(*k, &[joint::NECK, joint::HEAD]) > 0.5
        })
        .map(|(_, p)| ((p.x - neck.x).powi(2) + (p.z - neck.z).powi(2)).sqrt())
        .collect();
    radii.sort_by(Real::total_cmp);
    let neck_radius = radii.get(radii.len() / 2).copied().unwrap_or(0.055);
    let frame = Frame {
        joints: j,
        torso: neck.y - j[joint::PELVIS].y,
        head: crown - eye_y,
        eye_y,
        neck_radius,
    };
    let arms = [side_chain(&j, ARM_LEFT), side_chain(&j, ARM_RIGHT)];
    let legs = [side_chain(&j, LEG_LEFT), side_chain(&j, LEG_RIGHT)];
    // Shoulder to wrist, hip to ankle.
    let arm_lengths = arms.each_ref().map(|c| c.length_to(2));
    let leg_lengths = legs.each_ref().map(|c| c.length_to(2));
    let worn = SLOTS.map(|slot| outfit.garments.iter().any(|g| g.slot == slot));
    let mut out = Vec::with_capacity(v.len());
    for (k, &p) in v.iter().enumerate() {
        let side = usize::from(p.x < j[joint::PELVIS].x);
        let arm_joints = if side == 0 {
            &ARM_LEFT_ALL
        } else {
            &ARM_RIGHT_ALL
        };
        let leg_joints = if side == 0 { &LEG_LEFT } else { &LEG_RIGHT };
        let mut along_arm = arms[side].along(p);
        if limb_weight(k, arm_joints) < 0.5 {
            along_arm = along_arm.min(0.0);
        }
        let mut along_leg = legs[side].along(p);
        if limb_weight(k, leg_joints) < 0.5 {
            along_leg = along_leg.min(0.0);
        }
        let d = frame.distances(
            outfit,
            p,
            along_arm,
            along_leg,
            arm_lengths[side],
            leg_lengths[side],
        );
        let mut row = [0f32; FIELD_COLUMNS];
        for (c, dist) in d.iter().enumerate() {
            // A slot the outfit leaves empty: −1 everywhere.
            row[c] = if worn[c] {
                dist.clamp(-1.0, 1.0) as f32
            } else {
                -1.0
            };
        }
        row[SLOTS.len()..].copy_from_slice(&[p.x as f32, p.y as f32, p.z as f32]);
        out.push(row);
    }
    Ok(out)
}

const ARM_LEFT: [usize; 3] = [joint::LEFT_SHOULDER, joint::LEFT_ELBOW, joint::LEFT_WRIST];
const ARM_RIGHT: [usize; 3] = [
    joint::RIGHT_SHOULDER,
    joint::RIGHT_ELBOW,
    joint::RIGHT_WRIST,
];
const LEG_LEFT: [usize; 4] = [
    joint::LEFT_HIP,
    joint::LEFT_KNEE,
    joint::LEFT_ANKLE,
    joint::LEFT_FOOT,
];
const LEG_RIGHT: [usize; 4] = [
    joint::RIGHT_HIP,
    joint::RIGHT_KNEE,
    joint::RIGHT_ANKLE,
    joint::RIGHT_FOOT,
];
/// An arm's joints with its hand's (the fingers: joints 25–39 left, 40–54 right).
const ARM_LEFT_ALL: [usize; 18] = arm_with_hand(ARM_LEFT, 25);
const ARM_RIGHT_ALL: [usize; 18] = arm_with_hand(ARM_RIGHT, 40);

const fn arm_with_hand(arm: [usize; 3], first_finger: usize) -> [usize; 18] {
    let mut out = [0; 18];
    out[0] = arm[0];
    out[1] = arm[1];
    out[2] = arm[2];
    let mut k = 0;
    while k < 15 {
        out[3 + k] = first_finger + k;
        k += 1;
    }
    out
}

/// A limb's chain of joints, extended past its last joint by the last bone's length (the hand,
/// the toes).
struct Chain {
    points: Vec<Vec3>,
}

fn side_chain(joints: &[Vec3], chain: impl AsRef<[usize]>) -> Chain {
    let mut points: Vec<Vec3> = chain.as_ref().iter().map(|&k| joints[k]).collect();
    let n = points.len();
    let tip = points[n - 1] + (points[n - 1] - points[n - 2]);
    points.push(tip);
    Chain { points }
}

impl Chain {
    /// The chain's length from its first point to point `k`.
    fn length_to(&self, k: usize) -> Real {
        self.points
            .windows(2)
            .take(k)
            .map(|w| (w[1] - w[0]).length())
            .sum()
    }

    /// How far along the chain `p` lies (its projection on the nearest segment; before the
    /// first point negative, past the last beyond the length).
    fn along(&self, p: Vec3) -> Real {
        let n = self.points.len() - 1;
        let mut best = (Real::INFINITY, 0.0);
        let mut start = 0.0;
        for (i, w) in self.points.windows(2).enumerate() {
            let d = w[1] - w[0];
            let len = d.length();
            let mut t = (p - w[0]).dot(d) / (len * len);
            if i > 0 {
                t = t.max(0.0);
            }
            if i + 1 < n {
                t = t.min(1.0);
            }
            let dist = (p - (w[0] + t * d)).length();
            if dist < best.0 {
                best = (dist, start + t * len);
            }
            start += len;
        }
        best.1
    }
}

/// `0` below `lo`, `1` above `hi`, smooth between.
fn smoothstep(lo: Real, hi: Real, x: Real) -> Real {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl Frame {
    /// The distances of rest point `p` to each slot's garment as the outfit cuts it (positive on
    /// it), in `SLOTS` order.
    fn distances(
        &self,
        outfit: &Outfit,
        p: Vec3,
        along_arm: Real,
        along_leg: Real,
        arm_length: Real,
        leg_length: Real,
    ) -> [Real; SLOTS.len()] {
        let j = &self.joints;
        let cut = &outfit.cut;
        let pelvis_y = j[joint::PELVIS].y;
        let neck = j[joint::NECK];
        let ankle_y = 0.5 * (j[joint::LEFT_ANKLE].y + j[joint::RIGHT_ANKLE].y);
        let shin = 0.5 * (j[joint::LEFT_KNEE].y + j[joint::RIGHT_KNEE].y) - ankle_y;
        // The neck's opening: the neck above its base, and the neckline cut into the chest.
        let dx = p.x - neck.x;
        let radial = (dx * dx + (p.z - neck.z).powi(2)).sqrt();
        let base_y = neck.y - 0.05 * self.torso;
        let neck_open = (self.neck_radius + 0.012 - radial).min(p.y - base_y);
        let (width, power) = match cut.neckline {
            Neckline::V => (1.4 * self.neck_radius, 1.0),
            Neckline::Scoop => (1.8 * self.neck_radius, 2.0),
            Neckline::Crew => (1.25 * self.neck_radius, 2.0),
        };
        let shape = (1.0 - (dx.abs() / width).powf(power)).max(0.0);
        let cut_y = base_y - cut.neck_depth * self.torso * shape + (dx.abs() - width).max(0.0);
        let front_open = (p.y - cut_y).min(p.z - neck.z + 0.01);
        let open = neck_open.max(front_open);
        let top = (cut.sleeve * arm_length - along_arm)
            .min(p.y - (pelvis_y + cut.hem * self.torso))
            .min(-open);
        let bottom =
            ((pelvis_y + cut.waist * self.torso) - p.y).min(cut.leg * leg_length - along_leg);
        let socks = ankle_y + cut.socks * shin - p.y;
        let shoes = ankle_y + cut.shoes * shin - p.y;
        // Hair: above the hairline at the vertex's bearing round the head; never on an arm,
        // and below the neck's base only behind it.
        let head = j[joint::HEAD];
        let (hx, hz) = (p.x - head.x, p.z - head.z);
        let front = hz / (hx * hx + hz * hz).sqrt().max(1e-9);
        let [h_front, h_side, h_back] = cut.hairline;
        let level = if front >= 0.0 {
            h_side + (h_front - h_side) * smoothstep(0.0, 0.6, front)
        } else {
            h_side + (h_back - h_side) * smoothstep(0.0, 0.7, -front)
        };
        let behind = (neck.z - 0.02 - p.z) + 3.0 * (p.y - base_y).max(0.0);
        let hair = (p.y - (self.eye_y + level * self.head))
            .min(-along_arm - 0.02)
            .min(behind);
        [top, bottom, socks, shoes, hair]
    }
}
