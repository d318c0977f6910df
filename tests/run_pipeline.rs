//! `egogen-run` end to end: a short walk writes a complete sequence folder; bad configs fail
//! with the file and key named, a non-zero exit, and nothing written.

mod common;

use std::path::Path;
use std::process::Command;

fn egogen_run(config: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_egogen-run"))
        .arg(config)
        .output()
        .unwrap()
}

const GOOD: &str = r#"
[body]
betas = [1.0, -0.5]
[motion]
source = "scripted_walk"
duration_s = 0.5
frame_rate_hz = 40.0
[output]
dir = "seq"
mesh_every_n_frames = 10
"#;

#[test]
fn short_walk_writes_a_complete_sequence() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("run.toml");
    std::fs::write(&cfg, GOOD).unwrap();
    let out = egogen_run(&cfg);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let seq = dir.path().join("seq");
    for f in [
        "motion.npz",
        "cpf_trajectory.json",
        "preview.png",
        "manifest.json",
        "meshes/frame_00000.obj",
        "meshes/frame_00010.obj",
    ] {
        assert!(seq.join(f).is_file(), "{f} missing");
    }
    assert!(!dir.path().join("seq.partial").exists());
    let motion = egogen::motion::MotionSequence::read(&seq.join("motion.npz")).unwrap();
    assert_eq!(motion.len(), 20);
    assert_eq!(motion.betas, vec![1.0, -0.5]);
    let cpf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(seq.join("cpf_trajectory.json")).unwrap()).unwrap();
    let frames = cpf.as_array().unwrap();
    assert_eq!(frames.len(), 20);
    // Eyes of a walking adult: 1.3–1.9 m above the floor, moving along +x.
    let z0 = frames[0]["world_from_cpf"][2][3].as_f64().unwrap();
    let x_last = frames[19]["world_from_cpf"][0][3].as_f64().unwrap();
    let x0 = frames[0]["world_from_cpf"][0][3].as_f64().unwrap();
    assert!((1.3..1.9).contains(&z0), "eye height {z0}");
    assert!(x_last - x0 > 0.3, "walked {} m", x_last - x0);
    // The sequence folder's manifest has checksums: verify checks it.
    let report = egogen::supervisor::verify(&seq).unwrap();
    assert_eq!(report.files, 5, "motion, trajectory, preview, two meshes");

    // A second run refuses to overwrite and leaves the folder as it was.
    let before = std::fs::read(seq.join("manifest.json")).unwrap();
    let again = egogen_run(&cfg);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("already exists"));
    assert_eq!(std::fs::read(seq.join("manifest.json")).unwrap(), before);
}

fn expect_config_error(text: &str, needles: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("bad.toml");
    std::fs::write(&cfg, text).unwrap();
    let out = egogen_run(&cfg);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "must fail: {err}");
    assert!(err.contains("bad.toml"), "names the file: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` missing from: {err}");
    }
    let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(entries.len(), 1, "nothing written besides the config");
}

#[test]
fn unknown_key() {
    expect_config_error(
        &GOOD.replace("betas = [1.0, -0.5]", "betas = []\nheight_m = 1.8"),
        &["unknown field `height_m`"],
    );
}

#[test]
fn wrong_type() {
    expect_config_error(
        &GOOD.replace("duration_s = 0.5", "duration_s = \"long\""),
        &["duration_s", "invalid type"],
    );
}

#[test]
fn missing_model_file() {
    expect_config_error(
        &GOOD.replace("[body]", "[body]\nmodel = \"nowhere/SMPLX_NEUTRAL.npz\""),
        &["body.model", "not found"],
    );
}

#[test]
fn negative_duration() {
    expect_config_error(
        &GOOD.replace("duration_s = 0.5", "duration_s = -2.0"),
        &["motion.duration_s", "positive"],
    );
}

#[test]
fn too_many_betas() {
    expect_config_error(
        &GOOD.replace(
            "betas = [1.0, -0.5]",
            &format!("betas = [{}]", ["0.1"; 11].join(", ")),
        ),
        &["11 betas", "has 10"],
    );
}

#[test]
fn absurd_duration() {
    // 1e9 s used to abort on a failed allocation.
    expect_config_error(
        &GOOD.replace("duration_s = 0.5", "duration_s = 1e9"),
        &["motion.duration_s", "frames", "GB", "at most"],
    );
}

