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
//! never blended), except the surface point (depth, position): where the four rendered pixels
//! around the ray lie on one plane it is interpolated between them, so that it lies on the
//! pixel's own ray (to second order), else the nearest pixel's. Colour is
//! interpolated bilinearly. A render that is the target image
//! itself (a pinhole, or the native polynomial fisheye) is taken pixel for pixel, and its flow
//! is in its own pixels.

use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
    WritableImage,
};

use crate::camera::{Camera, CameraModel, Pixel};
use crate::exr_file::{ExrChannel, ExrContents, InspectError};
use crate::math::{Affine3, Real, Vec3};
use crate::render::passes::{Pass, Passes, CHANNEL_GROUPS};
use crate::render::render_camera::RenderCamera;

/// A frame that could not be assembled, written or validated.
#[derive(Debug, thiserror::Error)]
pub enum FrameFileError {
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
pub struct FrameImage {
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
    pub flow_forward: Option<Vec<[f32; 2]>>,
    pub flow_backward: Option<Vec<[f32; 2]>>,
    /// `depth` through a sensor noise model, where the camera has one.
    pub depth_noisy: Option<Vec<f32>>,
    /// Cycles' own seconds for the raw renders (`colour_sync`, `colour_path_tracing`, …), as
    /// their headers say; not written to the frame file.
    pub render_seconds: Vec<(&'static str, f64)>,
}

/// Rec. 709 luminance of linear RGB: how a monochrome camera's colour is stored.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// Four rendered pixels whose depths differ by at most this share of the nearest are taken as
/// one surface ([`Raw::surface_point`]): a floor seen at 80° from its normal spreads about
/// 3 % across a pixel at 1/4 Aria size; a depth edge far more.
const ONE_SURFACE_DEPTH_SPREAD: Real = 0.05;

/// ... and lie on one plane: the fourth within this share of the pixels' spacing of the plane
/// through the other three (the position pass is float32: about 1e-7 of the distance from
/// the origin, hence also 10 µm absolute).
const COPLANAR_TOLERANCE: Real = 1e-3;

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

