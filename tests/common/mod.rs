//! Test helpers: the deterministic random SMPL-X-shaped model (same formula as
//! `tools/random_smplx_model.py`), golden-file reading, npz writing.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use npyz::npz::{NpzArchive, NpzWriter};
use npyz::WriterBuilder;

pub const RANDOM_V: usize = 10475;
pub const RANDOM_F: usize = 20908;
pub const PARENTS: [i64; 55] = [
    -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 15, 15, 15, 20, 25,
    26, 20, 28, 29, 20, 31, 32, 20, 34, 35, 20, 37, 38, 21, 40, 41, 21, 43, 44, 21, 46, 47, 21, 49,
    50, 21, 52, 53,
];

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file below `dir` whose name ends in `.ext`, sorted.
pub fn files_with_extension(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            found.extend(files_with_extension(&path, ext));
        } else if path.extension().is_some_and(|e| e == ext) {
            found.push(path);
        }
    }
    found.sort();
    found
}

pub fn default_model_path() -> PathBuf {
    repo_root().join("assets/body/SMPLX_NEUTRAL.npz")
}

fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// U(stream, i) in [0, 1), exactly as the Python side computes it.
pub fn uniform(stream: u64, i: u64) -> f64 {
    (splitmix64((stream << 40) + i) >> 11) as f64 * 2f64.powi(-53)
}

/// One named array to write.
pub enum Arr {
    F64(Vec<u64>, Vec<f64>),
    I64(Vec<u64>, Vec<i64>),
    U32(Vec<u64>, Vec<u32>),
}

/// Writes arrays to an uncompressed `.npz`.
pub fn write_npz(path: &Path, arrays: &[(&str, Arr)]) {
    let mut npz = NpzWriter::create(path).unwrap();
    let opts = || {
        npyz::zip::write::FileOptions::default()
            .compression_method(npyz::zip::CompressionMethod::Stored)
    };
    for (name, arr) in arrays {
        match arr {
            Arr::F64(shape, data) => {
                let mut w = npz
                    .array::<f64>(name, opts())
                    .unwrap()
                    .default_dtype()
                    .shape(shape)
                    .begin_nd()
                    .unwrap();
                w.extend(data.iter().copied()).unwrap();
                w.finish().unwrap();
            }
            Arr::I64(shape, data) => {
                let mut w = npz
                    .array::<i64>(name, opts())
                    .unwrap()
                    .default_dtype()
                    .shape(shape)
                    .begin_nd()
                    .unwrap();
                w.extend(data.iter().copied()).unwrap();
                w.finish().unwrap();
            }
            Arr::U32(shape, data) => {
                let mut w = npz
                    .array::<u32>(name, opts())
                    .unwrap()
                    .default_dtype()
                    .shape(shape)
                    .begin_nd()
                    .unwrap();
                w.extend(data.iter().copied()).unwrap();
                w.finish().unwrap();
            }
        }
    }
    npz.zip_writer().finish().unwrap();
}

/// All arrays of the random official-shaped model, by the shared formula.
pub fn random_model_arrays() -> Vec<(&'static str, Arr)> {
    let v = RANDOM_V;
    let v_template: Vec<f64> = (0..v as u64 * 3).map(|i| uniform(1, i) - 0.5).collect();
    let shapedirs: Vec<f64> = (0..(v * 3 * 400) as u64)
        .map(|i| 0.02 * (uniform(2, i) - 0.5))
        .collect();
    let posedirs: Vec<f64> = (0..(v * 3 * 486) as u64)
        .map(|i| 0.01 * (uniform(3, i) - 0.5))
        .collect();
    let mut j_reg = vec![0.0; 55 * v];
    for j in 0..55u64 {
        for m in 0..8u64 {
            let vi = (uniform(4, 8 * j + m) * v as f64).floor() as usize;
            j_reg[j as usize * v + vi] += 0.125;
        }
    }
    let mut weights = vec![0.0; v * 55];
    for vi in 0..v {
        let idx = |m: usize| (4 * vi + m) as u64;
        let joints: Vec<usize> = (0..4)
            .map(|m| (uniform(5, idx(m)) * 55.0).floor() as usize)
            .collect();
        let raw: Vec<f64> = (0..4).map(|m| 0.1 + uniform(6, idx(m))).collect();
        let total = ((raw[0] + raw[1]) + raw[2]) + raw[3];
        for m in 0..4 {
            weights[vi * 55 + joints[m]] += raw[m] / total;
        }
    }
    let f: Vec<u32> = (0..RANDOM_F)
        .flat_map(|i| [(i % v) as u32, ((i + 1) % v) as u32, ((i + 2) % v) as u32])
        .collect();
    let kintree: Vec<i64> = PARENTS.iter().copied().chain(0..55).collect();
    let u = |x: usize| x as u64;
    vec![
        ("v_template", Arr::F64(vec![u(v), 3], v_template)),
        ("f", Arr::U32(vec![u(RANDOM_F), 3], f)),
        ("shapedirs", Arr::F64(vec![u(v), 3, 400], shapedirs)),
        ("posedirs", Arr::F64(vec![u(v), 3, 486], posedirs)),
        ("J_regressor", Arr::F64(vec![55, u(v)], j_reg)),
        ("weights", Arr::F64(vec![u(v), 55], weights)),
        ("kintree_table", Arr::I64(vec![2, 55], kintree)),
    ]
}

