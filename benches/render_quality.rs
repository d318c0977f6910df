//! Colour quality against time, in one run: frame 0 of the shipped default run
//! (`configs/default.toml`: the apartment with its HDRI and lamp, shutter ½ frame) for the Aria
//! RGB (352×352) and SLAM-left (160×120) cameras, colour only, rendered by `egogen-run` at
//! several sample counts with and without OpenImageDenoise and with adaptive sampling, against
//! a `REFERENCE_SAMPLES` reference of the same frames. Quality is measured on what a user looks
//! at: the linear colour times the reference frame's automatic exposure, sRGB-encoded and
//! clamped to [0, 1] (as `images/` are, before 8-bit rounding), over the valid pixels: PSNR
//! (peak 1) and SSIM (luminance, 11×11 Gaussian window, σ = 1.5, windows centred on valid
//! pixels). Time is the colour render call per frame (the attempts' `colour_render` stage:
//! Cycles' sync, path tracing, denoising and writing, without Blender's start-up).
//!
//! Prints a table per camera and writes `target/render_quality.json` for
//! `tools/plot_render_quality.py`. `cargo bench --bench render_quality` (about 20 minutes here).
//! `EGOGEN_QUALITY_SCALE=1` renders at full Aria size (1408×1408, 640×480) instead.

use std::path::Path;

use egogen::inspect::preview::auto_exposure;
use egogen::inspect::ExrContents;

mod common;
use common::{default_run_config, egogen_run_with};

const REFERENCE_SAMPLES: u32 = 1024;
const FRAMES: [u32; 1] = [0];
const CAMERAS: [&str; 2] = ["camera-rgb", "camera-slam-left"];

/// (samples, adaptive threshold, denoiser: `None` off, else its `denoise_prefilter`)
const SETTINGS: [(u32, f64, Option<&str>); 16] = [
    (1, 0.0, None),
    (4, 0.0, None),
    (16, 0.0, None),
    (64, 0.0, None),
    (1, 0.0, Some("accurate")),
    (2, 0.0, Some("accurate")),
    (4, 0.0, Some("accurate")),
    (8, 0.0, Some("accurate")),
    (16, 0.0, Some("accurate")),
    (64, 0.0, Some("accurate")),
    (1, 0.0, Some("fast")),
    (2, 0.0, Some("fast")),
    (4, 0.0, Some("fast")),
    (8, 0.0, Some("fast")),
    (64, 0.05, None),
    (16, 0.05, Some("accurate")),
];

/// A frame's linear colour (grey thrice for a monochrome camera), valid mask, size, and its
/// automatic exposure (as `images/` expose it).
struct Image {
    rgb: Vec<[f64; 3]>,
    valid: Vec<bool>,
    width: usize,
    height: usize,
    exposure: f64,
}

struct Frames {
    images: Vec<Image>,
    colour_seconds_per_frame: f64,
}

fn render(camera: &str, scale: &str, samples: u32, adaptive: f64, denoise: Option<&str>) -> Frames {
    let denoise = match denoise {
        None => "denoise = false".to_string(),
        Some(prefilter) => format!("denoise = true\ndenoise_prefilter = \"{prefilter}\""),
    };
    let render = format!(
        "cameras = [\"{camera}\"]\nsamples = {samples}\nadaptive_threshold = {adaptive}\n\
         {denoise}\npasses = [\"colour\"]\nevery_n_frames = 20\nresolution_scale = {scale}"
    );
    let config = default_run_config(&render, "workers = 1")
        .replace("resolution_scale = 0.25     #", "#")
        .replace("every_n_frames = 4          #", "#");
    assert!(config.matches("resolution_scale").count() == 1, "{config}");
    let run = egogen_run_with(&config, &["--duration", "0.5"]);
    let mut colour = 0.0;
    for shard in run.report["shards"].as_array().unwrap() {
        for attempt in shard["attempts"].as_array().unwrap() {
            colour += attempt["stages"]["colour_render"].as_f64().unwrap_or(0.0);
        }
    }
    let images = FRAMES
        .iter()
        .map(|f| read(&run.out().join(format!("cameras/{camera}/frame_{f:05}.exr"))))
        .collect();
    Frames {
        images,
        colour_seconds_per_frame: colour / FRAMES.len() as f64,
    }
}

fn read(path: &Path) -> Image {
    let exr = ExrContents::read(path).unwrap();
    let ch = |n: &str| exr.channel(n).map(|c| c.values.clone());
    let valid = ch("valid.V").unwrap();
    let (w, h) = {
        let c = exr.channel("valid.V").unwrap();
        (c.width, c.height)
    };
    let rgb: Vec<[f64; 3]> = match (ch("rgb.R"), ch("rgb.G"), ch("rgb.B")) {
        (Some(r), Some(g), Some(b)) => (0..r.len())
            .map(|i| [r[i] as f64, g[i] as f64, b[i] as f64])
            .collect(),
        _ => ch("gray.Y")
            .unwrap()
            .iter()
            .map(|&y| [y as f64; 3])
            .collect(),
    };
    let pass = exr
        .passes
        .iter()
        .find(|p| p.name == "rgb" || p.name == "gray")
        .unwrap();
    Image {
        rgb,
        valid: valid.iter().map(|&v| v > 0.5).collect(),
        width: w,
        height: h,
        exposure: auto_exposure(&exr, pass) as f64,
    }
}

