//! Checkpoints of a training run, so that `egogen train primitive --resume` continues a killed
//! run exactly where it stopped: the network and the optimiser's moments (burn records, full
//! precision), the random generator's position, the phase and step reached, any other state
//! the run needs (JSON: the seed pool of prior fine-tuning, the environments of policy
//! training) and the length of the log.
//!
//! A checkpoint is a folder next to the weights (`<weights>.checkpoint/`). Its `state.json`
//! names the record files it belongs to and is replaced atomically after they are written, so a
//! run killed at any moment leaves the previous checkpoint or the new one, never half of one.
//! The checkpoint before it stays beside it (`state.prev.json` and its files): when a file of
//! the newest is damaged, resuming says so and continues from the one before. `state.json`
//! carries a fingerprint of the plan: a checkpoint is resumed only by the plan that wrote it.

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::optim::Optimizer;
use burn::record::{BinFileRecorder, FullPrecisionSettings, Recorder};
use burn::tensor::backend::AutodiffBackend;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use sha2::Digest;

use super::train_error::TrainError;

/// Where the run stood when the checkpoint was written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct CheckpointState {
    /// SHA-256 of the plan (its debug form: every setting and path).
    pub plan_sha256: String,
    /// Index of the phase to continue (0 primitive, 1 rollout, 2 prior).
    pub phase: usize,
    /// Next step of that phase.
    pub step: usize,
    /// Steps taken over all phases.
    pub global_step: usize,
    pub last_loss: f64,
    /// Training time before the checkpoint (s).
    pub elapsed_s: f64,
    /// The random generator: seed (hex), stream and word position (decimal).
    pub rng_seed_hex: String,
    pub rng_stream: u64,
    pub rng_word_pos: String,
    /// Record files in the checkpoint folder (names).
    pub net_file: String,
    /// None at the start of a phase (its optimiser starts fresh).
    pub optim_file: Option<String>,
    /// The run's other state (JSON), if any.
    #[serde(alias = "pool_file")]
    pub extra_file: Option<String>,
    /// Bytes of the loss log that belong to the run up to here.
    pub log_bytes: u64,
    /// SHA-256 of each record file above, by name: a file that no longer matches is damaged,
    /// and the checkpoint before it is used instead (said on stderr). Checkpoints written
    /// before this field have none and are read unchecked.
    #[serde(default)]
    pub sha256: std::collections::BTreeMap<String, String>,
}

impl CheckpointState {
    /// The record files the checkpoint names (network, optimiser, other state).
    fn record_files(&self) -> Vec<String> {
        std::iter::once(&self.net_file)
            .chain(&self.optim_file)
            .chain(&self.extra_file)
            .cloned()
            .collect()
    }
}

/// The checkpoint folder of a run writing `weights_out`.
pub(crate) fn checkpoint_dir(weights_out: &Path) -> PathBuf {
    let mut name = weights_out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".checkpoint");
    weights_out.with_file_name(name)
}

/// Whether `dir` holds a checkpoint to resume.
pub(crate) fn exists(dir: &Path) -> bool {
    dir.join(STATE).is_file()
}

/// Whether a run may start (`resume` false) or resume (`resume` true) given the checkpoint
/// folder: a leftover checkpoint is never overwritten, and resuming needs one.
pub(crate) fn check_resume(dir: &Path, resume: bool) -> Result<(), TrainError> {
    match (resume, exists(dir)) {
        (false, true) => Err(TrainError::Data(format!(
            "an interrupted run left a checkpoint in {}: pass --resume to continue it, or \
             remove that folder to start over",
            dir.display()
        ))),
        (true, false) => Err(TrainError::Data(format!(
            "--resume: no checkpoint in {} (nothing to resume; run without --resume)",
            dir.display()
        ))),
        _ => Ok(()),
    }
}