/// Golden bodies and smplx's outputs, from `tools/make_skinning_golden.py`.
pub struct Golden {
    pub poses: Vec<f64>,
    pub betas: Vec<f64>,
    pub n_betas: usize,
    pub expression: Vec<f64>,
    pub n_expr: usize,
    pub transl: Vec<f64>,
    pub joints: Vec<f64>,
    pub subset: Vec<i64>,
    pub vertices_subset: Vec<f64>,
    pub vertices_full: Vec<f32>,
    pub n_full: usize,
    pub n_bodies: usize,
}

pub fn read_golden(path: &Path) -> Golden {
    let mut npz =
        NpzArchive::open(path).unwrap_or_else(|e| panic!("golden {}: {e}", path.display()));
    fn get<T: npyz::Deserialize>(
        npz: &mut NpzArchive<std::io::BufReader<std::fs::File>>,
        k: &str,
    ) -> (Vec<u64>, Vec<T>) {
        let f = npz
            .by_name(k)
            .unwrap()
            .unwrap_or_else(|| panic!("golden lacks {k}"));
        let shape = f.shape().to_vec();
        (shape, f.into_vec::<T>().unwrap())
    }
    let (ps, poses) = get::<f64>(&mut npz, "poses");
    let (bs, betas) = get::<f64>(&mut npz, "betas");
    let (es, expression) = get::<f64>(&mut npz, "expression");
    let transl = get::<f64>(&mut npz, "transl").1;
    let joints = get::<f64>(&mut npz, "joints").1;
    let subset = get::<i64>(&mut npz, "subset").1;
    let vertices_subset = get::<f64>(&mut npz, "vertices_subset").1;
    let (fs, vertices_full) = get::<f32>(&mut npz, "vertices_full");
    Golden {
        poses,
        betas,
        n_betas: bs[1] as usize,
        expression,
        n_expr: es[1] as usize,
        transl,
        joints,
        subset,
        vertices_subset,
        vertices_full,
        n_full: fs[0] as usize,
        n_bodies: ps[0] as usize,
    }
}

/// A tiny valid SMPL-X-layout model (20 vertices, 10 + 10 dirs, zero correctives).
pub fn tiny_model_arrays() -> Vec<(&'static str, Arr)> {
    let v = 20usize;
    let u = |x: usize| x as u64;
    let v_template: Vec<f64> = (0..v as u64 * 3).map(|i| uniform(11, i) - 0.5).collect();
    let shapedirs: Vec<f64> = (0..(v * 3 * 20) as u64)
        .map(|i| 0.01 * (uniform(12, i) - 0.5))
        .collect();
    let mut j_reg = vec![0.0; 55 * v];
    let mut weights = vec![0.0; v * 55];
    for j in 0..55 {
        j_reg[j * v + j % v] = 1.0;
    }
    for vi in 0..v {
        weights[vi * 55 + vi] = 1.0;
    }
    let f: Vec<u32> = (0..v)
        .flat_map(|i| [i as u32, ((i + 1) % v) as u32, ((i + 2) % v) as u32])
        .collect();
    let kintree: Vec<i64> = PARENTS.iter().copied().chain(0..55).collect();
    vec![
        ("v_template", Arr::F64(vec![u(v), 3], v_template)),
        ("f", Arr::U32(vec![u(v), 3], f)),
        ("shapedirs", Arr::F64(vec![u(v), 3, 20], shapedirs)),
        (
            "posedirs",
            Arr::F64(vec![u(v), 3, 486], vec![0.0; v * 3 * 486]),
        ),
        ("J_regressor", Arr::F64(vec![55, u(v)], j_reg)),
        ("weights", Arr::F64(vec![u(v), 55], weights)),
        ("kintree_table", Arr::I64(vec![2, 55], kintree)),
    ]
}

