//! The dataset's frame file: one multilayer EXR per camera and frame, made in Rust from
//! Blender's raw renders (blurred colour, unblurred ground truth: whichever the passes need), remapped to the rig's
//! camera model where Blender rendered an ideal stand-in.
//!
//! Channels (one part, ZIP, 32-bit float unless said), each group only where its pass is
//! asked for (`[render] passes`, [`crate::render::passes`]); `valid.V` always:
//! - `rgb.R, rgb.G, rgb.B, rgb.A` — colour with motion blur (linear, scene-referred); a
//!   monochrome camera holds `gray.Y` instead (Rec. 709 luminance of the linear colour).
//! - `depth.Z` — planar depth: z of the surface point in the OpenCV camera frame (m).
//! - `normal.X/Y/Z` — unit surface normal in the OpenCV camera frame.
//! - `position.X/Y/Z` — surface point in the world frame (m).
//! - `segmentation.id` — u32: scene object or agent id (0 = nothing).
//! - `segmentation.part` — u32: a person's body part at the pixel (1 and 2 the left and right
//!   hand, 3 and 4 the left and right forearm, 0 the rest of a person and everything else).
//! - `segmentation.garment` (only where people wear outfits) — u32: the garment on top at a
//!   person's pixel (its slot's place in [`crate::render::outfit::SLOTS`] + 1: 1 top, 2
//!   bottom, 3 socks, 4 shoes, 5 hair; 0 the skin and everything else).
//! - `flow_forward.X/Y`, `flow_backward.X/Y` — pixel displacement of the surface point to the
//!   next / previous saved frame (OpenCV pixels, x right, y down).
//! - `depth_noisy.Z` (only for cameras with a depth-noise model) — `depth.Z` through the
//!   sensor noise model of [`crate::render::depth_noise`]; 0 = no measurement.
//!
//! Where each pixel reads the render ([`RemapTable`]) is computed once per camera and take.
//! A frame is encoded with its ZIP blocks compressed on every thread and checked without
//! decoding it again: on the planes it was encoded from ([`FrameImage::contents`]) and the
//! encoded bytes' header and blocks (`check_encoded_header`).
//!
//! Pixels with no surface (background) or outside the camera's valid field of view hold 0 in
//! every ground-truth channel; outside the valid field of view the colour is 0 too. Ground
//! truth is sampled at the rendered pixel nearest to the exact ray (ids, normals and flow are
//! never blended), except the surface point (depth, position): where the ray meets the plane
//! of three of the four rendered pixels around it whose triangle holds the ray, all on the
//! nearest one's surface (one object; steps within the tangent planes and normals agreeing,
//! or without normals all four on one plane), so that it lies on the pixel's own ray and never
//! past the object's edge; else (an edge, a crease) the nearest pixel's. Colour is
//! interpolated bilinearly. A render that is the target image
//! itself (a pinhole, or the native polynomial fisheye) is taken pixel for pixel, and its flow
//! is in its own pixels.
//!
//! This file holds the frame ([`FrameImage`]) and its encoding; `assemble` makes it from the
//! raw renders, `check` checks a frame file.

mod assemble;
mod check;

use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
    WritableImage,
};

use crate::exr_file::{ExrChannel, ExrContents, InspectError};
use crate::render::passes::{Pass, Passes};
#[cfg(test)]
pub(crate) use assemble::assemble_frame;
pub(crate) use assemble::RemapTable;
#[cfg(test)]
pub(crate) use check::validate_frame;
pub(crate) use check::{check_encoded_header, check_frame_channels, validate_frame_contents};

