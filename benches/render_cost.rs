//! Where a rendered frame's time goes, and what each change to the renderer bought, in one run:
//! the shipped default run (`configs/default.toml`: three people in the apartment, the Aria rig,
//! RGB 352×352 and SLAM 160×120, HDRI and lamp, shutter ½ frame, 2 workers) cut to
//! `DURATION_S`, rendered by `egogen-run` under each variant in turn:
//!
//! 1. the renderer as it was: Fisheye624 from the wide equidistant render, Cycles' scene built
//!    afresh for every render, 16 samples;
//! 2. Fisheye624 remapped from the fitted polynomial fisheye (about the delivered pixels);
//! 3. and Cycles' scene kept between a shard's renders (persistent data);
//! 4. and 4 samples denoised by OIDN with its accurate prefilter (the default until 2026-11-28);
//! 5. and the bodies' deformation blur in 1 motion step (3 time samples, on the cache's
//!    samples) instead of 2 (5 time samples);
//! 6. and the denoiser's fast prefilter: the shipped colour settings (`SHIPPED`);
//! 7. the limit: the shipped settings with `fisheye = "native"` — Cycles path-tracing exactly the
//!    delivered pixels, nothing remapped.
//!
//! Per camera and variant: seconds per frame of each stage (the attempts' `stages` in the pool
//! report: Blender start-up and scene import, scene update, Cycles' sync and path tracing of the
//! colour and the ground truth, the rest of each render call, Rust's assembly and finishing, and
//! what no stage accounts for), frames per core-hour (frames over the attempts' seconds: with as
//! many workers as cores each worker has one core), and what is "ours": everything but the
//! limit's colour path tracing per frame.
//!
//! `cargo bench --bench render_cost -- --device gpu` renders the shipped settings on the CPU (2
//! workers) and then on the GPU Blender finds (OptiX, CUDA, HIP, oneAPI or Metal; 1 worker),
//! side by side: the "whole runs" table's wall seconds are the comparison. Without a GPU the
//! second run stops before staging, naming what Blender looked for.
//!
//! `cargo bench --bench render_cost -- --outfits` renders the shipped settings bare without the
//! body parts' AOV (`EGOGEN_BLENDER_PART_AOV=0`), with outfits off and on (`[render.outfits]`),
//! in turn, twice each: what the hand masks and dressing people cost per frame.
//!
//! `cargo bench --bench render_cost` (about 15 minutes on 2 cores).
//! `EGOGEN_RENDER_COST_SCALE=1 cargo bench --bench render_cost` renders the cameras at that
//! resolution scale instead of the default run's 0.25 (1 = full Aria size: RGB 1408×1408,
//! SLAM 640×480), variants 4, 6 and 7 only (about 30 minutes on 2 cores).

use std::collections::BTreeMap;

mod common;
use common::{default_run_config, egogen_run_env};

/// Seconds of motion rendered (every 4th frame at 40 Hz: 10 frames per second per camera).
const DURATION_S: &str = "0.5";
/// The shipped colour settings (configs/default.toml), as a literal for `concat!`.
macro_rules! shipped {
    () => {
        "samples = 4\ndenoise = true\ndenoise_prefilter = \"fast\""
    };
}
const SHIPPED: &str = shipped!();
/// The colour settings shipped until 2026-11-28.
const ACCURATE: &str = "samples = 4\ndenoise = true\ndenoise_prefilter = \"accurate\"";

/// Environment of the worker: Cycles' scene rebuilt per render, 2 motion steps.
const NO_PERSISTENT: &[(&str, &str)] = &[
    ("EGOGEN_BLENDER_PERSISTENT_DATA", "0"),
    ("EGOGEN_BLENDER_MOTION_STEPS", "2"),
];
const TWO_MOTION_STEPS: &[(&str, &str)] = &[("EGOGEN_BLENDER_MOTION_STEPS", "2")];

struct Variant {
    name: &'static str,
    render: &'static str,
    envs: &'static [(&'static str, &'static str)],
    /// Renders the colour as the limit does (same samples): "ours" is measured against it.
    as_limit: bool,
    /// Run at full size too (`EGOGEN_RENDER_COST_SCALE`).
    at_full_size: bool,
}