/// A temporary folder holding `run.toml` with `config`; returns both.
pub fn run_dir(config: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.toml");
    std::fs::write(&path, config).unwrap();
    (dir, path)
}

/// Runs `cmd`, failing the test with its stderr unless it succeeds; its output.
pub fn succeeds(cmd: &mut std::process::Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `egogen-run CONFIG`, failing the test with its stderr unless it succeeds.
pub fn egogen_run_ok(config: &Path) {
    succeeds(std::process::Command::new(env!("CARGO_BIN_EXE_egogen-run")).arg(config));
}

/// A finished dataset's manifest.
pub fn read_manifest(dataset: &Path) -> egogen::supervisor::Manifest {
    serde_json::from_str(&std::fs::read_to_string(dataset.join("manifest.json")).unwrap()).unwrap()
}

/// The lines of a JSON-lines log without their wall-clock fields.
pub fn log_without_times(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            for key in [
                "elapsed_s",
                "seconds",
                "wall_s",
                "env_s",
                "forward_s",
                "update_s",
            ] {
                v.as_object_mut().unwrap().remove(key);
            }
            v
        })
        .collect()
}

/// The tensors of a safetensors file by name, as raw bytes (the header's key order is not
/// fixed, the tensors are).
pub fn safetensors_tensors(path: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let bytes = std::fs::read(path).unwrap();
    let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n]).unwrap();
    let data = &bytes[8 + n..];
    header
        .as_object()
        .unwrap()
        .iter()
        .filter(|(k, _)| *k != "__metadata__")
        .map(|(k, v)| {
            let o = &v["data_offsets"];
            let (a, b) = (
                o[0].as_u64().unwrap() as usize,
                o[1].as_u64().unwrap() as usize,
            );
            (k.clone(), data[a..b].to_vec())
        })
        .collect()
}

/// A tiny campaign in `dir` (`campaign.toml` → `dir/out`): 3 takes over the shipped apartment
/// and one generated floor plan, 1 or 2 people, the SLAM-left camera at 1/10 size, colour,
/// depth and segmentation; its shards on the local pool, or with `slurm` on Slurm.
pub fn tiny_campaign(dir: &Path, slurm: bool) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    tiny_campaign_run(dir, slurm);
    let campaign = dir.join("campaign.toml");
    std::fs::write(
        &campaign,
        format!(
            r#"
[campaign]
run = "run.toml"
out = "out"
takes = 3
scenes = ["{}"]
floor_plans = [5]
crowd_count = [1, 2]
min_free_disk_gb = 0.0
"#,
            root.join("assets/scenes/apartment.glb").display()
        ),
    )
    .unwrap();
    campaign
}

/// The run config of [`tiny_campaign`]'s takes, `dir/run.toml`: two wanderers for 1 s, one
/// camera at 1/10 size, every 10th frame, 2 samples, on the local pool or on Slurm.
pub fn tiny_campaign_run(dir: &Path, slurm: bool) -> PathBuf {
    let supervisor = if slurm {
        "backend = \"slurm\"\n[supervisor.slurm]\ncpus_per_task = 1\nmem_gb = 1.0\npoll_interval_s = 0.5\n"
    } else {
        ""
    };
    std::fs::write(
        dir.join("run.toml"),
        r#"
[body]
[motion]
source = "agents"
duration_s = 1.0
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
every_n_frames = 10
samples = 2
frames_per_shard = 2
passes = ["colour", "depth", "segmentation"]
[supervisor]
workers = 2
retries = 40
"#
        .to_string()
            + supervisor,
    )
    .unwrap();
    dir.join("run.toml")
}

