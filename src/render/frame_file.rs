//! The dataset's frame file: one multilayer EXR per camera and frame, made in Rust from
//! Blender's two raw renders (blurred colour, unblurred ground truth), remapped to the rig's
//! camera model where Blender rendered an ideal stand-in.
//!
//! Channels (one part, ZIP, 32-bit float unless said):
//! - `rgb.R, rgb.G, rgb.B, rgb.A` — colour with motion blur (linear, scene-referred).
//! - `depth.Z` — planar depth: z of the surface point in the OpenCV camera frame (m).
//! - `normal.X/Y/Z` — unit surface normal in the OpenCV camera frame.
//! - `position.X/Y/Z` — surface point in the world frame (m).
//! - `segmentation.id` — u32: scene object or agent id (0 = nothing).
//! - `flow_forward.X/Y`, `flow_backward.X/Y` — pixel displacement of the surface point to the
//!   next / previous frame (OpenCV pixels, x right, y down).
//! - `depth_noisy.Z` (only for cameras with a depth-noise model) — `depth.Z` through the
//!   sensor noise model of [`crate::render::depth_noise`]; 0 = no measurement.
//!
//! Pixels with no surface (background) or outside the camera's valid field of view hold 0 in
//! every ground-truth channel; outside the valid field of view the colour is 0 too. Ground
//! truth is sampled at the rendered pixel nearest to the exact ray (ids, positions and normals
//! are never blended); colour is interpolated bilinearly. A render that is the target image
//! itself (a pinhole, or the native polynomial fisheye) is taken pixel for pixel, and its flow
//! is in its own pixels.

use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
    WritableImage,
};

use crate::camera::{Camera, CameraModel, Pixel};
use crate::exr_file::{ExrContents, InspectError};
use crate::math::{Affine3, Real, Vec3};
use crate::render::render_camera::RenderCamera;

/// Every channel a frame file holds, in file order (sorted, as EXR stores them).
pub const FRAME_CHANNELS: [&str; 17] = [
    "depth.Z",
    "flow_backward.X",
    "flow_backward.Y",
    "flow_forward.X",
    "flow_forward.Y",
    "normal.X",
    "normal.Y",
    "normal.Z",
    "position.X",
    "position.Y",
    "position.Z",
    "rgb.A",
    "rgb.B",
    "rgb.G",
    "rgb.R",
    "segmentation.id",
    // Marks pixels inside the camera's valid field of view (1) or outside (0).
    "valid.V",
];

/// Channels a frame file may hold besides [`FRAME_CHANNELS`]; checked like them when present.
pub const OPTIONAL_FRAME_CHANNELS: [&str; 1] = ["depth_noisy.Z"];

/// A frame that could not be assembled, written or validated.
#[derive(Debug, thiserror::Error)]
pub enum FrameFileError {
    #[error(transparent)]
    Read(#[from] InspectError),
    #[error("{path}: channel `{channel}` missing (Blender did not write the pass)")]
    MissingChannel { path: PathBuf, channel: String },
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

/// A frame's pixels, row-major, in the target camera's image.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameImage {
    pub width: usize,
    pub height: usize,
    pub rgba: Vec<[f32; 4]>,
    pub depth: Vec<f32>,
    pub normal: Vec<[f32; 3]>,
    pub position: Vec<[f32; 3]>,
    pub segmentation: Vec<u32>,
    pub flow_forward: Vec<[f32; 2]>,
    pub flow_backward: Vec<[f32; 2]>,
    pub valid: Vec<f32>,
    /// `depth` through a sensor noise model, where the camera has one.
    pub depth_noisy: Option<Vec<f32>>,
}

/// A raw render's planes, looked up by pass and component.
struct Raw {
    contents: ExrContents,
    width: usize,
    height: usize,
}

impl Raw {
    fn read(path: &Path, render: &RenderCamera) -> Result<Self, FrameFileError> {
        let contents = ExrContents::read(path)?;
        let res = render.resolution();
        let first = contents.channels.first();
        let (width, height) = first.map_or((0, 0), |c| (c.width, c.height));
        if (width, height) != (res.width_px as usize, res.height_px as usize) {
            return Err(FrameFileError::Size {
                path: path.into(),
                width,
                height,
                expected_w: res.width_px,
                expected_h: res.height_px,
            });
        }
        Ok(Self {
            contents,
            width,
            height,
        })
    }