    /// The surface point on the ray through `q` (world, m): the position pass interpolated
    /// bilinearly between the four rendered pixels around `q` where they lie on one plane —
    /// all hit and rendered, one object id, depths within [`ONE_SURFACE_DEPTH_SPREAD`] of each
    /// other, coplanar ([`COPLANAR_TOLERANCE`]) — which is the ray's own point to second order
    /// in the pixel spacing;
    /// `None` where they do not (edges, the image border): the nearest pixel's point is taken.
    fn surface_point(
        &self,
        pos: &[&[f32]; 3],
        hit: &[f32],
        ids: Option<&[f32]>,
        q: Pixel,
        renders: impl Fn(Pixel) -> bool,
        cam_from_world: &Affine3,
    ) -> Option<Vec3> {
        let (x0, y0) = (q.x.floor(), q.y.floor());
        if x0 < 0.0 || y0 < 0.0 || x0 + 1.0 >= self.width as Real || y0 + 1.0 >= self.height as Real
        {
            return None;
        }
        let (ax, ay) = (q.x - x0, q.y - y0);
        let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
        let weights = [
            (1.0 - ax) * (1.0 - ay),
            ax * (1.0 - ay),
            (1.0 - ax) * ay,
            ax * ay,
        ];
        let mut point = Vec3::ZERO;
        let mut corner_points = [Vec3::ZERO; 4];
        let (mut z_min, mut z_max) = (Real::INFINITY, Real::NEG_INFINITY);
        let first = (y0 as usize) * self.width + x0 as usize;
        for (k, ((dx, dy), w)) in corners.into_iter().zip(weights).enumerate() {
            let n = (y0 + dy) as usize * self.width + (x0 + dx) as usize;
            if hit[n] < 0.5
                || !renders(Pixel::new(x0 + dx, y0 + dy))
                || ids.is_some_and(|ids| ids[n] != ids[first])
            {
                return None;
            }
            let world = Vec3::new(pos[0][n] as Real, pos[1][n] as Real, pos[2][n] as Real);
            let z = cam_from_world.transform_point3(world).z;
            (z_min, z_max) = (z_min.min(z), z_max.max(z));
            point += w * world;
            corner_points[k] = world;
        }
        // One plane: the fourth point on the plane of the other three (a crease between two
        // faces of one object, a wall meeting the floor, is not; nor is a curved surface).
        let [p00, p10, p01, p11] = corner_points;
        let (u, v) = (p10 - p00, p01 - p00);
        let n = u.cross(v);
        let off_plane = n.dot(p11 - p00).abs() / n.length().max(Real::MIN_POSITIVE);
        let coplanar = off_plane <= COPLANAR_TOLERANCE * u.length().max(v.length()) + 1e-5;
        (coplanar && z_min > 0.0 && z_max - z_min <= ONE_SURFACE_DEPTH_SPREAD * z_min)
            .then_some(point)
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

/// Cycles' own times of a raw render, from the header Blender writes
/// (`cycles.ViewLayer.synchronization_time` and `.render_time`, `mm:ss.cc`): the scene's sync
/// (BVH build included) and path tracing, under the stage names `[sync, path_tracing]`.
fn cycles_seconds<'a>(
    contents: &'a ExrContents,
    stages: [&'static str; 2],
) -> impl Iterator<Item = (&'static str, f64)> + 'a {
    stages
        .into_iter()
        .zip(["synchronization_time", "render_time"])
        .filter_map(|(stage, key)| {
            let text = contents
                .attributes
                .get(&format!("cycles.ViewLayer.{key}"))?;
            Some((stage, blender_duration_seconds(text)?))
        })
}

/// Seconds of Blender's `[[hh:]mm:]ss.cc` duration.
fn blender_duration_seconds(text: &str) -> Option<f64> {
    text.trim()
        .split(':')
        .try_fold(0.0, |acc, part| {
            Some(acc * 60.0 + part.parse::<f64>().ok()?)
        })
        .filter(|s| s.is_finite() && *s >= 0.0)
}

/// Builds a frame from Blender's raw colour and ground-truth renders of `render` (each where
/// it was rendered), for the rig camera `target` whose pose at this frame is `world_from_cam`
/// (OpenCV axes). The ground truth holds the planes of the passes its render had: `Position`
/// gives depth and position, `Normal` normals, `IndexOB` segmentation, `Vector` flow.
/// The remap is computed for this frame alone; [`RemapTable::assemble`] reuses one across a
/// camera's frames.
pub fn assemble_frame(
    rgb_exr: Option<&Path>,
    ground_truth_exr: Option<&Path>,
    render: &RenderCamera,
    target: &Camera,
    world_from_cam: Affine3,
) -> Result<FrameImage, FrameFileError> {
    RemapTable::new(render, target).assemble(rgb_exr, ground_truth_exr, world_from_cam)
}

/// Where each pixel of a rig camera reads the render Blender made for it: the rendered pixel
/// (continuous) on the exact model's ray, or none outside the valid field of view. It is the
/// same for every frame of a camera, so a take computes it once per camera (16 bytes a pixel:
/// 32 MB for a full-size Aria RGB camera) instead of unprojecting and reprojecting every
/// pixel of every frame (0.5 s of a full-size RGB frame's assembly on one core).
pub struct RemapTable {
    render: RenderCamera,
    target: Camera,
    /// Per target pixel (row-major), NaN where it is not valid.
    source_px: Vec<Pixel>,
}

impl std::fmt::Debug for RemapTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let res = self.target.resolution();
        write!(f, "RemapTable({}×{})", res.width_px, res.height_px)
    }
}

impl RemapTable {
    /// The table of `target` read from `render` (rows on rayon's pool).
    pub fn new(render: &RenderCamera, target: &Camera) -> Self {
        use rayon::prelude::*;
        let res = target.resolution();
        let (w, h) = (res.width_px as usize, res.height_px as usize);
        let mut source_px = vec![Pixel::NAN; w * h];
        source_px
            .par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, q) in row.iter_mut().enumerate() {
                    let p = Pixel::new(x as Real, y as Real);
                    let Some(ray) = target.unproject(p) else {
                        continue;
                    };
                    let source = match render.is_identity() {
                        true => Some(p),
                        false => render.ray_to_pixel(ray),
                    };
                    if let Some(source) = source {
                        *q = source;
                    }
                }
            });
        Self {
            render: *render,
            target: target.clone(),
            source_px,
        }
    }

    /// [`assemble_frame`] with this table's render and camera.
    pub fn assemble(
        &self,
        rgb_exr: Option<&Path>,
        ground_truth_exr: Option<&Path>,
        world_from_cam: Affine3,
    ) -> Result<FrameImage, FrameFileError> {
        assemble_with(self, rgb_exr, ground_truth_exr, world_from_cam)
    }
}

