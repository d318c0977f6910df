//! A frame assembled from Blender's raw renders: their planes read (`Raw`) with Cycles' own
//! times, and the remap of each rig camera pixel to the rendered one (`RemapTable`), computed
//! once per camera.

use std::path::Path;

use super::{FrameFileError, FrameImage};
use crate::camera::{Camera, CameraModel, Pixel};
use crate::exr_file::ExrContents;
use crate::math::{Affine3, Real, Vec3};
use crate::render::render_camera::RenderCamera;

/// Two neighbouring rendered pixels are one surface ([`Raw::surface_point`]) where the step
/// between their points lies within this sine (20°) of both their tangent planes (the normal
/// pass): a floor seen edge-on is, a step in depth is not; bump and normal detail of the
/// drawn materials tilt a normal by a few degrees.
const ONE_SURFACE_TANGENT_SIN: Real = 0.342;

/// ... and whose normals agree within this cosine (30°): the two faces of a crease (a wall
/// meeting the floor) are two surfaces, even where a step runs along the crease.
const ONE_SURFACE_NORMAL_COS: Real = 0.866;

/// Without normals, four rendered pixels are one plane where the fourth lies within this share
/// of their spacing of the plane through the other three ([`coplanar`]).
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

    /// The surface point on the frame pixel's exact ray `ray` (unit, camera frame), which
    /// meets the render at `q`, in the camera frame: where the ray meets the plane of three of
    /// the four rendered pixels around `q` that are on the nearest one's surface (hit and
    /// rendered, its `ids`: the object, and on a person the body part; one surface by
    /// [`ONE_SURFACE_TANGENT_SIN`] and [`ONE_SURFACE_NORMAL_COS`]; without normals, all four on
    /// one plane) and whose triangle
    /// holds `q`: of all four, the half of the flatter split; of three, their triangle. Exactly
    /// on the ray; off the surface by its curvature over a rendered pixel, or at a crease by the
    /// chord across it; never past the surface's edge. Without the Normal pass only four
    /// coplanar pixels are taken (a crease is not told from a plane otherwise). `None` (the
    /// nearest pixel's point is taken) where no such three are: at the surface's edge, or a
    /// surface one pixel wide.
    fn surface_point(
        &self,
        pos: &[&[f32]; 3],
        nrm: Option<&[&[f32]; 3]>,
        hit: &[f32],
        ids: Option<&[f32]>,
        q: Pixel,
        renders: impl Fn(Pixel) -> bool,
        cam_from_world: &Affine3,
        ray: Vec3,
    ) -> Option<Vec3> {
        let n = self.nearest(q)?;
        let point = |i: usize| {
            cam_from_world.transform_point3(Vec3::new(
                pos[0][i] as Real,
                pos[1][i] as Real,
                pos[2][i] as Real,
            ))
        };
        let z_n = point(n).z;
        if z_n <= 0.0 {
            return None;
        }
        let normal = |i: usize| {
            nrm.map(|nrm| {
                cam_from_world
                    .transform_vector3(Vec3::new(
                        nrm[0][i] as Real,
                        nrm[1][i] as Real,
                        nrm[2][i] as Real,
                    ))
                    .normalize_or_zero()
            })
        };
        let (p_n, normal_n) = (point(n), normal(n));
        // A rendered pixel on the nearest one's surface: its point (camera frame).
        let on_surface = |x: i64, y: i64| -> Option<Vec3> {
            if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
                return None;
            }
            let i = y as usize * self.width + x as usize;
            if hit[i] < 0.5
                || !renders(Pixel::new(x as Real, y as Real))
                || ids.is_some_and(|ids| ids[i] != ids[n])
            {
                return None;
            }
            let p = point(i);
            let one_surface = match (normal_n, normal(i)) {
                // Both normals see the step between the two points in their tangent planes:
                // a floor seen edge-on is one surface, a step in depth is not.
                (Some(a), Some(b)) => {
                    let step = p - p_n;
                    let slack = ONE_SURFACE_TANGENT_SIN * step.length();
                    a.dot(step).abs() <= slack
                        && b.dot(step).abs() <= slack
                        && a.dot(b) >= ONE_SURFACE_NORMAL_COS
                }
                // Without normals the four pixels' plane decides ([`coplanar`]).
                _ => true,
            };
            one_surface.then_some(p)
        };
        let (x0, y0) = (q.x.floor() as i64, q.y.floor() as i64);
        let (ax, ay) = (q.x - x0 as Real, q.y - y0 as Real);
        let quad = [
            on_surface(x0, y0),
            on_surface(x0 + 1, y0),
            on_surface(x0, y0 + 1),
            on_surface(x0 + 1, y0 + 1),
        ];
        // The triangles to try, in order (no allocation: this runs for every pixel).
        let triangles: [Option<[Vec3; 3]>; 2] = match quad {
            // Without normals a crease is told only by four pixels off one plane: only four
            // coplanar ones are taken.
            [Some(p00), Some(p10), Some(p01), Some(p11)]
                if nrm.is_none() && !coplanar([p00, p10, p01, p11]) =>
            {
                [None, None]
            }
            [Some(p00), Some(p10), Some(p01), Some(p11)] => {
                // Of each split (along 00–11, along 10–01) the half holding q; the split that
                // folds less first.
                let main = [[p00, p10, p11], [p00, p11, p01]];
                let anti = [[p00, p10, p01], [p10, p11, p01]];
                let fold = |[a, b]: [[Vec3; 3]; 2]| -normal_of(a).dot(normal_of(b)).abs();
                let main_half = main[usize::from(ax < ay)];
                let anti_half = anti[usize::from(ax + ay > 1.0)];
                match fold(main) <= fold(anti) {
                    true => [Some(main_half), Some(anti_half)],
                    false => [Some(anti_half), Some(main_half)],
                }
            }
            _ if nrm.is_none() => [None, None],
            // Three on the surface: their triangle, where it holds q (the half of the quad
            // towards the fourth is past the surface's edge: never extrapolated).
            [None, Some(p10), Some(p01), Some(p11)] if ax + ay >= 1.0 => {
                [Some([p10, p01, p11]), None]
            }
            [Some(p00), None, Some(p01), Some(p11)] if ax <= ay => [Some([p00, p01, p11]), None],
            [Some(p00), Some(p10), None, Some(p11)] if ax >= ay => [Some([p00, p10, p11]), None],
            [Some(p00), Some(p10), Some(p01), None] if ax + ay <= 1.0 => {
                [Some([p00, p10, p01]), None]
            }
            _ => [None, None],
        };
        triangles
            .into_iter()
            .flatten()
            .find_map(|t| ray_meets_triangle_plane(t, ray))
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

