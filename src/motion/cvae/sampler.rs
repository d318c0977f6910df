//! Random-latent motion without a policy: each primitive of a chain is the most plausible of
//! `candidates` primitives decoded from latents z ~ N(0, I) (best-of-K sampling).
//!
//! EgoGen's locomotion policy picks latents towards a goal. This scores a few random draws per
//! step with what every plausible primitive has — feet on the floor without skating (the
//! foot-contact score, paper Eq. 12), pelvis at a human height, trunk near upright, walking
//! pace — and keeps the best; with one candidate it is the plain random chain. A goal point
//! (`PlausibilityRules::goal_xy`) makes it a minimal steering policy: it shows what the latent
//! space can do when latents are chosen (docs/MOTION.md). The candidates are decoded as one
//! batch.

use rand_chacha::ChaCha8Rng;

use super::contact::contact_score;
use super::infer::{BodyContext, DecodeError, DecodedPrimitive, MotionModel, PrimitiveSeed};
use super::tensor_body::RigGeometry;
use crate::body::joint;
use crate::math::random::normal_samples;
use crate::motion::primitive::{PRIMITIVE_RATE_HZ, SEED_FRAMES};

/// What makes a decoded primitive plausible, and how much each shortfall costs in the score
/// `ln(contact score) − Σ weight · shortfall`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PlausibilityRules {
    /// Pelvis heights above the floor (m) that cost nothing (the training clips' range is
    /// 0.71–1.18 m).
    pub pelvis_m: (f64, f64),
    /// Trunk (pelvis → neck) lean from the vertical that costs nothing (degrees).
    pub trunk_tilt_max_deg: f64,
    /// Mean horizontal pelvis speed below which a primitive costs (m/s): the training clips
    /// walk and run, standing still leads out of them.
    pub pelvis_speed_min: f64,
    /// Cost per metre of pelvis height outside `pelvis_m` (largest over the frames).
    pub pelvis_weight: f64,
    /// Cost per radian of lean beyond `trunk_tilt_max_deg` (largest over the frames).
    pub tilt_weight: f64,
    /// Cost per m/s short of `pelvis_speed_min`.
    pub speed_weight: f64,
    /// A point on the floor (world x, y) the chain is steered to, as the locomotion policy
    /// steers it: each metre between the pelvis at a primitive's end and the goal costs
    /// `goal_weight`. `None`: no goal.
    pub goal_xy: Option<[f64; 2]>,
    /// Cost per metre of distance to `goal_xy`.
    pub goal_weight: f64,
}

impl Default for PlausibilityRules {
    fn default() -> Self {
        Self {
            pelvis_m: (0.7, 1.2),
            trunk_tilt_max_deg: 12.0,
            pelvis_speed_min: 0.5,
            pelvis_weight: 10.0,
            tilt_weight: 20.0,
            speed_weight: 2.0,
            goal_xy: None,
            goal_weight: 2.0,
        }
    }
}

/// The terms of one primitive's plausibility.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct Plausibility {
    /// Foot-contact score (Eq. 12) of the 20 frames.
    pub contact: f64,
    /// Largest distance (m) of the pelvis height outside the plausible range.
    pub pelvis_out_m: f64,
    /// Largest trunk lean beyond the allowed one (rad).
    pub tilt_excess_rad: f64,
    /// How far the mean pelvis speed falls short of the minimum (m/s).
    pub speed_short: f64,
    /// Horizontal distance (m) of the pelvis at the primitive's end from the goal (0 without
    /// one).
    pub goal_distance_m: f64,
    /// `ln(contact) − weighted shortfalls`: higher is more plausible.
    pub score: f64,
}

/// Scores a decoded primitive; `foot_markers` are the marker indices of the feet
/// (`RigGeometry::foot_markers`).
pub(crate) fn plausibility(
    p: &DecodedPrimitive,
    foot_markers: &[usize],
    rules: &PlausibilityRules,
) -> Plausibility {
    let feet: Vec<Vec<[f64; 3]>> = p
        .markers
        .iter()
        .map(|m| foot_markers.iter().map(|&k| m[k].to_array()).collect())
        .collect();
    let contact = contact_score(&feet, p.floor_z);
    let decoded = &p.joints[SEED_FRAMES..];
    let (lo, hi) = rules.pelvis_m;
    let pelvis_out_m = decoded
        .iter()
        .map(|j| {
            let h = j[joint::PELVIS].z - p.floor_z;
            (lo - h).max(h - hi).max(0.0)
        })
        .fold(0.0, f64::max);
    let tilt_max = rules.trunk_tilt_max_deg.to_radians();
    let tilt_excess_rad = decoded
        .iter()
        .map(|j| {
            let up = (j[joint::NECK] - j[joint::PELVIS]).normalize();
            (up.z.clamp(-1.0, 1.0).acos() - tilt_max).max(0.0)
        })
        .fold(0.0, f64::max);
    let start = p.joints[SEED_FRAMES - 1][joint::PELVIS];
    let end = p.joints[p.joints.len() - 1][joint::PELVIS];
    let speed =
        end.truncate().distance(start.truncate()) * PRIMITIVE_RATE_HZ / decoded.len() as f64;
    let speed_short = (rules.pelvis_speed_min - speed).max(0.0);
    let goal_distance_m = rules
        .goal_xy
        .map_or(0.0, |goal| end.truncate().distance(goal.into()));
    let score = contact.max(1e-300).ln()
        - rules.pelvis_weight * pelvis_out_m
        - rules.tilt_weight * tilt_excess_rad
        - rules.speed_weight * speed_short
        - rules.goal_weight * goal_distance_m;
    Plausibility {
        contact,
        pelvis_out_m,
        tilt_excess_rad,
        speed_short,
        goal_distance_m,
        score: if score.is_nan() {
            f64::NEG_INFINITY
        } else {
            score
        },
    }
}