fn assemble_with(
    remap: &RemapTable,
    rgb_exr: Option<&Path>,
    ground_truth_exr: Option<&Path>,
    world_from_cam: Affine3,
) -> Result<FrameImage, FrameFileError> {
    let (render, target) = (&remap.render, &remap.target);
    let rgb = rgb_exr.map(|p| Raw::read(p, render)).transpose()?;
    let gt = ground_truth_exr.map(|p| Raw::read(p, render)).transpose()?;
    let mut render_seconds = Vec::new();
    for (raw, stages) in [
        (&rgb, ["colour_sync", "colour_path_tracing"]),
        (&gt, ["ground_truth_sync", "ground_truth_path_tracing"]),
    ] {
        if let Some(raw) = raw {
            render_seconds.extend(cycles_seconds(&raw.contents, stages));
        }
    }
    let colour = rgb
        .as_ref()
        .map(|r| r.planes("Combined", ["R", "G", "B", "A"]))
        .transpose()?;
    let (hit, pos, nrm, ids, vec) = match &gt {
        None => (None, None, None, None, None),
        Some(gt) => {
            let has = |pass: &str| gt.contents.channel(&format!("ViewLayer.{pass}")).is_some();
            (
                Some(gt.plane("Combined.A")?),
                has("Position.X")
                    .then(|| gt.planes("Position", ["X", "Y", "Z"]))
                    .transpose()?,
                has("Normal.X")
                    .then(|| gt.planes("Normal", ["X", "Y", "Z"]))
                    .transpose()?,
                has("IndexOB.X")
                    .then(|| gt.plane("IndexOB.X"))
                    .transpose()?,
                has("Vector.X")
                    .then(|| gt.planes("Vector", ["X", "Y", "Z", "W"]))
                    .transpose()?,
            )
        }
    };

    let res = target.resolution();
    let (w, h) = (res.width_px as usize, res.height_px as usize);
    let n_px = w * h;
    let cam_from_world = world_from_cam.inverse();
    let mut out = FrameImage {
        width: w,
        height: h,
        valid: vec![0.0; n_px],
        rgba: colour.map(|_| vec![[0.0; 4]; n_px]),
        monochrome: false,
        depth: pos.map(|_| vec![0.0; n_px]),
        normal: nrm.map(|_| vec![[0.0; 3]; n_px]),
        position: pos.map(|_| vec![[0.0; 3]; n_px]),
        segmentation: ids.map(|_| vec![0; n_px]),
        flow_forward: vec.map(|_| vec![[0.0; 2]; n_px]),
        flow_backward: vec.map(|_| vec![[0.0; 2]; n_px]),
        depth_noisy: None,
        render_seconds,
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
            let q = remap.source_px[i];
            if q.x.is_nan() {
                continue;
            }
            out.valid[i] = 1.0;
            if let (Some(planes), Some(rgb), Some(o)) = (&colour, &rgb, out.rgba.as_mut()) {
                for c in 0..4 {
                    o[i][c] = rgb.bilinear(planes[c], q);
                }
            }
            let (Some(gt), Some(hit)) = (&gt, hit) else {
                continue;
            };
            let Some(n) = gt.nearest(q) else { continue };
            let qn = Pixel::new((n % gt.width) as Real, (n / gt.width) as Real);
            if hit[n] < 0.5 || !render.renders(qn) {
                continue;
            }
            if let Some(pos) = &pos {
                let nearest = || Vec3::new(pos[0][n] as Real, pos[1][n] as Real, pos[2][n] as Real);
                let world = match render.is_identity() {
                    // The render's pixel is the frame's: its point is on the pixel's ray.
                    true => nearest(),
                    false => gt
                        .surface_point(pos, hit, ids, q, |px| render.renders(px), &cam_from_world)
                        .unwrap_or_else(nearest),
                };
                let in_cam = cam_from_world.transform_point3(world);
                out.depth.as_mut().unwrap()[i] = in_cam.z as f32;
                out.position.as_mut().unwrap()[i] = world.as_vec3().to_array();
            }
            if let Some(nrm) = &nrm {
                let normal = cam_from_world
                    .transform_vector3(Vec3::new(
                        nrm[0][n] as Real,
                        nrm[1][n] as Real,
                        nrm[2][n] as Real,
                    ))
                    .normalize_or_zero();
                out.normal.as_mut().unwrap()[i] = normal.as_vec3().to_array();
            }
            if let Some(ids) = ids {
                out.segmentation.as_mut().unwrap()[i] = ids[n].round() as u32;
            }
            if let Some(vec) = &vec {
                // Blender's vector pass, pixels in Blender's raster (y up), measured
                // (`tests/render_shard.rs`): (X, Y) = previous − here, (Z, W) = here − next.
                let prev = qn + Pixel::new(vec[0][n] as Real, -vec[1][n] as Real);
                let next = qn + Pixel::new(-vec[2][n] as Real, vec[3][n] as Real);
                if let Some(here) = to_target(qn) {
                    if let Some(t) = to_target(next) {
                        out.flow_forward.as_mut().unwrap()[i] = (t - here).as_vec2().to_array();
                    }
                    if let Some(t) = to_target(prev) {
                        out.flow_backward.as_mut().unwrap()[i] = (t - here).as_vec2().to_array();
                    }
                }
            }
        }
    }
    Ok(out)
}