    fn plane(&self, name: &str) -> Result<&[f32], FrameFileError> {
        let full = format!("ViewLayer.{name}");
        self.contents
            .channel(&full)
            .map(|c| c.values.as_slice())
            .ok_or_else(|| FrameFileError::MissingChannel {
                path: self.contents.path.clone(),
                channel: full,
            })
    }

    /// The planes of `pass`'s components, in the order given.
    fn planes<const N: usize>(
        &self,
        pass: &str,
        components: [&str; N],
    ) -> Result<[&[f32]; N], FrameFileError> {
        let mut out = [&[][..]; N];
        for (o, c) in out.iter_mut().zip(components) {
            *o = self.plane(&format!("{pass}.{c}"))?;
        }
        Ok(out)
    }

    fn nearest(&self, q: Pixel) -> Option<usize> {
        let (x, y) = (q.x.round(), q.y.round());
        (x >= 0.0 && y >= 0.0 && x < self.width as Real && y < self.height as Real)
            .then(|| y as usize * self.width + x as usize)
    }

    fn bilinear(&self, plane: &[f32], q: Pixel) -> f32 {
        let x = q.x.clamp(0.0, (self.width - 1) as Real);
        let y = q.y.clamp(0.0, (self.height - 1) as Real);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (ax, ay) = ((x - x0 as Real) as f32, (y - y0 as Real) as f32);
        let at = |xx: usize, yy: usize| plane[yy * self.width + xx];
        (1.0 - ay) * ((1.0 - ax) * at(x0, y0) + ax * at(x1, y0))
            + ay * ((1.0 - ax) * at(x0, y1) + ax * at(x1, y1))
    }
}

/// Builds a frame from Blender's raw colour and ground-truth renders of `render`, for the rig
/// camera `target` whose pose at this frame is `world_from_cam` (OpenCV axes).
pub fn assemble_frame(
    rgb_exr: &Path,
    ground_truth_exr: &Path,
    render: &RenderCamera,
    target: &Camera,
    world_from_cam: Affine3,
) -> Result<FrameImage, FrameFileError> {
    let rgb = Raw::read(rgb_exr, render)?;
    let gt = Raw::read(ground_truth_exr, render)?;
    let colour = rgb.planes("Combined", ["R", "G", "B", "A"])?;
    let hit = gt.plane("Combined.A")?;
    let pos = gt.planes("Position", ["X", "Y", "Z"])?;
    let nrm = gt.planes("Normal", ["X", "Y", "Z"])?;
    let ids = gt.plane("IndexOB.X")?;
    let vec = gt.planes("Vector", ["X", "Y", "Z", "W"])?;

    let res = target.resolution();
    let (w, h) = (res.width_px as usize, res.height_px as usize);
    let cam_from_world = world_from_cam.inverse();
    let mut out = FrameImage {
        width: w,
        height: h,
        rgba: vec![[0.0; 4]; w * h],
        depth: vec![0.0; w * h],
        normal: vec![[0.0; 3]; w * h],
        position: vec![[0.0; 3]; w * h],
        segmentation: vec![0; w * h],
        flow_forward: vec![[0.0; 2]; w * h],
        flow_backward: vec![[0.0; 2]; w * h],
        valid: vec![0.0; w * h],
        depth_noisy: None,
    };
    // Target pixel of a rendered pixel (continuous), through its ray.
    let to_target = |q: Pixel| {
        if render.is_identity() {
            return Some(q);
        }
        render
            .pixel_to_ray(q)
            .and_then(|r| target.project_unbounded(r))
    };
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let p = Pixel::new(x as Real, y as Real);
            let Some(ray) = target.unproject(p) else {
                continue;
            };
            let q = if render.is_identity() {
                p
            } else {
                match render.ray_to_pixel(ray) {
                    Some(q) => q,
                    None => continue,
                }
            };
            out.valid[i] = 1.0;
            for c in 0..4 {
                out.rgba[i][c] = rgb.bilinear(colour[c], q);
            }
            let Some(n) = gt.nearest(q) else { continue };
            let qn = Pixel::new((n % gt.width) as Real, (n / gt.width) as Real);
            if hit[n] < 0.5 || !render.renders(qn) {
                continue;
            }
            let world = Vec3::new(pos[0][n] as Real, pos[1][n] as Real, pos[2][n] as Real);
            let in_cam = cam_from_world.transform_point3(world);
            let normal = cam_from_world
                .transform_vector3(Vec3::new(
                    nrm[0][n] as Real,
                    nrm[1][n] as Real,
                    nrm[2][n] as Real,
                ))
                .normalize_or_zero();
            out.depth[i] = in_cam.z as f32;
            out.normal[i] = normal.as_vec3().to_array();
            out.position[i] = world.as_vec3().to_array();
            out.segmentation[i] = ids[n].round() as u32;
            // Blender's vector pass, pixels in Blender's raster (y up), measured
            // (`tests/render_shard.rs`): (X, Y) = previous − here, (Z, W) = here − next.
            let prev = qn + Pixel::new(vec[0][n] as Real, -vec[1][n] as Real);
            let next = qn + Pixel::new(-vec[2][n] as Real, vec[3][n] as Real);
            if let Some(here) = to_target(qn) {
                if let Some(t) = to_target(next) {
                    out.flow_forward[i] = (t - here).as_vec2().to_array();
                }
                if let Some(t) = to_target(prev) {
                    out.flow_backward[i] = (t - here).as_vec2().to_array();
                }
            }
        }
    }
    Ok(out)
}

