//! Progress on long work: an indicatif bar on a terminal, and where standard error is a file
//! or a farm log (no bar is drawn there) a plain line every few seconds instead
//! (`EGOGEN_PROGRESS_EVERY_S` sets how often; default 10 s).

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// How often progress is printed when standard error is not a terminal.
const PLAIN_PROGRESS_EVERY: Duration = Duration::from_secs(10);

/// A bar over `total` items of `unit` (e.g. "frames"), `done` of them already done; `what`
/// names the work (e.g. "rendering") and `program` the command the plain lines come from.
pub fn progress_bar(program: &str, what: &str, unit: &str, total: u64, done: u64) -> ProgressBar {
    let template = format!(
        "{what} {{bar:30}} {{pos}}/{{len}} {unit} [{{elapsed_precise}} < {{eta_precise}}] {{msg}}"
    );
    let style =
        ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar());
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
            eprintln!(
                "{program}: {what} {}/{} {unit}, {} s elapsed, about {} s left",
                bar.position(),
                bar.length().unwrap_or(0),
                bar.elapsed().as_secs(),
                bar.eta().as_secs()
            );
        });
    }
    bar
}
