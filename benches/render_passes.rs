//! What each `[render] passes` choice costs, in one run: the default (every pass) against a
//! depth-only, a colour-only and a depth + segmentation dataset, rendered alternately by
//! `egogen-run` (Aria RGB at 352×352 and SLAM-left at 160×120, 16 samples, shutter ½ frame,
//! a scripted walk in the apartment, 1 worker, one shard per camera). Reports the wall time of
//! `egogen-run` (Blender start-up, both renders, frame assembly, annotations, COLMAP export and
//! the manifest), the Blender attempts' seconds, and the dataset's size, each as the median of
//! the repeats and as a ratio to every pass.
//!
//! `cargo bench --bench render_passes`

mod common;
use common::{egogen_run, walk_config};

const FRAMES: usize = 8;
const REPEATS: usize = 2;

const VARIANTS: [(&str, &str); 4] = [
    ("every pass (default)", ""),
    ("depth only", r#"passes = ["depth"]"#),
    ("colour only", r#"passes = ["colour"]"#),
    (
        "depth + segmentation",
        r#"passes = ["depth", "segmentation"]"#,
    ),
];

fn config(passes: &str) -> String {
    walk_config(
        FRAMES,
        &format!(
            r#"cameras = ["camera-rgb", "camera-slam-left"]
resolution_scale = 0.25
samples = 16
frames_per_shard = {FRAMES}
{passes}
[supervisor]
workers = 1"#
        ),
    )
}

fn dir_bytes(dir: &std::path::Path) -> u64 {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| {
            let meta = e.metadata().unwrap();
            if meta.is_dir() {
                dir_bytes(&e.path())
            } else {
                meta.len()
            }
        })
        .sum()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let mut wall = vec![Vec::new(); VARIANTS.len()];
    let mut blender = vec![Vec::new(); VARIANTS.len()];
    let mut bytes = vec![0u64; VARIANTS.len()];
    for repeat in 0..REPEATS {
        for (v, (name, passes)) in VARIANTS.iter().enumerate() {
            let run = egogen_run(&config(passes));
            let attempts: f64 = run.attempt_seconds.iter().sum();
            // Only what is in the dataset: scratch (work/, logs/) is not part of it.
            let out = run.out();
            let size: u64 = ["cameras", "images", "colmap", "sequence"]
                .iter()
                .map(|d| out.join(d))
                .filter(|d| d.is_dir())
                .map(|d| dir_bytes(&d))
                .sum();
            eprintln!(
                "repeat {repeat}, {name}: {:.1} s wall, {attempts:.1} s in Blender, {size} bytes",
                run.wall_seconds
            );
            wall[v].push(run.wall_seconds);
            blender[v].push(attempts);
            bytes[v] = size;
        }
    }
    let (wall0, blender0) = (median(wall[0].clone()), median(blender[0].clone()));
    println!(
        "\n## Passes: {FRAMES} frames × 2 cameras, median of {REPEATS} runs each, alternated\n"
    );
    println!("| passes | egogen-run wall s | ratio | Blender attempts s | ratio | dataset MB |");
    println!("|---|---|---|---|---|---|");
    for (v, (name, _)) in VARIANTS.iter().enumerate() {
        let (w, b) = (median(wall[v].clone()), median(blender[v].clone()));
        println!(
            "| {name} | {w:.1} | {:.2} | {b:.1} | {:.2} | {:.2} |",
            w / wall0,
            b / blender0,
            bytes[v] as f64 / 1e6
        );
    }
}