impl FrameImage {
    /// Writes the frame file to `path` (callers that need atomicity write a temporary name,
    /// validate it and rename, as [`crate::supervisor::Dataset::finish_frame`] does).
    pub fn write(&self, path: &Path) -> Result<(), FrameFileError> {
        let plane = |f: &dyn Fn(usize) -> f32| (0..self.width * self.height).map(f).collect();
        let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
        let mut f32_channel = |name: &str, values: Vec<f32>| {
            channels.push(AnyChannel::new(name, FlatSamples::F32(values)))
        };
        f32_channel("depth.Z", self.depth.clone());
        if let Some(noisy) = &self.depth_noisy {
            f32_channel("depth_noisy.Z", noisy.clone());
        }
        for (c, axis) in ["X", "Y"].iter().enumerate() {
            f32_channel(
                &format!("flow_backward.{axis}"),
                plane(&|i| self.flow_backward[i][c]),
            );
            f32_channel(
                &format!("flow_forward.{axis}"),
                plane(&|i| self.flow_forward[i][c]),
            );
        }
        for (c, axis) in ["X", "Y", "Z"].iter().enumerate() {
            f32_channel(&format!("normal.{axis}"), plane(&|i| self.normal[i][c]));
            f32_channel(&format!("position.{axis}"), plane(&|i| self.position[i][c]));
        }
        for (c, name) in ["R", "G", "B", "A"].iter().enumerate() {
            f32_channel(&format!("rgb.{name}"), plane(&|i| self.rgba[i][c]));
        }
        f32_channel("valid.V", self.valid.clone());
        channels.push(AnyChannel::new(
            "segmentation.id",
            FlatSamples::U32(self.segmentation.clone()),
        ));
        let layer = Layer::new(
            (self.width, self.height),
            LayerAttributes::default(),
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(SmallVec::from_vec(channels)),
        );
        Image::from_layer(layer)
            .write()
            .non_parallel()
            .to_file(path)
            .map_err(|e| FrameFileError::Write {
                path: path.into(),
                message: e.to_string(),
            })
    }
}

/// Checks a frame file: it opens, has every channel at the expected size, and all values are
/// finite. Returns the file's contents.
pub fn validate_frame(path: &Path, width: u32, height: u32) -> Result<ExrContents, FrameFileError> {
    let contents = ExrContents::read(path)?;
    check_frame_channels(&contents, Some((width, height)))?;
    Ok(contents)
}

/// Every frame channel is present, and so are the optional ones that are there: at `size`, if
/// given (width, height), and finite.
pub fn check_frame_channels(
    contents: &ExrContents,
    size: Option<(u32, u32)>,
) -> Result<(), FrameFileError> {
    let path = &contents.path;
    let optional = OPTIONAL_FRAME_CHANNELS
        .into_iter()
        .filter(|name| contents.channel(name).is_some());
    for name in FRAME_CHANNELS.into_iter().chain(optional) {
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
