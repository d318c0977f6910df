//! A frame assembled from Blender's raw renders: their planes read (`Raw`) with Cycles' own
//! times, and the remap of each rig camera pixel to the rendered one (`RemapTable`), computed
//! once per camera.

use std::path::Path;

use super::{FrameFileError, FrameImage};
use crate::camera::{Camera, CameraModel, Pixel};
use crate::exr_file::ExrContents;
use crate::math::{Affine3, Real, Vec3};
use crate::render::render_camera::RenderCamera;

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
}
