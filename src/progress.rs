//! Progress on long work: an indicatif bar on a terminal, and where standard error is a file
//! or a farm log (no bar is drawn there) a plain line every few seconds instead
//! (`EGOGEN_PROGRESS_EVERY_S` sets how often; default 10 s).

use std::io::IsTerminal;
use std::sync::Arc;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// How often progress is printed when standard error is not a terminal.
const PLAIN_PROGRESS_EVERY: Duration = Duration::from_secs(10);

/// Time left at the average pace since the bar started: `elapsed` for the `pos − start` items
/// done since then, `len − pos` to go. `None` before the first item. Work that finishes in
/// bursts (a shard's frames come at its end) keeps a steady estimate this way, where a recent
/// rate would swing from seconds to days between bursts.
pub(crate) fn average_eta(pos: u64, len: u64, start: u64, elapsed: Duration) -> Option<Duration> {
    let done = pos.saturating_sub(start);
    (done > 0).then(|| {
        Duration::from_secs_f64(
            elapsed.as_secs_f64() / done as f64 * len.saturating_sub(pos) as f64,
        )
    })
}

/// How a bar estimates the time left from its position, length and elapsed time.
pub(crate) type Eta = Arc<dyn Fn(u64, u64, Duration) -> Option<Duration> + Send + Sync>;

/// A bar over `total` items of `unit` (e.g. "frames"), `done` of them already done; `what`
/// names the work (e.g. "rendering") and `program` the command the plain lines come from.
/// The time left is [`average_eta`]'s.
pub(crate) fn progress_bar(
    program: &str,
    what: &str,
    unit: &str,
    total: u64,
    done: u64,
) -> ProgressBar {
    let eta: Eta = Arc::new(move |pos, len, elapsed| average_eta(pos, len, done, elapsed));
    progress_bar_with_eta(program, what, unit, total, done, eta)
}

/// [`progress_bar`] with the time left estimated by `eta`.
pub(crate) fn progress_bar_with_eta(
    program: &str,
    what: &str,
    unit: &str,
    total: u64,
    done: u64,
    eta: Eta,
) -> ProgressBar {
    let template = format!(
        "{what} {{bar:30}} {{pos}}/{{len}} {unit} [{{elapsed_precise}} < {{eta_average}}] {{msg}}"
    );
    let bar_eta = eta.clone();
    let style = ProgressStyle::with_template(&template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .with_key(
            "eta_average",
            move |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let eta = bar_eta(state.pos(), state.len().unwrap_or(0), state.elapsed());
                let _ = match eta {
                    Some(t) => {
                        let s = t.as_secs();
                        write!(w, "{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
                    }
                    None => write!(w, "--:--:--"),
                };
            },
        );
    let bar = ProgressBar::new(total).with_style(style);
    bar.set_position(done);
    if !std::io::stderr().is_terminal() {
        let weak = bar.downgrade();
        let every = std::env::var("EGOGEN_PROGRESS_EVERY_S")
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|s| s.is_finite() && *s > 0.0)
            .map_or(PLAIN_PROGRESS_EVERY, Duration::from_secs_f64);
        let (program, what, unit) = (program.to_owned(), what.to_owned(), unit.to_owned());
        std::thread::spawn(move || loop {
            std::thread::sleep(every);
            let Some(bar) = weak.upgrade() else { break };
            if bar.is_finished() {
                break;
            }
            let (pos, len) = (bar.position(), bar.length().unwrap_or(0));
            let left = match eta(pos, len, bar.elapsed()) {
                Some(t) => format!("about {} s left", t.as_secs()),
                None => "time left not known yet".into(),
            };
            eprintln!(
                "{program}: {what} {pos}/{len} {unit}, {} s elapsed, {left}",
                bar.elapsed().as_secs(),
            );
        });
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn average_eta_uses_the_pace_since_the_start() {
        let s = Duration::from_secs;
        // 10 of 40 done in 20 s after starting at 0: 30 more at 2 s each.
        assert_eq!(average_eta(10, 40, 0, s(20)), Some(s(60)));
        // Resumed at 20: only the 5 done since count.
        assert_eq!(average_eta(25, 40, 20, s(10)), Some(s(30)));
        assert_eq!(average_eta(20, 40, 20, s(10)), None);
        assert_eq!(average_eta(40, 40, 0, s(10)), Some(s(0)));
    }
}
