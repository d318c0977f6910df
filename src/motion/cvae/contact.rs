//! The foot-contact score of EgoGen (paper Eq. 12, as its code computes it), per primitive.
//!
//! Foot-contact score of one primitive (20 frames at 40 Hz, feet markers `F`, floor height `h`):
//! `exp(−mean_t |min_{f∈F} z_{t,f} − h − 0.02|) · exp(−mean_t max(0, min_{f∈F} v_{t,f} − 0.075))`
//! with `v` the 3-D central-difference speed (m/s) over frames `1..T−1`, as EgoGen's and DIMOS's
//! code compute it (the paper's Eq. 12 numbers). GAMMA's code used the horizontal speed:
//! [`contact_score_horizontal`], which scores the same motion higher (a lifted foot's vertical
//! speed no longer counts as skating).

use crate::motion::primitive::PRIMITIVE_RATE_HZ;

/// Foot-contact score of one primitive from its foot markers `[T][F]` (z up) and floor height,
/// with 3-D foot speed (EgoGen/DIMOS, paper Eq. 12): the headline score everywhere.
pub(crate) fn contact_score(feet: &[Vec<[f64; 3]>], floor_z: f64) -> f64 {
    contact_score_with(feet, floor_z, |a, b| {
        glam::DVec3::from_array(b).distance(glam::DVec3::from_array(a))
    })
}

/// The foot-contact score with horizontal foot speed (GAMMA's code), a variant beside the
/// headline [`contact_score`].
pub(crate) fn contact_score_horizontal(feet: &[Vec<[f64; 3]>], floor_z: f64) -> f64 {
    contact_score_with(feet, floor_z, |a, b| {
        glam::DVec2::new(b[0], b[1]).distance(glam::DVec2::new(a[0], a[1]))
    })
}

fn contact_score_with(
    feet: &[Vec<[f64; 3]>],
    floor_z: f64,
    distance: impl Fn([f64; 3], [f64; 3]) -> f64,
) -> f64 {
    let (floor, skate) = contact_terms_with(feet, floor_z, distance);
    floor * skate
}

/// The two factors of the 3-D foot-contact score (paper Eq. 12), as EgoGen's reward uses
/// them: `exp(−mean |lowest foot − floor − 0.02|)` (floor term) and
/// `exp(−mean max(0, slowest foot speed − 0.075))` (skate term); NaN for fewer than 3 frames.
pub(crate) fn contact_terms(feet: &[Vec<[f64; 3]>], floor_z: f64) -> (f64, f64) {
    contact_terms_with(feet, floor_z, |a, b| {
        glam::DVec3::from_array(b).distance(glam::DVec3::from_array(a))
    })
}

fn contact_terms_with(
    feet: &[Vec<[f64; 3]>],
    floor_z: f64,
    distance: impl Fn([f64; 3], [f64; 3]) -> f64,
) -> (f64, f64) {
    let t = feet.len();
    if t < 3 {
        return (f64::NAN, f64::NAN);
    }
    let dist_floor = feet
        .iter()
        .map(|f| {
            let lowest = f.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
            (lowest - floor_z - 0.02).abs()
        })
        .sum::<f64>()
        / t as f64;
    let skate = (1..t - 1)
        .map(|i| {
            let slowest = (0..feet[i].len())
                .map(|k| distance(feet[i - 1][k], feet[i + 1][k]) * PRIMITIVE_RATE_HZ / 2.0)
                .fold(f64::INFINITY, f64::min);
            (slowest - 0.075).max(0.0)
        })
        .sum::<f64>()
        / (t - 2) as f64;
    ((-dist_floor).exp(), (-skate).exp())
}
