//! A campaign past one machine, by simulation: 1 000 and 10 000 takes (100 frames each: 0.1 M
//! and 1 M frames) planned from a real campaign file, scheduled through the real pools (local
//! workers, or Slurm arrays with `--slurm`), indexed and resumed, with Blender replaced by a
//! timed stand-in and a take's content (motion, caches, frame files) by a stand-in take. What
//! is real is what a campaign's supervisor does per take whatever its content: planning, the
//! feed, the pool's scheduling, worker processes and their `EGOGEN_DONE` lines, retries'
//! bookkeeping, `campaign.json` rewrites, each take's kept index rows, the pool report, the
//! interruption (SIGINT halfway, as Ctrl-C) and the resume from `campaign.json`, and
//! `index.parquet` over every take. The stand-in worker is this bench's own executable: it
//! sleeps `EGOGEN_FARM_FRAME_MS` (default 1) per frame and puts each raw render in place.
//!
//! `cargo bench --bench campaign_farm [-- --slurm] [--takes 1000,10000]` (knobs:
//! `EGOGEN_FARM_WORKERS` 16, `EGOGEN_FARM_FRAME_MS` 1, `EGOGEN_FARM_SHARD_FRAMES` 25,
//! `EGOGEN_FARM_DIR` where the campaigns are made, default the temporary folder); each size runs in
//! its own process (its own peak memory and CPU time). Results in docs/CAMPAIGNS.md ("Past
//! one machine").

mod common;
use common::campaign_file;

use std::collections::HashMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::Result;

use egogen::campaign::index::IndexRow;
use egogen::campaign::plan::TakeDef;
use egogen::campaign::takes::TakeMaker;
use egogen::campaign::{plan_campaign, render_takes, CampaignState, TakeStatus};
use egogen::plan::SlurmPlan;
use egogen::render::{BlenderKind, BlenderRuntime};
use egogen::supervisor::pool::{RenderTake, WrittenFrame};
use egogen::supervisor::{
    LocalPool, PoolRun, PoolSettings, PoolTake, Shard, ShardPool, SlurmPool, SlurmSettings,
};

const FRAMES_PER_TAKE: u32 = 100;
const CAMERA: &str = "camera-rgb";

/// What the stand-in worker reads: the raw renders of each frame, in order.
#[derive(serde::Serialize, serde::Deserialize)]
struct StandInSpec {
    frame_s: f64,
    frames: Vec<Vec<PathBuf>>,
}

/// The stand-in worker: `<exe> <render_shard.py> <spec>`, as the pools start Blender.
fn stand_in_worker(spec: &Path) -> Result<()> {
    let spec: StandInSpec = serde_json::from_slice(&std::fs::read(spec)?)?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "EGOGEN_TIMING ready 0")?;
    for raw in &spec.frames {
        std::thread::sleep(Duration::from_secs_f64(spec.frame_s));
        for path in raw {
            let part = path.with_extension("part");
            std::fs::write(&part, b"raw")?;
            std::fs::rename(&part, path)?;
            writeln!(out, "EGOGEN_DONE {}", path.display())?;
        }
        out.flush()?;
    }
    Ok(())
}

/// A stand-in take: one camera, 100 frames; a frame is finished by taking its raw render away.
#[derive(Debug)]
struct StandInTake {
    folder: PathBuf,
    frame_s: f64,
    done: Mutex<Vec<bool>>,
}

impl RenderTake for StandInTake {
    fn folder(&self) -> &Path {
        &self.folder
    }
    fn logs_dir(&self) -> PathBuf {
        self.folder.join("logs/start_01")
    }
    fn camera_name(&self, _: usize) -> &str {
        CAMERA
    }
    fn camera_pixels(&self, _: usize) -> u64 {
        1
    }
    fn total_frames(&self) -> usize {
        FRAMES_PER_TAKE as usize
    }
    fn shard_spec_json(&self, camera: usize, frames: &[u32]) -> Result<Vec<u8>> {
        Ok(serde_json::to_vec(&StandInSpec {
            frame_s: self.frame_s,
            frames: frames
                .iter()
                .map(|&f| self.raw_frame_files(camera, f))
                .collect(),
        })?)
    }
    fn raw_frame_files(&self, _: usize, frame: u32) -> Vec<PathBuf> {
        vec![self.folder.join(format!("raw/frame_{frame:05}.raw"))]
    }
    fn frame_done(&self, _: usize, frame: u32) -> bool {
        self.done.lock().unwrap()[frame as usize]
    }
    fn finish_frame(&self, camera: usize, frame: u32) -> Result<WrittenFrame> {
        let raw = self.raw_frame_files(camera, frame).remove(0);
        std::fs::remove_file(&raw)?;
        self.done.lock().unwrap()[frame as usize] = true;
        Ok(WrittenFrame {
            path: raw,
            seconds: Vec::new(),
        })
    }
}