/// Whether four neighbouring points lie on one plane: the fourth within
/// [`COPLANAR_TOLERANCE`] of their spacing of the plane through the other three (the position
/// pass is float32: about 1e-7 of the distance from the origin, hence also 10 µm absolute).
fn coplanar([p00, p10, p01, p11]: [Vec3; 4]) -> bool {
    let (u, v) = (p10 - p00, p01 - p00);
    let n = u.cross(v);
    let off_plane = n.dot(p11 - p00).abs() / n.length().max(Real::MIN_POSITIVE);
    off_plane <= COPLANAR_TOLERANCE * u.length().max(v.length()) + 1e-5
}

/// Unit normal of a triangle (zero if degenerate).
fn normal_of([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a).normalize_or_zero()
}

/// Where the ray from the origin along `ray` meets the plane of `triangle`, if it does within
/// the triangle's neighbourhood (no farther from its corners than twice its longest edge: a
/// plane seen edge-on sends the ray far away).
fn ray_meets_triangle_plane(triangle: [Vec3; 3], ray: Vec3) -> Option<Vec3> {
    let [a, b, c] = triangle;
    let normal = (b - a).cross(c - a);
    let denom = normal.dot(ray);
    if denom.abs() <= 1e-12 * normal.length() * ray.length() || normal == Vec3::ZERO {
        return None;
    }
    let t = normal.dot(a) / denom;
    let x = t * ray;
    let edge = (b - a).length().max((c - b).length()).max((a - c).length());
    (t > 0.0 && (x - a).length() <= 2.0 * edge + 1e-6).then_some(x)
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
#[cfg(test)]
pub(crate) fn assemble_frame(
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
/// same for every frame of a camera, so a take computes it once per camera (28 bytes a pixel:
/// 56 MB for a full-size Aria RGB camera) instead of unprojecting and reprojecting every
/// pixel of every frame (0.5 s of a full-size RGB frame's assembly on one core).
pub(crate) struct RemapTable {
    render: RenderCamera,
    target: Camera,
    /// Per target pixel (row-major), NaN where it is not valid.
    source_px: Vec<Pixel>,
    /// Per target pixel, its exact model's unit ray (camera frame; zero where not valid): where
    /// its surface point is sought.
    rays: Vec<[f32; 3]>,
}

impl std::fmt::Debug for RemapTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let res = self.target.resolution();
        write!(f, "RemapTable({}×{})", res.width_px, res.height_px)
    }
}

