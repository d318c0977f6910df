//! The primitive-model training config (`egogen train primitive --config FILE`): parsed
//! strictly (unknown keys refused), then resolved into a [`TrainPlan`].

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::config_file::resolve_body_model;
use super::config_file::{load_toml, Bad, ConfigError};
use crate::motion::cvae::loss::{LossWeights, PriorWeights};
use crate::motion::cvae::train::{ClipSpec, PhasePlan, PriorPlan, TrainPlan};
use crate::motion::cvae::ArchConfig;

/// `[[clips]]`: one training clip (AMASS-style `.npz` at 40 Hz).
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawClip {
    /// Relative to the config's folder.
    pub path: PathBuf,
    /// Hold the whole clip out of training (evaluation only).
    #[serde(default)]
    pub held_out: bool,
    /// Hold out the frames from this time on (s).
    pub held_out_from_s: Option<f64>,
}

/// `[primitive]` and `[rollout]`: one training phase.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPhase {
    pub steps: usize,
    pub batch_size: usize,
    pub learning_rate: f64,
}

/// `[rollout]`: a phase over chains of primitives.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRollout {
    pub steps: usize,
    pub batch_size: usize,
    pub learning_rate: f64,
    /// Primitives per chain.
    pub primitives: usize,
}

/// `[prior]`: fine-tuning on chains decoded from random latents.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPrior {
    pub steps: usize,
    /// Random chains per step (and as many mocap chains reconstructed, `rollout.primitives` long).
    pub batch_size: usize,
    pub learning_rate: f64,
    /// Primitives per random chain (gradients flow through the chain).
    pub primitives: usize,
    /// Share (0..=1) of random chains that start where an earlier one ended.
    pub pool_fraction: f64,
    /// Keep this many persistent random chains, continued step after step (each step draws
    /// `batch_size` of them; a chain whose body falls restarts from mocap); omit for the pool
    /// of the last 4 096 chain ends.
    pub pool_slots: Option<usize>,
    /// Pelvis height and trunk lean are kept between these quantiles (and 1 − it) of the
    /// training frames; 0 for their whole range.
    pub range_quantile: f64,
    /// Trunk lean (degrees from vertical) beyond which `prior.loss.upright` penalises; omit
    /// for the training frames' steepest lean (per `range_quantile`).
    pub trunk_tilt_max_deg: Option<f64>,
    /// Mean horizontal pelvis speed (m/s) below which `prior.loss.speed` penalises a
    /// primitive; omit for none.
    pub min_pelvis_speed_m_s: Option<f64>,
    /// `[prior.loss]`: weights of the losses on random chains.
    pub loss: PriorWeights,
}

/// `[data]`.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawData {
    /// Frames between the starts of consecutive training primitives.
    pub stride_frames: usize,
    /// Add left-right mirrored copies of the training clips.
    pub mirror: bool,
    /// Keep only primitives whose mocap foot-contact score reaches this (0..1); omit to keep all.
    pub min_contact_score: Option<f64>,
    /// Also drop primitives starting within this many seconds of one that fails
    /// `min_contact_score` (the run-up to a jump or a climb); omit for 0.
    pub contact_context_s: Option<f64>,
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTrainOutput {
    /// Weights file (safetensors), written atomically; relative to the config's folder.
    pub weights: PathBuf,
    /// Loss log (JSON lines), relative to the config's folder.
    pub log: PathBuf,
    /// Seconds between checkpoints (`<weights>.checkpoint/`, for `--resume`); default 300.
    pub checkpoint_every_s: Option<f64>,
}

