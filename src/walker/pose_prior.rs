//! The pose-plausibility prior of the reward's pose term: a Gaussian mixture with diagonal
//! covariances over the 21 body-joint rotations (axis-angle, 63 values; global orientation
//! excluded) fitted by EM on the training mocap's frames.
//!
//! EgoGen scores poses with VPoser, which is licence-gated; this prior is fitted on our own
//! training poses instead. Its score is the negative log-density per joint value,
//! `nll(θ) = −ln p(θ) / 63`, so that a score does not grow with the number of joints; mocap
//! frames score low, broken ones (joints bent past their range) high. `egogen policy
//! pose-prior` fits it and reports how well it separates mocap from random-latent and bent
//! poses (docs/POLICY.md).

use std::path::Path;

use rand_chacha::ChaCha8Rng;
use rand_core::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::body::BodyParams;

/// Body joints the prior covers (SMPL-X joints 1..=21).
pub(crate) const PRIOR_JOINTS: usize = 21;
/// Values per pose.
pub(crate) const PRIOR_DIM: usize = 3 * PRIOR_JOINTS;

/// Smallest variance of a component along one value (rad²): keeps a component from collapsing
/// onto a joint the data never moves.
const MIN_VARIANCE: f64 = 1e-4;

/// The body-joint rotations of a pose.
pub(crate) fn prior_values(params: &BodyParams) -> [f64; PRIOR_DIM] {
    std::array::from_fn(|k| params.pose[3 + k])
}

/// One mixture component.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Component {
    pub weight: f64,
    pub mean: Vec<f64>,
    pub variance: Vec<f64>,
}

/// A diagonal Gaussian mixture over body-joint rotations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PosePrior {
    /// Where the poses came from (config path and frame count), for the record.
    pub source: String,
    pub frames: usize,
    /// Largest mean score over a primitive's frames that still counts as plausible (the
    /// reward's pose term): a high quantile of the training primitives' mean scores.
    pub plausible_max_nll: f64,
    /// The quantile `plausible_max_nll` was set at.
    pub plausible_quantile: f64,
    pub components: Vec<Component>,
}

/// Why a prior file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum PosePriorError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: not a pose prior: {source}")]
    Parse {
        path: String,
        source: serde_json::Error,
    },
    #[error(
        "{path}: component {index}: expected {PRIOR_DIM} means and variances > 0 and a weight > 0"
    )]
    Invalid { path: String, index: usize },
    #[error("{path}: plausible_max_nll must be a finite number")]
    NoLimit { path: String },
    #[error("{path}: no components")]
    Empty { path: String },
}

/// `ln N(x; μ, diag σ²)` summed over the values, without the `−d/2 ln 2π` constant.
fn log_gauss(x: &[f64], mean: &[f64], var: &[f64]) -> f64 {
    x.iter()
        .zip(mean)
        .zip(var)
        .map(|((x, m), v)| -0.5 * ((x - m).powi(2) / v + v.ln()))
        .sum()
}

/// [`log_gauss`] with the variances' logarithms given (`ln_var[d] = var[d].ln()`): the same
/// operations in the same order, so the same bits, without a logarithm per value.
fn log_gauss_with(x: &[f64], mean: &[f64], var: &[f64], ln_var: &[f64]) -> f64 {
    x.iter()
        .zip(mean)
        .zip(var)
        .zip(ln_var)
        .map(|(((x, m), v), ln_v)| -0.5 * ((x - m).powi(2) / v + ln_v))
        .sum()
}

/// The logarithms a score takes of a prior's fixed numbers: each component's weight and
/// variances. Worked out once for the frames of a primitive instead of once per frame.
struct PriorLogs {
    weight: Vec<f64>,
    variance: Vec<Vec<f64>>,
    /// Per component: the sum of its variances' logarithms.
    variance_sum: Vec<f64>,
}

