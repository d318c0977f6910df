//! Colour quality vs time, in one run: the same Aria RGB frame (176×176, no motion blur)
//! rendered by `egogen-run` at several sample counts, with and without adaptive sampling and the
//! denoiser, against a 512-sample reference. Reports the Blender attempt time (start-up included,
//! measured separately with 1 sample) and the RMSE / mean absolute error of linear RGB over the
//! valid pixels.
//!
//! `cargo bench --bench render_quality`

use std::path::{Path, PathBuf};

use egogen::inspect::ExrContents;

mod common;
use common::{egogen_run, walk_config};

fn config(samples: u32, adaptive: f64, denoise: bool) -> String {
    walk_config(
        1,
        &format!(
            r#"cameras = ["camera-rgb"]
resolution_scale = 0.125
samples = {samples}
adaptive_threshold = {adaptive}
denoise = {denoise}
shutter_frames = 0.0"#
        ),
    )
}

/// Renders; returns (frame file, Blender attempt seconds, kept temp dir).
fn render(samples: u32, adaptive: f64, denoise: bool) -> (PathBuf, f64, tempfile::TempDir) {
    let run = egogen_run(&config(samples, adaptive, denoise));
    (
        run.out().join("cameras/camera-rgb/frame_00000.exr"),
        run.attempt_seconds[0],
        run.dir,
    )
}

fn rgb(path: &Path) -> (Vec<[f32; 3]>, Vec<f32>) {
    let exr = ExrContents::read(path).unwrap();
    let ch = |n: &str| exr.channel(n).unwrap().values.clone();
    let (r, g, b, v) = (ch("rgb.R"), ch("rgb.G"), ch("rgb.B"), ch("valid.V"));
    ((0..r.len()).map(|i| [r[i], g[i], b[i]]).collect(), v)
}

fn main() {
    let (reference, ref_s, _keep) = render(512, 0.0, false);
    let (want, valid) = rgb(&reference);
    let (_, startup_s, _) = render(1, 0.0, false);
    println!("reference: 512 samples, {ref_s:.2} s; 1 sample (≈ start-up + ground truth): {startup_s:.2} s");
    println!("| samples | adaptive | denoise | Blender s | RMSE | mean abs error |");
    println!("|---|---|---|---|---|---|");
    for (samples, adaptive, denoise) in [
        (4, 0.0, false),
        (16, 0.0, false),
        (64, 0.0, false),
        (128, 0.0, false),
        (64, 0.01, false),
        (128, 0.01, false),
        (4, 0.0, true),
        (16, 0.0, true),
        (64, 0.0, true),
    ] {
        let (path, s, _keep) = render(samples, adaptive, denoise);
        let (got, _) = rgb(&path);
        let (mut se, mut ae, mut n) = (0.0f64, 0.0f64, 0usize);
        for i in 0..got.len() {
            if valid[i] < 0.5 {
                continue;
            }
            for c in 0..3 {
                let d = (got[i][c] - want[i][c]) as f64;
                se += d * d;
                ae += d.abs();
            }
            n += 3;
        }
        println!(
            "| {samples} | {} | {} | {s:.2} | {:.4} | {:.4} |",
            if adaptive > 0.0 {
                adaptive.to_string()
            } else {
                "off".into()
            },
            if denoise { "OIDN" } else { "off" },
            (se / n as f64).sqrt(),
            ae / n as f64
        );
    }
}