/// The whole training config, as written.
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTrainPrimitive {
    /// Seed of weights, batches and noise.
    pub seed: u64,
    /// Body model (default: the shipped CC0 model).
    pub body_model: Option<PathBuf>,
    pub data: RawData,
    #[serde(default)]
    pub clips: Vec<RawClip>,
    /// Take the `[[clips]]` of another training config instead (relative to this config's
    /// folder; that config's own paths are relative to its folder).
    pub clips_from: Option<PathBuf>,
    pub model: ArchConfig,
    pub loss: LossWeights,
    /// Steps over which the KL weight ramps up from 0.
    pub kl_warmup_steps: usize,
    /// Gaussian noise on the seeds of mocap primitives, in feature standard deviations (the
    /// targets stay clean, so the decoder learns to return to the data); omit for 0.
    pub seed_noise: Option<f64>,
    pub primitive: RawPhase,
    pub rollout: RawRollout,
    /// Prior fine-tuning after the rollout phase.
    pub prior: Option<RawPrior>,
    /// Start from these weights (same `[model]`), relative to the config's folder.
    pub init_weights: Option<PathBuf>,
    pub output: RawTrainOutput,
}

impl RawTrainPrimitive {
    /// Reads and parses a config file; errors name the file, key and what was expected.
    pub(crate) fn load(path: &Path) -> Result<Self, ConfigError> {
        load_toml(path)
    }

    /// Resolves paths against the config's folder and checks values.
    pub(crate) fn resolve(self, config_path: &Path) -> Result<TrainPlan, ConfigError> {
        let base = config_path.parent().unwrap_or(Path::new("."));
        let bad = |key: &str, message: String| ConfigError::Value {
            path: config_path.into(),
            key: key.into(),
            message,
        };
        let body_model =
            resolve_body_model(self.body_model.clone(), base).map_err(|m| bad("body_model", m))?;
        let clips = self.resolve_clips(base, config_path, &bad)?;
        let positive = |key: &str, v: usize| positive(key, v, &bad);
        let rate = |key: &str, v: f64| rate(key, v, &bad);
        let weight = |key: &str, v: f64| weight(key, v, &bad);
        positive("data.stride_frames", self.data.stride_frames)?;
        if let Some(v) = self.data.min_contact_score {
            if !(0.0..=1.0).contains(&v) {
                return Err(bad(
                    "data.min_contact_score",
                    format!("expected a score in 0..=1, found {v}"),
                ));
            }
        }
        let contact_context_frames = match self.data.contact_context_s {
            None => 0,
            Some(t) if t.is_finite() && t >= 0.0 => {
                if self.data.min_contact_score.is_none() {
                    return Err(bad(
                        "data.contact_context_s",
                        "needs data.min_contact_score (the filter whose context it widens)".into(),
                    ));
                }
                (t * crate::motion::primitive::PRIMITIVE_RATE_HZ).round() as usize
            }
            Some(t) => {
                return Err(bad(
                    "data.contact_context_s",
                    format!("expected a time ≥ 0 s, found {t}"),
                ))
            }
        };
        let seed_noise = match self.seed_noise {
            None => 0.0,
            Some(v) if v.is_finite() && (0.0..=1.0).contains(&v) => v,
            Some(v) => {
                return Err(bad(
                    "seed_noise",
                    format!("expected feature standard deviations in 0..=1, found {v}"),
                ))
            }
        };
        positive("model.latent_dim", self.model.latent_dim)?;
        positive("model.encoder_width", self.model.encoder_width)?;
        positive("model.decoder_width", self.model.decoder_width)?;
        positive("primitive.batch_size", self.primitive.batch_size)?;
        positive("rollout.batch_size", self.rollout.batch_size)?;
        if self.rollout.primitives < 2 {
            return Err(bad(
                "rollout.primitives",
                format!(
                    "expected ≥ 2 chained primitives, found {}",
                    self.rollout.primitives
                ),
            ));
        }
        rate("primitive.learning_rate", self.primitive.learning_rate)?;
        rate("rollout.learning_rate", self.rollout.learning_rate)?;
        let l = &self.loss;
        for (key, v) in [
            ("loss.pose", l.pose),
            ("loss.transl", l.transl),
            ("loss.markers", l.markers),
            ("loss.velocity", l.velocity),
            ("loss.skate", l.skate),
            ("loss.floor", l.floor),
            ("loss.kl", l.kl),
        ] {
            weight(key, v)?;
        }
        let prior = self
            .prior
            .map(|p| resolve_prior(p, self.init_weights.is_some(), &bad))
            .transpose()?;
        let init_weights = match self.init_weights {
            None => None,
            Some(w) => {
                let path = base.join(w);
                if !path.is_file() {
                    return Err(bad(
                        "init_weights",
                        format!(
                            "file {} not found (train it first with the config that writes it)",
                            path.display()
                        ),
                    ));
                }
                Some(path)
            }
        };
        let checkpoint_every_s = self.output.checkpoint_every_s.unwrap_or(300.0);
        if !(checkpoint_every_s.is_finite() && checkpoint_every_s >= 0.0) {
            return Err(bad(
                "output.checkpoint_every_s",
                format!("expected seconds ≥ 0, found {checkpoint_every_s}"),
            ));
        }
        Ok(TrainPlan {
            seed: self.seed,
            body_model,
            clips,
            stride_frames: self.data.stride_frames,
            mirror: self.data.mirror,
            min_contact_score: self.data.min_contact_score,
            contact_context_frames,
            arch: self.model,
            loss: self.loss,
            kl_warmup_steps: self.kl_warmup_steps,
            seed_noise,
            primitive: PhasePlan {
                steps: self.primitive.steps,
                batch_size: self.primitive.batch_size,
                learning_rate: self.primitive.learning_rate,
            },
            rollout: PhasePlan {
                steps: self.rollout.steps,
                batch_size: self.rollout.batch_size,
                learning_rate: self.rollout.learning_rate,
            },
            rollout_primitives: self.rollout.primitives,
            prior,
            init_weights,
            weights_out: base.join(self.output.weights),
            log_out: base.join(self.output.log),
            checkpoint_every_s,
        })
    }