/// A frame that could not be assembled, written or validated.
#[derive(Debug, thiserror::Error)]
pub(crate) enum FrameFileError {
    #[error(transparent)]
    Read(#[from] InspectError),
    #[error("{path}: channel `{channel}` missing (Blender did not write the pass)")]
    MissingChannel { path: PathBuf, channel: String },
    #[error("{path}: channel `{channel}` is not one this frame file should hold ({why})")]
    UnexpectedChannel {
        path: PathBuf,
        channel: String,
        why: String,
    },
    #[error("{path}: {width}×{height} px, expected {expected_w}×{expected_h}")]
    Size {
        path: PathBuf,
        width: usize,
        height: usize,
        expected_w: u32,
        expected_h: u32,
    },
    #[error("{path}: writing: {message}")]
    Write { path: PathBuf, message: String },
    #[error("{path}: channel `{channel}` has {count} non-finite values")]
    NonFinite {
        path: PathBuf,
        channel: String,
        count: usize,
    },
}

/// A frame's pixels, row-major, in the target camera's image: the planes its raw renders
/// hold (none where a pass was not rendered).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FrameImage {
    pub width: usize,
    pub height: usize,
    pub valid: Vec<f32>,
    pub rgba: Option<Vec<[f32; 4]>>,
    /// Colour is written as one grey channel (`gray.Y`).
    pub monochrome: bool,
    pub depth: Option<Vec<f32>>,
    pub normal: Option<Vec<[f32; 3]>>,
    pub position: Option<Vec<[f32; 3]>>,
    pub segmentation: Option<Vec<u32>>,
    /// Each person's pixel's body part (`body::parts::BodyPart`: 0 the rest, 1 and 2 the left
    /// and right hand, 3 and 4 the forearms), beside `segmentation`.
    pub body_parts: Option<Vec<u32>>,
    /// Each person's pixel's garment (its slot's place in [`crate::render::outfit::SLOTS`] + 1;
    /// 0 the skin), beside `segmentation`, where people wear outfits.
    pub garments: Option<Vec<u32>>,
    pub flow_forward: Option<Vec<[f32; 2]>>,
    pub flow_backward: Option<Vec<[f32; 2]>>,
    /// `depth` through a sensor noise model, where the camera has one.
    pub depth_noisy: Option<Vec<f32>>,
    /// Cycles' own seconds for the raw renders (`colour_sync`, `colour_path_tracing`, …), as
    /// their headers say; not written to the frame file.
    pub render_seconds: Vec<(&'static str, f64)>,
}

/// Rec. 709 luminance of linear RGB: how a monochrome camera's colour is stored.
pub(crate) fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

impl FrameImage {
    /// Drops the planes of passes not in `passes` (the raw renders hold what those asked need:
    /// depth noise needs position and normals even where they are not kept).
    pub(crate) fn keep_only(&mut self, passes: Passes) {
        if !passes.has(Pass::Colour) {
            self.rgba = None;
        }
        if !passes.has(Pass::Depth) {
            self.depth = None;
        }
        if !passes.has(Pass::Position) {
            self.position = None;
        }
        if !passes.has(Pass::Normals) {
            self.normal = None;
        }
        if !passes.has(Pass::Segmentation) {
            self.segmentation = None;
            self.body_parts = None;
            self.garments = None;
        }
        if !passes.has(Pass::Flow) {
            self.flow_forward = None;
            self.flow_backward = None;
        }
        if !passes.has(Pass::DepthNoise) {
            self.depth_noisy = None;
        }
    }

    /// Writes the frame file to `path` ([`FrameImage::encode`], then the bytes; not atomic).
    #[cfg(test)]
    pub(crate) fn write(&self, path: &Path) -> Result<(), FrameFileError> {
        let bytes = self.encode(path)?;
        std::fs::write(path, bytes).map_err(|e| FrameFileError::Write {
            path: path.into(),
            message: e.to_string(),
        })
    }

    /// The frame file's bytes, with the planes it holds; `path` is where they are meant to go
    /// (named in errors). Callers write them under a temporary name and rename, as
    /// [`crate::supervisor::Dataset::finish_frame`] does. The file's blocks are compressed on
    /// every thread of rayon's pool.
    pub(crate) fn encode(&self, path: &Path) -> Result<Vec<u8>, FrameFileError> {
        let channels: Vec<AnyChannel<FlatSamples>> = self
            .channels()
            .into_iter()
            .map(|(name, samples)| AnyChannel::new(name.as_str(), samples))
            .collect();
        let layer = Layer::new(
            (self.width, self.height),
            LayerAttributes::default(),
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(SmallVec::from_vec(channels)),
        );
        let mut bytes = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer)
            .write()
            .to_buffered(&mut bytes)
            .map_err(|e| FrameFileError::Write {
                path: path.into(),
                message: e.to_string(),
            })?;
        Ok(bytes.into_inner())
    }