#[test]
fn absurd_betas() {
    // 1e300 used to pass and write NaN into the CPF trajectory.
    expect_config_error(
        &GOOD.replace("betas = [1.0, -0.5]", "betas = [1e300]"),
        &["body.betas", "value 0", "±10"],
    );
}

/// The good config with a `[render]` section (errors are found before anything renders).
fn with_render(render: &str) -> String {
    format!("{GOOD}\n[render]\n{render}\n")
}

#[test]
fn unknown_render_key() {
    expect_config_error(
        &with_render("samples = 4\nspp = 4"),
        &["unknown field `spp`"],
    );
}

#[test]
fn render_key_of_wrong_type() {
    expect_config_error(
        &with_render("samples = \"many\""),
        &["samples", "invalid type"],
    );
}

#[test]
fn negative_shutter() {
    expect_config_error(
        &with_render("shutter_frames = -0.5"),
        &["render.shutter_frames", "-0.5"],
    );
}

#[test]
fn a_denoise_prefilter_without_the_denoiser_or_unknown() {
    expect_config_error(
        &with_render("denoise_prefilter = \"fast\""),
        &["render.denoise_prefilter", "denoise = true"],
    );
    expect_config_error(
        &with_render("denoise = true\ndenoise_prefilter = \"quick\""),
        &[
            "denoise_prefilter",
            "unknown variant `quick`",
            "`accurate`",
            "`fast`",
        ],
    );
}

#[test]
fn floor_steps_out_of_range() {
    for steps in ["0.0", "0.8", "nan"] {
        expect_config_error(
            &format!("{GOOD}\n[scene]\nfloor_steps_m = {steps}\n"),
            &["scene.floor_steps_m", "at most 0.5 m"],
        );
    }
    expect_config_error(
        &format!("{GOOD}\n[scene]\nfloor_z_m = inf\n"),
        &["scene.floor_z_m", "finite height"],
    );
    // `egogen scene inspect` checks its flags the same way, before loading the scene.
    let out = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args([
            "scene",
            "inspect",
            "assets/scenes/stepped_house.obj",
            "--floor-steps-m",
            "0.8",
            "--out",
            "never_written.png",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--floor-steps-m") && err.contains("at most 0.5 m"),
        "{err}"
    );
    assert!(!Path::new("never_written.png").exists());
}

#[test]
fn unknown_fisheye_rendering() {
    expect_config_error(
        &with_render("fisheye = \"fast\""),
        &["fisheye", "unknown variant `fast`", "`exact`", "`native`"],
    );
}

#[test]
fn impossible_resolution() {
    expect_config_error(
        &with_render("resolution_scale = 0.3"),
        &["render.resolution_scale", "camera `camera-", "whole pixels"],
    );
}

#[test]
fn missing_rig_file() {
    expect_config_error(
        &with_render("rig = \"rigs/nowhere.json\""),
        &["render.rig", "nowhere.json", "not found"],
    );
}

#[test]
fn unknown_camera() {
    expect_config_error(
        &with_render("cameras = [\"camera-thermal\"]"),
        &["render.cameras", "camera-thermal"],
    );
}

#[test]
fn broken_rig_file() {
    let dir = tempfile::tempdir().unwrap();
    let rig = dir.path().join("broken_rig.json");
    std::fs::write(
        &rig,
        r#"{"egogen_rig": 1, "name": "x", "cameras": [{"name": "c", "resolution_px": [0, 480],
            "model": {"type": "pinhole", "params": [100, 100, 320, 240]},
            "cpf_from_cam": {"translation_m": [0, 0, 0], "rotation": [[1,0,0],[0,1,0],[0,0,1]]}}]}"#,
    )
    .unwrap();
    expect_config_error(
        &with_render(&format!("rig = \"{}\"", rig.display())),
        &["render.rig", "broken_rig.json"],
    );
}

#[test]
fn slurm_settings_without_the_slurm_backend() {
    expect_config_error(
        &with_render("samples = 4\n[supervisor.slurm]\ncpus_per_task = 4"),
        &["supervisor.slurm", "backend"],
    );
}

#[test]
fn slurm_memory_not_positive() {
    expect_config_error(
        &with_render(
            "samples = 4\n[supervisor]\nbackend = \"slurm\"\n[supervisor.slurm]\nmem_gb = 0.0",
        ),
        &["supervisor.slurm.mem_gb", "positive"],
    );
}