impl PriorLogs {
    fn of(prior: &PosePrior) -> Self {
        let variance: Vec<Vec<f64>> = prior
            .components
            .iter()
            .map(|c| c.variance.iter().map(|v| v.ln()).collect())
            .collect();
        Self {
            weight: prior.components.iter().map(|c| c.weight.ln()).collect(),
            variance_sum: variance.iter().map(|v| v.iter().sum()).collect(),
            variance,
        }
    }
}

fn log_sum_exp(v: &[f64]) -> f64 {
    let m = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !m.is_finite() {
        return m;
    }
    m + v.iter().map(|x| (x - m).exp()).sum::<f64>().ln()
}

impl PosePrior {
    /// Fits `components` components by EM (`iterations` rounds) to `poses`, initialised by
    /// k-means++ seeding with `seed`.
    pub(crate) fn fit(
        poses: &[[f64; PRIOR_DIM]],
        components: usize,
        iterations: usize,
        seed: u64,
        source: impl Into<String>,
    ) -> Self {
        assert!(!poses.is_empty(), "a pose prior needs poses");
        let n = poses.len();
        let k = components.clamp(1, n);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        // k-means++ seeding of the means.
        let mut means: Vec<Vec<f64>> = vec![poses[(rng.next_u64() % n as u64) as usize].to_vec()];
        let sq = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
        let mut nearest: Vec<f64> = poses.iter().map(|p| sq(p, &means[0])).collect();
        while means.len() < k {
            let pick = crate::math::random::weighted_index(&mut rng, nearest.iter().copied());
            means.push(poses[pick].to_vec());
            for (d, p) in nearest.iter_mut().zip(poses) {
                *d = d.min(sq(p, means.last().expect("just pushed")));
            }
        }
        let global_var: Vec<f64> = (0..PRIOR_DIM)
            .map(|d| {
                let m = poses.iter().map(|p| p[d]).sum::<f64>() / n as f64;
                (poses.iter().map(|p| (p[d] - m).powi(2)).sum::<f64>() / n as f64).max(MIN_VARIANCE)
            })
            .collect();
        let mut prior = Self {
            source: source.into(),
            frames: n,
            plausible_max_nll: f64::MAX,
            plausible_quantile: 1.0,
            components: means
                .into_iter()
                .map(|mean| Component {
                    weight: 1.0 / k as f64,
                    mean,
                    variance: global_var.clone(),
                })
                .collect(),
        };
        let mut resp = vec![0.0; n * k];
        for _ in 0..iterations {
            // E step.
            for (i, p) in poses.iter().enumerate() {
                let row = &mut resp[i * k..(i + 1) * k];
                for (r, c) in row.iter_mut().zip(&prior.components) {
                    *r = c.weight.ln() + log_gauss(p, &c.mean, &c.variance);
                }
                let lse = log_sum_exp(row);
                row.iter_mut().for_each(|r| *r = (*r - lse).exp());
            }
            // M step.
            for (j, c) in prior.components.iter_mut().enumerate() {
                let nk: f64 = (0..n).map(|i| resp[i * k + j]).sum();
                if nk < 1e-9 {
                    continue;
                }
                c.weight = nk / n as f64;
                for d in 0..PRIOR_DIM {
                    let m = (0..n).map(|i| resp[i * k + j] * poses[i][d]).sum::<f64>() / nk;
                    let v = (0..n)
                        .map(|i| resp[i * k + j] * (poses[i][d] - m).powi(2))
                        .sum::<f64>()
                        / nk;
                    c.mean[d] = m;
                    c.variance[d] = v.max(MIN_VARIANCE);
                }
            }
        }
        prior
    }

    /// Sets the plausibility limit to quantile `q` of `primitive_means` (mean scores of whole
    /// primitives).
    pub(crate) fn set_plausible_limit(&mut self, primitive_means: &[f64], q: f64) {
        let mut v: Vec<f64> = primitive_means
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .collect();
        v.sort_by(f64::total_cmp);
        if let Some(last) = v.len().checked_sub(1) {
            self.plausible_max_nll = v[((q.clamp(0.0, 1.0) * last as f64).round()) as usize];
            self.plausible_quantile = q;
        }
    }