/// SHA-256 of a plan's debug form.
pub(crate) fn plan_fingerprint(plan: &impl std::fmt::Debug) -> String {
    hex(&sha2::Sha256::digest(format!("{plan:?}").as_bytes()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> TrainError + '_ {
    move |source| TrainError::Io {
        path: path.into(),
        source,
    }
}

fn recorder_error(path: &Path, e: impl std::fmt::Display) -> TrainError {
    TrainError::Data(format!("checkpoint {}: {e}", path.display()))
}

/// The random generator's position as (seed hex, stream, word position).
pub(crate) fn rng_position(rng: &ChaCha8Rng) -> (String, u64, String) {
    (
        hex(&rng.get_seed()),
        rng.get_stream(),
        rng.get_word_pos().to_string(),
    )
}

/// What a checkpoint holds besides its state.
pub(crate) struct Restored<M, O, X> {
    pub state: CheckpointState,
    pub net: M,
    pub optim: Option<O>,
    pub rng: ChaCha8Rng,
    pub extra: Option<X>,
}

/// Writes a checkpoint of `net`, `optim` and `extra` with `state` (whose file names it fills
/// in) into `dir`, then removes the files of the previous one.
pub(crate) fn save<B, M, O, X>(
    dir: &Path,
    mut state: CheckpointState,
    net: &M,
    optim: Option<&O>,
    extra: Option<&X>,
) -> Result<(), TrainError>
where
    B: AutodiffBackend,
    M: Module<B> + burn::module::AutodiffModule<B>,
    O: Optimizer<M, B>,
    X: Serialize,
{
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let recorder = BinFileRecorder::<FullPrecisionSettings>::new();
    let tag = state.global_step;
    let net_path = dir.join(format!("net-{tag}"));
    Recorder::<B>::record(&recorder, net.clone().into_record(), net_path.clone())
        .map_err(|e| recorder_error(&net_path, e))?;
    state.net_file = format!("net-{tag}.bin");
    state.optim_file = match optim {
        Some(o) => {
            let path = dir.join(format!("optim-{tag}"));
            Recorder::<B>::record(&recorder, o.to_record(), path.clone())
                .map_err(|e| recorder_error(&path, e))?;
            Some(format!("optim-{tag}.bin"))
        }
        None => None,
    };
    state.extra_file = match extra {
        Some(p) => {
            let name = format!("extra-{tag}.json");
            let path = dir.join(&name);
            let bytes = serde_json::to_vec(p).map_err(|e| recorder_error(&path, e))?;
            crate::atomic_file::write_atomically(&path, &bytes).map_err(io(&path))?;
            Some(name)
        }
        None => None,
    };
    for name in state.record_files() {
        let path = dir.join(&name);
        let bytes = std::fs::read(&path).map_err(io(&path))?;
        let sum = hex(&sha2::Sha256::digest(&bytes));
        state.sha256.insert(name, sum);
    }
    let state_path = dir.join(STATE);
    let prev_path = dir.join(PREVIOUS_STATE);
    // The current checkpoint becomes the previous one, then the new one is current.
    let previous: Option<CheckpointState> = match std::fs::read(&state_path) {
        Ok(bytes) => {
            crate::atomic_file::write_atomically(&prev_path, &bytes).map_err(io(&prev_path))?;
            serde_json::from_slice(&bytes).ok()
        }
        Err(_) => None,
    };
    let json = serde_json::to_vec_pretty(&state).map_err(|e| recorder_error(&state_path, e))?;
    crate::atomic_file::write_atomically(&state_path, &json).map_err(io(&state_path))?;
    // Files of older checkpoints are no longer referenced.
    let mut keep = vec![STATE.to_string(), PREVIOUS_STATE.to_string()];
    for s in [Some(&state), previous.as_ref()].into_iter().flatten() {
        keep.extend(s.record_files());
    }
    for entry in std::fs::read_dir(dir).map_err(io(dir))?.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !keep.contains(&name) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
    Ok(())
}

/// The newest checkpoint's state file, and the one before it.
const STATE: &str = "state.json";
const PREVIOUS_STATE: &str = "state.prev.json";

/// Reads the checkpoint in `dir` into `net` (the freshly built network of the same plan) and an
/// optimiser from `fresh_optim` (used when the checkpoint has optimiser state). When a file of
/// the newest checkpoint cannot be read, warns on stderr and reads the one before it.
pub(crate) fn load<B, M, O, X>(
    dir: &Path,
    plan_sha256: &str,
    net: M,
    fresh_optim: impl Fn() -> O,
    device: &B::Device,
) -> Result<Restored<M, O, X>, TrainError>
where
    B: AutodiffBackend,
    M: Module<B> + burn::module::AutodiffModule<B>,
    O: Optimizer<M, B>,
    X: serde::de::DeserializeOwned,
{
    match load_state::<B, M, O, X>(dir, STATE, plan_sha256, net.clone(), fresh_optim(), device) {
        Err(e @ TrainError::Data(_)) | Err(e @ TrainError::Io { .. })
            if dir.join(PREVIOUS_STATE).is_file() && !is_foreign(&e) =>
        {
            eprintln!("warning: {e}; resuming from the checkpoint before it");
            load_state::<B, M, O, X>(dir, PREVIOUS_STATE, plan_sha256, net, fresh_optim(), device)
        }
        other => other,
    }
}

/// Whether an error says the checkpoint belongs to another plan (no fallback then).
fn is_foreign(e: &TrainError) -> bool {
    matches!(e, TrainError::Data(m) if m.contains("written by another config"))
}

fn load_state<B, M, O, X>(
    dir: &Path,
    state_file: &str,
    plan_sha256: &str,
    net: M,
    optim: O,
    device: &B::Device,
) -> Result<Restored<M, O, X>, TrainError>
where
    B: AutodiffBackend,
    M: Module<B> + burn::module::AutodiffModule<B>,
    O: Optimizer<M, B>,
    X: serde::de::DeserializeOwned,
{
    let state_path = dir.join(state_file);
    let text = std::fs::read(&state_path).map_err(io(&state_path))?;
    let state: CheckpointState =
        serde_json::from_slice(&text).map_err(|e| recorder_error(&state_path, e))?;
    if state.plan_sha256 != plan_sha256 {
        return Err(TrainError::Data(format!(
            "checkpoint {}: written by another config (plan fingerprint {} here, {} there); \
             resume with the config that started the run, or remove the folder to start over",
            dir.display(),
            plan_sha256,
            state.plan_sha256
        )));
    }
    for name in state.record_files() {
        let Some(want) = state.sha256.get(&name) else {
            continue;
        };
        let path = dir.join(&name);
        let bytes = std::fs::read(&path).map_err(io(&path))?;
        let got = hex(&sha2::Sha256::digest(&bytes));
        if &got != want {
            return Err(TrainError::Data(format!(
                "checkpoint file {} is damaged (SHA-256 {got}, the checkpoint recorded {want})",
                path.display()
            )));
        }
    }
    let recorder = BinFileRecorder::<FullPrecisionSettings>::new();
    let net_path = dir.join(&state.net_file);
    let record = Recorder::<B>::load(&recorder, net_path.clone(), device)
        .map_err(|e| recorder_error(&net_path, e))?;
    let net = net.load_record(record);
    let optim = match &state.optim_file {
        Some(f) => {
            let path = dir.join(f);
            let record = Recorder::<B>::load(&recorder, path.clone(), device)
                .map_err(|e| recorder_error(&path, e))?;
            Some(optim.load_record(record))
        }
        None => None,
    };
    let extra = match &state.extra_file {
        Some(f) => {
            let path = dir.join(f);
            let bytes = std::fs::read(&path).map_err(io(&path))?;
            Some(serde_json::from_slice(&bytes).map_err(|e| recorder_error(&path, e))?)
        }
        None => None,
    };
    let bad_rng = || recorder_error(&state_path, "bad random generator state");
    let seed_bytes: Vec<u8> = (0..state.rng_seed_hex.len())
        .step_by(2)
        .map(|i| {
            state
                .rng_seed_hex
                .get(i..i + 2)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
        })
        .collect::<Option<_>>()
        .ok_or_else(bad_rng)?;
    let seed: [u8; 32] = seed_bytes.try_into().map_err(|_| bad_rng())?;
    let mut rng = <ChaCha8Rng as rand_core::SeedableRng>::from_seed(seed);
    rng.set_stream(state.rng_stream);
    rng.set_word_pos(state.rng_word_pos.parse().map_err(|_| bad_rng())?);
    Ok(Restored {
        state,
        net,
        optim,
        rng,
        extra,
    })
}
