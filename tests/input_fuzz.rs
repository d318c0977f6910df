//! Every file reader against damaged input: a real file of each kind is truncated at many
//! points, has bytes flipped, or is replaced by random bytes, and the reader must answer with
//! `Ok` or an error — never a panic and never an abort (an abort ends this test process, which
//! fails the test too). Errors must name the file.
//!
//! CI runs a small form; `EGOGEN_FUZZ_CASES=2000 cargo test --test input_fuzz` runs a long one.

use std::path::{Path, PathBuf};

use egogen::body::BodyModel;
use egogen::inspect::ExrContents;
use egogen::motion::amass::MotionSequence;
use egogen::motion::bvh::BvhClip;
use egogen::motion::deepmimic::import_deepmimic;
use egogen::rig::Rig;
use egogen::scene::load_scene;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Cases per reader (beyond the fixed truncation points).
fn cases() -> usize {
    std::env::var("EGOGEN_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(24)
}

/// SplitMix64: a small deterministic generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Damaged versions of `good`: truncations, flipped bytes, overwritten runs, random bytes.
fn damaged(good: &[u8], seed: u64) -> Vec<(String, Vec<u8>)> {
    let n = good.len();
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    for cut in [
        0,
        1,
        2,
        7,
        16,
        n / 10,
        n / 3,
        n / 2,
        n - n / 5,
        n.saturating_sub(1),
    ] {
        out.push((format!("first {cut} bytes"), good[..cut.min(n)].to_vec()));
    }
    for case in 0..cases() {
        let mut b = good.to_vec();
        let what = match case % 4 {
            0 => {
                for _ in 0..1 + rng.below(8) {
                    let i = rng.below(n);
                    b[i] ^= 1 << rng.below(8);
                }
                "flipped bits"
            }
            1 => {
                // Header-heavy formats keep sizes and counts near the front.
                let i = rng.below(n.min(512));
                let v = rng.next().to_le_bytes();
                for (k, byte) in v.iter().enumerate() {
                    if i + k < n {
                        b[i + k] = *byte;
                    }
                }
                "overwritten header bytes"
            }
            2 => {
                let i = rng.below(n);
                let len = rng.below(64).min(n - i);
                b.drain(i..i + len);
                "removed run"
            }
            _ => {
                let len = rng.below(4096);
                b = (0..len).map(|_| rng.next() as u8).collect();
                "random bytes"
            }
        };
        out.push((format!("case {case}: {what}"), b));
    }
    out
}

/// Feeds every damaged version of `good` to `read` through a file named `name`.
fn fuzz<T, E: std::fmt::Display>(
    name: &str,
    good: &[u8],
    seed: u64,
    read: impl Fn(&Path) -> Result<T, E>,
) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    let (mut ok, mut errors) = (0, 0);
    for (what, bytes) in damaged(good, seed) {
        std::fs::write(&path, &bytes).unwrap();
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| read(&path)));
        match result {
            Err(_) => panic!("{name}, {what}: the reader panicked"),
            Ok(Ok(_)) => ok += 1,
            Ok(Err(e)) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(name),
                    "{name}, {what}: the error does not name the file: {msg}"
                );
                errors += 1;
            }
        }
    }
    eprintln!("{name}: {errors} errors, {ok} still readable");
    assert!(errors > 0, "{name}: no damaged version was refused");
}

fn read(p: &str) -> Vec<u8> {
    std::fs::read(root().join(p)).unwrap()
}

#[test]
fn run_config() {
    let good = read("configs/default.toml");
    fuzz("run.toml", &good, 1, |p| {
        egogen::cli::config::RawRun::load(p)
            .and_then(|raw| egogen::cli::resolve::resolve_run(raw, p))
    });
}

#[test]
fn rig_and_aria_calibration() {
    fuzz(
        "rig.json",
        &read("camera_rigs/aria_gen1.json"),
        2,
        Rig::load,
    );
    fuzz(
        "calibration.json",
        &read("tests/fixtures/aria_gen1_device_calibration.json"),
        3,
        Rig::load,
    );
}

#[test]
fn body_model_npz() {
    fuzz("body.npz", &read("assets/body/SMPLX_NEUTRAL.npz"), 4, |p| {
        BodyModel::load(p)
    });
}

