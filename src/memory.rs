//! The memory a run may plan for, and refusing a size that would not fit in it before anything
//! is allocated. The budget is the machine's physical memory, or less where a control group
//! limits this process (a container, a Slurm allocation), or `EGOGEN_MEMORY_GB` when set.
//! Callers estimate what a size asks for (a lower bound of the buffers it makes) and name the
//! keys that set it; fixed limits on each key stay beside this, since they hold on any machine.

use std::path::Path;

/// Environment variable that sets the budget, in GB (10⁹ bytes).
pub(crate) const MEMORY_ENV: &str = "EGOGEN_MEMORY_GB";

/// How much memory a run may plan for, and where that figure comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MemoryBudget {
    pub bytes: f64,
    /// `"EGOGEN_MEMORY_GB"`, `"the control group's limit"` or `"physical memory"`.
    pub source: &'static str,
}

impl MemoryBudget {
    /// This process's budget: `EGOGEN_MEMORY_GB` when set (an error names it when it is not a
    /// positive number), else the smaller of physical memory and the control group's limit.
    /// `None` when the system says neither.
    pub(crate) fn of_this_process() -> Result<Option<Self>, String> {
        if let Ok(text) = std::env::var(MEMORY_ENV) {
            return match text.trim().parse::<f64>() {
                Ok(gb) if gb.is_finite() && gb > 0.0 => Ok(Some(Self {
                    bytes: gb * 1e9,
                    source: MEMORY_ENV,
                })),
                _ => Err(format!(
                    "{MEMORY_ENV} = {text:?}: expected a positive number of GB"
                )),
            };
        }
        let physical = physical_bytes().map(|bytes| Self {
            bytes,
            source: "physical memory",
        });
        let group = cgroup_limit_bytes().map(|bytes| Self {
            bytes,
            source: "the control group's limit",
        });
        Ok(match (physical, group) {
            (Some(p), Some(g)) => Some(if g.bytes < p.bytes { g } else { p }),
            (p, g) => p.or(g),
        })
    }

    /// `Err` with what `what` needs against the budget when `bytes` exceed it.
    pub(crate) fn check(&self, what: &str, bytes: f64) -> Result<(), String> {
        match bytes <= self.bytes {
            true => Ok(()),
            false => Err(format!(
                "{what} needs at least {} of memory, more than the {} this run may use ({}{})",
                gigabytes(bytes),
                gigabytes(self.bytes),
                self.source,
                match self.source {
                    MEMORY_ENV => "",
                    _ => "; EGOGEN_MEMORY_GB sets another budget",
                }
            )),
        }
    }
}

/// Checks `bytes` against this process's budget (see [`MemoryBudget::of_this_process`]); no
/// budget known is no refusal.
pub(crate) fn check_fits(what: &str, bytes: f64) -> Result<(), String> {
    match MemoryBudget::of_this_process()? {
        Some(budget) => budget.check(what, bytes),
        None => Ok(()),
    }
}

/// `12.3 GB`, `850 MB`.
fn gigabytes(bytes: f64) -> String {
    match bytes >= 1e9 {
        true => format!("{:.1} GB", bytes / 1e9),
        false => format!("{:.0} MB", bytes / 1e6),
    }
}

fn physical_bytes() -> Option<f64> {
    // SAFETY: sysconf reads system constants and has no preconditions.
    let (pages, page) = unsafe {
        (
            libc::sysconf(libc::_SC_PHYS_PAGES),
            libc::sysconf(libc::_SC_PAGESIZE),
        )
    };
    (pages > 0 && page > 0).then_some(pages as f64 * page as f64)
}

/// The memory limit of this process's control group (v2 `memory.max`, v1
/// `memory.limit_in_bytes`); `None` when unlimited or not there.
fn cgroup_limit_bytes() -> Option<f64> {
    let own = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let mut files = Vec::new();
    for line in own.lines() {
        // "0::/path" (v2) or "N:memory:/path" (v1).
        let mut parts = line.splitn(3, ':');
        let (_, controllers, group) = (parts.next()?, parts.next()?, parts.next()?);
        let group = group.trim_start_matches('/');
        if controllers.is_empty() {
            files.push(Path::new("/sys/fs/cgroup").join(group).join("memory.max"));
        } else if controllers.split(',').any(|c| c == "memory") {
            files.push(
                Path::new("/sys/fs/cgroup/memory")
                    .join(group)
                    .join("memory.limit_in_bytes"),
            );
        }
    }
    files
        .iter()
        .filter_map(|f| std::fs::read_to_string(f).ok())
        .filter_map(|t| t.trim().parse::<f64>().ok())
        // v1 writes "unlimited" as a number near 2⁶³.
        .filter(|&b| b > 0.0 && b < 1e18)
        .reduce(f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_size_over_the_budget_is_refused_with_both_figures() {
        let budget = MemoryBudget {
            bytes: 8e9,
            source: "physical memory",
        };
        assert!(budget.check("a rollout", 7.9e9).is_ok());
        let err = budget.check("a rollout", 141e9).unwrap_err();
        assert!(err.contains("a rollout needs at least 141.0 GB"), "{err}");
        assert!(
            err.contains("8.0 GB") && err.contains("EGOGEN_MEMORY_GB"),
            "{err}"
        );
        assert!(budget.check("it", f64::NAN).is_err());
    }

    #[test]
    fn this_machine_has_a_budget() {
        let b = MemoryBudget::of_this_process().unwrap().unwrap();
        assert!(b.bytes > 1e8, "{b:?}");
    }
}