    /// What [`FrameImage::encode`]'s file holds, read back as [`ExrContents::read`] would
    /// (`path` names it): channels in the file's order (sorted by name), the same samples. The
    /// frame file's ZIP compression is lossless and its samples are stored as given (`f32`,
    /// `u32`), so decoding the encoded bytes gives exactly these planes (tested); a finished
    /// frame is checked on them and on the encoded file's header
    /// (`check_encoded_header`) instead of decoding the whole file again.
    pub(crate) fn contents(&self, path: &Path) -> ExrContents {
        let mut named = self.channels();
        named.sort_by(|a, b| a.0.cmp(&b.0));
        let channels: Vec<ExrChannel> = named
            .into_iter()
            .map(|(name, samples)| {
                let (sample_type, values) = match samples {
                    FlatSamples::F32(v) => ("f32", v),
                    FlatSamples::U32(v) => ("u32", v.into_iter().map(|x| x as f32).collect()),
                    FlatSamples::F16(v) => ("f16", v.into_iter().map(f32::from).collect()),
                };
                ExrChannel {
                    name,
                    sample_type,
                    width: self.width,
                    height: self.height,
                    values,
                    compression: format!("{:?}", Encoding::SMALL_LOSSLESS.compression),
                }
            })
            .collect();
        ExrContents::from_channels(path, channels)
    }