const VARIANTS: [Variant; 7] = [
    Variant {
        name: "as it was (equidistant, no persistent data, 16 spp)",
        render: "samples = 16\nfisheye = \"equidistant\"",
        envs: NO_PERSISTENT,
        as_limit: false,
        at_full_size: false,
    },
    Variant {
        name: "+ polynomial source",
        render: "samples = 16",
        envs: NO_PERSISTENT,
        as_limit: false,
        at_full_size: false,
    },
    Variant {
        name: "+ persistent data",
        render: "samples = 16",
        envs: TWO_MOTION_STEPS,
        as_limit: false,
        at_full_size: false,
    },
    Variant {
        name: "+ 4 spp + OIDN, accurate prefilter",
        render: ACCURATE,
        envs: TWO_MOTION_STEPS,
        as_limit: false,
        at_full_size: true,
    },
    Variant {
        name: "+ 1 motion step",
        render: ACCURATE,
        envs: &[],
        as_limit: false,
        at_full_size: false,
    },
    Variant {
        name: "+ fast prefilter (shipped)",
        render: SHIPPED,
        envs: &[],
        as_limit: true,
        at_full_size: true,
    },
    Variant {
        name: "limit: native fisheye, shipped colour",
        render: "samples = 4\ndenoise = true\ndenoise_prefilter = \"fast\"\nfisheye = \"native\"",
        envs: &[],
        as_limit: true,
        at_full_size: true,
    },
];

/// Stages as the table shows them, each a sum of the report's stages.
const COLUMNS: [(&str, &[&str]); 9] = [
    (
        "start-up + import",
        &["blender_start_up", "scene_import", "camera_setup"],
    ),
    (
        "scene update",
        &["colour_frame_update", "ground_truth_frame_update"],
    ),
    ("colour sync", &["colour_sync"]),
    ("colour path tracing", &["colour_path_tracing"]),
    ("colour rest", &["colour_render_rest"]),
    ("ground truth sync", &["ground_truth_sync"]),
    ("ground truth path tracing", &["ground_truth_path_tracing"]),
    ("ground truth rest", &["ground_truth_render_rest"]),
    ("Rust assemble + finish", &["assemble", "finish"]),
];

/// Per camera: (frames, attempt seconds, stage seconds).
type PerCamera = BTreeMap<String, (f64, f64, BTreeMap<String, f64>)>;

fn per_camera(report: &serde_json::Value) -> PerCamera {
    let mut out = PerCamera::new();
    for shard in report["shards"].as_array().unwrap() {
        let camera = shard["camera"].as_str().unwrap().to_owned();
        let entry = out.entry(camera).or_default();
        for attempt in shard["attempts"].as_array().unwrap() {
            entry.0 += attempt["finished"].as_f64().unwrap();
            entry.1 += attempt["seconds"].as_f64().unwrap();
            for (stage, s) in attempt["stages"].as_object().unwrap() {
                *entry.2.entry(stage.clone()).or_default() += s.as_f64().unwrap();
            }
        }
    }
    // The rest of a render call: what Cycles' own sync and path tracing do not cover (film,
    // denoising, compositing, writing the EXR).
    for (_, _, stages) in out.values_mut() {
        for kind in ["colour", "ground_truth"] {
            let get = |k: &str| stages.get(&format!("{kind}_{k}")).copied().unwrap_or(0.0);
            let rest = get("render") - get("sync") - get("path_tracing");
            stages.insert(format!("{kind}_render_rest"), rest);
        }
    }
    out
}

/// `-- --device gpu`: the shipped settings on the CPU (2 workers) and on the GPU Blender finds
/// (1 worker), side by side.
const ON_CPU_AND_GPU: [Variant; 2] = [
    Variant {
        name: "shipped, CPU (2 workers)",
        render: SHIPPED,
        envs: &[],
        as_limit: false,
        at_full_size: true,
    },
    Variant {
        name: "shipped, GPU (1 worker)",
        render: concat!(shipped!(), "\ndevice = \"gpu\""),
        envs: &[],
        as_limit: false,
        at_full_size: true,
    },
];

/// Environment of the worker: the ground truth without the bodies' part AOV (the hand masks'
/// `segmentation.part` then reads 0).
const NO_PART_AOV: &[(&str, &str)] = &[("EGOGEN_BLENDER_PART_AOV", "0")];

/// `--outfits`: the shipped settings with every person bare without the body parts' AOV, bare
/// and dressed (`[render.outfits]`, with the garments' AOV), in turn, twice: what the hand
/// masks and dressing people cost per frame.
const OUTFITS: [Variant; 6] = [
    outfits_variant("bare, no body parts (1)", "off", NO_PART_AOV),
    outfits_variant("outfits off (1)", "off", &[]),
    outfits_variant("outfits on (1)", "on", &[]),
    outfits_variant("bare, no body parts (2)", "off", NO_PART_AOV),
    outfits_variant("outfits off (2)", "off", &[]),
    outfits_variant("outfits on (2)", "on", &[]),
];