/// The floor point (world x, y) `ahead_m` metres in front of the body in the seed's last frame:
/// along the horizontal normal of its hip axis, the way the body faces.
pub(crate) fn goal_ahead(
    body: &BodyContext,
    seed: &PrimitiveSeed,
    ahead_m: f64,
) -> Result<[f64; 2], DecodeError> {
    goal_toward(body, seed, ahead_m, 0.0)
}

/// The floor point (world x, y) `distance_m` metres from the pelvis in the seed's last frame,
/// `bearing_rad` from the way the body faces (positive: to its left, seen from above).
pub(crate) fn goal_toward(
    body: &BodyContext,
    seed: &PrimitiveSeed,
    distance_m: f64,
    bearing_rad: f64,
) -> Result<[f64; 2], DecodeError> {
    let last = &seed.frames[seed.frames.len() - 1];
    let joints = body.shaped.skeleton(&last.pose, last.transl)?.joints;
    let right = joints[joint::RIGHT_HIP] - joints[joint::LEFT_HIP];
    let forward = glam::DVec2::new(-right.y, right.x).normalize();
    let direction = glam::DVec2::from_angle(bearing_rad).rotate(forward);
    Ok((joints[joint::PELVIS].truncate() + direction * distance_m).to_array())
}

/// Draws latents and keeps the most plausible primitive of each step.
pub(crate) struct BestOfK {
    /// Latents drawn per primitive (1: the plain random chain).
    pub candidates: usize,
    pub rules: PlausibilityRules,
    /// Primitives each candidate is continued for (random latents, one draw each) before
    /// choosing; a candidate is worth the least plausible primitive of its continuation. 0
    /// judges candidates alone.
    pub horizon: usize,
    foot_markers: Vec<usize>,
}

impl BestOfK {
    /// A sampler for `body` with `candidates` ≥ 1 draws per primitive.
    pub(crate) fn new(
        body: &BodyContext,
        candidates: usize,
        rules: PlausibilityRules,
    ) -> Result<Self, DecodeError> {
        Ok(Self {
            candidates: candidates.max(1),
            rules,
            horizon: 0,
            foot_markers: RigGeometry::new(body.model, &body.betas)?.foot_markers,
        })
    }

    /// The next primitive after `seed`: the most plausible of `candidates` decoded from fresh
    /// latents z ~ N(0, I) drawn from `rng` (the first of equals wins).
    pub(crate) fn next(
        &self,
        model: &MotionModel,
        body: &BodyContext,
        seed: &PrimitiveSeed,
        rng: &mut ChaCha8Rng,
    ) -> Result<Sampled, DecodeError> {
        let latents: Vec<Vec<f32>> = (0..self.candidates)
            .map(|_| normal_samples(rng, model.latent_dim()))
            .collect();
        let seeds = vec![seed.clone(); self.candidates];
        let mut kept: Vec<Sampled> = Vec::with_capacity(self.candidates);
        let mut non_finite = 0;
        let mut last_error = None;
        for decoded in model.decode_each(body, &seeds, &latents)? {
            match decoded {
                Ok(primitive) => {
                    let plausibility = plausibility(&primitive, &self.foot_markers, &self.rules);
                    kept.push(Sampled {
                        primitive,
                        plausibility,
                        non_finite_candidates: 0,
                    });
                }
                Err(e @ DecodeError::NonFinite { .. }) => {
                    non_finite += 1;
                    last_error = Some(e);
                }
                Err(e) => return Err(e),
            }
        }
        if kept.is_empty() {
            return Err(last_error.expect("a candidate failed"));
        }
        // Worth of each candidate: its own score, or the worst along its continuation.
        let mut worth: Vec<f64> = kept.iter().map(|c| c.plausibility.score).collect();
        if self.candidates > 1 && self.horizon > 0 {
            let mut ends: Vec<PrimitiveSeed> =
                kept.iter().map(|c| c.primitive.next_seed()).collect();
            for _ in 0..self.horizon {
                let latents: Vec<Vec<f32>> = (0..ends.len())
                    .map(|_| normal_samples(rng, model.latent_dim()))
                    .collect();
                for (i, decoded) in model
                    .decode_each(body, &ends, &latents)?
                    .into_iter()
                    .enumerate()
                {
                    match decoded {
                        Ok(p) => {
                            let s = plausibility(&p, &self.foot_markers, &self.rules).score;
                            worth[i] = worth[i].min(s);
                            ends[i] = p.next_seed();
                        }
                        Err(DecodeError::NonFinite { .. }) => worth[i] = f64::NEG_INFINITY,
                        Err(e) => return Err(e),
                    }
                }
            }
        }
        let best = (0..kept.len()).fold(0, |b, i| if worth[i] > worth[b] { i } else { b });
        let mut chosen = kept.swap_remove(best);
        chosen.non_finite_candidates = non_finite;
        Ok(chosen)
    }
}

/// One step of a best-of-K chain.
#[derive(Debug, Clone)]
pub(crate) struct Sampled {
    pub primitive: DecodedPrimitive,
    pub plausibility: Plausibility,
    /// Candidates of this step dropped because they decoded to non-finite values.
    pub non_finite_candidates: usize,
}