impl FrameImage {
    /// Drops the planes of passes not in `passes` (the raw renders hold what those asked need:
    /// depth noise needs position and normals even where they are not kept).
    pub fn keep_only(&mut self, passes: Passes) {
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
    pub fn write(&self, path: &Path) -> Result<(), FrameFileError> {
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
    pub fn encode(&self, path: &Path) -> Result<Vec<u8>, FrameFileError> {
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
    pub fn contents(&self, path: &Path) -> ExrContents {
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
        channels
    }
}

/// Checks that `bytes`, the encoding of `contents` ([`FrameImage::encode`],
/// [`FrameImage::contents`]), open as an EXR file whose header names exactly those channels,
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
/// [`Passes::frame_channels`]) at `width × height`, and all values are finite. Returns the
/// file's contents.
pub fn validate_frame(
    path: &Path,
    width: u32,
    height: u32,
    channels: &[&str],
) -> Result<ExrContents, FrameFileError> {
    let contents = ExrContents::read(path)?;
    validate_frame_contents(contents, width, height, channels)
}

/// [`validate_frame`] of a frame file already read (from disk, or from the bytes about to be
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blender_durations_read_as_seconds() {
        assert_eq!(blender_duration_seconds("00:00.20"), Some(0.2));
        assert_eq!(blender_duration_seconds("01:02:03.50"), Some(3723.5));
        assert_eq!(blender_duration_seconds(" 00:13.25 "), Some(13.25));
        assert_eq!(blender_duration_seconds("00:xx"), None);
        assert_eq!(blender_duration_seconds(""), None);
    }

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