    /// `[[clips]]`, or those of the config `clips_from` names (its paths relative to it).
    fn resolve_clips(
        &self,
        base: &Path,
        config_path: &Path,
        bad: Bad,
    ) -> Result<Vec<ClipSpec>, ConfigError> {
        let (raw_clips, clips_base, clips_file) = match &self.clips_from {
            None => (
                self.clips.clone(),
                base.to_path_buf(),
                config_path.to_path_buf(),
            ),
            Some(_) if !self.clips.is_empty() => {
                return Err(bad(
                    "clips_from",
                    "give either [[clips]] or clips_from, not both".into(),
                ))
            }
            Some(from) => {
                let file = base.join(from);
                let other = RawTrainPrimitive::load(&file)?;
                if other.clips_from.is_some() {
                    return Err(bad(
                        "clips_from",
                        format!(
                            "{} takes its clips from a third config; name that one",
                            file.display()
                        ),
                    ));
                }
                let dir = file.parent().unwrap_or(Path::new(".")).to_path_buf();
                (other.clips, dir, file)
            }
        };
        let bad_clip = |key: &str, message: String| ConfigError::Value {
            path: clips_file.clone(),
            key: key.into(),
            message,
        };
        if raw_clips.is_empty() {
            return Err(bad_clip("clips", "list at least one clip".into()));
        }
        let mut clips = Vec::new();
        for (i, c) in raw_clips.into_iter().enumerate() {
            let path = clips_base.join(&c.path);
            if !path.is_file() {
                return Err(bad_clip(
                    &format!("clips[{i}].path"),
                    format!("file {} not found", path.display()),
                ));
            }
            if let Some(t) = c.held_out_from_s {
                if !(t.is_finite() && t >= 0.0) {
                    return Err(bad_clip(
                        &format!("clips[{i}].held_out_from_s"),
                        format!("expected a time ≥ 0 s, found {t}"),
                    ));
                }
                if c.held_out {
                    return Err(bad_clip(
                        &format!("clips[{i}].held_out_from_s"),
                        "the clip is wholly held out (held_out = true); remove one of the two"
                            .into(),
                    ));
                }
            }
            clips.push(ClipSpec {
                path,
                held_out: c.held_out,
                held_out_from_s: c.held_out_from_s,
            });
        }
        Ok(clips)
    }
}

