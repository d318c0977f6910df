//! Latents chosen for a target velocity and heading: a cross-entropy-method (CEM) optimiser per
//! primitive. It shows what the latent space can reach (pace, turns) before any policy is
//! trained on it: a policy that picks one latent per primitive cannot do better than an
//! optimiser that tries hundreds.
//!
//! Per primitive: draw `samples` latents from N(μ, diag σ²) (μ = 0, σ = 1 at first), decode
//! them as one batch, keep the `elites` of lowest cost, refit μ and σ to them, and repeat for
//! `iterations`; the best primitive decoded on the way is kept. Cost of a decoded primitive:
//!
//! `speed_weight·|v − v*| + heading_weight·|ψ_end − ψ*| + travel_weight·|dir(d) − ψ*|·min(1, v/0.3)
//!  − contact_weight·ln(contact) + pelvis and lean shortfalls + prior_weight·max(0, |z|/√L − 1)`
//!
//! with `v` its pelvis speed and `d` its horizontal pelvis displacement ([`super::pace`]), `ψ`
//! headings (rad), the foot-contact score (3-D, paper Eq. 12) and the pelvis-height and
//! trunk-lean shortfalls of [`super::sampler::plausibility`] with their weights, and the last
//! term keeping latents in the typical set of the prior N(0, I).

use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::infer::{BodyContext, DecodeError, DecodedPrimitive, MotionModel, PrimitiveSeed};
use super::pace::{heading_rad, Pace, PACE_SPAN_S};
use super::sampler::{plausibility, Plausibility, PlausibilityRules};
use super::tensor_body::RigGeometry;
use crate::body::joint;
use crate::math::random::normal_samples;
use crate::math::wrap_rad;
use crate::motion::primitive::SEED_FRAMES;
use crate::motion::MotionSequence;

/// What one primitive should do: move the pelvis at `speed_m_s` along `heading_rad` (world
/// yaw, counter-clockwise from +x) and end facing that way.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct PaceTarget {
    pub speed_m_s: f64,
    pub heading_rad: f64,
}

/// Settings of the optimiser (the speed/accuracy knob is `samples × iterations`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CemSettings {
    /// Latents decoded per iteration (one batch).
    pub samples: usize,
    /// Lowest-cost samples the distribution is refitted to.
    pub elites: usize,
    pub iterations: usize,
    /// Cost per m/s of speed error.
    pub speed_weight: f64,
    /// Cost per radian between the heading at the primitive's end and the target.
    pub heading_weight: f64,
    /// Cost per radian between the direction of travel and the target heading.
    pub travel_weight: f64,
    /// Cost per unit of `−ln(foot-contact score)`.
    pub contact_weight: f64,
    /// Cost per unit of `|z|/√L` beyond 1.
    pub prior_weight: f64,
    /// Plausibility terms (their `pelvis_speed_min` and goal are not used).
    pub rules: PlausibilityRules,
}

impl Default for CemSettings {
    fn default() -> Self {
        Self {
            samples: 128,
            elites: 8,
            iterations: 4,
            speed_weight: 4.0,
            heading_weight: 2.0,
            travel_weight: 1.0,
            contact_weight: 20.0,
            prior_weight: 4.0,
            rules: PlausibilityRules {
                pelvis_speed_min: 0.0,
                goal_xy: None,
                ..PlausibilityRules::default()
            },
        }
    }
}

/// One primitive chosen for a target.
#[derive(Debug, Clone)]
pub(crate) struct Controlled {
    pub primitive: DecodedPrimitive,
    pub latent: Vec<f32>,
    pub plausibility: Plausibility,
    pub pace: Pace,
    /// Heading at the primitive's end (rad).
    pub heading_rad: f64,
    pub cost: f64,
}

/// The CEM latent optimiser for one body.
pub(crate) struct LatentController {
    pub settings: CemSettings,
    foot_markers: Vec<usize>,
}

impl LatentController {
    pub(crate) fn new(body: &BodyContext, settings: CemSettings) -> Result<Self, DecodeError> {
        Ok(Self {
            settings,
            foot_markers: RigGeometry::new(body.model, &body.betas)?.foot_markers,
        })
    }

    /// Cost of a decoded primitive for `target` (lower is better) and its pieces.
    fn judge(&self, p: DecodedPrimitive, latent: Vec<f32>, target: &PaceTarget) -> Controlled {
        let s = &self.settings;
        let plaus = plausibility(&p, &self.foot_markers, &s.rules);
        let pace = Pace::of_frames(&p.joints);
        let first = p.joints[SEED_FRAMES - 1][joint::PELVIS].truncate();
        let last_joints = &p.joints[p.joints.len() - 1];
        let d = last_joints[joint::PELVIS].truncate() - first;
        let heading = heading_rad(last_joints);
        let travel_err = if d.length() > 1e-9 {
            wrap_rad(d.y.atan2(d.x) - target.heading_rad).abs() * (pace.speed_m_s / 0.3).min(1.0)
        } else {
            0.0
        };
        let norm = relative_norm(&latent);
        let cost = s.speed_weight * (pace.speed_m_s - target.speed_m_s).abs()
            + s.heading_weight * wrap_rad(heading - target.heading_rad).abs()
            + s.travel_weight * travel_err
            - s.contact_weight * plaus.contact.max(1e-300).ln()
            + s.rules.pelvis_weight * plaus.pelvis_out_m
            + s.rules.tilt_weight * plaus.tilt_excess_rad
            + s.prior_weight * (norm - 1.0).max(0.0);
        Controlled {
            primitive: p,
            latent,
            plausibility: plaus,
            pace,
            heading_rad: heading,
            cost: if cost.is_nan() { f64::INFINITY } else { cost },
        }
    }