impl RemapTable {
    /// The table of `target` read from `render` (rows on rayon's pool).
    pub(crate) fn new(render: &RenderCamera, target: &Camera) -> Self {
        use rayon::prelude::*;
        let res = target.resolution();
        let (w, h) = (res.width_px as usize, res.height_px as usize);
        let mut source_px = vec![Pixel::NAN; w * h];
        let mut rays = vec![[0.0f32; 3]; w * h];
        source_px
            .par_chunks_mut(w.max(1))
            .zip(rays.par_chunks_mut(w.max(1)))
            .enumerate()
            .for_each(|(y, (row, row_rays))| {
                for (x, (q, r)) in row.iter_mut().zip(row_rays).enumerate() {
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
                        *r = ray.normalize().as_vec3().to_array();
                    }
                }
            });
        Self {
            render: *render,
            target: target.clone(),
            source_px,
            rays,
        }
    }

    /// `assemble_frame` with this table's render and camera.
    pub(crate) fn assemble(
        &self,
        rgb_exr: Option<&Path>,
        ground_truth_exr: Option<&Path>,
        world_from_cam: Affine3,
    ) -> Result<FrameImage, FrameFileError> {
        let rgb = rgb_exr.map(|p| Raw::read(p, &self.render)).transpose()?;
        let gt = ground_truth_exr
            .map(|p| Raw::read(p, &self.render))
            .transpose()?;
        assemble_with(self, rgb, gt, world_from_cam)
    }
}