/// Stages stand-in takes; raises SIGINT (Ctrl-C) once `interrupt_after` takes are finished.
struct StandInMaker {
    out: PathBuf,
    frame_s: f64,
    frames_per_shard: usize,
    staged: HashMap<String, PathBuf>,
    finished: usize,
    interrupt_after: Option<usize>,
}

impl TakeMaker for StandInMaker {
    fn stage(&mut self, def: &TakeDef) -> Result<Option<PoolTake>> {
        let folder = self.out.join("takes").join(format!("{}.partial", def.id));
        std::fs::create_dir_all(folder.join("raw"))?;
        self.staged.insert(def.id.clone(), folder.clone());
        let shards = (0..FRAMES_PER_TAKE)
            .collect::<Vec<_>>()
            .chunks(self.frames_per_shard)
            .enumerate()
            .map(|(id, frames)| Shard {
                id,
                camera: 0,
                frames: frames.to_vec(),
            })
            .collect();
        Ok(Some(PoolTake {
            name: def.id.clone(),
            dataset: Arc::new(StandInTake {
                folder,
                frame_s: self.frame_s,
                done: Mutex::new(vec![false; FRAMES_PER_TAKE as usize]),
            }),
            shards,
        }))
    }
    fn finish(&mut self, id: &str) -> Result<()> {
        let folder = self.staged.remove(id).expect("staged");
        std::fs::rename(&folder, folder.with_extension(""))?;
        self.finished += 1;
        if self.interrupt_after == Some(self.finished) {
            // SAFETY: raising a signal this process handles (the pools wait for Ctrl-C).
            unsafe { libc::raise(libc::SIGINT) };
        }
        Ok(())
    }
    fn forget(&mut self, id: &str) {
        self.staged.remove(id);
    }
    fn rows(&self, def: &TakeDef) -> Result<Vec<IndexRow>> {
        Ok((0..FRAMES_PER_TAKE)
            .map(|f| IndexRow {
                take: def.id.clone(),
                scene: def.scene.display().to_string(),
                seed: def.seed,
                camera: CAMERA.into(),
                wearer: "crowd_00".into(),
                frame: f,
                time_s: f as f64 / 30.0,
                file: format!("takes/{}/cameras/{CAMERA}/frame_{f:05}.exr", def.id),
                agents_in_view: f % 3,
                colour_exposure: Some(1.0),
                activity: None,
                activity_phase: None,
                activities_in_view: None,
            })
            .collect())
    }
}

/// CPU seconds of this process (user + system), its children (the stand-in workers) apart.
fn cpu_seconds() -> f64 {
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `u` is a writable rusage.
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) };
    let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    s(u.ru_utime) + s(u.ru_stime)
}

/// Peak resident memory of this process (MB).
fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1e3)
}

/// The simulation's knobs (environment variables, defaults in `main`).
#[derive(Clone, Copy)]
struct Settings {
    workers: usize,
    frame_s: f64,
    frames_per_shard: usize,
}

#[derive(serde::Serialize, serde::Deserialize, Debug)]
struct SizeResult {
    takes: usize,
    backend: String,
    workers: usize,
    frames_per_shard: usize,
    frames: usize,
    plan_s: f64,
    first_start_s: f64,
    resume_s: f64,
    resume_read_s: f64,
    supervisor_cpu_s: f64,
    peak_rss_mb: f64,
    state_mb: f64,
    index_mb: f64,
    index_read_s: f64,
    pool_report_mb: f64,
    utilisation: f64,
}