const fn outfits_variant(
    name: &'static str,
    mode: &'static str,
    envs: &'static [(&'static str, &'static str)],
) -> Variant {
    Variant {
        name,
        render: match mode.as_bytes()[1] {
            b'f' => concat!(shipped!(), "\noutfits = { mode = \"off\" }"),
            _ => concat!(shipped!(), "\noutfits = { mode = \"on\" }"),
        },
        envs,
        as_limit: false,
        at_full_size: true,
    }
}

fn main() {
    let scale = std::env::var("EGOGEN_RENDER_COST_SCALE").ok();
    let args: Vec<String> = std::env::args().collect();
    let on_gpu = args.windows(2).any(|w| w[0] == "--device" && w[1] == "gpu");
    let outfits = args.iter().any(|a| a == "--outfits");
    let variants: Vec<&Variant> = match (on_gpu, &scale) {
        _ if outfits => OUTFITS.iter().collect(),
        (true, _) => ON_CPU_AND_GPU.iter().collect(),
        (false, Some(_)) => VARIANTS.iter().filter(|v| v.at_full_size).collect(),
        (false, None) => VARIANTS.iter().collect(),
    };
    let mut results: Vec<(&Variant, PerCamera, f64)> = Vec::new();
    for v in variants {
        let workers = match v.render.contains("device = \"gpu\"") {
            true => "workers = 1",
            false => "workers = 2",
        };
        let mut config = default_run_config(v.render, workers);
        if let Some(scale) = &scale {
            const SHIPPED_SCALE: &str = "resolution_scale = 0.25";
            assert!(config.contains(SHIPPED_SCALE), "{config}");
            config = config.replace(SHIPPED_SCALE, &format!("resolution_scale = {scale}"));
        }
        let run = egogen_run_env(&config, &["--duration", DURATION_S], v.envs);
        eprintln!("{}: {:.1} s", v.name, run.wall_seconds);
        results.push((v, per_camera(&run.report), run.wall_seconds));
    }
    let limit = &results.last().unwrap().1;
    let before = &results[0].1;
    let scale = scale.as_deref().unwrap_or("0.25");
    println!(
        "## Seconds per frame by stage (default run, resolution scale {scale}, {DURATION_S} s of motion, 2 workers)\n"
    );
    let header: Vec<&str> = COLUMNS.iter().map(|c| c.0).collect();
    println!(
        "| camera | variant | {} | unaccounted | total s/frame | frames per core-hour | × the first variant | ours: all but the limit's path tracing |",
        header.join(" | ")
    );
    println!("|{}", "---|".repeat(COLUMNS.len() + 7));
    for camera in limit.keys() {
        for (v, cams, _) in &results {
            let (frames, seconds, stages) = &cams[camera];
            let per = |s: f64| s / frames;
            let cols: Vec<f64> = COLUMNS
                .iter()
                .map(|(_, keys)| {
                    keys.iter()
                        .map(|k| stages.get(*k).copied().unwrap_or(0.0))
                        .sum()
                })
                .collect();
            let accounted: f64 = cols.iter().sum();
            let fph = 3600.0 * frames / seconds;
            let fph_before = 3600.0 * before[camera].0 / before[camera].1;
            let limit_pt = limit[camera]
                .2
                .get("colour_path_tracing")
                .copied()
                .unwrap_or(0.0)
                / limit[camera].0;
            let total = per(*seconds);
            let cells: Vec<String> = cols.iter().map(|c| format!("{:.3}", per(*c))).collect();
            let ours = if v.as_limit {
                format!("{:.0} %", 100.0 * (total - limit_pt).max(0.0) / total)
            } else {
                "—".into()
            };
            println!(
                "| {camera} | {} | {} | {:.3} | {total:.3} | {fph:.0} | {:.2} | {ours} |",
                v.name,
                cells.join(" | "),
                per(seconds - accounted),
                fph / fph_before,
            );
        }
    }
    println!("\n## Whole runs\n");
    println!("| variant | egogen-run wall s |");
    println!("|---|---|");
    for (v, _, wall) in &results {
        println!("| {} | {wall:.1} |", v.name);
    }
}
