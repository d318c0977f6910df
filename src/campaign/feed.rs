//! The campaign's [`TakeFeed`]: stages takes one at a time as the pool's workers run short of
//! shards (motion made ahead of rendering, scratch held only for takes in flight), pauses
//! staging while free disk is below the campaign's floor, finishes each take when the pool
//! hands it back (manifest, index rows), and records every change in `campaign.json`. A take
//! that cannot be staged or finished is recorded with its reason; the others go on.

use std::collections::HashMap;
use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::Result;

use super::index::keep_rows;
use super::plan::CampaignPlan;
use super::state::{CampaignState, TakeStatus};
use super::takes::TakeMaker;
use crate::supervisor::{PoolTake, TakeFailure, TakeFeed};

/// Feeds a campaign's takes to one pool.
pub(crate) struct CampaignFeed {
    pub plan: CampaignPlan,
    pub state: CampaignState,
    /// Stages and finishes the takes.
    maker: Box<dyn TakeMaker>,
    /// The next take to look at.
    next: usize,
    /// Frames of each take: estimated until staged.
    frames: Vec<usize>,
    /// Their sum.
    frames_total: usize,
    done_before: usize,
    /// Seconds between free-disk checks while paused.
    pub disk_poll: Duration,
    /// Whether staging is paused for want of free disk (said when it starts and ends).
    paused: bool,
    /// Each take's position by id.
    positions: HashMap<String, usize>,
    /// When `campaign.json` was last rewritten (it is rewritten at most every
    /// [`STATE_EVERY`]: a campaign of many takes would otherwise spend its time rewriting it).
    saved: Option<Instant>,
}

/// How often `campaign.json` is rewritten while takes change (and always at the end). A kill
/// loses at most this much of its record; `--resume` rebuilds it from the takes' folders.
pub(crate) const STATE_EVERY: Duration = Duration::from_secs(2);

impl CampaignFeed {
    /// A feed over `plan`'s takes not complete in `state`; `frames` estimates each take's
    /// frames (exact once staged), `done_before` of them finished in earlier starts.
    pub(crate) fn new(
        plan: CampaignPlan,
        state: CampaignState,
        maker: Box<dyn TakeMaker>,
        frames: Vec<usize>,
        done_before: usize,
    ) -> Self {
        let positions = state
            .takes
            .iter()
            .enumerate()
            .map(|(k, t)| (t.def.id.clone(), k))
            .collect();
        CampaignFeed {
            plan,
            state,
            maker,
            next: 0,
            frames_total: frames.iter().sum(),
            frames,
            done_before,
            disk_poll: Duration::from_secs(5),
            paused: false,
            saved: None,
            positions,
        }
    }

    /// Rewrites `campaign.json` if [`STATE_EVERY`] has passed since the last time.
    fn save(&mut self) {
        if self.saved.is_some_and(|t| t.elapsed() < STATE_EVERY) {
            return;
        }
        self.save_now();
    }

    /// Rewrites `campaign.json` now.
    pub(crate) fn save_now(&mut self) {
        if let Err(e) = self.state.write(&self.plan.out) {
            eprintln!("egogen-run: {e:#}");
        }
        self.saved = Some(Instant::now());
    }

    fn say(&self, what: &str) {
        let s = &self.state;
        eprintln!(
            "egogen-run: campaign: {what} ({} of {} takes complete, {} failed)",
            s.count(TakeStatus::Complete),
            s.takes.len(),
            s.count(TakeStatus::Failed)
        );
    }

    /// Whether staging waits: while the campaign folder's file system has less free space than
    /// the floor (said once when it starts and once when it ends).
    fn disk_pause(&mut self) -> Option<Duration> {
        match free_bytes(&self.plan.out) {
            Some(free) if free < self.plan.min_free_disk_bytes => {
                if !self.paused {
                    eprintln!(
                        "egogen-run: campaign: paused: {:.3} GB free under {} < the floor of {:.3} GB (`campaign.min_free_disk_gb`); takes already staged go on; free some space and staging goes on",
                        free as f64 / 1e9,
                        self.plan.out.display(),
                        self.plan.min_free_disk_bytes as f64 / 1e9
                    );
                    self.paused = true;
                }
                Some(self.disk_poll)
            }
            _ => {
                if self.paused {
                    eprintln!("egogen-run: campaign: free disk is back above the floor; going on");
                    self.paused = false;
                }
                None
            }
        }
    }