/// The planes of a ground-truth raw, each where it was rendered.
#[derive(Default)]
struct GroundTruthPlanes<'a> {
    /// Alpha: 1 where a surface was hit.
    hit: Option<&'a [f32]>,
    pos: Option<[&'a [f32]; 3]>,
    nrm: Option<[&'a [f32]; 3]>,
    ids: Option<&'a [f32]>,
    vec: Option<[&'a [f32]; 4]>,
    /// The bodies' parts (an AOV beside the object index; absent where a raw has none).
    parts: Option<&'a [f32]>,
    /// The bodies' garments (an AOV, where people wear outfits).
    garments: Option<&'a [f32]>,
}

impl<'a> GroundTruthPlanes<'a> {
    fn of(gt: &'a Raw) -> Result<Self, FrameFileError> {
        let has = |pass: &str| gt.contents.channel(&format!("ViewLayer.{pass}")).is_some();
        Ok(Self {
            hit: Some(gt.plane("Combined.A")?),
            pos: has("Position.X")
                .then(|| gt.planes("Position", ["X", "Y", "Z"]))
                .transpose()?,
            nrm: has("Normal.X")
                .then(|| gt.planes("Normal", ["X", "Y", "Z"]))
                .transpose()?,
            ids: has("IndexOB.X")
                .then(|| gt.plane("IndexOB.X"))
                .transpose()?,
            vec: has("Vector.X")
                .then(|| gt.planes("Vector", ["X", "Y", "Z", "W"]))
                .transpose()?,
            parts: has("part.X").then(|| gt.plane("part.X")).transpose()?,
            garments: has("garment.X")
                .then(|| gt.plane("garment.X"))
                .transpose()?,
        })
    }
}

/// Copies the label (an id, a body part, a garment) at rendered pixel `n` of `plane` to pixel
/// `i` of `out`, where both are there.
fn copy_label(out: &mut Option<Vec<u32>>, plane: Option<&[f32]>, i: usize, n: usize) {
    if let (Some(out), Some(plane)) = (out.as_mut(), plane) {
        out[i] = plane[n].round() as u32;
    }
}

fn assemble_with(
    remap: &RemapTable,
    rgb: Option<Raw>,
    gt: Option<Raw>,
    world_from_cam: Affine3,
) -> Result<FrameImage, FrameFileError> {
    let (render, target) = (&remap.render, &remap.target);
    let render_seconds = [
        (&rgb, ["colour_sync", "colour_path_tracing"]),
        (&gt, ["ground_truth_sync", "ground_truth_path_tracing"]),
    ]
    .into_iter()
    .filter_map(|(raw, stages)| Some(cycles_seconds(&raw.as_ref()?.contents, stages)))
    .flatten()
    .collect();
    let colour = rgb
        .as_ref()
        .map(|r| r.planes("Combined", ["R", "G", "B", "A"]))
        .transpose()?;
    let GroundTruthPlanes {
        hit,
        pos,
        nrm,
        ids,
        vec,
        parts,
        garments,
    } = match &gt {
        None => GroundTruthPlanes::default(),
        Some(gt) => GroundTruthPlanes::of(gt)?,
    };
    // A surface point is taken from pixels of one object, and on a person of one body part: a
    // hand held before the torso is not one surface with it.
    let surfaces: Option<Vec<f32>> = ids.map(|ids| match parts {
        Some(parts) => ids.iter().zip(parts).map(|(&i, &p)| i * 8.0 + p).collect(),
        None => ids.to_vec(),
    });
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
        body_parts: ids.map(|_| vec![0; n_px]),
        garments: ids.and(garments).map(|_| vec![0; n_px]),
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
                let nearest = || {
                    cam_from_world.transform_point3(Vec3::new(
                        pos[0][n] as Real,
                        pos[1][n] as Real,
                        pos[2][n] as Real,
                    ))
                };
                let ray = Vec3::from(remap.rays[i].map(Real::from));
                let in_cam = match render.is_identity() {
                    // The render's pixel is the frame's: its point is on the pixel's ray.
                    true => nearest(),
                    false => gt
                        .surface_point(
                            pos,
                            nrm.as_ref(),
                            hit,
                            surfaces.as_deref(),
                            q,
                            |px| render.renders(px),
                            &cam_from_world,
                            ray,
                        )
                        .unwrap_or_else(nearest),
                };
                let world = world_from_cam.transform_point3(in_cam);
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
            copy_label(&mut out.segmentation, ids, i, n);
            copy_label(&mut out.body_parts, ids.and(parts), i, n);
            copy_label(&mut out.garments, ids.and(garments), i, n);
            if let Some(vec) = &vec {
                // Blender's vector pass, pixels in Blender's raster (y up), measured
                // (`src/supervisor/render_tests/`): (X, Y) = previous − here, (Z, W) = here − next.
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

    /// A ground-truth raw of `render` looking (camera = world frame) at a floor (`y = 1`,
    /// OpenCV axes: below the camera) meeting a back wall (`z = 3`) in one object, and a
    /// ball of another in front of them; and the true surface point of every ray.
    fn room_raw(render: &RenderCamera, normals: bool) -> (Raw, impl Fn(Vec3) -> Option<Vec3>) {
        let (centre, radius) = (Vec3::new(0.3, -0.2, 1.5), 0.3);
        let hit = move |d: Vec3| -> Option<(Vec3, Vec3, f32)> {
            let mut best: Option<(Real, Vec3, f32)> = None;
            let mut take = |t: Real, normal: Vec3, id: f32| {
                if t > 0.0 && best.is_none_or(|b| t < b.0) {
                    best = Some((t, normal, id));
                }
            };
            if d.y > 0.0 {
                take(1.0 / d.y, Vec3::new(0.0, -1.0, 0.0), 1.0);
            }
            if d.z > 0.0 {
                take(3.0 / d.z, Vec3::new(0.0, 0.0, -1.0), 1.0);
            }
            let (b, c) = (d.dot(centre), centre.length_squared() - radius * radius);
            if b * b - c >= 0.0 {
                let t = b - (b * b - c).sqrt();
                take(t, (t * d - centre) / radius, 2.0);
            }
            best.map(|(t, normal, id)| (t * d, normal, id))
        };
        let res = render.resolution();
        let (w, h) = (res.width_px as usize, res.height_px as usize);
        let mut planes = vec![vec![0.0f32; w * h]; 8];
        for i in 0..w * h {
            let px = Pixel::new((i % w) as Real, (i / w) as Real);
            let Some((p, normal, id)) = render.pixel_to_ray(px).and_then(hit) else {
                continue;
            };
            let v = [1.0, p.x, p.y, p.z, normal.x, normal.y, normal.z, id as Real];
            for (plane, v) in planes.iter_mut().zip(v) {
                plane[i] = v as f32;
            }
        }
        let names = [
            "Combined.A",
            "Position.X",
            "Position.Y",
            "Position.Z",
            "Normal.X",
            "Normal.Y",
            "Normal.Z",
            "IndexOB.X",
        ];
        let channels = names
            .iter()
            .zip(planes)
            .filter(|(name, _)| normals || !name.starts_with("Normal"))
            .map(|(name, values)| crate::exr_file::ExrChannel {
                name: format!("ViewLayer.{name}"),
                sample_type: "f32",
                width: w,
                height: h,
                values,
                compression: "ZIP".into(),
            })
            .collect();
        let contents = ExrContents {
            path: "room.exr".into(),
            parts: 1,
            channels,
            passes: Vec::new(),
            attributes: Default::default(),
        };
        let raw = Raw {
            contents,
            width: w,
            height: h,
        };
        (raw, move |d: Vec3| hit(d).map(|(p, _, _)| p))
    }

    /// Every Aria camera at SLAM and RGB size: the surface point of (nearly) every pixel lies
    /// on the pixel's own ray, on the surface the ray meets (planes: to float precision), and
    /// no farther from it than the nearest rendered pixel's point is.
    #[test]
    fn surface_points_lie_on_their_pixels_rays() {
        use crate::rig::Rig;
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let rig = Rig::load(&root.join("camera_rigs/aria_gen1.json")).unwrap();
        for (name, scale, normals) in [
            ("camera-slam-left", 0.25, true),
            ("camera-slam-right", 0.5, true),
            ("camera-rgb", 0.125, true),
            // Without the Normal pass: only four coplanar pixels are interpolated.
            ("camera-slam-left", 0.25, false),
        ] {
            let target = rig.camera(name).unwrap().model.scaled(scale).unwrap();
            let render = RenderCamera::exact(&target, 1.0);
            assert!(!render.is_identity(), "{name}: remapped");
            let (raw, truth) = room_raw(&render, normals);
            let remap = RemapTable::new(&render, &target);
            let frame = assemble_with(&remap, None, Some(raw), Affine3::IDENTITY).unwrap();
            let (mut surface, mut on_ray, mut on_plane, mut planar) = (0, 0, 0, 0);
            let mut errors = Vec::new();
            for (i, p) in frame.position.as_ref().unwrap().iter().enumerate() {
                if frame.depth.as_ref().unwrap()[i] <= 0.0 {
                    continue;
                }
                surface += 1;
                let px = Pixel::new((i % frame.width) as Real, (i / frame.width) as Real);
                let p = Vec3::new(p[0] as Real, p[1] as Real, p[2] as Real);
                // Never past its object's edge: a ball pixel's point inside the ball, a room
                // pixel's inside the room.
                let past_edge = match frame.segmentation.as_ref().unwrap()[i] {
                    2 => (p - Vec3::new(0.3, -0.2, 1.5)).length() > 0.3 + 1e-4,
                    _ => p.y > 1.0 + 1e-4 || p.z > 3.0 + 1e-4,
                };
                assert!(!past_edge, "{name}: {p:?} past its object's edge");
                if let Some(back) = target.project(p) {
                    on_ray += usize::from((back - px).length() < 1e-3);
                }
                let ray = target.unproject(px).unwrap();
                let Some(truth) = truth(ray) else { continue };
                let err = (p - truth).length();
                errors.push(err);
                // Floor or wall pixels 2–3 rendered pixels away from the crease and the ball's
                // outline.
                let ball = Vec3::new(0.3, -0.2, 1.5);
                let off_ball = ray.angle_between(ball) - (0.3 / ball.length()).asin();
                let planar_here = ((truth.y - 1.0).abs() < 1e-9 && truth.z < 2.85)
                    || ((truth.z - 3.0).abs() < 1e-9 && truth.y < 0.85);
                if planar_here && off_ball > 0.05 {
                    planar += 1;
                    let exact = err < 2e-5 * truth.length();
                    on_plane += usize::from(exact);
                }
            }
            errors.sort_by(Real::total_cmp);
            let on_ray_share = on_ray as Real / surface as Real;
            eprintln!(
                "{name} ×{scale}: {surface} surface pixels, {:.2} % on their own ray, plane \
                 pixels exact {on_plane}/{planar}, error median {:.2e} m, p99 {:.2e} m",
                100.0 * on_ray_share,
                errors[errors.len() / 2],
                errors[errors.len() * 99 / 100]
            );
            // Without normals a quad across a crease is not interpolated; nor, far away, is a
            // plane pixel within a rendered pixel of the crease.
            let (share, missed) = if normals {
                (0.98, 0)
            } else {
                (0.95, planar / 1000)
            };
            assert!(on_ray_share > share, "{name}: {on_ray_share}");
            assert!(
                planar > 100 && on_plane + missed >= planar,
                "{name}: {on_plane}/{planar}"
            );
        }
    }

    #[test]
    fn blender_durations_read_as_seconds() {
        assert_eq!(blender_duration_seconds("00:00.20"), Some(0.2));
        assert_eq!(blender_duration_seconds("01:02:03.50"), Some(3723.5));
        assert_eq!(blender_duration_seconds(" 00:13.25 "), Some(13.25));
        assert_eq!(blender_duration_seconds("00:xx"), None);
        assert_eq!(blender_duration_seconds(""), None);
    }
}