fn srgb(linear: f64) -> f64 {
    let v = linear.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// PSNR (peak 1) and SSIM of `got` against `want`, both exposed by the reference's factor.
fn quality(want: &Image, got: &Image) -> (f64, f64) {
    let (w, h) = (want.width, want.height);
    let enc = |img: &Image| -> Vec<[f64; 3]> {
        img.rgb
            .iter()
            .map(|p| p.map(|v| srgb(want.exposure * v)))
            .collect()
    };
    let (a, b) = (enc(want), enc(got));
    let valid = &want.valid;
    let (mut se, mut n) = (0.0, 0usize);
    for i in 0..a.len() {
        if valid[i] {
            for c in 0..3 {
                se += (a[i][c] - b[i][c]).powi(2);
            }
            n += 3;
        }
    }
    let psnr = 10.0 * (1.0 / (se / n as f64)).log10();
    let luma = |img: &Vec<[f64; 3]>| -> Vec<f64> {
        img.iter()
            .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
            .collect()
    };
    (psnr, ssim(&luma(&a), &luma(&b), valid, w, h))
}

/// Mean SSIM (Wang et al. 2004: 11×11 Gaussian window, σ = 1.5, K1 = 0.01, K2 = 0.03, range 1)
/// over windows centred on valid pixels; the window is cut at the image border.
fn ssim(a: &[f64], b: &[f64], valid: &[bool], w: usize, h: usize) -> f64 {
    const R: isize = 5;
    let g: Vec<f64> = (-R..=R)
        .map(|d| (-(d * d) as f64 / (2.0 * 1.5 * 1.5)).exp())
        .collect();
    let (c1, c2) = (0.01f64.powi(2), 0.03f64.powi(2));
    let (mut sum, mut count) = (0.0, 0usize);
    for y in 0..h as isize {
        for x in 0..w as isize {
            if !valid[y as usize * w + x as usize] {
                continue;
            }
            let (mut wsum, mut ma, mut mb, mut aa, mut bb, mut ab) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for dy in -R..=R {
                for dx in -R..=R {
                    let (xx, yy) = (x + dx, y + dy);
                    if xx < 0 || yy < 0 || xx >= w as isize || yy >= h as isize {
                        continue;
                    }
                    let k = g[(dx + R) as usize] * g[(dy + R) as usize];
                    let i = yy as usize * w + xx as usize;
                    wsum += k;
                    ma += k * a[i];
                    mb += k * b[i];
                    aa += k * a[i] * a[i];
                    bb += k * b[i] * b[i];
                    ab += k * a[i] * b[i];
                }
            }
            let (ma, mb) = (ma / wsum, mb / wsum);
            let (va, vb, cov) = (
                aa / wsum - ma * ma,
                bb / wsum - mb * mb,
                ab / wsum - ma * mb,
            );
            sum += ((2.0 * ma * mb + c1) * (2.0 * cov + c2))
                / ((ma * ma + mb * mb + c1) * (va + vb + c2));
            count += 1;
        }
    }
    sum / count as f64
}

fn main() {
    let scale = std::env::var("EGOGEN_QUALITY_SCALE").unwrap_or_else(|_| "0.25".into());
    let mut json = Vec::new();
    for camera in CAMERAS {
        let reference = render(camera, &scale, REFERENCE_SAMPLES, 0.0, None);
        let (w, h) = (reference.images[0].width, reference.images[0].height);
        println!(
            "\n## {camera} {w}×{h} (reference: {REFERENCE_SAMPLES} samples, {:.1} s per frame)\n",
            reference.colour_seconds_per_frame
        );
        println!("| samples | adaptive | denoise | colour s/frame | PSNR dB | SSIM |");
        println!("|---|---|---|---|---|---|");
        for (samples, adaptive, denoise) in SETTINGS {
            let got = render(camera, &scale, samples, adaptive, denoise);
            let (mut psnr, mut ssim) = (0.0, 0.0);
            for (want, img) in reference.images.iter().zip(&got.images) {
                let (p, s) = quality(want, img);
                psnr += p / FRAMES.len() as f64;
                ssim += s / FRAMES.len() as f64;
            }
            println!(
                "| {samples} | {} | {} | {:.3} | {psnr:.2} | {ssim:.4} |",
                if adaptive > 0.0 {
                    adaptive.to_string()
                } else {
                    "off".into()
                },
                match denoise {
                    None => "off".to_string(),
                    Some(prefilter) => format!("OIDN, {prefilter} prefilter"),
                },
                got.colour_seconds_per_frame
            );
            json.push(serde_json::json!({
                "camera": camera, "width": w, "height": h, "samples": samples,
                "adaptive_threshold": adaptive, "denoise": denoise.is_some(),
                "denoise_prefilter": denoise,
                "colour_seconds_per_frame": got.colour_seconds_per_frame,
                "psnr_db": psnr, "ssim": ssim,
            }));
        }
    }
    let out =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("target/render_quality_{scale}.json"));
    std::fs::write(&out, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
    eprintln!("wrote {}", out.display());
}