/// Every file of a campaign's finished takes with its bytes' SHA-256, and the index's.
pub fn campaign_digest(out: &Path) -> Vec<(String, String)> {
    let mut files = vec![(
        "index.parquet".to_string(),
        egogen::manifest::sha256_file(&out.join("index.parquet")).unwrap(),
    )];
    let mut takes: Vec<PathBuf> = std::fs::read_dir(out.join("takes"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    takes.sort();
    for take in takes {
        let name = take.file_name().unwrap().to_string_lossy().into_owned();
        files.push((
            format!("{name}/manifest.json"),
            egogen::manifest::sha256_file(&take.join("manifest.json")).unwrap(),
        ));
    }
    files
}

/// A Python with `packages` from PyPI: a virtual environment `name` of the egogen cache,
/// made on first use at `<venv>.partial` and renamed when complete; an error when PyPI cannot
/// be reached.
pub fn cached_python(name: &str, packages: &[&str]) -> Result<PathBuf, String> {
    let venv = egogen::render::blender_runtime::cache_dir().join(name);
    let python = venv.join("bin/python");
    if python.is_file() {
        return Ok(python);
    }
    let ok = |c: &mut std::process::Command| c.status().map(|s| s.success()).unwrap_or(false);
    let partial = PathBuf::from(format!("{}.partial", venv.display()));
    let _ = std::fs::remove_dir_all(&partial);
    std::fs::create_dir_all(partial.parent().unwrap()).map_err(|e| e.to_string())?;
    if !ok(std::process::Command::new("python3")
        .args(["-m", "venv"])
        .arg(&partial))
    {
        return Err("python3 -m venv failed".into());
    }
    if !ok(std::process::Command::new(partial.join("bin/python"))
        .args(["-m", "pip", "install", "-q", "--disable-pip-version-check"])
        .args(packages))
    {
        return Err(format!("pip install {} failed", packages.join(" ")));
    }
    std::fs::rename(&partial, &venv).map_err(|e| e.to_string())?;
    Ok(python)
}

/// A Python with what the reader package (`python/`) and its tests need (numpy, OpenEXR,
/// pyarrow, pytest): [`cached_python`] (the reader itself goes in with [`install_reader`]).
pub fn reader_python() -> Result<PathBuf, String> {
    cached_python(
        "python-reader-2",
        &[
            "numpy",
            "OpenEXR==3.5.3",
            "pyarrow",
            "pytest",
            "setuptools",
            "wheel",
        ],
    )
}

/// Installs the reader package as the checkout has it now into `python`'s environment (built
/// in a temporary folder: nothing is left in the checkout); panics when pip cannot.
pub fn install_reader(python: &Path) {
    let build = tempfile::tempdir().unwrap();
    let src = build.path().join("python");
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("python"), &src).unwrap();
    let out = std::process::Command::new(python)
        .args([
            "-m",
            "pip",
            "install",
            "-q",
            "--disable-pip-version-check",
            "--no-deps",
            "--no-build-isolation",
            "--force-reinstall",
        ])
        .arg(&src)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "pip install python/ failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A copy of the folder `from` (a take, say) at `to`, every file.
pub fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

fn copy_dir(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let e = e?;
        let name = e.file_name();
        if name == "__pycache__" || name == "build" || name.to_string_lossy().ends_with(".egg-info")
        {
            continue;
        }
        if e.file_type()?.is_dir() {
            copy_dir(&e.path(), &to.join(&name))?;
        } else {
            std::fs::copy(e.path(), to.join(&name))?;
        }
    }
    Ok(())
}

/// Pids of processes whose command line contains every needle.
pub fn pids_with(needles: &[&str]) -> Vec<i32> {
    let mut out = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<i32>() else {
            continue;
        };
        let Ok(cmd) = std::fs::read(e.path().join("cmdline")) else {
            continue;
        };
        let cmd = String::from_utf8_lossy(&cmd).replace('\0', " ");
        if needles.iter().all(|n| cmd.contains(n)) {
            out.push(pid);
        }
    }
    out
}

/// Width and height of a PNG file.
pub fn png_size(path: &std::path::Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    (info.width, info.height)
}

/// An 8 × 8 m floor and a 2.5 m wall (x 2.0–2.2, y −4…1) as an OBJ written y up in
/// centimetres, as a modelling tool writes one: the z-up point (x, y, z) m is the file's
/// (100 x, 100 z, −100 y).
pub fn room_y_up_cm_obj() -> String {
    let p = |x: f64, y: f64, z: f64| format!("v {} {} {}\n", 100.0 * x, 100.0 * z, -100.0 * y);
    let mut obj = String::from("o floor\n");
    for (x, y) in [(-4.0, -4.0), (4.0, -4.0), (4.0, 4.0), (-4.0, 4.0)] {
        obj += &p(x, y, 0.0);
    }
    obj += "f 1 2 3 4\no wall\n";
    for z in [0.0, 2.5] {
        for (x, y) in [(2.0, -4.0), (2.2, -4.0), (2.2, 1.0), (2.0, 1.0)] {
            obj += &p(x, y, z);
        }
    }
    obj += "f 5 8 7 6\nf 9 10 11 12\nf 5 6 10 9\nf 6 7 11 10\nf 7 8 12 11\nf 8 5 9 12\n";
    obj
}