    /// Stages take `k`: `None` when it is already finished.
    fn stage(&mut self, k: usize) -> Result<Option<PoolTake>> {
        let def = self.state.takes[k].def.clone();
        match self.maker.stage(&def)? {
            None => {
                self.completed(k)?;
                Ok(None)
            }
            Some(take) => {
                let frames = take.dataset.total_frames();
                self.frames_total = self.frames_total - self.frames[k] + frames;
                self.frames[k] = frames;
                Ok(Some(take))
            }
        }
    }

    /// Records take `k` as complete with its index rows.
    fn completed(&mut self, k: usize) -> Result<()> {
        let def = self.state.takes[k].def.clone();
        let rows = self.maker.rows(&def)?;
        keep_rows(&self.plan.out, &def.id, &rows)?;
        let t = &mut self.state.takes[k];
        t.status = TakeStatus::Complete;
        t.reason = None;
        t.frames = Some(rows.len());
        self.save();
        self.say(&format!("take {} complete, {} frames", def.id, rows.len()));
        Ok(())
    }

    /// Where take `id` is in the campaign.
    fn position(&self, id: &str) -> Option<usize> {
        self.positions.get(id).copied()
    }
}

impl TakeFeed for CampaignFeed {
    fn frames(&self) -> (usize, usize) {
        (self.frames_total, self.done_before)
    }

    fn pause(&mut self) -> Option<Duration> {
        // Nothing left to stage: no reason to wait.
        let left = self.state.takes[self.next.min(self.state.takes.len())..]
            .iter()
            .any(|t| t.status == TakeStatus::Planned);
        if left {
            self.disk_pause()
        } else {
            None
        }
    }

    fn next_take(&mut self) -> Option<Result<PoolTake, TakeFailure>> {
        while self.next < self.state.takes.len() {
            let k = self.next;
            self.next += 1;
            // Complete, or a finished folder that does not match its manifest (left as it is).
            if self.state.takes[k].status != TakeStatus::Planned {
                continue;
            }
            match self.stage(k) {
                Ok(None) => continue,
                Ok(Some(take)) => return Some(Ok(take)),
                Err(e) => {
                    let failure = TakeFailure {
                        take: self.state.takes[k].def.id.clone(),
                        reason: format!("{e:#}"),
                    };
                    self.take_failed(&failure);
                    return Some(Err(failure));
                }
            }
        }
        None
    }

    fn take_rendered(&mut self, take: &PoolTake) -> Result<()> {
        self.maker.finish(&take.name)?;
        match self.position(&take.name) {
            Some(k) => self.completed(k),
            None => Ok(()),
        }
    }

    fn take_failed(&mut self, failure: &TakeFailure) {
        self.maker.forget(&failure.take);
        if let Some(k) = self.position(&failure.take) {
            let t = &mut self.state.takes[k];
            t.status = TakeStatus::Failed;
            t.reason = Some(failure.reason.clone());
            self.save();
            self.say(&format!("take {} failed: {}", failure.take, failure.reason));
        }
    }
}

/// Free bytes for an unprivileged user on the file system holding `path`.
pub(crate) fn free_bytes(path: &Path) -> Option<u64> {
    disk_space(path).map(|(free, _)| free)
}

/// Free bytes for an unprivileged user and the size in bytes of the file system holding
/// `path`.
pub(crate) fn disk_space(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?;
    let mut s: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `c` is a valid NUL-terminated path and `s` a writable statvfs.
    if unsafe { libc::statvfs(c.as_ptr(), &mut s) } != 0 {
        return None;
    }
    let unit = s.f_frsize as u64;
    Some((s.f_bavail as u64 * unit, s.f_blocks as u64 * unit))
}