#[test]
fn unknown_backend() {
    expect_config_error(
        &with_render("samples = 4\n[supervisor]\nbackend = \"kubernetes\""),
        &["backend", "unknown variant `kubernetes`", "slurm"],
    );
}

#[test]
fn existing_output_is_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("run.toml");
    std::fs::write(&cfg, with_render("samples = 1")).unwrap();
    let out_dir = dir.path().join("seq");
    std::fs::create_dir_all(&out_dir).unwrap();
    std::fs::write(out_dir.join("keep.txt"), "mine").unwrap();
    let out = egogen_run(&cfg);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("already exists"));
    let entries: Vec<_> = std::fs::read_dir(&out_dir).unwrap().collect();
    assert_eq!(entries.len(), 1);
    assert_eq!(
        std::fs::read_to_string(out_dir.join("keep.txt")).unwrap(),
        "mine"
    );
    assert!(!dir.path().join("seq.partial").exists());
}

#[test]
fn depth_noise_for_an_unrendered_camera() {
    expect_config_error(
        &with_render("[render.depth_noise]\ncameras = [\"depth-long-throw\"]"),
        &[
            "render.depth_noise.cameras",
            "depth-long-throw",
            "camera-rgb",
        ],
    );
}

#[test]
fn depth_noise_with_a_bad_range() {
    let rig = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("camera_rigs/hololens2.json");
    expect_config_error(
        &with_render(&format!(
            "rig = \"{}\"\n[render.depth_noise]\ncameras = [\"depth-long-throw\"]\nmax_range_m = 0.1",
            rig.display()
        )),
        &["render.depth_noise.max_range_m", "min_range_m"],
    );
}

/// A real render of the HoloLens 2 depth camera (40×36) with the noise model on: the frame
/// file holds `depth_noisy.Z` beside the exact depth, within the model's σ of it, validated and
/// readable by `egogen inspect`, and the same again from a second run.
#[test]
fn depth_noise_channel_is_written_and_reproducible() {
    use egogen::inspect::ExrContents;
    use egogen::render::depth_noise::DepthNoise;
    let rig = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("camera_rigs/hololens2.json");
    let render = format!(
        "rig = \"{}\"\ncameras = [\"depth-long-throw\"]\nresolution_scale = 0.125\nsamples = 1\nevery_n_frames = 10\n[render.depth_noise]\ncameras = [\"depth-long-throw\"]\nseed = 3",
        rig.display()
    );
    let config = with_render(&render).replace("duration_s = 0.5", "duration_s = 0.05");
    let noisy_of_a_run = || {
        let dir = tempfile::tempdir().unwrap();
        let cfg = dir.path().join("run.toml");
        std::fs::write(&cfg, &config).unwrap();
        let out = egogen_run(&cfg);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let frame = dir
            .path()
            .join("seq/cameras/depth-long-throw/frame_00000.exr");
        let inspect = Command::new(env!("CARGO_BIN_EXE_egogen"))
            .arg("inspect")
            .arg(&frame)
            .output()
            .unwrap();
        assert!(inspect.status.success());
        let listing = String::from_utf8_lossy(&inspect.stdout);
        assert!(listing.contains("depth_noisy"), "{listing}");
        let ann = std::fs::read_to_string(
            dir.path()
                .join("seq/cameras/depth-long-throw/annotations.json"),
        )
        .unwrap();
        assert!(ann.contains("\"depth_noisy.Z\"") && ann.contains("\"seed\": 3"));
        let exr = ExrContents::read(&frame).unwrap();
        let ch = |n: &str| exr.channel(n).unwrap().values.clone();
        (ch("depth.Z"), ch("depth_noisy.Z"))
    };
    let (depth, noisy) = noisy_of_a_run();
    let model = DepthNoise::default();
    let (mut measured, mut changed) = (0, 0);
    for (&z, &n) in depth.iter().zip(&noisy) {
        if n == 0.0 {
            continue;
        }
        measured += 1;
        changed += usize::from(n != z);
        // Within 6σ at the steepest incidence measured (75°), plus the 1 mm step.
        let bound = 6.0 * model.sigma_m(z as f64, 75f64.to_radians()) + 0.0005;
        assert!(((n - z) as f64).abs() <= bound, "{z} → {n}");
    }
    eprintln!(
        "{measured} measured pixels of {}, {changed} changed",
        depth.len()
    );
    assert!(
        measured > 100 && changed > measured / 2,
        "{measured} {changed}"
    );
    assert_eq!(noisy_of_a_run().1, noisy, "same seed, same noise");
}

