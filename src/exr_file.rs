//! Reading every channel of an EXR file (`exr` crate) into named `f32` planes, grouped into
//! passes by name: Blender writes `ViewLayer.Depth.Z` as one channel of a single part (4.5) or
//! channel `Z` of a part named `ViewLayer.Depth` (5.0); both become pass `ViewLayer.Depth`,
//! component `Z`. A frame file's contents can also be made in memory from its planes
//! (`ExrContents::from_channels`), as reading the file it encodes to would give them.

use std::path::{Path, PathBuf};

/// One channel, flattened row-major.
#[derive(Debug, Clone)]
pub struct ExrChannel {
    /// Full name: `part.channel` where the part has a name.
    pub name: String,
    /// `f16`, `f32` or `u32` as stored.
    pub sample_type: &'static str,
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
    /// Compression of the part this channel came from.
    pub compression: String,
}

/// A pass: channels sharing a prefix (`ViewLayer.Normal` → X, Y, Z).
#[derive(Debug, Clone)]
pub struct ExrPass {
    pub name: String,
    /// (component name, index into `ExrContents::channels`), in file order.
    pub components: Vec<(String, usize)>,
}

/// Everything in a file.
#[derive(Debug, Clone)]
pub struct ExrContents {
    pub path: PathBuf,
    pub parts: usize,
    pub channels: Vec<ExrChannel>,
    pub passes: Vec<ExrPass>,
    /// The headers' text attributes by name (e.g. Blender's `cycles.ViewLayer.render_time`).
    pub attributes: std::collections::BTreeMap<String, String>,
}

/// Statistics of one channel over its finite values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelStats {
    pub min: f32,
    pub max: f32,
    pub mean: f64,
    pub nan: usize,
    pub inf: usize,
}

/// A file that could not be inspected.
#[derive(Debug, thiserror::Error)]
pub enum InspectError {
    #[error("EXR {path}: cannot read ({message})")]
    Read { path: PathBuf, message: String },
    #[error("EXR {path}: no channels")]
    Empty { path: PathBuf },
}

impl ExrChannel {
    /// Min, max, mean over finite values, and counts of NaN and infinite values.
    pub fn stats(&self) -> ChannelStats {
        let (mut min, mut max, mut sum, mut n, mut nan, mut inf) =
            (f32::INFINITY, f32::NEG_INFINITY, 0.0f64, 0usize, 0, 0);
        for &v in &self.values {
            if v.is_nan() {
                nan += 1;
            } else if v.is_infinite() {
                inf += 1;
            } else {
                min = min.min(v);
                max = max.max(v);
                sum += v as f64;
                n += 1;
            }
        }
        let mean = if n > 0 { sum / n as f64 } else { f64::NAN };
        ChannelStats {
            min,
            max,
            mean,
            nan,
            inf,
        }
    }
}

impl ExrContents {
    /// Reads all parts and channels of a file.
    pub fn read(path: &Path) -> Result<Self, InspectError> {
        let reader = std::fs::File::open(path).map_err(|e| InspectError::Read {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        Self::read_from(path, std::io::BufReader::new(reader))
    }

    /// Reads all parts and channels of a file's bytes held in memory (`path` names them in
    /// messages and in [`ExrContents::path`]).
    pub(crate) fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self, InspectError> {
        Self::read_from(path, std::io::Cursor::new(bytes))
    }

    fn read_from(
        path: &Path,
        reader: impl std::io::Read + std::io::Seek,
    ) -> Result<Self, InspectError> {
        use exr::prelude::*;
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .from_buffered(reader)
            .map_err(|e| InspectError::Read {
                path: path.to_owned(),
                message: e.to_string(),
            })?;
        let mut channels = Vec::new();
        let mut attributes = std::collections::BTreeMap::new();
        let text = |(name, value): (&Text, &AttributeValue)| match value {
            AttributeValue::Text(t) => Some((name.to_string(), t.to_string())),
            _ => None,
        };
        attributes.extend(image.attributes.other.iter().filter_map(text));
        for layer in &image.layer_data {
            attributes.extend(layer.attributes.other.iter().filter_map(text));
            let (width, height) = (layer.size.width(), layer.size.height());
            let prefix = layer.attributes.layer_name.as_ref().map(|n| n.to_string());
            let compression = format!("{:?}", layer.encoding.compression);
            for ch in &layer.channel_data.list {
                let name = match &prefix {
                    Some(p) => format!("{p}.{}", ch.name),
                    None => ch.name.to_string(),
                };
                let sample_type = match ch.sample_data {
                    FlatSamples::F16(_) => "f16",
                    FlatSamples::F32(_) => "f32",
                    FlatSamples::U32(_) => "u32",
                };
                let values: Vec<f32> = ch.sample_data.values_as_f32().collect();
                channels.push(ExrChannel {
                    name,
                    sample_type,
                    width,
                    height,
                    values,
                    compression: compression.clone(),
                });
            }
        }
        if channels.is_empty() {
            return Err(InspectError::Empty {
                path: path.to_owned(),
            });
        }
        let passes = group_passes(&channels);
        Ok(Self {
            path: path.to_owned(),
            parts: image.layer_data.len(),
            channels,
            passes,
            attributes,
        })
    }

    /// A one-part file's contents made in memory from its channels (in file order), as
    /// [`ExrContents::read`] would give them; no text attributes.
    pub(crate) fn from_channels(path: &Path, channels: Vec<ExrChannel>) -> Self {
        let passes = group_passes(&channels);
        Self {
            path: path.to_owned(),
            parts: 1,
            channels,
            passes,
            attributes: Default::default(),
        }
    }

    /// The channel called `name`.
    pub fn channel(&self, name: &str) -> Option<&ExrChannel> {
        self.channels.iter().find(|c| c.name == name)
    }
}

fn group_passes(channels: &[ExrChannel]) -> Vec<ExrPass> {
    let mut passes: Vec<ExrPass> = Vec::new();
    for (i, c) in channels.iter().enumerate() {
        let (pass, comp) = match c.name.rsplit_once('.') {
            Some((p, comp)) => (p.to_string(), comp.to_string()),
            None => (String::new(), c.name.clone()),
        };
        match passes.iter_mut().find(|p| p.name == pass) {
            Some(p) => p.components.push((comp, i)),
            None => passes.push(ExrPass {
                name: pass,
                components: vec![(comp, i)],
            }),
        }
    }
    passes
}
