//! Supervisor overhead and parallel efficiency, in one run: the same tiny dataset (Aria SLAM-left
//! at 64×48, 16 frames, 2 frames per shard) rendered by `egogen-run` with 1 and with 2 Blender
//! workers, alternating, `ROUNDS` times each. Reports per run: wall time, the pool's wall time,
//! the summed Blender attempt time, and what is left for the supervisor (synth, placement,
//! caches, annotations, manifest); then parallel efficiency `T1 / (2 · T2)`.
//!
//! `cargo bench --bench supervisor` (needs Blender: the managed install is provisioned on first
//! use).

use std::process::Command;

mod common;
use common::{egogen_run_with, walk_config};

const ROUNDS: usize = 2;

/// Aria SLAM-left at 64×48, 16 of 32 frames, 2 frames per shard.
const RENDER: &str = r#"
cameras = ["camera-slam-left"]
resolution_scale = 0.1
every_n_frames = 2
samples = 4
frames_per_shard = 2
"#;

struct Measured {
    wall_s: f64,
    pool_s: f64,
    blender_s: f64,
    frames: usize,
}

/// Slurm settings appended to the config for the Slurm rows: tasks poll twice a second.
const SLURM: &str = r#"
[supervisor]
backend = "slurm"
[supervisor.slurm]
cpus_per_task = 1
mem_gb = 1.0
poll_interval_s = 0.5
"#;

#[derive(Clone, Copy, PartialEq)]
enum Backend {
    Local,
    Slurm,
}

fn run(workers: usize, backend: Backend) -> Measured {
    let config = match backend {
        Backend::Local => walk_config(32, RENDER),
        Backend::Slurm => format!("{}{SLURM}", walk_config(32, RENDER)),
    };
    let run = egogen_run_with(&config, &["--workers", &workers.to_string()]);
    let attempts = run.report["shards"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["attempts"].as_array().unwrap().clone());
    let (mut blender_s, mut frames) = (0.0, 0);
    for a in attempts {
        blender_s += a["seconds"].as_f64().unwrap();
        frames += a["finished"].as_u64().unwrap() as usize;
    }
    Measured {
        wall_s: run.wall_seconds,
        pool_s: run.report["wall_seconds"].as_f64().unwrap(),
        blender_s,
        frames,
    }
}

/// Whether a Slurm cluster answers here (start one with `tools/slurm_single_node.sh`).
fn slurm_answers() -> bool {
    Command::new("sinfo")
        .arg("--noheader")
        .output()
        .is_ok_and(|o| o.status.success())
}

fn main() {
    // Warm-up: provisions Blender if needed, warms the file cache.
    run(1, Backend::Local);
    let slurm = slurm_answers();
    if !slurm {
        println!("no Slurm cluster answers `sinfo`: Slurm rows skipped");
    }
    let mut by_workers = [Vec::new(), Vec::new()];
    let mut slurm_by_workers = [Vec::new(), Vec::new()];
    for round in 0..ROUNDS {
        for workers in [1, 2] {
            if slurm {
                let m = run(workers, Backend::Slurm);
                println!(
                    "round {round} Slurm, {workers} task(s) at once: {} frames, wall {:.2} s, tasks' run time summed {:.2} s",
                    m.frames, m.wall_s, m.blender_s
                );
                slurm_by_workers[workers - 1].push(m);
            }
            let m = run(workers, Backend::Local);
            println!(
                "round {round} workers {workers}: {} frames, wall {:.2} s, pool {:.2} s, Blender attempts {:.2} s, supervisor outside the pool {:.2} s ({:.1} %)",
                m.frames,
                m.wall_s,
                m.pool_s,
                m.blender_s,
                m.wall_s - m.pool_s,
                100.0 * (m.wall_s - m.pool_s) / m.wall_s
            );
            by_workers[workers - 1].push(m);
        }
    }
    let mean =
        |v: &[Measured], f: fn(&Measured) -> f64| v.iter().map(f).sum::<f64>() / v.len() as f64;
    let (t1, t2) = (
        mean(&by_workers[0], |m| m.wall_s),
        mean(&by_workers[1], |m| m.wall_s),
    );
    let (p1, p2) = (
        mean(&by_workers[0], |m| m.pool_s),
        mean(&by_workers[1], |m| m.pool_s),
    );
    println!(
        "mean wall: 1 worker {t1:.2} s, 2 workers {t2:.2} s; speed-up {:.2}, parallel efficiency {:.0} % (pool only: {:.0} %)",
        t1 / t2,
        100.0 * t1 / (2.0 * t2),
        100.0 * p1 / (2.0 * p2)
    );
    if slurm {
        let (s1, s2) = (
            mean(&slurm_by_workers[0], |m| m.wall_s),
            mean(&slurm_by_workers[1], |m| m.wall_s),
        );
        println!(
            "mean wall with Slurm: 1 task at once {s1:.2} s ({:.2}× local), 2 at once {s2:.2} s ({:.2}× local); speed-up {:.2}",
            s1 / t1,
            s2 / t2,
            s1 / s2
        );
    }
}
