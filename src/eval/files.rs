//! The result files of `egogen eval` (`results/*.json`): Table 1's and the speed suite's
//! scenario × controller rows, Tables 2 and 3's policy rows, the pose-norm calibration they
//! carry, as written and read back.

use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use crate::body::BodyParams;
use crate::walker::PosePrior;

/// One row of Table 2 or 3: a controller (a policy with sampled or mean actions, or the
/// sampling controller) on a set of held-out episodes.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct PolicyRow {
    pub policy: String,
    pub weights: String,
    pub config: String,
    pub set: String,
    pub actions: String,
    pub episodes: usize,
    pub success_rate: f64,
    pub contact: f64,
    pub penetration_share: f64,
    /// Share of frames with ≥ 40 body vertices inside the scene (paper Eq. 11; Table 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_penetration_share: Option<f64>,
    pub view_cos: f64,
    #[serde(deserialize_with = "null_as_nan")]
    pub final_distance_median_m: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_distance_mean_m: Option<f64>,
    /// The mean over episodes of their primitives' largest pose embedding norms (‖VP‖₂'s
    /// role), raw ([`PoseNormCalibration`] sets it on the paper's scale);
    /// absent in rows written before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose_norm_max_mean: Option<f64>,
    /// NaN (JSON null) when no episode succeeded.
    #[serde(deserialize_with = "null_as_nan")]
    pub speed_successful_median_m_s: f64,
    pub wall_s: f64,
    /// Time to load the scene and build its 3D SDF (the SDF-resolution rows).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub setup_s: Option<f64>,
}

/// A number written as JSON null (serde_json writes NaN so) read back as NaN.
fn null_as_nan<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    use serde::Deserialize;
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

impl PolicyRow {
    pub(crate) fn new(
        (policy, weights, config): (&str, &str, &str),
        set: &str,
        actions: &str,
        report: &crate::policy::held_out::EvalReport,
        scene: bool,
    ) -> Self {
        Self {
            policy: policy.into(),
            weights: weights.into(),
            config: config.into(),
            set: set.into(),
            actions: actions.into(),
            episodes: report.episodes,
            success_rate: report.success_rate,
            contact: report.contact_mean,
            penetration_share: report.penetration_share_mean,
            scene_penetration_share: scene.then_some(report.scene_penetration_share_mean),
            view_cos: report.view_cos_mean,
            final_distance_median_m: report.final_distance_m.p50,
            final_distance_mean_m: scene.then_some(report.final_distance_m.mean),
            pose_norm_max_mean: Some(report.pose_norm_max_mean),
            speed_successful_median_m_s: report.speed_successful_m_s.p50,
            wall_s: report.wall_s,
            setup_s: None,
        }
    }
}

/// `results/table2.json` and `results/table3.json`.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct PolicyRowsFile {
    pub command: String,
    pub episodes: usize,
    pub seed: u64,
    pub wall_s: f64,
    pub rows: Vec<PolicyRow>,
    /// How the rows' pose embedding norms relate to real motion (absent in files written
    /// before them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose_norm: Option<PoseNormCalibration>,
}

/// `results/table1.json` and `results/speed.json`: scenario × controller rows.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct RowsFile {
    pub command: String,
    pub episodes: usize,
    pub seed: u64,
    pub policy: String,
    /// Latents per primitive of Table 1's sampling and path-following rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<usize>,
    pub wall_s: f64,
    pub rows: Vec<crate::eval::metrics::Row>,
    /// Rows kept from earlier runs (`--keep-other-rows`), grouped by the run that measured
    /// them; `rows` holds them too, `wall_s` is this run's own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub kept: Vec<KeptRows>,
}

/// Rows of `table1.json` that `--keep-other-rows` kept from the run that measured them.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct KeptRows {
    pub command: String,
    pub policy: String,
    pub wall_s: f64,
    /// `scenario/controller` of each row kept.
    pub rows: Vec<String>,
}

/// A results file of this egogen, `None` where there is none.
pub(crate) fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Option<T>> {
    if !path.is_file() {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Ok(Some(serde_json::from_str(&text).with_context(|| {
        format!("{}: not a results file of this egogen", path.display())
    })?))
}

/// The paper's pose embedding norm above which poses are abnormal (Table 3's note).
pub(crate) const PAPER_ABNORMAL_VP: f64 = 15.0;

/// The share of real (held-out mocap) frames whose pose embedding norm maps to
/// [`PAPER_ABNORMAL_VP`] on the paper's scale: 1 in 1 000 real frames counts as abnormal.
pub(crate) const ABNORMAL_QUANTILE: f64 = 0.999;

/// Our pose embedding norm ([`PosePrior::embedding_norms`]: a Mahalanobis distance over 63
/// values) set on the paper's ‖VP‖₂ scale: held-out mocap's [`ABNORMAL_QUANTILE`] of frames
/// maps to the paper's 15 ("> 15 is abnormal"), so a figure above 15 is a pose rarer than
/// 1 in 1 000 frames of real walking.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct PoseNormCalibration {
    /// Held-out mocap frames measured.
    pub frames: usize,
    /// Their norm at [`ABNORMAL_QUANTILE`] (raw, before scaling).
    pub norm_at_quantile: f64,
    /// Multiplies a raw norm onto the paper's scale.
    pub scale: f64,
    /// The mean over held-out mocap primitives (20 frames) of their largest norm, on the
    /// paper's scale: what real motion scores.
    pub mocap_primitive_max_mean: f64,
}

impl PoseNormCalibration {
    /// Calibrates on held-out mocap primitives (each a list of frames).
    pub(crate) fn new(prior: &PosePrior, primitives: &[Vec<BodyParams>]) -> Option<Self> {
        let each: Vec<Vec<f64>> = primitives
            .iter()
            .map(|p| prior.embedding_norms(p))
            .collect();
        let mut norms: Vec<f64> = each
            .iter()
            .flatten()
            .copied()
            .filter(|n| n.is_finite())
            .collect();
        norms.sort_by(f64::total_cmp);
        let last = norms.len().checked_sub(1)?;
        let at = norms[(ABNORMAL_QUANTILE * last as f64).round() as usize];
        if at <= 0.0 {
            return None;
        }
        let scale = PAPER_ABNORMAL_VP / at;
        let maxima: Vec<f64> = each
            .iter()
            .filter(|n| !n.is_empty())
            .map(|n| n.iter().copied().fold(0.0, f64::max))
            .collect();
        Some(Self {
            frames: norms.len(),
            norm_at_quantile: at,
            scale,
            mocap_primitive_max_mean: scale * maxima.iter().sum::<f64>()
                / maxima.len().max(1) as f64,
        })
    }
}
