//! Weights files: safetensors holding the network's tensors, with the architecture in the
//! header metadata (`egogen.arch`, JSON) so that loading needs nothing else.

use std::io::Read;
use std::path::{Path, PathBuf};

use burn::prelude::*;
use burn::store::{ApplyError, ModuleSnapshot, SafetensorsStore};

use super::net::{ArchConfig, InputStats, PrimitiveVae};

/// Metadata key holding the [`ArchConfig`].
const ARCH_KEY: &str = "egogen.arch";

/// Why a weights file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum WeightsError {
    #[error("weights file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "weights file {path}: not a safetensors file ({message}); the file is damaged or \
         truncated (an interrupted copy or download?): copy it again, or retrain"
    )]
    Format { path: PathBuf, message: String },
    #[error("weights file {path}: no `{key}` metadata; was it written by `egogen train`?")]
    NoArchitecture { path: PathBuf, key: &'static str },
    #[error("weights file {path}: tensor `{tensor}` {message}")]
    Tensor {
        path: PathBuf,
        tensor: String,
        message: String,
    },
    #[error("weights file {path}: {message}")]
    Store { path: PathBuf, message: String },
}

/// Reads the architecture from a weights file's header.
pub fn read_arch(path: &Path) -> Result<ArchConfig, WeightsError> {
    read_metadata(path, ARCH_KEY)
}

/// A safetensors file's header: its length in bytes and its JSON.
fn read_header(path: &Path) -> Result<(u64, serde_json::Value), WeightsError> {
    let format = |message: String| WeightsError::Format {
        path: path.into(),
        message,
    };
    let mut file = std::fs::File::open(path).map_err(|source| WeightsError::Io {
        path: path.into(),
        source,
    })?;
    let mut len = [0u8; 8];
    file.read_exact(&mut len)
        .map_err(|e| format(format!("header length: {e}")))?;
    let len = u64::from_le_bytes(len);
    if len > 100_000_000 {
        return Err(format(format!("header of {len} bytes")));
    }
    let mut header = vec![0u8; len as usize];
    file.read_exact(&mut header)
        .map_err(|e| format(format!("header: {e}")))?;
    let header =
        serde_json::from_slice(&header).map_err(|e| format(format!("header JSON: {e}")))?;
    Ok((len, header))
}

/// Checks that a safetensors file holds all the tensor data its header lists (a file cut short
/// after its header would otherwise be reported by the reader as "incomplete metadata").
fn check_complete(path: &Path) -> Result<(), WeightsError> {
    let (len, header) = read_header(path)?;
    let listed = header
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(k, _)| *k != "__metadata__")
        .filter_map(|(_, t)| t.get("data_offsets")?.get(1)?.as_u64())
        .max()
        .unwrap_or(0);
    let size = std::fs::metadata(path)
        .map_err(|source| WeightsError::Io {
            path: path.into(),
            source,
        })?
        .len();
    let held = size.saturating_sub(8 + len);
    if held < listed {
        return Err(WeightsError::Format {
            path: path.into(),
            message: format!(
                "its tensors' data is cut short: the header lists {listed} bytes, the file holds {held}"
            ),
        });
    }
    Ok(())
}

/// Reads the JSON value under metadata `key` of a safetensors file's header.
pub(crate) fn read_metadata<A: serde::de::DeserializeOwned>(
    path: &Path,
    key: &'static str,
) -> Result<A, WeightsError> {
    let format = |message: String| WeightsError::Format {
        path: path.into(),
        message,
    };
    let (_, header) = read_header(path)?;
    let arch = header
        .get("__metadata__")
        .and_then(|m| m.get(key))
        .and_then(|a| a.as_str())
        .ok_or_else(|| WeightsError::NoArchitecture {
            path: path.into(),
            key,
        })?;
    serde_json::from_str(arch).map_err(|e| format(format!("`{key}` metadata: {e}")))
}

/// Loads a network from a weights file written by [`save`].
pub(crate) fn load<B: Backend>(
    path: &Path,
    device: &B::Device,
) -> Result<(ArchConfig, PrimitiveVae<B>), WeightsError> {
    let arch = read_arch(path)?;
    let mut net = arch.init::<B>(&InputStats::default(), device);
    load_into(path, &mut net, &format!("{arch:?}"))?;
    Ok((arch, net))
}

