//! What the latent space can reach, measured with the CEM optimiser of [`super::control`]:
//! sustained straight walks at a target pace and turns by a target angle, each with its foot
//! contact (3-D, paper Eq. 12) and plausibility. `egogen motion control` prints these reports.

use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::control::{chain_speed_m_s, relative_norm, Controlled, LatentController, PaceTarget};
use super::infer::{BodyContext, DecodeError, MotionModel, PrimitiveSeed};
use super::pace::{Pace, PACE_SPAN_S};
use crate::math::{wrap_rad, Quantiles};

/// A straight walk asked for one pace.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct WalkReport {
    pub target_speed_m_s: f64,
    pub primitives: usize,
    /// Seconds of decoded motion.
    pub seconds: f64,
    /// Start → end pelvis displacement over the time (m/s).
    pub speed_m_s: f64,
    /// The same over the second half of the walk (after any acceleration from the seed).
    pub speed_second_half_m_s: f64,
    /// Per-primitive pelvis speed.
    pub primitive_speed_m_s: Quantiles,
    /// Mean absolute heading error at primitive ends (degrees).
    pub heading_error_mean_deg: f64,
    /// Foot contact (3-D, Eq. 12) of the primitives: mean and 10th percentile.
    pub contact_mean: f64,
    pub contact_p10: f64,
    /// Primitives whose pelvis left 0.7–1.2 m above the floor or whose trunk leant beyond 12°.
    pub implausible_primitives: usize,
    /// Mean `|z|/√L` of the chosen latents (1 is typical of N(0, I)).
    pub latent_norm_mean: f64,
    /// Whether the walk held the pace: second-half speed within 10 % of the target and mean
    /// contact ≥ 0.95.
    pub reached: bool,
    /// Wall time (s).
    pub wall_s: f64,
}

/// A turn asked for one angle.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct TurnReport {
    pub target_turn_deg: f64,
    pub target_speed_m_s: f64,
    /// Primitives until the heading was within `TURN_TOLERANCE_DEG` of the target heading
    /// (either way round: a 180° turn may go left or right; None: not within
    /// `max_primitives`).
    pub primitives_to_turn: Option<usize>,
    /// Heading change achieved after the first 1, 2, … primitives (degrees).
    pub turned_deg: Vec<f64>,
    pub contact_mean: f64,
    pub implausible_primitives: usize,
    pub wall_s: f64,
}

/// The primitive walking nearest 1.0 m/s straight ahead (where walks and turns start), by
/// index into `paces`; None when there are none.
pub(crate) fn steady_walk_index(paces: &[Pace]) -> Option<usize> {
    let cost = |p: &Pace| (p.speed_m_s - 1.0).abs() + p.turn_deg.abs() / 30.0;
    (0..paces.len()).min_by(|&a, &b| cost(&paces[a]).total_cmp(&cost(&paces[b])))
}

/// Heading error (degrees) under which a turn counts as done.
pub(crate) const TURN_TOLERANCE_DEG: f64 = 15.0;

fn contact_stats(steps: &[Controlled]) -> (f64, f64, usize) {
    let q = Quantiles::of(steps.iter().map(|s| s.plausibility.contact));
    let implausible = steps
        .iter()
        .filter(|s| s.plausibility.pelvis_out_m > 0.0 || s.plausibility.tilt_excess_rad > 0.0)
        .count();
    (q.mean, q.p10, implausible)
}

/// A walk of `primitives` from `seed` asked to keep `speed_m_s` along the heading the seed
/// faces.
pub(crate) fn sustained_walk(
    controller: &LatentController,
    model: &MotionModel,
    body: &BodyContext,
    seed: &PrimitiveSeed,
    speed_m_s: f64,
    primitives: usize,
    rng: &mut ChaCha8Rng,
) -> Result<(WalkReport, Vec<Controlled>), DecodeError> {
    let started = std::time::Instant::now();
    let mut heading0 = None;
    let steps = controller.chain(
        model,
        body,
        seed.clone(),
        primitives,
        |_, now| PaceTarget {
            speed_m_s,
            heading_rad: *heading0.get_or_insert(now),
        },
        rng,
    )?;
    let heading0 = heading0.unwrap_or(0.0);
    let prims: Vec<_> = steps.iter().map(|s| &s.primitive).collect();
    let (contact_mean, contact_p10, implausible) = contact_stats(&steps);
    let n = steps.len().max(1) as f64;
    let speed = chain_speed_m_s(&prims);
    let second = chain_speed_m_s(&prims[prims.len() / 2..]);
    let report = WalkReport {
        target_speed_m_s: speed_m_s,
        primitives,
        seconds: primitives as f64 * PACE_SPAN_S,
        speed_m_s: speed,
        speed_second_half_m_s: second,
        primitive_speed_m_s: Quantiles::of(steps.iter().map(|s| s.pace.speed_m_s)),
        heading_error_mean_deg: steps
            .iter()
            .map(|s| wrap_rad(s.heading_rad - heading0).abs().to_degrees())
            .sum::<f64>()
            / n,
        contact_mean,
        contact_p10,
        implausible_primitives: implausible,
        latent_norm_mean: steps.iter().map(|s| relative_norm(&s.latent)).sum::<f64>() / n,
        reached: (second - speed_m_s).abs() <= 0.1 * speed_m_s && contact_mean >= 0.95,
        wall_s: started.elapsed().as_secs_f64(),
    };
    Ok((report, steps))
}

/// A turn by `turn_deg` (positive: to the left) from `seed`, walking at `speed_m_s`, for at
/// most `max_primitives`.
pub(crate) fn turn(
    controller: &LatentController,
    model: &MotionModel,
    body: &BodyContext,
    seed: &PrimitiveSeed,
    turn_deg: f64,
    speed_m_s: f64,
    max_primitives: usize,
    rng: &mut ChaCha8Rng,
) -> Result<(TurnReport, Vec<Controlled>), DecodeError> {
    let started = std::time::Instant::now();
    let mut goal = None;
    let steps = controller.chain(
        model,
        body,
        seed.clone(),
        max_primitives,
        |_, now| {
            let h = *goal.get_or_insert(now + turn_deg.to_radians());
            PaceTarget {
                speed_m_s,
                heading_rad: h,
            }
        },
        rng,
    )?;
    // Turned angle, unwrapped primitive by primitive (a 180° turn passes ±180°).
    let mut turned = Vec::with_capacity(steps.len());
    let mut total = 0.0;
    for s in &steps {
        total += s.pace.turn_deg;
        turned.push(total);
    }
    let primitives_to_turn = turned
        .iter()
        .position(|t| {
            wrap_rad((t - turn_deg).to_radians()).abs().to_degrees() <= TURN_TOLERANCE_DEG
        })
        .map(|i| i + 1);
    let (contact_mean, _, implausible) = contact_stats(&steps);
    Ok((
        TurnReport {
            target_turn_deg: turn_deg,
            target_speed_m_s: speed_m_s,
            primitives_to_turn,
            turned_deg: turned,
            contact_mean,
            implausible_primitives: implausible,
            wall_s: started.elapsed().as_secs_f64(),
        },
        steps,
    ))
}