fn pool_of(slurm: bool, workers: usize) -> Box<dyn ShardPool> {
    let timeout = Duration::from_secs(600);
    if slurm {
        Box::new(SlurmPool(SlurmSettings {
            plan: SlurmPlan {
                partition: None,
                cpus_per_task: 1,
                mem_gb: 0.1,
                poll_interval_s: 1.0,
                sbatch_args: Vec::new(),
            },
            max_running: workers,
            shard_timeout: timeout,
            retries: 2,
        }))
    } else {
        Box::new(LocalPool(PoolSettings {
            workers,
            shard_timeout: timeout,
            retries: 2,
            keep_blender: false,
        }))
    }
}

/// One campaign of `takes` stand-in takes: a start interrupted halfway, then a resume.
fn run_size(takes: usize, slurm: bool, settings: &Settings) -> Result<SizeResult> {
    let Settings {
        workers,
        frame_s,
        frames_per_shard,
    } = *settings;
    let dir = tempfile::tempdir_in(
        std::env::var_os("EGOGEN_FARM_DIR").map_or_else(std::env::temp_dir, PathBuf::from),
    )?;
    let file = campaign_file(dir.path(), takes);
    let cpu0 = cpu_seconds();
    let t = Instant::now();
    let plan = plan_campaign(&file)?;
    let plan_s = t.elapsed().as_secs_f64();
    let out = plan.out.clone();
    std::fs::create_dir_all(out.join("takes"))?;
    let state = CampaignState::new(&plan);
    state.write(&out)?;
    let runtime = BlenderRuntime {
        path: std::env::current_exe()?,
        kind: BlenderKind::PythonModule,
        version: "stand-in".into(),
    };
    let pool = pool_of(slurm, workers);
    let maker = |interrupt_after| StandInMaker {
        out: out.clone(),
        frame_s,
        frames_per_shard,
        staged: HashMap::new(),
        finished: 0,
        interrupt_after,
    };
    let frames = vec![FRAMES_PER_TAKE as usize; takes];
    let run = |start: u32| PoolRun {
        logs_dir: out.join("logs").join(format!("start_{start:02}")),
        work_dir: out.join("work"),
        stop_on_failure: false,
    };
    // The first start, interrupted (Ctrl-C) once half the takes are finished.
    let t = Instant::now();
    let first = render_takes(
        &plan,
        state,
        Box::new(maker(Some(takes / 2))),
        frames.clone(),
        0,
        &*pool,
        runtime.clone(),
        &run(1),
        false,
    );
    let first_start_s = t.elapsed().as_secs_f64();
    match first {
        Err(e) if format!("{e:#}").contains("interrupted") => {}
        other => anyhow::bail!("the first start should have been interrupted: {other:?}"),
    }
    // The resume: what campaign.json says is complete is kept.
    let t = Instant::now();
    let state = CampaignState::read(&out)?;
    let resume_read_s = t.elapsed().as_secs_f64();
    let done_before: usize = state
        .takes
        .iter()
        .filter(|t| t.status == TakeStatus::Complete)
        .filter_map(|t| t.frames)
        .sum();
    anyhow::ensure!(
        done_before >= takes / 2 * FRAMES_PER_TAKE as usize,
        "only {done_before} frames recorded complete after the first start"
    );
    let summary = render_takes(
        &plan,
        state,
        Box::new(maker(None)),
        frames,
        done_before,
        &*pool,
        runtime,
        &run(2),
        false,
    )?;
    let resume_s = t.elapsed().as_secs_f64();
    anyhow::ensure!(
        summary.complete == takes && summary.failed.is_empty(),
        "{} of {takes} takes complete, failed: {:?}",
        summary.complete,
        summary.failed
    );
    let supervisor_cpu_s = cpu_seconds() - cpu0;
    let index = out.join("index.parquet");
    let t = Instant::now();
    {
        use parquet::file::reader::{FileReader, SerializedFileReader};
        let r = SerializedFileReader::new(std::fs::File::open(&index)?)?;
        let n = r.get_row_iter(None)?.count();
        anyhow::ensure!(n == takes * FRAMES_PER_TAKE as usize, "index has {n} rows");
    }
    let index_read_s = t.elapsed().as_secs_f64();
    let mb = |p: PathBuf| std::fs::metadata(p).map_or(0.0, |m| m.len() as f64 / 1e6);
    let report = summary.report.expect("a pool report");
    Ok(SizeResult {
        takes,
        backend: if slurm { "slurm" } else { "local" }.into(),
        workers,
        frames_per_shard,
        frames: summary.frames_indexed,
        plan_s,
        first_start_s,
        resume_s,
        resume_read_s,
        supervisor_cpu_s,
        peak_rss_mb: peak_rss_mb(),
        state_mb: mb(out.join("campaign.json")),
        index_mb: mb(index),
        index_read_s,
        pool_report_mb: mb(out.join("logs/start_02/pool_report.json")),
        utilisation: report.utilisation,
    })
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    // Started by a pool as Blender: `<exe> <render_shard.py> <spec>`.
    if args.len() == 3 && args[1].ends_with("render_shard.py") {
        return stand_in_worker(Path::new(&args[2]));
    }
    let slurm = args.iter().any(|a| a == "--slurm");
    let var = |name: &str, default: f64| {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(default)
    };
    let settings = Settings {
        workers: var("EGOGEN_FARM_WORKERS", 16.0) as usize,
        frame_s: var("EGOGEN_FARM_FRAME_MS", 1.0) * 1e-3,
        frames_per_shard: var("EGOGEN_FARM_SHARD_FRAMES", 25.0) as usize,
    };
    // One size, in this process (a child of the run below).
    if let Some(k) = args.iter().position(|a| a == "--one") {
        let takes: usize = args[k + 1].parse()?;
        let result = run_size(takes, slurm, &settings)?;
        println!("EGOGEN_FARM {}", serde_json::to_string(&result)?);
        return Ok(());
    }
    let sizes: Vec<usize> = match args.iter().position(|a| a == "--takes") {
        Some(k) => args[k + 1]
            .split(',')
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?,
        None => vec![1_000, 10_000],
    };
    let mut results = Vec::new();
    for &takes in &sizes {
        let mut cmd = std::process::Command::new(std::env::current_exe()?);
        cmd.args(["--one", &takes.to_string()]);
        if slurm {
            cmd.arg("--slurm");
        }
        let log = std::env::temp_dir().join(format!("campaign_farm_{takes}.log"));
        let output = cmd.stderr(std::fs::File::create(&log)?).output()?;
        let text = String::from_utf8_lossy(&output.stdout);
        let Some(line) = text.lines().find_map(|l| l.strip_prefix("EGOGEN_FARM ")) else {
            anyhow::bail!(
                "{takes} takes: no result ({}; its log: {})",
                output.status,
                log.display()
            );
        };
        let r: SizeResult = serde_json::from_str(line)?;
        results.push(r);
    }
    println!(
        "{} worker(s), {:.1} ms a frame, {} frames a shard",
        settings.workers,
        settings.frame_s * 1e3,
        settings.frames_per_shard
    );
    println!(
        "{:>7} {:>7} {:>8} {:>8} {:>9} {:>9} {:>10} {:>11} {:>9} {:>9} {:>9} {:>9} {:>10} {:>6}",
        "takes",
        "backend",
        "frames",
        "plan s",
        "start1 s",
        "resume s",
        "super cpu",
        "cpu/take ms",
        "peak MB",
        "state MB",
        "index MB",
        "index r s",
        "report MB",
        "util"
    );
    for r in &results {
        println!(
            "{:>7} {:>7} {:>8} {:>8.2} {:>9.1} {:>9.1} {:>10.1} {:>11.2} {:>9.1} {:>9.2} {:>9.1} {:>9.2} {:>10.1} {:>5.0}%",
            r.takes,
            r.backend,
            r.frames,
            r.plan_s,
            r.first_start_s,
            r.resume_s,
            r.supervisor_cpu_s,
            1e3 * r.supervisor_cpu_s / r.takes as f64,
            r.peak_rss_mb,
            r.state_mb,
            r.index_mb,
            r.index_read_s,
            r.pool_report_mb,
            100.0 * r.utilisation
        );
    }
    if let [a, .., b] = &results[..] {
        let per = |r: &SizeResult| r.supervisor_cpu_s / r.takes as f64;
        println!(
            "supervisor CPU per take, {} over {} takes: {:.2}x; peak memory {:.1} MB over {:.1} MB (1.0 = flat)",
            b.takes,
            a.takes,
            per(b) / per(a),
            b.peak_rss_mb,
            a.peak_rss_mb
        );
    }
    Ok(())
}