/// Loads every tensor of `net` (built for the architecture `described`) from a safetensors
/// file, refusing missing, extra and misshapen tensors.
pub(crate) fn load_into<B: Backend, M: burn::module::Module<B>>(
    path: &Path,
    net: &mut M,
    described: &str,
) -> Result<(), WeightsError> {
    check_complete(path)?;
    let mut store = SafetensorsStore::from_file(path)
        .validate(false)
        .allow_partial(true);
    let result = net.load_from(&mut store).map_err(|e| WeightsError::Store {
        path: path.into(),
        message: e.to_string(),
    })?;
    let tensor = |tensor: &str, message: String| WeightsError::Tensor {
        path: path.into(),
        tensor: tensor.into(),
        message,
    };
    if let Some(e) = result.errors.first() {
        return Err(match e {
            ApplyError::ShapeMismatch {
                path: t,
                expected,
                found,
            } => tensor(
                t,
                format!(
                    "has shape {:?}, expected {:?} for {described}",
                    found.as_slice(),
                    expected.as_slice()
                ),
            ),
            ApplyError::DTypeMismatch {
                path: t,
                expected,
                found,
            } => tensor(t, format!("has type {found:?}, expected {expected:?}")),
            ApplyError::AdapterError { path: t, message }
            | ApplyError::LoadError { path: t, message } => tensor(t, message.clone()),
        });
    }
    if let Some((t, _)) = result.missing.first() {
        return Err(tensor(t, "is missing".into()));
    }
    if let Some(t) = result.unused.first() {
        return Err(tensor(t, "is not part of the network".into()));
    }
    Ok(())
}

/// Writes the network atomically (temporary file, then rename).
pub fn save<B: Backend>(
    net: &PrimitiveVae<B>,
    arch: &ArchConfig,
    path: &Path,
) -> Result<(), WeightsError> {
    save_module(net, ARCH_KEY, arch, path)
}

/// Writes a module atomically with `metadata` (JSON) under `key` in the header.
pub(crate) fn save_module<B: Backend, M: burn::module::Module<B>>(
    net: &M,
    key: &str,
    metadata: &impl serde::Serialize,
    path: &Path,
) -> Result<(), WeightsError> {
    let tmp = path.with_extension("safetensors.partial");
    let json = serde_json::to_string(metadata).map_err(|e| WeightsError::Store {
        path: path.into(),
        message: e.to_string(),
    })?;
    let mut store = SafetensorsStore::from_file(&tmp)
        .overwrite(true)
        .metadata(key, json);
    net.save_into(&mut store).map_err(|e| WeightsError::Store {
        path: tmp.clone(),
        message: e.to_string(),
    })?;
    canonical_header(&tmp)?;
    std::fs::rename(&tmp, path).map_err(|source| WeightsError::Io {
        path: path.into(),
        source,
    })
}

/// Rewrites a safetensors file's header with its keys sorted (the store writes them in hash
/// order), padded with spaces to 8 bytes as the format recommends: the same weights give the
/// same bytes, run after run. The tensors' bytes and offsets are unchanged.
fn canonical_header(path: &Path) -> Result<(), WeightsError> {
    let io = |source| WeightsError::Io {
        path: path.into(),
        source,
    };
    let bad = |message: String| WeightsError::Store {
        path: path.into(),
        message,
    };
    let bytes = std::fs::read(path).map_err(io)?;
    let n = bytes
        .get(..8)
        .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")) as usize)
        .filter(|&n| n <= bytes.len() - 8)
        .ok_or_else(|| bad("the written file has no header".into()))?;
    // serde_json's maps are sorted: parsing and writing again orders every key.
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n])
        .map_err(|e| bad(format!("the written header does not parse: {e}")))?;
    let mut sorted = serde_json::to_vec(&header).map_err(|e| bad(e.to_string()))?;
    sorted.resize(sorted.len().div_ceil(8) * 8, b' ');
    let mut out = Vec::with_capacity(8 + sorted.len() + bytes.len() - 8 - n);
    out.extend_from_slice(&(sorted.len() as u64).to_le_bytes());
    out.extend_from_slice(&sorted);
    out.extend_from_slice(&bytes[8 + n..]);
    std::fs::write(path, out).map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_cut_short_after_their_header_say_so() {
        let shipped = crate::paths::crate_root().join("assets/motion/primitive_cvae.safetensors");
        let bytes = std::fs::read(&shipped).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let cut = dir.path().join("cut.safetensors");
        std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).unwrap();
        let Err(err) = load::<burn::backend::Flex>(&cut, &Default::default()) else {
            panic!("a cut file loaded");
        };
        let err = err.to_string();
        assert!(
            err.contains("cut.safetensors: not a safetensors file (its tensors' data is cut short: the header lists")
                && err.contains("truncated"),
            "{err}"
        );
    }
}