#[test]
fn motion_npz() {
    fuzz(
        "motion.npz",
        &read("assets/motion/cmu_01_01.npz"),
        5,
        MotionSequence::read,
    );
}

#[test]
fn bvh() {
    fuzz(
        "clip.bvh",
        &read("tests/fixtures/cmu_01_01_excerpt.bvh"),
        6,
        BvhClip::read,
    );
}

#[test]
fn deepmimic() {
    let model = BodyModel::load(root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    // Two frames of a humanoid3d clip: duration, root position, 8 quaternions, 4 angles.
    let frame = |x: f64| {
        let mut f = vec![0.0333, x, 0.85, 0.0];
        for k in 0..15 {
            if [4, 8, 11, 14].contains(&k) {
                f.push(0.1);
            } else {
                f.extend([1.0, 0.0, 0.0, 0.0]);
            }
        }
        f.truncate(44);
        f
    };
    let good = serde_json::json!({"Loop": "wrap", "Frames": [frame(0.0), frame(0.05)]});
    let good = serde_json::to_vec(&good).unwrap();
    fuzz("walk.txt", &good, 7, |p| import_deepmimic(p, &model));
}

#[test]
fn scenes() {
    fuzz("room.glb", &read("assets/scenes/apartment.glb"), 8, |p| {
        load_scene(p, Default::default())
    });
    let obj = b"o floor\nv 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nf 1 2 3\nf 1 3 4\n\
o box\nv 1 0 1\nv 2 0 1\nv 2 1 1\nf 5 6 7\n";
    fuzz("room.obj", obj, 9, |p| load_scene(p, Default::default()));
    let ply = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n4 0 0\n4 0 4\n0 0 4\n3 0 1 2\n3 0 2 3\n";
    fuzz("room.ply", ply, 10, |p| load_scene(p, Default::default()));
}

/// Random bytes under a scene's name are refused with what the file should have been, not
/// only the parser's words.
#[test]
fn random_bytes_as_a_scene_say_what_the_file_should_be() {
    let dir = tempfile::tempdir().unwrap();
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let bytes: Vec<u8> = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    for (name, format) in [
        ("scan.glb", "glTF"),
        ("scan.gltf", "glTF"),
        ("scan.obj", "Wavefront OBJ"),
        ("scan.ply", "PLY"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        let msg = load_scene(&path, Default::default())
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains(&path.display().to_string())
                && msg.contains(&format!("not a valid {format} file"))
                && msg.contains("check that the file is complete"),
            "{name}: {msg}"
        );
    }
}

#[test]
fn exr() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.exr");
    write_rgba_file(&path, 16, 8, |x, y| {
        (x as f32 / 16.0, y as f32 / 8.0, 0.5f32, 1.0f32)
    })
    .unwrap();
    fuzz(
        "frame.exr",
        &std::fs::read(&path).unwrap(),
        11,
        ExrContents::read,
    );
}

#[test]
fn weights_files() {
    let device = Default::default();
    fuzz(
        "motion.safetensors",
        &read("assets/motion/primitive_cvae.safetensors"),
        12,
        egogen::motion::cvae::weights::read_arch,
    );
    fuzz(
        "policy.safetensors",
        &read("assets/policy/policy.safetensors"),
        13,
        |p| {
            egogen::policy::weights::load_policy::<egogen::motion::cvae::infer::InferBackend>(
                p, &device,
            )
        },
    );
}

/// `configs/train_policy.toml` with its paths made absolute, so that changed versions get past
/// the files they name.
fn training_config() -> String {
    String::from_utf8(read("configs/train_policy.toml"))
        .unwrap()
        .replace("\"../", &format!("\"{}/", root().display()))
        .replace(
            "\"train_primitive.toml",
            &format!("\"{}/configs/train_primitive.toml", root().display()),
        )
}

#[test]
fn training_configs() {
    let text = training_config();
    fuzz(
        "train_policy.toml",
        text.as_bytes(),
        14,
        egogen::cli::train_policy::load_policy_plan,
    );
}

#[test]
fn point_cache() {
    use egogen::vertex_cache::PointCache;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.pc2");
    let cache = PointCache {
        start_frame: 0.0,
        sample_rate: 1.0,
        samples: vec![vec![[0.0, 1.0, 2.0]; 5]; 3],
    };
    cache.write(&path).unwrap();
    fuzz(
        "body.pc2",
        &std::fs::read(&path).unwrap(),
        15,
        PointCache::read,
    );
}