    /// The frame file's channels by name, in the order they are made.
    fn channels(&self) -> Vec<(String, FlatSamples)> {
        let mut channels: Vec<(String, FlatSamples)> = Vec::new();
        let mut f32_channel =
            |name: &str, values: Vec<f32>| channels.push((name.into(), FlatSamples::F32(values)));
        fn component<const N: usize>(v: &[[f32; N]], c: usize) -> Vec<f32> {
            v.iter().map(|p| p[c]).collect()
        }
        f32_channel("valid.V", self.valid.clone());
        match (&self.rgba, self.monochrome) {
            (Some(rgba), true) => f32_channel(
                "gray.Y",
                rgba.iter().map(|p| luminance([p[0], p[1], p[2]])).collect(),
            ),
            (Some(rgba), false) => {
                for (c, name) in ["R", "G", "B", "A"].iter().enumerate() {
                    f32_channel(&format!("rgb.{name}"), component(rgba, c));
                }
            }
            (None, _) => {}
        }
        if let Some(depth) = &self.depth {
            f32_channel("depth.Z", depth.clone());
        }
        if let Some(noisy) = &self.depth_noisy {
            f32_channel("depth_noisy.Z", noisy.clone());
        }
        for (c, axis) in ["X", "Y", "Z"].iter().enumerate() {
            if let Some(normal) = &self.normal {
                f32_channel(&format!("normal.{axis}"), component(normal, c));
            }
            if let Some(position) = &self.position {
                f32_channel(&format!("position.{axis}"), component(position, c));
            }
        }
        if let (Some(fwd), Some(bwd)) = (&self.flow_forward, &self.flow_backward) {
            for (c, axis) in ["X", "Y"].iter().enumerate() {
                f32_channel(&format!("flow_backward.{axis}"), component(bwd, c));
                f32_channel(&format!("flow_forward.{axis}"), component(fwd, c));
            }
        }
        if let Some(ids) = &self.segmentation {
            channels.push(("segmentation.id".into(), FlatSamples::U32(ids.clone())));
        }
        if let Some(parts) = &self.body_parts {
            channels.push(("segmentation.part".into(), FlatSamples::U32(parts.clone())));
        }
        if let Some(garments) = &self.garments {
            channels.push((
                "segmentation.garment".into(),
                FlatSamples::U32(garments.clone()),
            ));
        }
        channels
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame of every plane, `w × h`, values spread over many magnitudes (and ids past
    /// 2²⁴, which an `f32` cannot hold exactly).
    fn every_plane(w: usize, h: usize, monochrome: bool) -> FrameImage {
        let n = w * h;
        let v =
            |k: usize, c: usize| ((k * 7 + c * 13) as f32).sin() * 10f32.powi((k % 9) as i32 - 4);
        FrameImage {
            width: w,
            height: h,
            valid: (0..n).map(|k| (k % 3 == 0) as u8 as f32).collect(),
            rgba: Some((0..n).map(|k| [v(k, 0), v(k, 1), v(k, 2), 1.0]).collect()),
            monochrome,
            depth: Some((0..n).map(|k| v(k, 3).abs()).collect()),
            normal: Some((0..n).map(|k| [v(k, 4), v(k, 5), v(k, 6)]).collect()),
            position: Some((0..n).map(|k| [v(k, 7) + 1e5, v(k, 8), -v(k, 9)]).collect()),
            segmentation: Some((0..n).map(|k| (k as u32) * 40_001 + 16_777_217).collect()),
            body_parts: Some((0..n).map(|k| (k % 5) as u32).collect()),
            garments: Some((0..n).map(|k| (k % 6) as u32).collect()),
            flow_forward: Some((0..n).map(|k| [v(k, 10), v(k, 11)]).collect()),
            flow_backward: Some((0..n).map(|k| [v(k, 12), v(k, 13)]).collect()),
            depth_noisy: Some((0..n).map(|k| v(k, 14).abs()).collect()),
            render_seconds: Vec::new(),
        }
    }

    /// What a frame is checked on instead of decoding its file again is what decoding it
    /// gives: every channel's name, type, size, compression and every value bit for bit
    /// (a frame taller than one ZIP block of 16 rows, its width odd).
    #[test]
    fn a_frames_contents_are_its_decoded_file() {
        let path = Path::new("frame_00000.exr");
        for monochrome in [false, true] {
            let image = every_plane(37, 53, monochrome);
            let bytes = image.encode(path).unwrap();
            let decoded = ExrContents::from_bytes(path, &bytes).unwrap();
            let made = image.contents(path);
            assert_eq!(made.parts, decoded.parts);
            assert_eq!(made.channels.len(), decoded.channels.len());
            for (a, b) in made.channels.iter().zip(&decoded.channels) {
                assert_eq!(
                    (&a.name, a.sample_type, a.width, a.height, &a.compression),
                    (&b.name, b.sample_type, b.width, b.height, &b.compression)
                );
                let bits =
                    |c: &ExrChannel| c.values.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(a), bits(b), "{}", a.name);
            }
            let passes = |c: &ExrContents| {
                c.passes
                    .iter()
                    .map(|p| (p.name.clone(), p.components.clone()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(passes(&made), passes(&decoded));
            check_encoded_header(&made, &bytes).unwrap();
        }
    }

    /// The encoded file's check catches a file cut short, a block damaged in its framing, and
    /// bytes that are not the frame's encoding.
    #[test]
    fn the_encoded_check_fails_on_other_bytes() {
        let path = Path::new("frame_00000.exr");
        let image = every_plane(19, 40, false);
        let bytes = image.encode(path).unwrap();
        let made = image.contents(path);
        let cut = &bytes[..bytes.len() - 10];
        assert!(check_encoded_header(&made, cut).is_err());
        let mut other = image.clone();
        other.depth_noisy = None;
        let err = check_encoded_header(&other.contents(path), &bytes).unwrap_err();
        assert!(err.to_string().contains("depth_noisy.Z"), "{err}");
        let smaller = every_plane(19, 39, false);
        assert!(check_encoded_header(&smaller.contents(path), &bytes).is_err());
        assert!(check_encoded_header(&made, b"not an exr file").is_err());
    }
}