#[test]
fn a_camera_listed_twice() {
    expect_config_error(
        &with_render("cameras = [\"camera-rgb\", \"camera-rgb\"]"),
        &["render.cameras", "\"camera-rgb\" is listed twice"],
    );
}

/// OBJ and PLY scenes render (tests/scene_formats.rs); a format Blender is not given is refused
/// by key before anything is written.
#[test]
fn rendering_a_scene_of_another_format_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("room.stl"), "solid room\nendsolid room\n").unwrap();
    let cfg = dir.path().join("run.toml");
    std::fs::write(
        &cfg,
        format!(
            "[scene]\npath = \"room.stl\"\n{}",
            with_render("samples = 1")
        ),
    )
    .unwrap();
    let out = egogen_run(&cfg);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("scene.path")
            && err.contains("glTF")
            && err.contains("OBJ")
            && err.contains("PLY")
            && err.contains("room.stl"),
        "{err}"
    );
    assert!(!dir.path().join("seq.partial").exists());
}

#[test]
fn a_motion_only_run_leaves_an_interrupted_render_run_alone() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("run.toml");
    std::fs::write(&cfg, GOOD).unwrap();
    // What an interrupted render run into the same folder leaves.
    let staging = dir.path().join("seq.partial");
    std::fs::create_dir_all(staging.join("work")).unwrap();
    std::fs::write(staging.join("work/run.json"), "{}").unwrap();
    std::fs::create_dir_all(staging.join("cameras/camera-rgb")).unwrap();
    std::fs::write(
        staging.join("cameras/camera-rgb/frame_00000.exr"),
        "a frame",
    )
    .unwrap();
    let out = egogen_run(&cfg);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("seq.partial") && err.contains("--resume"),
        "{err}"
    );
    assert!(staging.join("cameras/camera-rgb/frame_00000.exr").is_file());
    assert!(!dir.path().join("seq").exists());
}

#[test]
fn a_workers_override_gets_the_configs_check() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("run.toml");
    std::fs::write(&cfg, GOOD).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_egogen-run"))
        .arg(&cfg)
        .args(["--workers", "100000"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("supervisor.workers") && err.contains("1..=256"),
        "{err}"
    );
    assert!(!dir.path().join("seq").exists());
}

#[test]
fn unknown_or_inconsistent_passes() {
    expect_config_error(
        &with_render("passes = [\"depth\", \"rgb\"]"),
        &["render.passes", "\"colour\"", "found \"rgb\""],
    );
    expect_config_error(
        &with_render("passes = [\"colour\", \"colmap\"]"),
        &["render.passes", "not a pass", "[render] colmap"],
    );
    expect_config_error(
        &with_render("passes = [\"depth\"]\ncolmap = true"),
        &["render.colmap", "list \"colour\""],
    );
    expect_config_error(
        &with_render("passes = []"),
        &["render.passes", "empty list"],
    );
    expect_config_error(
        &with_render("passes = [\"depth_noise\"]"),
        &["render.passes", "[render.depth_noise]"],
    );
    expect_config_error(
        &with_render("device = \"tpu\""),
        &["device = \"tpu\"", "unknown variant `tpu`", "`gpu`"],
    );
}

