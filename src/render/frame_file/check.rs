//! Checks of a frame file without decoding it again: the encoded bytes' header and blocks, and
//! the channels a frame's contents must hold.

use exr::prelude::Encoding;

use super::FrameFileError;
use crate::exr_file::{ExrContents, InspectError};
use crate::render::passes::CHANNEL_GROUPS;

/// Checks that `bytes`, the encoding of `contents` ([`super::FrameImage::encode`],
/// [`super::FrameImage::contents`]), open as an EXR file whose header names exactly those channels,
/// sample types, size and compression, and whose offset tables and compressed blocks are all
/// there; nothing is decompressed.
pub(crate) fn check_encoded_header(
    contents: &ExrContents,
    bytes: &[u8],
) -> Result<(), FrameFileError> {
    let path = &contents.path;
    let unreadable = |message: String| {
        FrameFileError::Read(InspectError::Read {
            path: path.clone(),
            message,
        })
    };
    let reader = exr::block::reader::Reader::read_from_buffered(std::io::Cursor::new(bytes), true)
        .map_err(|e| unreadable(e.to_string()))?;
    let headers = reader.headers().to_vec();
    let [header] = headers.as_slice() else {
        return Err(unreadable(format!(
            "{} parts in the encoded file, expected 1",
            headers.len()
        )));
    };
    use exr::block::reader::ChunksReader;
    let chunks = reader
        .all_chunks(true)
        .map_err(|e| unreadable(e.to_string()))?;
    let expected = chunks.expected_chunk_count();
    let mut found = 0usize;
    for chunk in chunks {
        chunk.map_err(|e| unreadable(e.to_string()))?;
        found += 1;
    }
    if found != expected {
        return Err(unreadable(format!(
            "{found} blocks in the encoded file, its header says {expected}"
        )));
    }
    let size = header.layer_size;
    let in_header: Vec<(String, &'static str)> = header
        .channels
        .list
        .iter()
        .map(|c| {
            let kind = match c.sample_type {
                exr::meta::attribute::SampleType::F16 => "f16",
                exr::meta::attribute::SampleType::F32 => "f32",
                exr::meta::attribute::SampleType::U32 => "u32",
            };
            (c.name.to_string(), kind)
        })
        .collect();
    let made: Vec<(String, &'static str)> = contents
        .channels
        .iter()
        .map(|c| (c.name.clone(), c.sample_type))
        .collect();
    if in_header != made {
        return Err(unreadable(format!(
            "the encoded header lists channels {in_header:?}, the frame holds {made:?}"
        )));
    }
    for c in &contents.channels {
        if (c.width, c.height) != (size.width(), size.height()) {
            return Err(FrameFileError::Size {
                path: path.clone(),
                width: size.width(),
                height: size.height(),
                expected_w: c.width as u32,
                expected_h: c.height as u32,
            });
        }
    }
    if header.compression != Encoding::SMALL_LOSSLESS.compression {
        return Err(unreadable(format!(
            "encoded with {:?}, expected {:?}",
            header.compression,
            Encoding::SMALL_LOSSLESS.compression
        )));
    }
    Ok(())
}

/// Checks a frame file: it opens, holds exactly `channels` (e.g. from
/// [`Passes::frame_channels`](crate::render::passes::Passes::frame_channels)) at
/// `width × height`, and all values are finite. Returns the file's contents.
#[cfg(test)]
pub(crate) fn validate_frame(
    path: &std::path::Path,
    width: u32,
    height: u32,
    channels: &[&str],
) -> Result<ExrContents, FrameFileError> {
    let contents = ExrContents::read(path)?;
    validate_frame_contents(contents, width, height, channels)
}

/// `validate_frame` of a frame file already read (from disk, or from the bytes about to be
/// written).
pub(crate) fn validate_frame_contents(
    contents: ExrContents,
    width: u32,
    height: u32,
    channels: &[&str],
) -> Result<ExrContents, FrameFileError> {
    let path = contents.path.as_path();
    if let Some(extra) = contents
        .channels
        .iter()
        .find(|c| !channels.contains(&c.name.as_str()))
    {
        return Err(FrameFileError::UnexpectedChannel {
            path: path.into(),
            channel: extra.name.clone(),
            why: format!("the run's passes give {}", channels.join(", ")),
        });
    }
    check_channels(&contents, channels, Some((width, height)))?;
    Ok(contents)
}

/// Checks a frame file without knowing the run that made it (`verify`): `valid.V` is there,
/// every channel belongs to a frame file's channel group ([`CHANNEL_GROUPS`]) and every group
/// present is whole, and all values are finite.
pub(crate) fn check_frame_channels(contents: &ExrContents) -> Result<(), FrameFileError> {
    let path = &contents.path;
    let mut expected: Vec<&str> = Vec::new();
    for c in &contents.channels {
        let Some(group) = CHANNEL_GROUPS.iter().find(|g| g.contains(&c.name.as_str())) else {
            return Err(FrameFileError::UnexpectedChannel {
                path: path.clone(),
                channel: c.name.clone(),
                why: "not a frame-file channel".into(),
            });
        };
        for name in group.iter() {
            if !expected.contains(name) {
                expected.push(name);
            }
        }
    }
    if !expected.contains(&"valid.V") {
        expected.push("valid.V");
    }
    check_channels(contents, &expected, None)
}

/// Every channel of `names` is present, at `size` if given (width, height), and finite.
fn check_channels(
    contents: &ExrContents,
    names: &[&str],
    size: Option<(u32, u32)>,
) -> Result<(), FrameFileError> {
    let path = &contents.path;
    for &name in names {
        let ch = contents
            .channel(name)
            .ok_or_else(|| FrameFileError::MissingChannel {
                path: path.clone(),
                channel: name.into(),
            })?;
        if let Some((width, height)) = size {
            if (ch.width, ch.height) != (width as usize, height as usize) {
                return Err(FrameFileError::Size {
                    path: path.clone(),
                    width: ch.width,
                    height: ch.height,
                    expected_w: width,
                    expected_h: height,
                });
            }
        }
        let count = ch.values.iter().filter(|v| !v.is_finite()).count();
        if count > 0 {
            return Err(FrameFileError::NonFinite {
                path: path.clone(),
                channel: name.into(),
                count,
            });
        }
    }
    Ok(())
}
