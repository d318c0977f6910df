//! `campaign.json`: the campaign's state, rewritten atomically as takes change (at most every
//! two seconds, and at the end) — what
//! defines the campaign (so `--resume` continues only the same one), and each take's
//! definition, status (planned, complete, failed and why) and the command that renders it
//! alone. A finished take's own marker is its folder `takes/<id>/` with its manifest: it
//! appears only by the rename that completes the take.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use super::plan::{CampaignPlan, TakeDef};

/// The state file's name in the campaign folder.
pub(crate) const STATE_FILE: &str = "campaign.json";

/// Where a take stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TakeStatus {
    /// Not finished (not started, or staged in `takes/<id>.partial`).
    Planned,
    /// `takes/<id>/` is finished and matched its manifest.
    Complete,
    /// Given up in this start (`reason` says why); `--resume` tries it again.
    Failed,
}

/// A take in the state file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct TakeState {
    #[serde(flatten)]
    pub def: TakeDef,
    pub status: TakeStatus,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Frames over all cameras, once finished.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<usize>,
    /// The `egogen-run` command rendering this take alone.
    pub command: String,
}

/// The whole state file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CampaignState {
    pub egogen_campaign: u32,
    /// The campaign file it was started from.
    pub config: PathBuf,
    /// SHA-256 of the takes' definitions.
    pub fingerprint: String,
    pub takes: Vec<TakeState>,
}

impl CampaignState {
    /// Every take planned.
    pub fn new(plan: &CampaignPlan) -> Self {
        let takes_dir = plan.out.join("takes");
        CampaignState {
            egogen_campaign: 1,
            config: plan.config.clone(),
            fingerprint: plan.fingerprint.clone(),
            takes: plan
                .takes
                .iter()
                .map(|t| TakeState {
                    def: t.clone(),
                    status: TakeStatus::Planned,
                    reason: None,
                    frames: None,
                    command: t.command(&plan.run, &takes_dir),
                })
                .collect(),
        }
    }

    /// Reads `campaign.json` from a campaign folder.
    pub fn read(out: &Path) -> Result<Self> {
        let path = out.join(STATE_FILE);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("{}: not an egogen campaign state", path.display()))
    }

    /// Rewrites `campaign.json` atomically.
    pub fn write(&self, out: &Path) -> Result<()> {
        let path = out.join(STATE_FILE);
        crate::atomic_file::write_atomically(&path, &serde_json::to_vec_pretty(self)?)
            .with_context(|| format!("writing {}", path.display()))
    }

    /// How many takes have `status`.
    pub fn count(&self, status: TakeStatus) -> usize {
        self.takes.iter().filter(|t| t.status == status).count()
    }
}