/// The error of loading the shipped policy written to `dir/name.safetensors` with its header's
/// architecture changed by `claims`.
fn load_policy_claiming(dir: &Path, name: &str, claims: &[(&str, u64)]) -> String {
    let good = read("assets/policy/policy.safetensors");
    let n = u64::from_le_bytes(good[..8].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&good[8..8 + n]).unwrap();
    let arch = header["__metadata__"]["egogen.policy_arch"]
        .as_str()
        .unwrap()
        .to_owned();
    let mut arch: serde_json::Value = serde_json::from_str(&arch).unwrap();
    for (key, value) in claims {
        arch[*key] = serde_json::json!(value);
    }
    header["__metadata__"]["egogen.policy_arch"] = serde_json::json!(arch.to_string());
    let mut bytes = serde_json::to_vec(&header).unwrap();
    let mut file = (bytes.len() as u64).to_le_bytes().to_vec();
    file.append(&mut bytes);
    file.extend_from_slice(&good[8 + n..]);
    let path = dir.join(format!("{name}.safetensors"));
    std::fs::write(&path, file).unwrap();
    match egogen::policy::weights::load_policy::<egogen::motion::cvae::infer::InferBackend>(
        &path,
        &Default::default(),
    ) {
        Ok(_) => panic!("{name}: a policy claiming {claims:?} was loaded"),
        Err(e) => e.to_string(),
    }
}

/// Sizes that scale memory are refused by key, before anything is allocated — never an abort
/// (`memory allocation failed`, which ends this test process): a policy file whose header
/// claims a huge network, training configs asking for one or for huge batches, a synth crowd of
/// 10¹³ people or 10¹² shape coefficients, `policy eval --episodes 1e12`.
#[test]
fn sizes_that_would_exhaust_memory_are_refused_by_key() {
    let dir = tempfile::tempdir().unwrap();
    // The shipped policy with its header's architecture claiming hidden = 10⁹.
    let err = load_policy_claiming(dir.path(), "huge_policy", &[("hidden", 1_000_000_000)]);
    assert!(
        err.contains("huge_policy.safetensors") && err.contains("hidden"),
        "{err}"
    );

    // Training configs.
    let text = training_config();
    for (section, key, value) in [
        ("[policy]", "hidden", "1000000000"),
        ("[ppo]", "envs", "1000000000000"),
        ("[validation]", "episodes", "1000000000000"),
    ] {
        let config = dir.path().join(format!("train_{key}.toml"));
        let changed = format!("{section}\n{key} = {value}");
        let body = if text.contains(&format!("\n{key} =")) {
            text.lines()
                .filter(|l| !l.starts_with(&format!("{key} =")))
                .collect::<Vec<_>>()
                .join("\n")
        } else {
            text.clone()
        };
        std::fs::write(&config, body.replacen(section, &changed, 1)).unwrap();
        let err = egogen::cli::train_policy::load_policy_plan(&config)
            .err()
            .unwrap_or_else(|| panic!("{key} = {value} accepted"))
            .to_string();
        assert!(
            err.contains(key) && err.contains(&format!("train_{key}.toml")),
            "{err}"
        );
    }

    // A synth crowd.
    for (key, line) in [
        ("crowd.count", "count = 10000000000000"),
        (
            "crowd.betas_count",
            "count = 3\nbetas_count = 1000000000000",
        ),
    ] {
        let config = dir.path().join("synth.toml");
        std::fs::write(
            &config,
            format!(
                "[scene]\nfloor_m = 8.0\n[motion]\nduration_s = 1.0\n[crowd]\n{line}\nlayout = \"random\"\nsteering = \"sampling\"\nk = 2\n[output]\ndir = \"out\"\n"
            ),
        )
        .unwrap();
        let err = egogen::cli::synth_config::load_synth_plan(&config)
            .err()
            .unwrap_or_else(|| panic!("{line} accepted"))
            .to_string();
        assert!(err.contains(key), "{err}");
    }

    // policy eval.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["policy", "eval", "--episodes", "1000000000000"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--episodes"), "{err}");
}

