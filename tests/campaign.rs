//! Campaigns against real Blender workers: a tiny campaign (3 takes over the apartment and a
//! generated floor plan, two crowd sizes, one camera) on the local pool. Its `--dry-run` writes
//! nothing; every take is finished and listed in `campaign.json`; `index.parquet` lists every
//! frame file; a take is byte-identical to the same take rendered alone with its recorded
//! command; a campaign whose supervisor is killed with SIGKILL several times (and a Blender
//! worker once) and resumed ends with the same manifests and index as the uninterrupted one;
//! the Python reader (`python/`, installed with pip) reads it under pytest.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::record::RowAccessor;

mod common;

fn egogen_run() -> Command {
    Command::new(env!("CARGO_BIN_EXE_egogen-run"))
}

fn state(out: &Path) -> egogen::campaign::CampaignState {
    egogen::campaign::CampaignState::read(out).unwrap()
}

/// `dir/NAME.toml`: a campaign of `takes` takes from `dir/run.toml` into `out`, with `keys`
/// (`scenes`, …) and, unless they give one, no free-disk floor.
fn campaign_file(dir: &Path, name: &str, out: &Path, takes: usize, keys: &str) -> PathBuf {
    let floor = if keys.contains("min_free_disk_gb") {
        ""
    } else {
        "min_free_disk_gb = 0.0\n"
    };
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(
        &path,
        format!(
            "[campaign]\nrun = \"run.toml\"\nout = \"{}\"\ntakes = {takes}\n{keys}\n{floor}",
            out.display()
        ),
    )
    .unwrap();
    path
}

