//! What `--resume` of a campaign pays per finished take: verifying it in full against its
//! manifest (every file's SHA-256, every frame file opened: `supervisor::verify`, as every
//! resume did before stamps, and as `--rehash` still does) against comparing its stamp (one
//! `stat` per file, the manifest hashed, the folder listed: `campaign::stamp`), side by side
//! in one run on one real take: the shipped default run cut to 2 s (3 cameras at its sizes,
//! 20 frames each). Files are in the page cache (a warm disk): the lower bound of what
//! verifying costs; on a farm's network storage reading the bytes costs more.
//! `cargo bench --bench campaign_resume`; results in docs/CAMPAIGNS.md ("Resume").
//!
//! Plain timing harness (medians of repeated runs).

mod common;
use common::{default_run_config, egogen_run_with, median_s};

use egogen::campaign::stamp::{stamp_matches, write_stamp};

fn main() {
    let run = egogen_run_with(
        &default_run_config("samples = 1\nframes_per_shard = 20", "workers = 2"),
        &["--duration", "2"],
    );
    let take = run.out();
    let campaign = run.dir.path();
    let report = egogen::supervisor::verify(&take).unwrap();
    write_stamp(campaign, "take", &take).unwrap();
    assert!(stamp_matches(campaign, "take", &take));
    let verify_s = median_s(
        || {
            egogen::supervisor::verify(&take).unwrap();
        },
        5,
    );
    let stamp_s = median_s(|| assert!(stamp_matches(campaign, "take", &take)), 5);
    let mb = report.bytes as f64 / 1e6;
    println!(
        "one take: {} files, {} frame files, {mb:.1} MB",
        report.files, report.frames
    );
    println!(
        "{:<28} {:>10} {:>14} {:>20}",
        "check", "take ms", "per frame µs", "1 M frames (min)"
    );
    for (name, s) in [
        ("verify in full (--rehash)", verify_s),
        ("stamp (default)", stamp_s),
    ] {
        let per_frame = s / report.frames as f64;
        println!(
            "{name:<28} {:>10.1} {:>14.1} {:>20.1}",
            s * 1e3,
            per_frame * 1e6,
            per_frame * 1e6 / 60.0
        );
    }
    println!("verify / stamp: {:.0}x", verify_s / stamp_s);
}