    /// Negative log-density per value, `−ln p(θ)/63` (lower is more plausible).
    #[cfg(test)]
    pub(crate) fn nll(&self, values: &[f64; PRIOR_DIM]) -> f64 {
        self.scores_with(values, &PriorLogs::of(self)).0
    }

    /// The score and the embedding norm ([`Self::embedding_norms`]) together: the norm is read
    /// off the terms of the score (a component's log-density holds its Mahalanobis distance).
    fn scores_with(&self, values: &[f64; PRIOR_DIM], logs: &PriorLogs) -> (f64, f64) {
        let terms: Vec<f64> = self
            .components
            .iter()
            .zip(&logs.weight)
            .zip(&logs.variance)
            .map(|((c, ln_weight), ln_var)| {
                ln_weight + log_gauss_with(values, &c.mean, &c.variance, ln_var)
                    - 0.5 * PRIOR_DIM as f64 * std::f64::consts::TAU.ln()
            })
            .collect();
        let half_ln_tau = 0.5 * PRIOR_DIM as f64 * std::f64::consts::TAU.ln();
        let norm = terms
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(f64::NAN, |(k, t)| {
                // t = ln w − ½ (Σ (x − μ)² / σ² + Σ ln σ²) − ½ d ln 2π.
                let squared = -2.0 * (t - logs.weight[k] + half_ln_tau) - logs.variance_sum[k];
                squared.max(0.0).sqrt()
            });
        (-log_sum_exp(&terms) / PRIOR_DIM as f64, norm)
    }

    /// Each of `frames`' pose embedding norm, in VPoser's role (EgoGen's ‖VP‖₂: the norm of the
    /// pose's latent code, near 0 for likely poses): the Mahalanobis distance of the body-joint
    /// rotations from the mixture component most responsible for them, i.e. the norm of the
    /// pose whitened by that component (63 values); the prior's logarithms taken once.
    pub(crate) fn embedding_norms(&self, frames: &[BodyParams]) -> Vec<f64> {
        let logs = PriorLogs::of(self);
        frames
            .iter()
            .map(|f| self.scores_with(&prior_values(f), &logs).1)
            .collect()
    }

    /// The mean score of `frames` ([`Self::mean_pose_nll`], the same bits) and the largest
    /// embedding norm among them ([`Self::embedding_norms`]); (0, 0) for none.
    pub(crate) fn mean_nll_and_max_norm(&self, frames: &[BodyParams]) -> (f64, f64) {
        let logs = PriorLogs::of(self);
        let (sum, max) = frames.iter().fold((0.0, 0.0f64), |(sum, max), f| {
            let (nll, norm) = self.scores_with(&prior_values(f), &logs);
            (sum + nll, max.max(norm))
        });
        (sum / frames.len().max(1) as f64, max)
    }

    /// [`Self::nll`] of a body's pose.
    #[cfg(test)]
    pub(crate) fn pose_nll(&self, params: &BodyParams) -> f64 {
        self.nll(&prior_values(params))
    }

    /// The mean over `frames` of `nll` of each frame's pose (0 for none): the reward's
    /// pose score of a primitive, the prior's logarithms taken once for all its frames (the
    /// same bits as averaging frame by frame).
    pub(crate) fn mean_pose_nll(&self, frames: &[BodyParams]) -> f64 {
        self.mean_nll_and_max_norm(frames).0
    }

    /// Writes the prior as JSON (atomically).
    pub(crate) fn save(&self, path: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string(self).map_err(std::io::Error::other)?;
        crate::atomic_file::write_atomically(path, text.as_bytes())
    }