/// Runs a campaign to its end: every take complete (else what it said), its state.
fn run_to_completion(campaign: &Path, out: &Path) -> egogen::campaign::CampaignState {
    let run = common::succeeds(egogen_run().arg(campaign));
    let s = state(out);
    assert!(
        s.takes
            .iter()
            .all(|t| t.status == egogen::campaign::TakeStatus::Complete),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    s
}

/// (take, camera, frame, file) of every index row.
fn index_rows(out: &Path) -> Vec<(String, String, i32, String)> {
    let file = std::fs::File::open(out.join("index.parquet")).unwrap();
    let reader = SerializedFileReader::new(file).unwrap();
    let names: Vec<String> = reader
        .metadata()
        .file_metadata()
        .schema_descr()
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    assert_eq!(
        names,
        [
            "take",
            "scene",
            "seed",
            "camera",
            "wearer",
            "frame",
            "time_s",
            "file",
            "agents_in_view",
            "colour_exposure",
            "activity",
            "activity_phase",
            "activities_in_view"
        ]
    );
    reader
        .get_row_iter(None)
        .unwrap()
        .map(|r| {
            let r = r.unwrap();
            (
                r.get_string(0).unwrap().clone(),
                r.get_string(3).unwrap().clone(),
                r.get_int(5).unwrap(),
                r.get_string(7).unwrap().clone(),
            )
        })
        .collect()
}

#[test]
fn a_campaign_renders_indexes_resumes_and_reads_back() {
    let a = tempfile::tempdir().unwrap();
    let campaign = common::tiny_campaign(a.path(), false);
    let out = a.path().join("out");

    // The budget before work: takes and frames, nothing written.
    let dry = common::succeeds(egogen_run().arg(&campaign).arg("--dry-run"));
    let said = String::from_utf8_lossy(&dry.stderr);
    assert!(said.contains("3 takes over 2 scene(s)"), "{said}");
    assert!(!out.exists(), "--dry-run wrote {}", out.display());

    let run = common::succeeds(egogen_run().arg(&campaign));
    let said = String::from_utf8_lossy(&run.stderr);
    let s = state(&out);
    assert_eq!(s.takes.len(), 3);
    assert!(
        s.takes
            .iter()
            .all(|t| t.status == egogen::campaign::TakeStatus::Complete),
        "{said}"
    );
    let counts: std::collections::BTreeSet<usize> =
        s.takes.iter().filter_map(|t| t.def.crowd_count).collect();
    assert_eq!(counts.len(), 2, "two crowd sizes: {counts:?}");
    assert!(s.takes.iter().any(|t| t.def.scene.ends_with("plan_5.obj")));
    for t in &s.takes {
        egogen::supervisor::verify(&out.join("takes").join(&t.def.id)).unwrap();
    }
    // One tile per take on the contact sheet (cells of 176 px, two to a row for three takes).
    let sheet = std::fs::read(out.join("contact_sheet.png")).unwrap();
    let (w, h) = (
        u32::from_be_bytes(sheet[16..20].try_into().unwrap()),
        u32::from_be_bytes(sheet[20..24].try_into().unwrap()),
    );
    assert_eq!((w, h), (2 * 176, 2 * 176));

    // The index lists every frame file, once, in take order.
    let rows = index_rows(&out);
    let mut files: Vec<String> = glob::glob(&out.join("takes/*/cameras/*/*.exr").to_string_lossy())
        .unwrap()
        .map(|p| p.unwrap().strip_prefix(&out).unwrap().display().to_string())
        .collect();
    files.sort();
    let mut listed: Vec<String> = rows.iter().map(|r| r.3.clone()).collect();
    listed.sort();
    assert_eq!(listed, files);
    let order: Vec<&str> = s.takes.iter().map(|t| t.def.id.as_str()).collect();
    let mut seen: Vec<&str> = rows.iter().map(|r| r.0.as_str()).collect();
    seen.dedup();
    assert_eq!(seen, order);
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("logs/start_01/pool_report.json")).unwrap(),
    )
    .unwrap();
    assert!(report["utilisation"].as_f64().unwrap() > 0.0, "{report}");
    let baseline = common::campaign_digest(&out);

    // A take rendered alone with its recorded flags is the same bytes.
    let take = &s.takes[1];
    let dir = out.join("takes").join(&take.def.id);
    let moved = a.path().join("campaign_take");
    std::fs::rename(&dir, &moved).unwrap();
    let mut alone = egogen_run();
    alone
        .arg(a.path().join("run.toml"))
        .arg("--out")
        .arg(&dir)
        .args(["--seed", &take.def.seed.to_string(), "--scene"])
        .arg(&take.def.scene)
        .args(["--crowd-count", &take.def.crowd_count.unwrap().to_string()]);
    assert!(take.command.contains("--crowd-count"), "{}", take.command);
    common::succeeds(&mut alone);
    assert_eq!(
        std::fs::read(dir.join("manifest.json")).unwrap(),
        std::fs::read(moved.join("manifest.json")).unwrap(),
        "the take alone differs from the campaign's"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::rename(&moved, &dir).unwrap();

    // A second start of a finished campaign needs --resume, and then does nothing new.
    let again = egogen_run().arg(&campaign).output().unwrap();
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("--resume"));
    let resumed = egogen_run()
        .arg(&campaign)
        .arg("--resume")
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&resumed.stderr);
    assert!(resumed.status.success(), "{said}");
    assert!(
        said.contains(
            "3 finished take(s): 3 unchanged since they were finished, 0 verified in full"
        ),
        "a finished take was read again: {said}"
    );
    assert_eq!(common::campaign_digest(&out), baseline);

    // A frame damaged without changing its size or modification time is not seen by the
    // stamps; --rehash finds it, records the take as failed (not complete) and leaves it as it
    // is; put back, the take is complete again.
    let first = &state(&out).takes[0].def.id;
    let cameras = out.join("takes").join(first).join("cameras");
    let camera = std::fs::read_dir(&cameras)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let frame = std::fs::read_dir(camera)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "exr"))
        .unwrap();
    let kept = a.path().join("kept.exr");
    common::succeeds(Command::new("cp").arg("-p").arg(&frame).arg(&kept));
    let mut bytes = std::fs::read(&frame).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0xff;
    std::fs::write(&frame, &bytes).unwrap();
    common::succeeds(Command::new("touch").arg("-r").arg(&kept).arg(&frame));
    common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
    let rehashed = egogen_run()
        .arg(&campaign)
        .args(["--resume", "--rehash"])
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&rehashed.stderr);
    assert!(!rehashed.status.success(), "{said}");
    assert!(
        said.contains("does not match its manifest") && said.contains(first.as_str()),
        "{said}"
    );
    let failed = &state(&out).takes[0];
    assert_eq!(failed.status, egogen::campaign::TakeStatus::Failed);
    assert_eq!(
        std::fs::read(&frame).unwrap(),
        bytes,
        "the damaged take was touched"
    );
    common::succeeds(Command::new("cp").arg("-p").arg(&kept).arg(&frame));
    common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
    assert_eq!(common::campaign_digest(&out), baseline);

    // The campaign's own state is rebuilt from the take folders: campaign.json cut short
    // (kept in work/), or deleted (a start without --resume says to give it); a finished take
    // whose manifest was deleted is named, left as it is, and the others stay complete.
    let state_file = out.join("campaign.json");
    let text = std::fs::read(&state_file).unwrap();
    std::fs::write(&state_file, &text[..text.len() / 2]).unwrap();
    let rebuilt = common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
    let said = String::from_utf8_lossy(&rebuilt.stderr);
    assert!(said.contains("rebuilt from the take folders"), "{said}");
    assert_eq!(std::fs::read(&state_file).unwrap(), text, "{said}");
    assert_eq!(
        std::fs::read(out.join("work/campaign.json.unreadable")).unwrap(),
        &text[..text.len() / 2]
    );
    std::fs::remove_file(&state_file).unwrap();
    let refused = egogen_run().arg(&campaign).output().unwrap();
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success()
            && said
                .contains("holds this campaign's takes but no campaign.json; rerun with --resume"),
        "{said}"
    );
    common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
    assert_eq!(std::fs::read(&state_file).unwrap(), text);
    assert_eq!(common::campaign_digest(&out), baseline);
    let manifest = out.join("takes").join(first).join("manifest.json");
    let kept_manifest = std::fs::read(&manifest).unwrap();
    std::fs::remove_file(&manifest).unwrap();
    let resumed = egogen_run()
        .arg(&campaign)
        .arg("--resume")
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&resumed.stderr);
    assert!(!resumed.status.success(), "{said}");
    assert!(
        said.contains(&format!(
            "{first} is a finished take's folder without its manifest.json"
        )) && !said.contains("output.dir"),
        "{said}"
    );
    assert_eq!(state(&out).count(egogen::campaign::TakeStatus::Complete), 2);
    std::fs::write(&manifest, kept_manifest).unwrap();
    common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
    assert_eq!(common::campaign_digest(&out), baseline);
    // A folder holding anything else is not rebuilt from: refused, untouched.
    std::fs::remove_file(&state_file).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let refused = egogen_run()
        .arg(&campaign)
        .arg("--resume")
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && said.contains("it holds `notes.txt`, not this campaign's"),
        "{said}"
    );
    std::fs::remove_file(out.join("notes.txt")).unwrap();
    common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
    assert_eq!(common::campaign_digest(&out), baseline);

    // The same campaign again in the same place (the uninterrupted one moved aside), its
    // supervisor killed with SIGKILL three times at random moments (a worker once), resumed.
    std::fs::rename(&out, a.path().join("uninterrupted")).unwrap();
    let campaign_b = &campaign;
    let out_b = &out;
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        rng
    };
    let mut kills = 0;
    let mut worker_killed = false;
    let mut failures_after_kills = 0;
    let deadline = Instant::now() + Duration::from_secs(600);
    loop {
        assert!(Instant::now() < deadline, "the campaign never finished");
        let mut cmd = egogen_run();
        cmd.arg(campaign_b);
        if out_b.join("campaign.json").is_file() {
            cmd.arg("--resume");
        }
        let mut child = cmd
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        if kills < 3 {
            let wait = Duration::from_millis(1500 + next() % 4000);
            let started = Instant::now();
            while started.elapsed() < wait {
                if !worker_killed {
                    let out_b = out_b.display().to_string();
                    if let Some(&pid) = common::pids_with(&["render_shard.py", &out_b]).first() {
                        std::thread::sleep(Duration::from_millis(next() % 800));
                        let _ = Command::new("kill").args(["-9", &pid.to_string()]).status();
                        worker_killed = true;
                    }
                }
                if child.try_wait().unwrap().is_some() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            if child.try_wait().unwrap().is_none() {
                child.kill().unwrap();
                kills += 1;
            }
            child.wait().unwrap();
            continue;
        }
        // Killed no more: a resume that fails twice in a row is stuck, not unlucky.
        let status = child.wait().unwrap();
        if status.success() {
            break;
        }
        failures_after_kills += 1;
        if failures_after_kills >= 2 {
            // Fails the test with what the resume refused.
            common::succeeds(egogen_run().arg(campaign_b).arg("--resume"));
            break;
        }
    }
    // Orphaned Blender workers of the killed supervisors finish writing raw renders only.
    assert_eq!(common::campaign_digest(out_b), baseline);

    // The Python reader, pip-installed from the checkout, reads the campaign.
    let python = match common::reader_python() {
        Ok(p) => p,
        Err(e) if std::env::var_os("EGOGEN_REQUIRE_SYSTEM_TOOLS").is_none() => {
            eprintln!("SKIPPED the Python reader: {e}");
            return;
        }
        Err(e) => panic!("{e}"),
    };
    common::install_reader(&python);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let pytest = Command::new(&python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(root.join("python/tests"))
        .env("EGOGEN_CAMPAIGN", &out)
        .current_dir(a.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&pytest.stdout);
    assert!(pytest.status.success(), "pytest failed:\n{text}");
    assert!(
        text.contains(" passed") && !text.contains("skipped"),
        "{text}"
    );
}

/// A campaign whose scenes lie in different frames: a y-up centimetre OBJ room given its frame
/// in its `scenes` entry beside the apartment (glTF, metres). Both takes finish; the room's
/// take walks it in metres (about 60 m² walkable of its 64 m² floor: read in its file's
/// default frame it has no floor) and records the frame; rendered alone with its recorded
/// command's flags (`--up y --unit-m 0.01`) it is the same bytes.
#[test]
fn a_campaign_reads_each_scene_in_the_frame_its_entry_gives() {
    let a = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let run_config = common::tiny_campaign_run(a.path(), false);
    std::fs::write(a.path().join("room_cm.obj"), common::room_y_up_cm_obj()).unwrap();
    let out = a.path().join("framed");
    let campaign = campaign_file(
        a.path(),
        "framed",
        &out,
        2,
        &format!(
            "scenes = [{{ path = \"room_cm.obj\", up_axis = \"y\", unit_m = 0.01 }}, \"{}\"]\ncrowd_count = [1, 1]",
            root.join("assets/scenes/apartment.glb").display()
        ),
    );
    let s = run_to_completion(&campaign, &out);
    let room = &s.takes[0];
    assert!(room.def.scene.ends_with("room_cm.obj"));
    assert!(
        room.command.contains("--up y --unit-m 0.01"),
        "{}",
        room.command
    );
    assert!(
        !s.takes[1].command.contains("--up"),
        "{}",
        s.takes[1].command
    );
    let dir = out.join("takes").join(&room.def.id);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sequence/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["about"]["scene_up_axis"], "y", "{summary}");
    assert_eq!(summary["about"]["scene_unit_m"], 0.01, "{summary}");
    let walkable = summary["totals"]["checks"]["walkable_m2"].as_f64().unwrap();
    assert!((55.0..64.0).contains(&walkable), "walkable {walkable} m²");

    let moved = a.path().join("framed_take");
    std::fs::rename(&dir, &moved).unwrap();
    common::succeeds(
        egogen_run()
            .arg(&run_config)
            .arg("--out")
            .arg(&dir)
            .args(["--seed", &room.def.seed.to_string(), "--scene"])
            .arg(&room.def.scene)
            .args(["--up", "y", "--unit-m", "0.01", "--crowd-count", "1"]),
    );
    assert_eq!(
        std::fs::read(dir.join("manifest.json")).unwrap(),
        std::fs::read(moved.join("manifest.json")).unwrap(),
        "the take alone differs from the campaign's"
    );
    // A bad flag is refused by name before anything is made.
    let bad = egogen_run()
        .arg(&run_config)
        .args(["--out"])
        .arg(a.path().join("never"))
        .args(["--unit-m", "0"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--unit-m"));
    assert!(!a.path().join("never").exists());
}

/// A campaign varying what people do per take: take 0 walks only, take 1 stands and picks
/// things up. `index.parquet` says what each frame's wearer does (as the take's own
/// `summary.json` has it) and what the people in view do, nothing in a take where people only
/// walk; the take's recorded command (with `--activity-weights`) renders it alone byte for
/// byte; index rows kept before those columns existed are read again from the take.
#[test]
fn a_campaign_varies_the_activities_per_take_and_indexes_them() {
    use parquet::record::Field;
    let a = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    std::fs::write(
        a.path().join("run.toml"),
        r#"
[body]
[motion]
source = "agents"
duration_s = 14.0
[crowd]
count = 2
layout = "random"
wander = true
[output]
dir = "single"
mesh_every_n_frames = 0
[render]
cameras = ["camera-slam-left"]
resolution_scale = 0.1
every_n_frames = 20
samples = 2
frames_per_shard = 30
passes = ["colour", "segmentation"]
[supervisor]
workers = 2
"#,
    )
    .unwrap();
    let out = a.path().join("acts");
    let campaign = campaign_file(
        a.path(),
        "acts",
        &out,
        2,
        &format!(
            "scenes = [\"{}\"]\nactivity_weights = [{{ walk = 1 }}, {{ stand = 1, pick_up = 1.5 }}]",
            root.join("assets/scenes/apartment.glb").display()
        ),
    );
    let s = run_to_completion(&campaign, &out);
    assert!(
        s.takes[0].command.ends_with("--activity-weights walk=1"),
        "{}",
        s.takes[0].command
    );
    assert!(
        s.takes[1]
            .command
            .ends_with("--activity-weights stand=1,pick_up=1.5"),
        "{}",
        s.takes[1].command
    );

    // (take, wearer, frame, activity, phase, in view) of every row.
    let read_index = || -> Vec<(String, String, i64, [Option<String>; 3])> {
        let file = std::fs::File::open(out.join("index.parquet")).unwrap();
        let reader = SerializedFileReader::new(file).unwrap();
        let text = |f: &Field| match f {
            Field::Str(s) => Some(s.clone()),
            Field::Null => None,
            other => panic!("{other:?}"),
        };
        reader
            .get_row_iter(None)
            .unwrap()
            .map(|r| {
                let r = r.unwrap();
                let cols: Vec<&Field> = r.get_column_iter().map(|(_, f)| f).collect();
                (
                    r.get_string(0).unwrap().clone(),
                    r.get_string(4).unwrap().clone(),
                    r.get_int(5).unwrap() as i64,
                    [text(cols[10]), text(cols[11]), text(cols[12])],
                )
            })
            .collect()
    };
    let rows = read_index();
    let summary = |take: &str| -> serde_json::Value {
        let p = out.join("takes").join(take).join("sequence/summary.json");
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let mut acted = 0;
    for t in &s.takes {
        let sum = summary(&t.def.id);
        let mine: Vec<_> = rows.iter().filter(|r| r.0 == t.def.id).collect();
        assert!(mine.len() >= 10, "{}: {} rows", t.def.id, mine.len());
        if t.def.index == 0 {
            assert!(mine.iter().all(|r| r.3 == [None, None, None]), "{mine:?}");
            assert!(sum["agents"]
                .as_array()
                .unwrap()
                .iter()
                .all(|a| a["activities"].as_array().is_none_or(|v| v.is_empty())));
            continue;
        }
        for (_, wearer, frame, [activity, phase, in_view]) in mine {
            let agent = sum["agents"]
                .as_array()
                .unwrap()
                .iter()
                .find(|a| a["name"] == wearer.as_str())
                .unwrap();
            let segment = agent["activity_segments"]
                .as_array()
                .into_iter()
                .flatten()
                .find(|s| {
                    (s["start_frame"].as_i64().unwrap()..s["end_frame"].as_i64().unwrap())
                        .contains(frame)
                });
            let want = segment.map_or(("walk".to_string(), None), |s| {
                (
                    s["activity"].as_str().unwrap().to_string(),
                    Some(s["phase"].as_str().unwrap().to_string()),
                )
            });
            assert_eq!(
                (activity.clone().unwrap(), phase.clone()),
                want,
                "frame {frame}"
            );
            acted += usize::from(want.0 != "walk");
            let in_view = in_view.as_ref().unwrap();
            assert!(
                in_view.is_empty()
                    || in_view
                        .split(',')
                        .all(|n| ["walk", "stand", "pick_up"].contains(&n)),
                "{in_view}"
            );
        }
    }
    assert!(
        acted >= 2,
        "the wearer of take 1 did no activity in its frames"
    );

    // Take 1 rendered alone with its recorded command, where the campaign put it: the same
    // take.
    let take = &s.takes[1];
    let dir = out.join("takes").join(&take.def.id);
    let moved = a.path().join("moved");
    std::fs::rename(&dir, &moved).unwrap();
    let weights = take.command.rsplit(' ').next().unwrap();
    common::succeeds(
        egogen_run()
            .arg(a.path().join("run.toml"))
            .arg("--out")
            .arg(&dir)
            .args(["--seed", &take.def.seed.to_string(), "--scene"])
            .arg(&take.def.scene)
            .args(["--activity-weights", weights]),
    );
    assert!(
        std::fs::read(dir.join("manifest.json")).unwrap()
            == std::fs::read(moved.join("manifest.json")).unwrap(),
        "the take alone differs from the campaign's"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::rename(&moved, &dir).unwrap();

    // Rows kept without the activity columns (an older egogen): a resume reads them again.
    let before = std::fs::read(out.join("index.parquet")).unwrap();
    let kept = out.join("work/index").join(format!("{}.json", take.def.id));
    let mut old: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(&kept).unwrap()).unwrap();
    for row in &mut old {
        let row = row.as_object_mut().unwrap();
        for key in ["activity", "activity_phase", "activities_in_view"] {
            assert!(row.remove(key).is_some());
        }
    }
    std::fs::write(&kept, serde_json::to_vec(&old).unwrap()).unwrap();
    std::fs::remove_file(out.join("index.parquet")).unwrap();
    common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
    assert_eq!(std::fs::read(out.join("index.parquet")).unwrap(), before);

    // A bad mix is refused by key before anything is made.
    std::fs::write(
        &campaign,
        std::fs::read_to_string(&campaign)
            .unwrap()
            .replace("out = \"acts\"", "out = \"never\"")
            .replace("pick_up = 1.5", "pick_up = -1"),
    )
    .unwrap();
    let bad = egogen_run().arg(&campaign).output().unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success());
    assert!(
        err.contains("campaign.activity_weights[1]") && err.contains("`pick_up`"),
        "{err}"
    );
    assert!(!a.path().join("never").exists());
}

/// What would fail a take is found before any take is staged, even by `--dry-run`: a scene of
/// random bytes, a rig without the run's camera, a crowd beyond the limit and a free-disk floor
/// beyond the disk are refused naming the take or the campaign key, nothing written; a scene
/// read on its side is warned of naming the take; `--throughput-from` a missing folder or a
/// file is an error.
#[test]
fn a_campaign_s_takes_are_checked_before_any_is_staged() {
    let a = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    common::tiny_campaign_run(a.path(), false);
    std::fs::write(
        a.path().join("noise.glb"),
        [0x5a_u8, 0x13, 0xc7, 0x01].repeat(500),
    )
    .unwrap();
    std::fs::write(a.path().join("room_cm.obj"), common::room_y_up_cm_obj()).unwrap();
    let apartment = root
        .join("assets/scenes/apartment.glb")
        .display()
        .to_string();
    let cases = [
        (
            format!("scenes = [\"{apartment}\", \"noise.glb\"]"),
            vec!["take ", "noise.glb", "cannot read"],
        ),
        (
            format!(
                "scenes = [\"{apartment}\"]\nrigs = [\"{}\"]",
                root.join("camera_rigs/hololens2.json").display()
            ),
            vec![
                "take ",
                "hololens2.json: no camera named `camera-slam-left`",
            ],
        ),
        (
            format!("scenes = [\"{apartment}\"]\ncrowd_count = [842, 842]"),
            vec!["key `campaign.crowd_count`: [842, 842]: at most 32 people"],
        ),
        (
            format!("scenes = [\"{apartment}\"]\nduration_s = [0.01, 0.04]"),
            vec!["key `campaign.duration_s`", "0.1 s steps"],
        ),
        (
            format!("scenes = [\"{apartment}\"]\nmin_free_disk_gb = 1e9"),
            vec!["key `campaign.min_free_disk_gb`: 1000000000.00 GB is more than the whole file system"],
        ),
    ];
    // A campaign whose `run` is itself, and one that is no TOML: each says so, --dry-run or not.
    let own = a.path().join("own.toml");
    std::fs::write(
        &own,
        format!(
            "[campaign]\nrun = \"own.toml\"\nout = \"{}\"\ntakes = 1\n",
            a.path().join("own_out").display()
        ),
    )
    .unwrap();
    let broken = a.path().join("broken.toml");
    std::fs::write(&broken, "[campaign]\nrun = \"run.toml\"\ntakes = = 2\n").unwrap();
    for (file, says) in [
        (&own, ["campaign.run", "the campaign file itself"]),
        (&broken, ["broken.toml", "TOML parse error"]),
    ] {
        for dry in [true, false] {
            let mut cmd = egogen_run();
            cmd.arg(file);
            if dry {
                cmd.arg("--dry-run");
            }
            let o = cmd.output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success(), "{} accepted: {err}", file.display());
            for s in says {
                assert!(
                    err.contains(s),
                    "{}: expected `{s}` in: {err}",
                    file.display()
                );
            }
        }
    }
    assert!(!a.path().join("own_out").exists());
    // A scene read on its side is warned of, naming the take, before any is staged.
    let campaign = campaign_file(
        a.path(),
        "sideways",
        &a.path().join("sideways"),
        2,
        &format!("scenes = [\"{apartment}\", \"room_cm.obj\"]"),
    );
    let dry = common::succeeds(egogen_run().arg(&campaign).arg("--dry-run"));
    let said = String::from_utf8_lossy(&dry.stderr);
    assert!(
        said.contains("take room_cm-s1-") && said.contains("warning") && said.contains("up_axis"),
        "{said}"
    );
    assert!(!a.path().join("sideways").exists());
    // Throughput read from a folder that is not there, or from a file, is an error.
    for (from, says) in [("nowhere", "no such folder"), ("run.toml", "not a folder")] {
        let o = egogen_run()
            .arg(&campaign)
            .args(["--dry-run", "--throughput-from"])
            .arg(a.path().join(from))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("--throughput-from") && err.contains(says),
            "{err}"
        );
    }
    for (k, (keys, says)) in cases.iter().enumerate() {
        let campaign = campaign_file(
            a.path(),
            &format!("c{k}"),
            &a.path().join(format!("out{k}")),
            2,
            keys,
        );
        for dry in [true, false] {
            let mut cmd = egogen_run();
            cmd.arg(&campaign);
            if dry {
                cmd.arg("--dry-run");
            }
            let o = cmd.output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success(), "case {k} accepted: {err}");
            for s in says {
                assert!(err.contains(s), "case {k}: expected `{s}` in: {err}");
            }
            assert!(
                !a.path().join(format!("out{k}")).exists(),
                "case {k} wrote its folder"
            );
        }
    }
}