/// `passes = ["depth"]` renders only the ground truth's position pass: the frame files hold
/// `depth.Z` and `valid.V` only, there are no COLMAP images, annotations say occlusion is not
/// known, and `verify` accepts the dataset. The Aria SLAM camera asked for colour stores one
/// grey channel, and its COLMAP image (written by default with colour) is grey.
#[test]
fn only_the_asked_passes_are_rendered_and_monochrome_cameras_store_grey() {
    use egogen::inspect::ExrContents;
    let run = |render: &str| {
        let dir = tempfile::tempdir().unwrap();
        let cfg = dir.path().join("run.toml");
        let config = with_render(render).replace("duration_s = 0.5", "duration_s = 0.05");
        std::fs::write(&cfg, config).unwrap();
        let out = egogen_run(&cfg);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        dir
    };
    let channels = |path: &Path| -> Vec<String> {
        let exr = ExrContents::read(path).unwrap();
        exr.channels.iter().map(|c| c.name.clone()).collect()
    };
    let verify = |dataset: &Path| {
        common::succeeds(
            Command::new(env!("CARGO_BIN_EXE_egogen-run"))
                .arg("verify")
                .arg(dataset),
        );
    };

    let depth = run("cameras = [\"camera-rgb\"]\nresolution_scale = 0.0625\nsamples = 1\nevery_n_frames = 2\npasses = [\"depth\"]");
    let seq = depth.path().join("seq");
    assert_eq!(
        channels(&seq.join("cameras/camera-rgb/frame_00000.exr")),
        ["depth.Z", "valid.V"]
    );
    assert!(!seq.join("images").exists() && !seq.join("colmap").exists());
    let ann = std::fs::read_to_string(seq.join("cameras/camera-rgb/annotations.json")).unwrap();
    assert!(!ann.contains("\"occluded\"") && !ann.contains("\"visible\""));
    verify(&seq);

    let mono = run("cameras = [\"camera-slam-left\"]\nresolution_scale = 0.1\nsamples = 1\nevery_n_frames = 2\npasses = [\"colour\"]");
    let seq = mono.path().join("seq");
    assert_eq!(
        channels(&seq.join("cameras/camera-slam-left/frame_00000.exr")),
        ["gray.Y", "valid.V"]
    );
    let png = seq.join("images/camera-slam-left/frame_00000.png");
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = &buf[..info.buffer_size()];
    assert!(px.chunks(3).all(|p| p[0] == p[1] && p[1] == p[2]));
    assert!(px.iter().any(|&v| v > 0), "a black image");
    verify(&seq);
}

/// `device = "gpu"` on a machine without one fails before the take is staged, naming the
/// setting and what Blender looked for, and leaves nothing: no dataset, no `.partial` (when a
/// GPU is there, the run succeeds instead).
#[test]
fn gpu_device_without_a_gpu_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("run.toml");
    let config = with_render(
        "cameras = [\"camera-rgb\"]\nresolution_scale = 0.0625\nsamples = 1\ndevice = \"gpu\"",
    )
    .replace("duration_s = 0.5", "duration_s = 0.05");
    std::fs::write(&cfg, config).unwrap();
    let out = egogen_run(&cfg);
    let err = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        eprintln!("this machine has a GPU: {err}");
        return;
    }
    assert!(
        err.contains("render.device = \"gpu\"") && err.contains("found no GPU"),
        "{err}"
    );
    assert!(!dir.path().join("seq").exists() && !dir.path().join("seq.partial").exists());
    assert!(
        !err.contains("shard"),
        "failed in a shard, after staging: {err}"
    );
}

/// Command-line values out of range are refused by the option's name before any work: negative
/// numbers reach the option's parser (not clap's "use `-- -1`" advice), a seed a config cannot
/// hold, and `--out` naming an existing file.
#[test]
fn out_of_range_options_and_an_output_that_is_a_file_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("run.toml");
    std::fs::write(&cfg, GOOD).unwrap();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_egogen-run"))
            .arg(&cfg)
            .args(args)
            .output()
            .unwrap()
    };
    for (args, needle) in [
        (&["--seed", "-1"][..], "--seed"),
        (&["--seed", "18446744073709551615"][..], "--seed"),
        (&["--workers", "-1"][..], "--workers"),
        (&["--workers", "0"][..], "supervisor.workers"),
    ] {
        let out = run(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} accepted");
        assert!(
            err.contains(needle) && !err.contains("-- -1"),
            "{args:?}: {err}"
        );
    }
    let file = dir.path().join("taken");
    std::fs::write(&file, "a file").unwrap();
    let out = run(&["--out", file.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("is a file"), "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "a file");
    assert!(!dir.path().join("taken.partial").exists());
    // The tools take negative numbers to their range checks too.
    let out = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["policy", "eval", "--action-spread", "-1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--action-spread") && !err.contains("-- -1"),
        "{err}"
    );
    // A held-out scene evaluates a policy: without one the error says to give it.
    let out = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["policy", "eval", "--scene", "assets/scenes/apartment.glb"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("give --policy FILE") && !err.contains("--k"),
        "{err}"
    );
    // Keeping to the middle of doorways is the guide's: without a lookahead it is refused.
    let out = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["policy", "eval", "--guide-centre-weight", "2"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--guide-centre-weight") && err.contains("lookahead"),
        "{err}"
    );
}