fn positive(key: &str, v: usize, bad: Bad) -> Result<usize, ConfigError> {
    match v {
        0 => Err(bad(key, "expected a positive integer, found 0".into())),
        v => Ok(v),
    }
}

fn rate(key: &str, v: f64, bad: Bad) -> Result<f64, ConfigError> {
    match v.is_finite() && v > 0.0 && v < 1.0 {
        true => Ok(v),
        false => Err(bad(
            key,
            format!("expected a learning rate in (0, 1), found {v}"),
        )),
    }
}

fn weight(key: &str, v: f64, bad: Bad) -> Result<f64, ConfigError> {
    match v.is_finite() && v >= 0.0 {
        true => Ok(v),
        false => Err(bad(key, format!("expected a weight ≥ 0, found {v}"))),
    }
}

/// `[prior]`: the prior phase's settings and loss weights (`anchor` needs `init_weights`).
fn resolve_prior(p: RawPrior, has_init_weights: bool, bad: Bad) -> Result<PriorPlan, ConfigError> {
    positive("prior.batch_size", p.batch_size, bad)?;
    positive("prior.primitives", p.primitives, bad)?;
    rate("prior.learning_rate", p.learning_rate, bad)?;
    if !(0.0..=1.0).contains(&p.pool_fraction) {
        return Err(bad(
            "prior.pool_fraction",
            format!("expected a share in 0..=1, found {}", p.pool_fraction),
        ));
    }
    if let Some(n) = p.pool_slots {
        if n < p.batch_size {
            return Err(bad(
                "prior.pool_slots",
                format!(
                    "expected at least prior.batch_size = {} slots, found {n}",
                    p.batch_size
                ),
            ));
        }
    }
    if !(0.0..0.5).contains(&p.range_quantile) {
        return Err(bad(
            "prior.range_quantile",
            format!("expected a quantile in 0..0.5, found {}", p.range_quantile),
        ));
    }
    if let Some(deg) = p.trunk_tilt_max_deg {
        if !(deg > 0.0 && deg < 90.0) {
            return Err(bad(
                "prior.trunk_tilt_max_deg",
                format!("expected degrees in (0, 90), found {deg}"),
            ));
        }
    }
    if let Some(v) = p.min_pelvis_speed_m_s {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad(
                "prior.min_pelvis_speed_m_s",
                format!("expected a speed ≥ 0 m/s, found {v}"),
            ));
        }
    }
    let w = &p.loss;
    for (key, v) in [
        ("prior.loss.contact", w.contact),
        ("prior.loss.skate", w.skate),
        ("prior.loss.penetration", w.penetration),
        ("prior.loss.pelvis", w.pelvis),
        ("prior.loss.upright", w.upright),
        ("prior.loss.speed", w.speed),
        ("prior.loss.recovery", w.recovery),
        ("prior.loss.anchor", w.anchor),
    ] {
        weight(key, v, bad)?;
    }
    if w.anchor > 0.0 && !has_init_weights {
        return Err(bad(
            "prior.loss.anchor",
            "expected init_weights too: the anchor keeps random latents where \
             those weights take them"
                .into(),
        ));
    }
    Ok(PriorPlan {
        phase: PhasePlan {
            steps: p.steps,
            batch_size: p.batch_size,
            learning_rate: p.learning_rate,
        },
        primitives: p.primitives,
        pool_fraction: p.pool_fraction,
        pool_slots: p.pool_slots,
        range_quantile: p.range_quantile,
        trunk_tilt_max_deg: p.trunk_tilt_max_deg,
        min_pelvis_speed_m_s: p.min_pelvis_speed_m_s.unwrap_or(0.0),
        weights: p.loss,
    })
}

/// Loads and resolves a training config.
pub fn load_train_plan(path: &Path) -> Result<TrainPlan, ConfigError> {
    RawTrainPrimitive::load(path)?.resolve(path)
}

/// [`load_train_plan`] as the jobs that take a loader call it (the error as `anyhow`'s).
pub(crate) fn train_plan_for_job(path: &Path) -> anyhow::Result<TrainPlan> {
    Ok(load_train_plan(path)?)
}
