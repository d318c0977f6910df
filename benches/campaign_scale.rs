//! What a campaign's supervisor does per take, at 1 000 and 10 000 takes, side by side in one
//! run: planning the takes (ids from each take's effective config), rewriting and reading
//! `campaign.json`, writing and reading `index.parquet` (100 frames a take: 100 000 and
//! 1 000 000 rows), and the memory those hold. `cargo bench --bench campaign_scale`; results
//! in docs/CAMPAIGNS.md ("At scale"). Rendering is not part of it: Blender's time per frame is
//! measured by the pool reports and the render benchmarks.
//!
//! Plain timing harness (medians of repeated runs).

mod common;
use common::{campaign_file, median_s};

use std::time::Instant;

use egogen::campaign::index::{write_index, IndexRow};
use egogen::campaign::{plan_campaign, CampaignState, TakeStatus};

/// Resident memory of this process (bytes), from /proc.
fn rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|t| t.split_whitespace().nth(1)?.parse::<u64>().ok())
        .map_or(0, |pages| pages * 4096)
}

fn rows_of(state: &CampaignState, per_take: usize) -> Vec<IndexRow> {
    state
        .takes
        .iter()
        .flat_map(|t| {
            (0..per_take).map(move |k| IndexRow {
                take: t.def.id.clone(),
                scene: t.def.scene.display().to_string(),
                seed: t.def.seed,
                camera: "camera-rgb".into(),
                wearer: "crowd_00".into(),
                frame: 4 * k as u32,
                time_s: k as f64 * 0.1,
                file: format!(
                    "takes/{}/cameras/camera-rgb/frame_{:05}.exr",
                    t.def.id,
                    4 * k
                ),
                agents_in_view: (k % 3) as u32,
                colour_exposure: Some(1.0 + k as f32 * 1e-3),
                activity: None,
                activity_phase: None,
                activities_in_view: None,
            })
        })
        .collect()
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    println!(
        "{:>7} {:>10} {:>12} {:>12} {:>12} {:>12} {:>12} {:>10}",
        "takes",
        "plan ms",
        "state w ms",
        "state r ms",
        "index w ms",
        "index r ms",
        "index MB",
        "MB held"
    );
    let mut per_take = Vec::new();
    for takes in [1_000usize, 10_000] {
        let file = campaign_file(dir.path(), takes);
        let before = rss_bytes();
        let t = Instant::now();
        let plan = plan_campaign(&file).unwrap();
        let plan_s = t.elapsed().as_secs_f64();
        let out = dir.path().join(format!("out_{takes}"));
        std::fs::create_dir_all(&out).unwrap();
        let mut state = CampaignState::new(&plan);
        for (k, t) in state.takes.iter_mut().enumerate() {
            if k % 2 == 0 {
                t.status = TakeStatus::Complete;
                t.frames = Some(100);
            }
        }
        let state_w = median_s(|| state.write(&out).unwrap(), 5);
        let state_r = median_s(
            || {
                CampaignState::read(&out).unwrap();
            },
            5,
        );
        let rows = rows_of(&state, 100);
        let index = out.join("index.parquet");
        let index_w = median_s(
            || {
                write_index(&index, rows.chunks(100).map(|c| Ok(c.to_vec()))).unwrap();
            },
            3,
        );
        let index_r = median_s(
            || {
                use parquet::file::reader::{FileReader, SerializedFileReader};
                let r = SerializedFileReader::new(std::fs::File::open(&index).unwrap()).unwrap();
                assert_eq!(r.metadata().file_metadata().num_rows() as usize, rows.len());
                let n = r.get_row_iter(None).unwrap().count();
                assert_eq!(n, rows.len());
            },
            3,
        );
        let held = rss_bytes().saturating_sub(before) as f64 / 1e6;
        let index_mb = std::fs::metadata(&index).unwrap().len() as f64 / 1e6;
        println!(
            "{takes:>7} {:>10.1} {:>12.1} {:>12.1} {:>12.1} {:>12.1} {:>12.1} {:>10.1}",
            plan_s * 1e3,
            state_w * 1e3,
            state_r * 1e3,
            index_w * 1e3,
            index_r * 1e3,
            index_mb,
            held
        );
        per_take.push((
            takes,
            plan_s / takes as f64,
            state_w / takes as f64,
            index_w / takes as f64,
        ));
    }
    let (a, b) = (per_take[0], per_take[1]);
    println!(
        "per take, 10 000 over 1 000: plan {:.2}x, state write {:.2}x, index write {:.2}x (1.0 = flat)",
        b.1 / a.1,
        b.2 / a.2,
        b.3 / a.3
    );
}