    /// Reads a prior written by [`Self::save`], checking its shape.
    pub fn load(path: &Path) -> Result<Self, PosePriorError> {
        let p = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| PosePriorError::Io {
            path: p.clone(),
            source,
        })?;
        let prior: Self = serde_json::from_str(&text).map_err(|source| PosePriorError::Parse {
            path: p.clone(),
            source,
        })?;
        if prior.components.is_empty() {
            return Err(PosePriorError::Empty { path: p });
        }
        for (index, c) in prior.components.iter().enumerate() {
            let ok = c.weight > 0.0
                && c.weight.is_finite()
                && c.mean.len() == PRIOR_DIM
                && c.variance.len() == PRIOR_DIM
                && c.mean.iter().all(|m| m.is_finite())
                && c.variance.iter().all(|v| *v > 0.0 && v.is_finite());
            if !ok {
                return Err(PosePriorError::Invalid { path: p, index });
            }
        }
        if !prior.plausible_max_nll.is_finite() {
            return Err(PosePriorError::NoLimit { path: p });
        }
        Ok(prior)
    }
}

/// Default path of the shipped prior, relative to the crate root.
pub(crate) const SHIPPED_POSE_PRIOR: &str = "assets/policy/pose_prior.json";

/// The shipped prior's path.
pub fn shipped_pose_prior_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(SHIPPED_POSE_PRIOR)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_primitive_scores_the_mean_of_its_frames_bit_for_bit() {
        // Poses spread over joints and components, some far from any mean.
        let pose = |i: usize| -> [f64; PRIOR_DIM] {
            std::array::from_fn(|d| ((i * 31 + d * 7) as f64 * 0.173).sin() * (1.0 + i as f64))
        };
        let poses: Vec<[f64; PRIOR_DIM]> = (0..40).map(pose).collect();
        let prior = PosePrior::fit(&poses, 3, 5, 7, "sines");
        let frames: Vec<BodyParams> = (0..20)
            .map(|i| {
                let mut p = BodyParams::default();
                p.pose[3..3 + PRIOR_DIM].copy_from_slice(&pose(3 * i + 1));
                p
            })
            .collect();
        let frame_by_frame =
            frames.iter().map(|f| prior.pose_nll(f)).sum::<f64>() / frames.len() as f64;
        assert_eq!(
            prior.mean_pose_nll(&frames).to_bits(),
            frame_by_frame.to_bits()
        );
        // The logarithms taken once score as `log_gauss` does per value.
        let logs = PriorLogs::of(&prior);
        for (c, ln_var) in prior.components.iter().zip(&logs.variance) {
            let x = pose(5);
            assert_eq!(
                log_gauss(&x, &c.mean, &c.variance).to_bits(),
                log_gauss_with(&x, &c.mean, &c.variance, ln_var).to_bits()
            );
        }
        assert_eq!(prior.mean_pose_nll(&[]), 0.0);
        // Score and norm together: the same score bits, the largest frame's norm.
        let (mean, max) = prior.mean_nll_and_max_norm(&frames);
        assert_eq!(mean.to_bits(), frame_by_frame.to_bits());
        let norms: Vec<f64> = prior.embedding_norms(&frames);
        assert_eq!(max, norms.iter().copied().fold(0.0, f64::max));
    }

    #[test]
    fn the_embedding_norm_is_the_whitened_distance_from_the_nearest_component() {
        let c = |m: f64, v: f64, w: f64| Component {
            weight: w,
            mean: vec![m; PRIOR_DIM],
            variance: vec![v; PRIOR_DIM],
        };
        let prior = PosePrior {
            source: String::new(),
            frames: 0,
            plausible_max_nll: 0.0,
            plausible_quantile: 0.0,
            components: vec![c(0.0, 0.01, 0.5), c(1.0, 0.04, 0.5)],
        };
        let at = |x: f64| {
            let mut p = BodyParams::default();
            p.pose[3..3 + PRIOR_DIM].fill(x);
            p
        };
        let d = PRIOR_DIM as f64;
        // At a component's mean the norm is 0; 0.1 rad off every value of the first (σ = 0.1)
        // it is √63; near the second (σ = 0.2), 0.1 off is √63 / 2.
        assert!(prior.embedding_norms(&[at(0.0)])[0] < 1e-6);
        assert!((prior.embedding_norms(&[at(0.1)])[0] - d.sqrt()).abs() < 1e-6);
        assert!((prior.embedding_norms(&[at(0.9)])[0] - 0.5 * d.sqrt()).abs() < 1e-6);
    }
}