/// A tmpfs mounted on a folder for a test, unmounted when dropped.
struct Tmpfs(PathBuf);

impl Tmpfs {
    /// Mounts a tmpfs of `size` (as `mount -o size=` takes it) on `dir`; why not, where this
    /// machine does not let the test mount one.
    fn mount(dir: &Path, size: &str) -> Result<Tmpfs, String> {
        std::fs::create_dir_all(dir).unwrap();
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir)
            .output()
            .map_err(|e| format!("mount: {e}"))?;
        if !o.status.success() {
            return Err(String::from_utf8_lossy(&o.stderr).trim().to_string());
        }
        Ok(Tmpfs(dir.to_path_buf()))
    }

    /// Makes it `size` (its files kept).
    fn resize(&self, size: &str) {
        common::succeeds(
            Command::new("mount")
                .args(["-o", &format!("remount,size={size}")])
                .arg(&self.0),
        );
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// A campaign on a disk that fills up — while its takes are staged (three takes on 10 MB) and
/// while its one take renders (7.6 MB) — fails its takes naming the full disk; once space is
/// freed, `--resume` finishes it, identical by SHA-256 (every manifest and the index) to the
/// same campaign run uninterrupted in the same place; below its free-disk floor it pauses
/// staging while staged takes finish. Needs a tmpfs (root, as on CI): skipped where none can be
/// mounted.
#[test]
fn a_campaign_on_a_disk_that_fills_resumes_to_the_same_bytes() {
    let a = tempfile::tempdir().unwrap();
    let disk = match Tmpfs::mount(&a.path().join("disk"), "200m") {
        Ok(d) => d,
        Err(e) => {
            eprintln!("SKIPPED: no tmpfs to fill ({e})");
            return;
        }
    };
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // The tiny campaign's takes, each frame tried once more at most: a full disk fails at once.
    let run = common::tiny_campaign_run(a.path(), false);
    let text = std::fs::read_to_string(&run).unwrap();
    std::fs::write(&run, text.replace("retries = 40", "retries = 1")).unwrap();
    let scenes = format!(
        "scenes = [\"{}\"]\ncrowd_count = [1, 2]",
        root.join("assets/scenes/apartment.glb").display()
    );
    let out = disk.0.join("out");
    for (takes, full) in [(3, "10m"), (1, "7600k")] {
        let campaign = campaign_file(a.path(), &format!("c{takes}"), &out, takes, &scenes);
        disk.resize("200m");
        run_to_completion(&campaign, &out);
        let uninterrupted = common::campaign_digest(&out);
        std::fs::remove_dir_all(&out).unwrap();

        disk.resize(full);
        let filled = egogen_run().arg(&campaign).output().unwrap();
        let said = String::from_utf8_lossy(&filled.stderr);
        assert!(
            !filled.status.success() && said.contains("No space left on device"),
            "{takes} take(s) on {full}: {said}"
        );
        disk.resize("200m");
        common::succeeds(egogen_run().arg(&campaign).arg("--resume"));
        assert_eq!(
            common::campaign_digest(&out),
            uninterrupted,
            "{takes} take(s) on {full}"
        );
        std::fs::remove_dir_all(&out).unwrap();
    }

    // Below its free-disk floor, the campaign stops staging, not rendering: on 40 MB with a
    // 35 MB floor, the first take staged leaves less free; it renders and finishes meanwhile,
    // which frees the space, and the second is staged. (The wait once held the feed, so the
    // first take could not finish: the campaign waited for ever.)
    let campaign = campaign_file(
        a.path(),
        "floor",
        &out,
        2,
        &format!("{scenes}\nmin_free_disk_gb = 0.035"),
    );
    disk.resize("40m");
    let mut child = egogen_run()
        .arg(&campaign)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(300);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            child.kill().unwrap();
            panic!("the campaign below its disk floor never finished");
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    let o = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{said}");
    assert!(
        said.contains("paused: ") && said.contains("free disk is back above the floor"),
        "{said}"
    );
    assert_eq!(state(&out).count(egogen::campaign::TakeStatus::Complete), 2);
}

/// A campaign folder copied elsewhere with its campaign and run config (its scenes outside it)
/// — one take interrupted, its supervisor killed with SIGKILL once the take has a frame —
/// resumes there: the state is rebuilt for the new place and says so, the interrupted take is
/// continued where it lies (its `config.toml` now names the new folder), and the frame files
/// are those of an uninterrupted run of the same campaign elsewhere. Before, the copy was
/// refused as "a campaign of other takes".
#[test]
fn a_campaign_copied_elsewhere_resumes_there() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let a = tempfile::tempdir().unwrap();
    let write_campaign = |dir: &Path| -> PathBuf {
        std::fs::create_dir_all(dir).unwrap();
        common::tiny_campaign_run(dir, false);
        let keys = format!(
            "scenes = [\"{}\"]\nfirst_seed = 3",
            root.join("assets/scenes/apartment.glb").display()
        );
        campaign_file(dir, "campaign", Path::new("out"), 2, &keys)
    };
    // The uninterrupted campaign, in a folder of its own.
    let reference = a.path().join("reference");
    run_to_completion(&write_campaign(&reference), &reference.join("out"));

    // The same campaign elsewhere, stopped once its first take has a frame.
    let here = a.path().join("here");
    let campaign = write_campaign(&here);
    let mut child = egogen_run()
        .arg(&campaign)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(300);
    let has_a_frame = |takes: &Path| -> bool {
        std::fs::read_dir(takes).is_ok_and(|d| {
            d.flatten().any(|t| {
                t.file_name().to_string_lossy().ends_with(".partial")
                    && std::fs::read_dir(t.path().join("cameras/camera-slam-left")).is_ok_and(|f| {
                        f.flatten()
                            .any(|f| f.path().extension().is_some_and(|e| e == "exr"))
                    })
            })
        })
    };
    while !has_a_frame(&here.join("out/takes")) {
        assert!(Instant::now() < deadline, "no frame appeared");
        assert!(
            child.try_wait().unwrap().is_none(),
            "the campaign ended before it was stopped"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    // Its Blender workers stop at their next frame.
    let needle = here.display().to_string();
    while !common::pids_with(&["render_shard.py", &needle]).is_empty() {
        assert!(
            Instant::now() < deadline,
            "workers outlived their supervisor"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // Copied elsewhere, then resumed there.
    let there = a.path().join("there");
    let copied = Command::new("cp")
        .arg("-a")
        .arg(&here)
        .arg(&there)
        .status()
        .unwrap();
    assert!(copied.success());
    assert!(
        has_a_frame(&there.join("out/takes")),
        "no interrupted take was copied"
    );
    let resumed = common::succeeds(
        egogen_run()
            .arg(there.join("campaign.toml"))
            .arg("--resume"),
    );
    let said = String::from_utf8_lossy(&resumed.stderr);
    assert!(said.contains("campaign was moved or copied here"), "{said}");
    assert!(said.contains("was started in another folder"), "{said}");
    let s = state(&there.join("out"));
    assert!(
        s.takes
            .iter()
            .all(|t| t.status == egogen::campaign::TakeStatus::Complete),
        "{said}"
    );
    for t in &s.takes {
        let take = there.join("out/takes").join(&t.def.id);
        egogen::supervisor::verify(&take).unwrap();
        assert!(
            t.command.contains(&there.display().to_string()),
            "{}",
            t.command
        );
        let config = std::fs::read_to_string(take.join("config.toml")).unwrap();
        assert!(config.contains(&take.display().to_string()), "{config}");
    }
    // The frame files are the uninterrupted campaign's, byte for byte.
    let frames = |out: &Path| -> Vec<(String, String)> {
        let mut listed = Vec::new();
        for take in std::fs::read_dir(out.join("takes")).unwrap().flatten() {
            let name = take.file_name().to_string_lossy().into_owned();
            let manifest: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(take.path().join("manifest.json")).unwrap(),
            )
            .unwrap();
            for f in manifest["files"].as_array().unwrap() {
                let path = f["path"].as_str().unwrap();
                if path.ends_with(".exr") {
                    listed.push((format!("{name}/{path}"), f["sha256"].to_string()));
                }
            }
        }
        listed.sort();
        listed
    };
    let expected = frames(&reference.join("out"));
    assert!(!expected.is_empty());
    assert_eq!(frames(&there.join("out")), expected);
}