    /// The lowest-cost primitive after `seed` for `target` found by CEM, with `rng` drawing
    /// the samples.
    pub(crate) fn next(
        &self,
        model: &MotionModel,
        body: &BodyContext,
        seed: &PrimitiveSeed,
        target: &PaceTarget,
        rng: &mut ChaCha8Rng,
    ) -> Result<Controlled, DecodeError> {
        let s = &self.settings;
        let l = model.latent_dim();
        let n = s.samples.max(1);
        let elites = s.elites.clamp(1, n);
        let mut mean = vec![0f64; l];
        let mut std = vec![1f64; l];
        let mut best: Option<Controlled> = None;
        let seeds = vec![seed.clone(); n];
        let mut last_error = None;
        for _ in 0..s.iterations.max(1) {
            let noise = normal_samples(rng, n * l);
            let latents: Vec<Vec<f32>> = (0..n)
                .map(|i| {
                    (0..l)
                        .map(|k| (mean[k] + std[k] * noise[i * l + k] as f64) as f32)
                        .collect()
                })
                .collect();
            let mut judged: Vec<Controlled> = Vec::with_capacity(n);
            for (decoded, z) in model
                .decode_each(body, &seeds, &latents)?
                .into_iter()
                .zip(latents)
            {
                match decoded {
                    Ok(p) => judged.push(self.judge(p, z, target)),
                    Err(e @ DecodeError::NonFinite { .. }) => last_error = Some(e),
                    Err(e) => return Err(e),
                }
            }
            judged.sort_by(|a, b| a.cost.total_cmp(&b.cost));
            let k = elites.min(judged.len());
            if k == 0 {
                continue;
            }
            for d in 0..l {
                let m = judged[..k].iter().map(|c| c.latent[d] as f64).sum::<f64>() / k as f64;
                let v = judged[..k]
                    .iter()
                    .map(|c| (c.latent[d] as f64 - m).powi(2))
                    .sum::<f64>()
                    / k as f64;
                mean[d] = m;
                // A floor on σ keeps the search from collapsing onto one latent.
                std[d] = v.sqrt().max(0.05);
            }
            let first = judged.swap_remove(0);
            if best.as_ref().is_none_or(|b| first.cost < b.cost) {
                best = Some(first);
            }
        }
        best.ok_or_else(|| last_error.expect("every candidate failed"))
    }

    /// A chain of `primitives` from `seed`, the target of each primitive given by
    /// `target(i, heading_at_start)`.
    pub(crate) fn chain(
        &self,
        model: &MotionModel,
        body: &BodyContext,
        seed: PrimitiveSeed,
        primitives: usize,
        mut target: impl FnMut(usize, f64) -> PaceTarget,
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<Controlled>, DecodeError> {
        let mut seed = seed;
        let mut out: Vec<Controlled> = Vec::with_capacity(primitives);
        for i in 0..primitives {
            let last = &seed.frames[SEED_FRAMES - 1];
            let joints = body.shaped.skeleton(&last.pose, last.transl)?.joints;
            let t = target(i, heading_rad(&joints));
            let step = self.next(model, body, &seed, &t, rng)?;
            seed = step.primitive.next_seed();
            out.push(step);
        }
        Ok(out)
    }
}

/// `|z|/√L`: the length of a latent relative to the typical length of a draw from N(0, I).
pub(crate) fn relative_norm(z: &[f32]) -> f64 {
    let l = z.len().max(1) as f64;
    z.iter().map(|&x| (x as f64).powi(2)).sum::<f64>().sqrt() / l.sqrt()
}

/// A chain of decoded primitives as one motion sequence at 40 Hz: the first primitive's seed
/// frames, then every primitive's decoded frames (world coordinates, the body's betas; the mean
/// shape, `betas` empty, is written as 10 zeros, so that loaders that slice `betas[:10]` work).
pub(crate) fn chain_sequence(prims: &[&DecodedPrimitive], betas: &[f64]) -> MotionSequence {
    let betas = if betas.is_empty() {
        vec![0.0; 10]
    } else {
        betas.to_vec()
    };
    let mut poses = Vec::new();
    let mut trans = Vec::new();
    for (i, p) in prims.iter().enumerate() {
        let from = if i == 0 { 0 } else { SEED_FRAMES };
        for f in &p.world[from..] {
            poses.push(f.pose);
            trans.push(f.transl);
        }
    }
    MotionSequence {
        frame_rate_hz: crate::motion::primitive::PRIMITIVE_RATE_HZ,
        betas,
        gender: "neutral".into(),
        poses,
        trans,
    }
}

/// Mean pelvis speed (m/s) of a chain: horizontal displacement start → end over its time.
pub(crate) fn chain_speed_m_s(prims: &[&DecodedPrimitive]) -> f64 {
    let (Some(a), Some(b)) = (prims.first(), prims.last()) else {
        return f64::NAN;
    };
    let start = a.joints[SEED_FRAMES - 1][joint::PELVIS].truncate();
    let end = b.joints[b.joints.len() - 1][joint::PELVIS].truncate();
    end.distance(start) / (PACE_SPAN_S * prims.len() as f64)
}