/// Sizes each within its key's fixed limit whose product would not fit in memory are refused
/// before anything is allocated, naming the key, what they need and the budget: a training
/// rollout, a policy file's network, a synth crowd, a scene's walkable map and `egogen-run`'s
/// scripted walk under a small `EGOGEN_MEMORY_GB`.
#[test]
fn sizes_within_their_limits_that_would_not_fit_in_memory_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // 65 536 environments × 4 096 steps: each key within its limit, the rollout hundreds of GB.
    let text = training_config();
    let config = dir.path().join("train_rollout.toml");
    let body: String = text
        .lines()
        .filter(|l| !l.starts_with("envs =") && !l.starts_with("steps_per_env ="))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(
        &config,
        body.replacen("[ppo]", "[ppo]\nenvs = 65536\nsteps_per_env = 4096", 1),
    )
    .unwrap();
    let err = egogen::cli::train_policy::load_policy_plan(&config)
        .expect_err("a rollout of 2.7e8 steps was accepted")
        .to_string();
    assert!(
        err.contains("ppo.envs") && err.contains("train_rollout.toml") && err.contains("GB"),
        "{err}"
    );

    // A policy file whose header asks for hidden = 4 096 with 64 residual blocks (each within
    // its limit): a network of 69 GB.
    let err = load_policy_claiming(
        dir.path(),
        "wide_policy",
        &[("hidden", 4096), ("residual_blocks", 64)],
    );
    assert!(
        err.contains("wide_policy.safetensors") && err.contains("hidden = 4096"),
        "{err}"
    );

    // A crowd of 32 agents for 10 minutes under a 1 GB budget; a budget that is not a number.
    let synth = |budget: &str| {
        let config = dir.path().join("synth_memory.toml");
        std::fs::write(
            &config,
            "[scene]\nfloor_m = 8.0\n[motion]\nduration_s = 600.0\n[crowd]\ncount = 32\nbetas_count = 300\nlayout = \"random\"\nsteering = \"sampling\"\nk = 2\n[output]\ndir = \"out\"\n",
        )
        .unwrap();
        std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
            .args(["synth", "--quiet"])
            .arg(&config)
            .env("EGOGEN_MEMORY_GB", budget)
            .output()
            .unwrap()
    };
    let out = synth("1");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("motion.duration_s")
            && err.contains("32 agents × 24014 frames")
            && err.contains("EGOGEN_MEMORY_GB"),
        "{err}"
    );
    let out = synth("lots");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("EGOGEN_MEMORY_GB = \"lots\""),
        "{err}"
    );

    // A 300 m square floor scene: its walkable map (9 · 10⁶ cells, within the cell limit) needs
    // 279 MB, refused under 0.1 GB naming the scene file.
    std::fs::write(
        dir.path().join("floor.obj"),
        "v -150 -150 0\nv 150 -150 0\nv 150 150 0\nv -150 150 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let config = dir.path().join("synth_floor.toml");
    std::fs::write(
        &config,
        "[scene]\npath = \"floor.obj\"\n[motion]\nduration_s = 1.0\n[crowd]\ncount = 1\nlayout = \"random\"\nsteering = \"sampling\"\nk = 2\n[output]\ndir = \"out\"\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["synth", "--quiet"])
        .arg(&config)
        .env("EGOGEN_MEMORY_GB", "0.1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("floor.obj") && err.contains("3002 × 3002 cells") && err.contains("279 MB"),
        "{err}"
    );
    assert!(!dir.path().join("out").exists() && !dir.path().join("out.partial").exists());

    // egogen-run's scripted walk at its frame limit (10⁶ frames) under a 1 GB budget.
    let config = dir.path().join("walk.toml");
    std::fs::write(
        &config,
        "[body]\nbetas = []\n[motion]\nsource = \"scripted_walk\"\nduration_s = 25000.0\n\
         frame_rate_hz = 40.0\n[output]\ndir = \"walk\"\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_egogen-run"))
        .arg(&config)
        .env("EGOGEN_MEMORY_GB", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("motion.duration_s") && err.contains("a scripted walk of 1000000 frames"),
        "{err}"
    );
    assert!(!dir.path().join("walk").exists() && !dir.path().join("walk.partial").exists());
}
