#!/usr/bin/env python3
"""Standard vision on a finished egogen take: does it work on these images, depth and poses?

A take is the dataset folder `egogen-run` writes (`manifest.json`, `cameras/<camera>/` frame
files and `annotations.json`, `images/<camera>/` and `colmap/<camera>/`, the COLMAP export;
docs/ANNOTATIONS.md, docs/RENDERING.md). Three measures, each on one camera (default
`camera-rgb`), each printing a short table and, with `--json OUT`, writing its numbers:

  features  SIFT features per frame and two-view geometry between consecutive frames
            (pycolmap): features per frame, putative and inlier matches per pair (medians), the
            share of pairs with a valid calibrated relative pose, and for those the error of the
            estimated relative rotation against the ground truth's (median, share < 5 deg).
  sfm       pycolmap's incremental mapping (its default options, the exported camera held
            fixed, no poses given): share of frames registered, camera-centre error after a
            similarity (Umeyama, with scale) alignment to the ground-truth centres (RMSE,
            median) beside the ground-truth path length. Nothing reconstructed is a result,
            not an error: it is said and the tool exits 0.
  tsdf      the take's depth fused with the ground-truth poses (Open3D TSDF) against the scene
            mesh: Chamfer distance (mean of both directions), share of fused points within
            2 cm of the mesh; and per-pixel checks of the depth against the mesh and the
            position pass. `--depth noisy` fuses the sensor-noise channel (depth_noisy.Z)
            instead of the exact depth.

Install (Python >= 3.11; Open3D's Linux wheel needs the system's libusb-1.0, e.g. Debian's
`apt-get install libusb-1.0-0`):

  python3 -m venv VENV
  VENV/bin/pip install -r tools/vision_checks_requirements.txt ./python

Run (TAKE: the take's folder, e.g. out/default; each prints its table in seconds for a
take of ~40 frames):

  VENV/bin/python tools/vision_checks.py features TAKE [--camera NAME] [--max-frames N] [--rectify] [--mask-people] [--threads N] [--json OUT [--replace]]
  VENV/bin/python tools/vision_checks.py sfm TAKE [--camera NAME] [--max-frames N] [--rectify | --colmap-defaults] [--mask-people] [--threads N] [--json OUT [--replace]]
  VENV/bin/python tools/vision_checks.py tsdf TAKE [--camera NAME] [--voxel-m 0.02] [--max-frames N] [--scene FILE] [--json OUT [--replace]]

Conventions (as docs/RENDERING.md "COLMAP export" uses them with the colmap CLI):

- The camera is the take's `colmap/<camera>/cameras.txt` as it is: COLMAP's model name and
  parameters (Aria Fisheye624 -> `RAD_TAN_THIN_PRISM_FISHEYE`, exact; principal point written
  as c + 0.5, COLMAP's pixel convention), given to the feature extractor as a single camera
  with known parameters (`ImageReaderOptions.camera_model/camera_params`), so two-view
  geometry is the calibrated one and the mapper starts from that camera. The images are the
  export's `images/<camera>/frame_NNNNN.png`. Outside the lens's valid field of view the
  images are black; a camera mask from the frame files' `valid.V` (eroded by 2 px) keeps SIFT
  off that border (`ImageReaderOptions.camera_mask_path`).
- Ground truth is each frame's `T_world_cam` in `cameras/<camera>/annotations.json` (OpenCV
  camera frame, world z up). `features` also checks that `colmap/<camera>/images.txt` holds
  the same poses.
- features: `pycolmap.extract_features` (default SIFT options, CPU),
  `pycolmap.match_sequential` with `SequentialPairingOptions(overlap=1,
  quadratic_overlap=False)` (each frame with the next; default matching and two-view
  geometry options otherwise). Putative matches are the database's `matches`, inliers its
  `two_view_geometries`. A pair has a valid relative pose when its geometry is CALIBRATED,
  PLANAR, PANORAMIC or PLANAR_OR_PANORAMIC and `pycolmap.estimate_two_view_geometry_pose`
  recovers cam2_from_cam1 from the inliers; its rotation error is the angle of
  R_est^T R_gt with R_gt = R_world_cam2^T R_world_cam1. The translation direction's angle
  error is printed too (ill-posed at small baselines).
  Caveat, COLMAP's own: when a homography explains > 80 % of the E inliers (small motion
  between frames: every pair here) the pair is PLANAR_OR_PANORAMIC and its pose comes from a
  homography fitted to the raw (fisheye) pixels and decomposed with the pinhole part of the
  camera, which is not the fisheye's geometry. Two rows beside it tell that from the data:
  the rotation of an essential matrix on the same inliers' camera rays
  (`pycolmap.estimate_relative_pose` + `refine_relative_pose`), and the inliers' epipolar
  error under the ground-truth relative pose (symmetric angle to the epipolar plane, in
  pixels at the focal length): small when images, camera model and poses agree.
- sfm: `pycolmap.extract_features` on every frame, `pycolmap.match_exhaustive` (default
  options), `pycolmap.incremental_mapping` with `IncrementalPipelineOptions()` except that
  the camera is held fixed (`ba_refine_focal_length`, `ba_refine_principal_point`,
  `ba_refine_extra_params`, and the mapper's `abs_pose_refine_focal_length`,
  `abs_pose_refine_extra_params` all false). The model with the most registered frames is
  measured; the others are counted. COLMAP's default `max_extra_param` (1) rejects a camera
  with a larger distortion coefficient as diverged self-calibration ("bad initial pair",
  nothing reconstructed); the Aria RGB Fisheye624 has |k| up to 1.77 by design, so with the
  camera held fixed the limit is raised just above the camera's own coefficients
  (`--colmap-defaults` keeps 1). Seeds are fixed (`pycolmap.set_random_seed(0)`, RANSAC and
  mapper `random_seed = 0`), but COLMAP's threads still make runs differ (on one take: SfM
  centre RMSE 0.31-1.10 m over repeats, docs/VISION_CHECKS.md); `--threads 1` (features, sfm:
  `num_threads` of extraction, matching and mapping) makes a run repeat exactly.
- `--rectify` (features, sfm): the frames are first resampled onto a pinhole ("linear")
  camera of the same size and focal length, principal point at the image centre, as
  projectaria_tools' `distort_by_calibration` onto `get_linear_camera_calibration` does: each
  pinhole pixel's ray projected into the fisheye image with the exported camera (exact), the
  8-bit colour interpolated bilinearly there; the camera mask is the pinhole pixels whose four
  source pixels lie inside `valid.V`, eroded by 2 px. The measure then runs on the `PINHOLE`
  camera (no distortion parameters: COLMAP's `max_extra_param` is never raised). The ground
  truth is unchanged: the pinhole has the fisheye's camera frame.
- `--mask-people` (features, sfm): per-image masks (`ImageReaderOptions.mask_path`) instead of
  the camera mask: each frame's `valid.V` without its people (`segmentation.id` >= 1000), grown
  by 1/200 of the width (the segmentation is rendered without motion blur, the colour with it),
  eroded by 2 px; resampled like the images with `--rectify`.
- tsdf: the fisheye is resampled to pinholes, not integrated as a fisheye. Each pixel's ray
  comes from the exported COLMAP camera (`Camera.cam_from_img`, egogen pixel centre (u, v) =
  COLMAP (u + 0.5, v + 0.5); pixels whose ray does not project back within 0.01 px are
  dropped and counted), the depth (planar: z in the camera frame) gives the pixel's point in
  the camera frame, and the frame is resampled onto five 90-degree pinhole faces of a cube
  around the camera (each face pixel's ray projected into the fisheye image, the range there
  interpolated bilinearly between the four pixels around it where they hold one surface, else
  the nearest pixel's, so that the face's point lies on its own ray; front,
  left, right, up, down: together they hold every ray < 90 deg off axis, the whole fisheye),
  each integrated with the ground-truth pose into Open3D's tensor TSDF
  (`open3d.t.geometry.VoxelBlockGrid`: voxel `--voxel-m`, truncation 4 voxels, depth up to
  `--max-depth-m`). The fused surface is the vertices of its zero crossing
  (`extract_triangle_mesh(weight_threshold=0.5)`: every surface at least one frame saw; the
  legacy `ScalableTSDFVolume` and `extract_point_cloud` return nothing in open3d-cpu 0.20).
  Masks: only pixels inside `valid.V`, with depth, whose `segmentation.id` is an object of the
  scene file are fused: people (ids of the agents, from 1000), the ceiling egogen adds
  (`egogen_ceiling`) and `[[obstacles]]` boxes (`obstacle_NN`) are not in the scene file and
  are left out.
  The scene mesh is the file the take names (`sequence/summary.json`, `about.scene`,
  `scene_up_axis`, `scene_unit_m`; `--scene` overrides the path), read with trimesh (node
  transforms applied) and turned into egogen's world as `src/scene/load/` does: a y-up
  file's (x, y, z) becomes (x, -z, y) (glTF is y up unless the take says otherwise; OBJ and
  PLY z up), times `unit_m`.
  What the camera saw: the same pixels' rays (ground-truth pose, exported camera) cast
  against the scene mesh (Open3D `RaycastingScene`); their first hits, thinned to one per
  voxel/2 cube, are the seen part of the mesh. Chamfer = (mean distance of fused points to
  the whole mesh's triangles + mean distance of seen-mesh points to the nearest fused point)
  / 2. The share within 2 cm is of fused points, to the mesh's triangles.
  Per-pixel checks beside it: the depth's ray length against the mesh hit's (median |diff|,
  share within 2 cm, rays that miss the mesh); where the take has the `position` pass, the
  depth-unprojected world point against it, and its points' distance to the mesh (which
  tells a wrong scene transform from wrong depth or poses).

Errors (no take, no such camera, no COLMAP export, no depth, no scene file) print one line
naming the file and what was expected, and exit 2.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import arguments
import outputs


class ToolError(Exception):
    """A clear, expected failure: printed as one line, exit status 2."""


# ---------------------------------------------------------------------------------------------
# The take


def _import_reader():
    try:
        from egogen import reader
    except ImportError:
        here = Path(__file__).resolve().parent.parent / "python"
        sys.path.insert(0, str(here))
        try:
            from egogen import reader
        except ImportError as e:
            raise ToolError(f"cannot import egogen's reader ({e}); install it: pip install ./python") from e
    return reader


def open_take(path: str):
    reader = _import_reader()
    p = Path(path)
    if not p.exists():
        raise ToolError(f"{p}: no such folder (expected a take: the folder egogen-run writes, with manifest.json)")
    if not p.is_dir():
        raise ToolError(f"{p}: not a folder (expected a take: the folder egogen-run writes, with manifest.json)")
    if not (p / "manifest.json").is_file():
        hint = ""
        if Path(str(p) + ".partial").is_dir() or p.name.endswith(".partial"):
            hint = "; an unfinished run: finish it with `egogen-run CONFIG --resume`"
        elif (p / "campaign.json").is_file():
            hint = "; this is a campaign: pass one of its takes, TAKE/takes/<id>"
        raise ToolError(f"{p / 'manifest.json'}: no such file (expected a finished egogen take{hint})")
    return reader.Take(p)


def camera_annotations(take, camera: str) -> dict:
    p = take.path / "cameras" / camera / "annotations.json"
    if not p.is_file():
        cams = take.cameras if (take.path / "cameras").is_dir() else []
        raise ToolError(f"{p}: no such file (no camera {camera!r} in this take; its cameras: {', '.join(cams) or 'none'})")
    return take.annotations(camera)


def camera_frames(take, camera: str, max_frames: int | None) -> list:
    camera_annotations(take, camera)
    frames = list(take.frames(camera))
    if not frames:
        raise ToolError(f"{take.path / 'cameras' / camera / 'annotations.json'}: key frames: empty (expected rendered frames)")
    frames.sort(key=lambda f: f.index)
    if max_frames is not None:
        if max_frames < 1:
            raise ToolError(f"--max-frames {max_frames}: expected at least 1")
        frames = frames[:max_frames]
    return frames


def image_name(frame) -> str:
    return Path(frame.path.name).with_suffix(".png").name


def read_colmap_camera_file(take, camera: str):
    """(model, width, height, params) of `colmap/<camera>/cameras.txt`."""
    p = take.path / "colmap" / camera / "cameras.txt"
    if not p.is_file():
        raise ToolError(
            f"{p}: no such file (expected the take's COLMAP export of {camera}: "
            "a take rendered with colour and `[render] colmap` on, the default)"
        )
    lines = [l.split() for l in p.read_text().splitlines() if l.strip() and not l.lstrip().startswith("#")]
    if len(lines) != 1 or len(lines[0]) < 5:
        raise ToolError(f"{p}: expected one camera line `1 MODEL WIDTH HEIGHT PARAMS...`, found {len(lines)} lines")
    f = lines[0]
    try:
        return f[1], int(f[2]), int(f[3]), [float(x) for x in f[4:]]
    except ValueError as e:
        raise ToolError(f"{p}: camera line not `ID MODEL WIDTH HEIGHT PARAMS...` ({e})") from e


def colmap_camera_from_annotations(take, camera: str):
    """The COLMAP camera egogen's export writes (src/export/colmap.rs), from the annotations:
    for a take without the COLMAP export (depth only)."""
    doc = camera_annotations(take, camera)
    cam = doc["camera"]
    m = cam["model"]
    w, h = cam["resolution_px"]
    t = m.get("type")
    if t == "fisheye624":
        f, cx, cy, *rest = m["params"]
        return "RAD_TAN_THIN_PRISM_FISHEYE", w, h, [f, f, cx + 0.5, cy + 0.5, *rest]
    if t == "pinhole":
        return "PINHOLE", w, h, [m["fx"], m["fy"], m["cx"] + 0.5, m["cy"] + 0.5]
    if t == "kannala_brandt4":
        return "OPENCV_FISHEYE", w, h, [m["fx"], m["fy"], m["cx"] + 0.5, m["cy"] + 0.5, m["k1"], m["k2"], m["k3"], m["k4"]]
    p = take.path / "cameras" / camera / "annotations.json"
    raise ToolError(f"{p}: key camera.model.type: {t!r} (expected fisheye624, pinhole or kannala_brandt4)")


def pycolmap_camera(model, w, h, params):
    import pycolmap

    cam = pycolmap.Camera(model=model, width=w, height=h, params=params, camera_id=1)
    return cam


def read_colmap_images(take, camera: str) -> dict:
    """name -> T_cam_world (4x4) of `colmap/<camera>/images.txt`."""
    p = take.path / "colmap" / camera / "images.txt"
    if not p.is_file():
        return {}
    out = {}
    lines = [l for l in p.read_text().splitlines() if not l.startswith("#")]
    for i in range(0, len(lines), 2):
        f = lines[i].split()
        if len(f) < 10:
            continue
        qw, qx, qy, qz, tx, ty, tz = map(float, f[1:8])
        T = np.eye(4)
        T[:3, :3] = quat_to_rot(qw, qx, qy, qz)
        T[:3, 3] = [tx, ty, tz]
        out[f[9]] = T
    return out


def quat_to_rot(w, x, y, z) -> np.ndarray:
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def epipolar_errors_px(camera, p1, p2, T_c2_c1) -> np.ndarray:
    """Per match, how far the ground-truth relative pose puts the two rays off their epipolar
    plane (symmetric angle, in pixels at the camera's focal length); with no baseline, the
    angle between the second ray and the first one rotated."""
    r1 = np.asarray(camera.cam_ray_from_img(p1), dtype=np.float64)
    r2 = np.asarray(camera.cam_ray_from_img(p2), dtype=np.float64)
    R, t = T_c2_c1[:3, :3], T_c2_c1[:3, 3]
    r1r = r1 @ R.T
    if np.linalg.norm(t) < 1e-9:
        ang = np.arccos(np.clip((r1r * r2).sum(1), -1, 1))
    else:
        n2 = np.cross(t, r1r)  # the epipolar plane in camera 2
        n1 = np.cross(R.T @ t, r2 @ R)  # ... and in camera 1
        s2 = np.abs((n2 * r2).sum(1)) / np.maximum(np.linalg.norm(n2, axis=1), 1e-15)
        s1 = np.abs((n1 * r1).sum(1)) / np.maximum(np.linalg.norm(n1, axis=1), 1e-15)
        ang = (np.arcsin(np.clip(s1, 0, 1)) + np.arcsin(np.clip(s2, 0, 1))) / 2
    return ang * float(camera.mean_focal_length())


def rot_angle_deg(R: np.ndarray) -> float:
    c = (np.trace(R) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def read_frame(frame, groups):
    """A frame file's groups; ToolError naming the file when it lacks one or is damaged."""
    reader = _import_reader()
    try:
        return frame.read(groups)
    except FileNotFoundError as e:
        raise ToolError(str(e)) from e
    except reader.FormatError as e:
        raise ToolError(str(e)) from e
    except KeyError as e:
        msg = e.args[0] if e.args else str(e)
        raise ToolError(str(msg)) from e


def frame_groups(frame) -> set:
    """The channel groups a frame file holds (`depth`, `segmentation`, `position`, ...)."""
    if not frame.path.is_file():
        raise ToolError(f"{frame.path}: no such frame file (named by {frame.annotations})")
    return set(read_frame(frame, None))


def valid_mask(frame) -> np.ndarray:
    return read_frame(frame, ["valid"])["valid"] > 0.5


def write_camera_mask(frames, out: Path, size) -> Path | None:
    """A COLMAP camera mask (white = use) from the first frame's valid.V, eroded by 2 px."""
    from PIL import Image

    if not frames[0].path.is_file():
        return None
    v = valid_mask(frames[0])
    if v.shape[::-1] != tuple(size):
        return None
    v = erode(v, 2)
    Image.fromarray((v * 255).astype(np.uint8)).save(out)
    return out


def erode(v: np.ndarray, px: int) -> np.ndarray:
    for _ in range(px):
        e = v.copy()
        e[1:, :] &= v[:-1, :]
        e[:-1, :] &= v[1:, :]
        e[:, 1:] &= v[:, :-1]
        e[:, :-1] &= v[:, 1:]
        v = e
    return v


def bilinear(img: np.ndarray, at: np.ndarray) -> np.ndarray:
    """img (h, w[, c]) at continuous pixels `at` (..., 2; centres at integers, all finite and
    inside [-0.5, w-0.5] x [-0.5, h-0.5]), bilinear, edges clamped."""
    h, w = img.shape[:2]
    x = np.clip(at[..., 0], 0, w - 1)
    y = np.clip(at[..., 1], 0, h - 1)
    x0 = np.clip(np.floor(x).astype(np.int64), 0, max(w - 2, 0))
    y0 = np.clip(np.floor(y).astype(np.int64), 0, max(h - 2, 0))
    ax, ay = x - x0, y - y0
    if img.ndim == 3:
        ax, ay = ax[..., None], ay[..., None]
    f = img.astype(np.float64)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    return (1 - ay) * ((1 - ax) * f[y0, x0] + ax * f[y0, x1]) + ay * ((1 - ax) * f[y1, x0] + ax * f[y1, x1])


def people_dilation_px(w: int) -> int:
    """How far a person's mask is grown: their motion-blurred edge reaches past the
    segmentation, which is rendered without blur (1/200 of the width, at least 2 px)."""
    return max(2, round(w / 200))


def frame_masks(frames, size, people: bool):
    """Per frame (image name -> bool array, True = use), the frame's `valid.V`, and with
    `people` its people (`segmentation.id` >= 1000, docs/ANNOTATIONS.md) taken out, grown by
    `people_dilation_px`; None without `people` (the camera mask serves every frame)."""
    if not people:
        return None
    w, h = size
    groups = frame_groups(frames[0])
    if "segmentation" not in groups:
        raise ToolError(
            f"{frames[0].path}: no segmentation.id channel (its channel groups: {', '.join(sorted(groups))}); "
            "--mask-people needs a take rendered with the `segmentation` pass"
        )
    out = {}
    for f in frames:
        d = read_frame(f, ["valid", "segmentation"])
        person = d["segmentation"] >= 1000
        grown = ~erode(~person, people_dilation_px(w))
        out[image_name(f)] = (d["valid"] > 0.5) & ~grown
    return out


def write_masks(masks: dict, out: Path) -> Path:
    """COLMAP's per-image masks: `<out>/<image name>.png`, white = use, eroded by 2 px."""
    from PIL import Image

    out.mkdir(parents=True, exist_ok=True)
    for name, m in masks.items():
        Image.fromarray((erode(m, 2) * 255).astype(np.uint8)).save(out / f"{name}.png")
    return out


def rectified_images(frames, image_dir: Path, names, fisheye, out: Path, masks=None):
    """The frames resampled onto a pinhole ("linear") camera of the same size and focal length,
    principal point at the image centre, as projectaria_tools' `distort_by_calibration` does onto
    `get_linear_camera_calibration`: each pinhole pixel's ray projected into the fisheye image
    (the exported camera, exact), its colour interpolated bilinearly there. Returns the pinhole's
    COLMAP camera (model, width, height, params), the folder of its images and its camera mask
    (pixels whose four source pixels are all inside the lens's valid field, eroded by 2 px);
    with per-frame `masks` (`frame_masks`), those resampled the same way instead."""
    from PIL import Image

    model, w, h, params = fisheye
    camera = pycolmap_camera(model, w, h, params)
    f = float(camera.mean_focal_length())
    cx, cy = w / 2.0, h / 2.0  # COLMAP's convention: the image centre
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    rays = np.stack([(u.ravel() + 0.5 - cx) / f, (v.ravel() + 0.5 - cy) / f, np.ones(w * h)], axis=1)
    _, ray_ok = fisheye_rays(camera, w, h)
    at = fisheye_pixels_of_rays(camera, rays, w, h, ray_ok).reshape(h, w, 2)
    inside = np.isfinite(at).all(axis=2)
    x0 = np.clip(np.floor(np.nan_to_num(at[..., 0])).astype(np.int64), 0, w - 2)
    y0 = np.clip(np.floor(np.nan_to_num(at[..., 1])).astype(np.int64), 0, h - 2)

    def resampled(src_ok: np.ndarray) -> np.ndarray:
        """Pinhole pixels whose four source pixels are all `src_ok`."""
        return inside & src_ok[y0, x0] & src_ok[y0, x0 + 1] & src_ok[y0 + 1, x0] & src_ok[y0 + 1, x0 + 1]

    src_valid = ray_ok
    if frames[0].path.is_file():
        src_valid = src_valid & valid_mask(frames[0])
    ok = resampled(src_valid)
    out.mkdir(parents=True, exist_ok=True)
    at_ok = at[ok]
    for name in names:
        img = np.asarray(Image.open(image_dir / name).convert("RGB"))
        rect = np.zeros((h, w, 3), np.uint8)
        rect[ok] = np.clip(np.rint(bilinear(img, at_ok)), 0, 255).astype(np.uint8)
        Image.fromarray(rect).save(out / name)
    camera_out = ("PINHOLE", w, h, [f, f, cx, cy])
    if masks is not None:
        rect_masks = {n: resampled(m & ray_ok) for n, m in masks.items()}
        return camera_out, out, None, write_masks(rect_masks, out.parent / "rectified_masks")
    mask = out.parent / "rectified_mask.png"
    Image.fromarray((erode(ok, 2) * 255).astype(np.uint8)).save(mask)
    return camera_out, out, mask, None


def prepare_images(args, frames, fisheye, image_dir: Path, work: Path):
    """(camera, image folder, camera mask, per-image mask folder) the measure runs on: the
    export's own, or with `--rectify` the frames resampled onto a pinhole camera
    (`rectified_images`); with `--mask-people`, per-image masks without the people."""
    names = [image_name(f) for f in frames]
    _, w, h, _ = fisheye
    masks = frame_masks(frames, (w, h), args.mask_people)
    if args.rectify:
        return rectified_images(frames, image_dir, names, fisheye, work / "rectified", masks)
    if masks is not None:
        return fisheye, image_dir, None, write_masks(masks, work / "masks")
    return fisheye, image_dir, write_camera_mask(frames, work / "mask.png", (w, h)), None


def quiet_colmap():
    import pycolmap

    try:
        pycolmap.logging.minloglevel = 3  # COLMAP's own log off: what failed is in the table
        pycolmap.logging.stderrthreshold = 3
    except Exception:
        pass


def check_images(take, camera: str, frames) -> Path:
    d = take.path / "images" / camera
    if not d.is_dir():
        raise ToolError(
            f"{d}: no such folder (expected the COLMAP export's images of {camera}: a take rendered "
            "with colour and `[render] colmap` on, the default)"
        )
    from PIL import Image

    for f in frames:
        path = d / image_name(f)
        if not path.is_file():
            raise ToolError(f"{path}: no such file (expected the image of frame {f.index}, named in {f.annotations})")
        try:
            with Image.open(path) as im:
                im.load()  # every byte decoded: a truncated file is refused, not counted as a frame
        except (OSError, SyntaxError, ValueError) as e:
            raise ToolError(f"{path}: not a whole image ({e}); the take's image of frame {f.index} is damaged")
    return d


def seeded_verification():
    """COLMAP's default two-view geometry options with RANSAC's random seed fixed."""
    import pycolmap

    opts = pycolmap.TwoViewGeometryOptions()
    opts.ransac.random_seed = 0
    return opts


def threads(args) -> int:
    """COLMAP's num_threads: -1 (every core, its default) unless `--threads N`."""
    return args.threads or -1


def matching_options(args):
    import pycolmap

    opts = pycolmap.FeatureMatchingOptions()
    opts.num_threads = threads(args)
    return opts


def extract(db: Path, image_dir: Path, names, model, params, mask, image_masks=None, num_threads=-1):
    import pycolmap

    extraction_options = pycolmap.FeatureExtractionOptions()
    extraction_options.num_threads = num_threads
    reader_options = pycolmap.ImageReaderOptions(camera_model=model, camera_params=",".join(repr(float(p)) for p in params))
    if mask is not None:
        reader_options.camera_mask_path = str(mask)
    if image_masks is not None:
        reader_options.mask_path = str(image_masks)
    pycolmap.extract_features(
        db,
        image_dir,
        image_names=list(names),
        camera_mode=pycolmap.CameraMode.SINGLE,
        reader_options=reader_options,
        extraction_options=extraction_options,
        device=pycolmap.Device.cpu,
    )


def median(xs):
    return float(np.median(xs)) if len(xs) else None


def fmt(x, spec=".3f", unit=""):
    if x is None:
        return "-"
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    return f"{x:{spec}}{unit}"


def print_table(title: str, rows):
    print(title)
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"  {k:<{width}}  {v}")


def write_json(path, doc, replace=False):
    if path is None:
        return
    outputs.write_json(path, doc, replace)
    print(f"wrote {path}")


# ---------------------------------------------------------------------------------------------
# features


def images_and_camera(args):
    """The take, the camera's frames, its exported COLMAP camera (model, width, height,
    parameters) and the folder of its images."""
    take = open_take(args.take)
    frames = camera_frames(take, args.camera, args.max_frames)
    camera = read_colmap_camera_file(take, args.camera)
    return take, frames, camera, check_images(take, args.camera, frames)


def cmd_features(args) -> dict:
    import pycolmap

    t0 = time.time()
    take, frames, (model, w, h, params), image_dir = images_and_camera(args)
    if len(frames) < 2:
        raise ToolError(f"{frames[0].annotations}: {len(frames)} frame; two-view geometry needs at least 2")

    # The export's poses against the annotations'.
    exported = read_colmap_images(take, args.camera)
    pose_check = None
    if exported:
        drot, dt = 0.0, 0.0
        for f in frames:
            T = exported.get(image_name(f))
            if T is None:
                continue
            G = np.linalg.inv(f.T_world_cam)
            drot = max(drot, rot_angle_deg(T[:3, :3].T @ G[:3, :3]))
            dt = max(dt, float(np.linalg.norm(T[:3, 3] - G[:3, 3])))
        pose_check = {"max_rotation_deg": drot, "max_translation_m": dt}

    quiet_colmap()
    pycolmap.set_random_seed(0)
    names = [image_name(f) for f in frames]
    work = Path(tempfile.mkdtemp(prefix="vision_checks_"))
    try:
        db_path = work / "database.db"
        (model, w, h, params), image_dir, mask, image_masks = prepare_images(args, frames, (model, w, h, params), image_dir, work)
        extract(db_path, image_dir, names, model, params, mask, image_masks, threads(args))
        pycolmap.match_sequential(
            db_path,
            matching_options=matching_options(args),
            pairing_options=pycolmap.SequentialPairingOptions(overlap=1, quadratic_overlap=False),
            verification_options=seeded_verification(),
            device=pycolmap.Device.cpu,
        )
        db = pycolmap.Database.open(db_path)
        try:
            ids = {im.name: im.image_id for im in db.read_all_images()}
            cam_db = db.read_all_cameras()[0]
            n_features = [int(db.num_keypoints_for_image(ids[n])) if n in ids else 0 for n in names]
            pairs = []
            ok_configs = {
                pycolmap.TwoViewGeometryConfiguration.CALIBRATED,
                pycolmap.TwoViewGeometryConfiguration.PLANAR,
                pycolmap.TwoViewGeometryConfiguration.PANORAMIC,
                pycolmap.TwoViewGeometryConfiguration.PLANAR_OR_PANORAMIC,
            }
            for a, b in zip(frames[:-1], frames[1:]):
                na, nb = image_name(a), image_name(b)
                ia, ib = ids.get(na), ids.get(nb)
                pair = {"frame1": a.index, "frame2": b.index, "putative": 0, "inliers": 0, "config": "UNDEFINED", "pose": False}
                T_c2_c1 = np.linalg.inv(b.T_world_cam) @ a.T_world_cam
                pair["gt_rotation_deg"] = rot_angle_deg(T_c2_c1[:3, :3])
                pair["gt_translation_m"] = float(np.linalg.norm(T_c2_c1[:3, 3]))
                if ia is not None and ib is not None and db.exists_matches(ia, ib):
                    pair["putative"] = int(len(db.read_matches(ia, ib)))
                if ia is not None and ib is not None and db.exists_two_view_geometry(ia, ib):
                    tvg = db.read_two_view_geometry(ia, ib)
                    config = pycolmap.TwoViewGeometryConfiguration(int(tvg.config))
                    pair["config"] = config.name
                    inl = np.asarray(tvg.inlier_matches)
                    pair["inliers"] = int(len(inl))
                    if config in ok_configs and len(inl) >= 5:
                        k1 = np.asarray(db.read_keypoints(ia))[:, :2].astype(np.float64)
                        k2 = np.asarray(db.read_keypoints(ib))[:, :2].astype(np.float64)
                        p1, p2 = k1[inl[:, 0]], k2[inl[:, 1]]
                        pair["gt_epipolar_error_px"] = epipolar_errors_px(cam_db, p1, p2, T_c2_c1).tolist()
                        # The essential matrix on the camera's rays, refined: what COLMAP's
                        # PLANAR/PANORAMIC path (a homography on raw fisheye pixels) skips.
                        e = pycolmap.estimate_relative_pose(cam_db, p1, cam_db, p2, pycolmap.RANSACOptions(random_seed=0))
                        if e is not None:
                            rr = pycolmap.refine_relative_pose(e["cam2_from_cam1"], cam_db, p1, cam_db, p2, np.asarray(e["inlier_mask"]))
                            pose = (rr or e)["cam2_from_cam1"]
                            pair["rays_E_rotation_error_deg"] = rot_angle_deg(np.asarray(pose.rotation.matrix()).T @ T_c2_c1[:3, :3])
                        ok = pycolmap.estimate_two_view_geometry_pose(cam_db, p1, cam_db, p2, tvg)
                        if ok:
                            R = np.asarray(tvg.cam2_from_cam1.rotation.matrix())
                            tt = np.asarray(tvg.cam2_from_cam1.translation)
                            pair["pose"] = True
                            pair["rotation_error_deg"] = rot_angle_deg(R.T @ T_c2_c1[:3, :3])
                            gt = T_c2_c1[:3, 3]
                            if np.linalg.norm(tt) > 1e-12 and np.linalg.norm(gt) > 1e-9:
                                c = float(np.dot(tt, gt) / np.linalg.norm(tt) / np.linalg.norm(gt))
                                pair["translation_direction_error_deg"] = math.degrees(math.acos(max(-1.0, min(1.0, c))))
                pairs.append(pair)
        finally:
            db.close()
    finally:
        shutil.rmtree(work, ignore_errors=True)

    posed = [p for p in pairs if p["pose"]]
    rot_err = [p["rotation_error_deg"] for p in posed]
    t_err = [p["translation_direction_error_deg"] for p in posed if "translation_direction_error_deg" in p]
    configs = {}
    for p in pairs:
        configs[p["config"]] = configs.get(p["config"], 0) + 1
    res = {
        "measure": "features",
        "take": str(take.path),
        "camera": args.camera,
        "colmap_camera": {"model": model, "width": w, "height": h, "params": params},
        "camera_mask": mask is not None or image_masks is not None,
        "rectified": bool(args.rectify),
        "people_masked": bool(args.mask_people),
        "frames": len(frames),
        "pairs": len(pairs),
        "features_per_frame_median": median(n_features),
        "features_per_frame_min": int(min(n_features)),
        "features_per_frame_max": int(max(n_features)),
        "putative_matches_median": median([p["putative"] for p in pairs]),
        "inlier_matches_median": median([p["inliers"] for p in pairs]),
        "pair_configs": configs,
        "valid_pose_share": len(posed) / len(pairs),
        "rotation_error_deg_median": median(rot_err),
        "rotation_error_below_5deg_share_of_posed": (sum(e < 5.0 for e in rot_err) / len(posed)) if posed else None,
        "rotation_error_below_5deg_share_of_pairs": sum(e < 5.0 for e in rot_err) / len(pairs),
        "translation_direction_error_deg_median": median(t_err),
        "gt_epipolar_error_px_median": median([e for p in pairs for e in p.get("gt_epipolar_error_px", [])]),
        "rays_E_rotation_error_deg_median": median([p["rays_E_rotation_error_deg"] for p in pairs if "rays_E_rotation_error_deg" in p]),
        "rays_E_pairs": sum("rays_E_rotation_error_deg" in p for p in pairs),
        "gt_relative_rotation_deg_median": median([p["gt_rotation_deg"] for p in pairs]),
        "gt_baseline_m_median": median([p["gt_translation_m"] for p in pairs]),
        "exported_poses_vs_annotations": pose_check,
        "features_per_frame": n_features,
        "pair_list": pairs,
        "seconds": time.time() - t0,
    }
    rows = [
        ("camera", f"{args.camera} ({model} {w}x{h}{', rectified' if args.rectify else ''}{', people masked' if args.mask_people else ''}), {len(frames)} frames, {len(pairs)} consecutive pairs"),
        ("SIFT features per frame", f"median {fmt(res['features_per_frame_median'], '.0f')} (min {res['features_per_frame_min']}, max {res['features_per_frame_max']})"),
        ("putative matches per pair", f"median {fmt(res['putative_matches_median'], '.0f')}"),
        ("inlier matches per pair", f"median {fmt(res['inlier_matches_median'], '.0f')}"),
        ("two-view configurations", ", ".join(f"{k} {v}" for k, v in sorted(configs.items()))),
        ("valid relative pose", f"{len(posed)}/{len(pairs)} pairs ({100 * res['valid_pose_share']:.0f} %)"),
        ("rotation error (posed pairs)", f"median {fmt(res['rotation_error_deg_median'], '.2f', ' deg')}"
         + (f", < 5 deg: {sum(e < 5.0 for e in rot_err)}/{len(posed)} posed ({100 * res['rotation_error_below_5deg_share_of_posed']:.0f} %)" if posed else "")),
        ("translation direction error", f"median {fmt(res['translation_direction_error_deg_median'], '.1f', ' deg')}"),
        ("E on camera rays (5-point+refine)", f"rotation error median {fmt(res['rays_E_rotation_error_deg_median'], '.2f', ' deg')} ({res['rays_E_pairs']} pairs)"),
        ("inliers vs ground-truth pose", f"epipolar error median {fmt(res['gt_epipolar_error_px_median'], '.2f', ' px')}"),
        ("ground truth between frames", f"median rotation {fmt(res['gt_relative_rotation_deg_median'], '.2f', ' deg')}, baseline {fmt(res['gt_baseline_m_median'], '.3f', ' m')}"),
    ]
    if pose_check is not None:
        rows.append(("colmap/images.txt vs annotations", f"max {pose_check['max_rotation_deg']:.2g} deg, {pose_check['max_translation_m']:.2g} m"))
    rows.append(("time", f"{res['seconds']:.1f} s"))
    print_table(f"features: {take.path}", rows)
    if not posed:
        print("  no consecutive pair gave a relative pose (too few features/matches in these images)")
    return res


# ---------------------------------------------------------------------------------------------
# sfm


def umeyama(src: np.ndarray, dst: np.ndarray):
    """s, R, t minimising |dst - (s R src + t)|^2 (Umeyama 1991, with scale)."""
    n = len(src)
    ms, md = src.mean(0), dst.mean(0)
    xs, xd = src - ms, dst - md
    cov = xd.T @ xs / n
    U, D, Vt = np.linalg.svd(cov)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2, 2] = -1
    R = U @ S @ Vt
    var_s = (xs**2).sum() / n
    s = float(np.trace(np.diag(D) @ S) / var_s) if var_s > 0 else 1.0
    t = md - s * R @ ms
    return s, R, t


def cmd_sfm(args) -> dict:
    import pycolmap

    t0 = time.time()
    take, frames, (model, w, h, params), image_dir = images_and_camera(args)
    names = [image_name(f) for f in frames]
    gt_centre = {image_name(f): f.T_world_cam[:3, 3] for f in frames}
    centres = np.array([gt_centre[n] for n in names])
    path_length = float(np.linalg.norm(np.diff(centres, axis=0), axis=1).sum()) if len(centres) > 1 else 0.0

    quiet_colmap()
    pycolmap.set_random_seed(0)
    work = Path(tempfile.mkdtemp(prefix="vision_checks_"))
    try:
        db_path = work / "database.db"
        (model, w, h, params), image_dir, mask, image_masks = prepare_images(args, frames, (model, w, h, params), image_dir, work)
        extract(db_path, image_dir, names, model, params, mask, image_masks, threads(args))
        pycolmap.match_exhaustive(
            db_path,
            matching_options=matching_options(args),
            verification_options=seeded_verification(),
            device=pycolmap.Device.cpu,
        )
        db = pycolmap.Database.open(db_path)
        try:
            n_features = [int(db.num_keypoints_for_image(im.image_id)) for im in db.read_all_images()]
            _, geoms = db.read_two_view_geometries()
            bad = {int(pycolmap.TwoViewGeometryConfiguration.UNDEFINED), int(pycolmap.TwoViewGeometryConfiguration.DEGENERATE)}
            verified_pairs = sum(int(g.config) not in bad for g in geoms)
        finally:
            db.close()
        opts = pycolmap.IncrementalPipelineOptions()
        opts.num_threads = threads(args)
        opts.random_seed = opts.mapper.random_seed = opts.triangulation.random_seed = 0
        opts.ba_refine_focal_length = False
        opts.ba_refine_principal_point = False
        opts.ba_refine_extra_params = False
        opts.mapper.abs_pose_refine_focal_length = False
        opts.mapper.abs_pose_refine_extra_params = False
        # COLMAP rejects a camera whose distortion coefficients exceed `max_extra_param`
        # (default 1) as diverged self-calibration: every initial pair is then "bad" and nothing
        # is reconstructed. The Aria RGB Fisheye624 has |k| up to ~1.8 by design; with the camera
        # held fixed the filter guards nothing, so it is raised just above this camera's own
        # coefficients (not with --colmap-defaults).
        camera = pycolmap_camera(model, w, h, params)
        extra = max((abs(params[i]) for i in camera.extra_params_idxs()), default=0.0)
        lifted = None
        if not args.colmap_defaults and camera.has_bogus_params(opts.min_focal_length_ratio, opts.max_focal_length_ratio, opts.max_extra_param):
            lifted = float(math.ceil(extra * 1.01 * 100) / 100)
            opts.max_extra_param = opts.mapper.max_extra_param = opts.triangulation.max_extra_param = lifted
        out = work / "sparse"
        out.mkdir()
        models = pycolmap.incremental_mapping(db_path, image_dir, out, options=opts)
        models = dict(models) if models else {}
        best = None
        for rec in models.values():
            if best is None or rec.num_reg_images() > best.num_reg_images():
                best = rec
        est, gt, reg_names = [], [], []
        stats = {}
        if best is not None:
            for im in best.images.values():
                if im.has_pose and im.name in gt_centre:
                    est.append(np.asarray(im.projection_center()))
                    gt.append(gt_centre[im.name])
                    reg_names.append(im.name)
            stats = {
                "points3D": int(best.num_points3D()),
                "mean_reprojection_error_px": float(best.compute_mean_reprojection_error()),
                "camera_params_after": list(map(float, next(iter(best.cameras.values())).params)),
            }
    finally:
        shutil.rmtree(work, ignore_errors=True)

    res = {
        "measure": "sfm",
        "take": str(take.path),
        "camera": args.camera,
        "colmap_camera": {"model": model, "width": w, "height": h, "params": params},
        "camera_mask": mask is not None or image_masks is not None,
        "rectified": bool(args.rectify),
        "people_masked": bool(args.mask_people),
        "frames": len(frames),
        "features_per_frame_median": median(n_features),
        "verified_image_pairs": verified_pairs,
        "max_extra_param": lifted if lifted is not None else opts.max_extra_param,
        "max_extra_param_raised": lifted is not None,
        "camera_max_abs_extra_param": extra,
        "models": len(models),
        "registered": len(est),
        "registered_share": len(est) / len(frames),
        "registered_frames": reg_names,
        "gt_path_length_m": path_length,
        **stats,
        "alignment": None,
        "centre_error_rmse_m": None,
        "centre_error_median_m": None,
    }
    if len(est) >= 3:
        E, G = np.array(est), np.array(gt)
        s, R, t = umeyama(E, G)
        err = np.linalg.norm((s * (R @ E.T)).T + t - G, axis=1)
        res["alignment"] = {"scale": s, "rotation": R.tolist(), "translation": t.tolist()}
        res["centre_error_rmse_m"] = float(np.sqrt((err**2).mean()))
        res["centre_error_median_m"] = float(np.median(err))
        res["centre_error_m_by_frame"] = {n: float(e) for n, e in sorted(zip(reg_names, err))}
        reg_sorted = [gt_centre[n] for n in names if n in set(reg_names)]
        res["gt_path_length_registered_m"] = float(np.linalg.norm(np.diff(np.array(reg_sorted), axis=0), axis=1).sum())
    res["seconds"] = time.time() - t0

    rows = [
        ("camera", f"{args.camera} ({model} {w}x{h}{', rectified' if args.rectify else ''}{', people masked' if args.mask_people else ''}, held fixed), {len(frames)} frames"),
        ("SIFT features per frame", f"median {fmt(res['features_per_frame_median'], '.0f')}"),
        ("verified image pairs", f"{verified_pairs} of {len(frames) * (len(frames) - 1) // 2} (exhaustive matching; not degenerate)"),
        ("COLMAP max_extra_param", (f"{lifted:g} (default 1 would reject this camera: |k| up to {extra:.2f}; held fixed)" if lifted is not None else f"{res['max_extra_param']:g}")),
        ("models", f"{len(models)}"),
        ("registered frames", f"{len(est)}/{len(frames)} ({100 * res['registered_share']:.0f} %)"),
    ]
    if stats:
        rows.append(("points / reprojection error", f"{stats['points3D']} / {stats['mean_reprojection_error_px']:.3f} px"))
    if res["centre_error_rmse_m"] is not None:
        rows.append(("camera-centre error (Sim3)", f"RMSE {res['centre_error_rmse_m']:.3f} m, median {res['centre_error_median_m']:.3f} m (scale {res['alignment']['scale']:.3g})"))
    rows.append(("ground-truth path length", f"{path_length:.2f} m"))
    rows.append(("time", f"{res['seconds']:.1f} s"))
    print_table(f"sfm: {take.path}", rows)
    if not models:
        print("  nothing reconstructed: incremental mapping found no initial pair / no model (too few features and matches)")
    elif len(est) < 3:
        print(f"  {len(est)} frames registered: too few to align (a similarity needs 3)")
    return res


# ---------------------------------------------------------------------------------------------
# tsdf


def take_scene(take, override: str | None):
    """(scene file, up axis 'y' or 'z', metres per unit) the take used."""
    summary = take.path / "sequence" / "summary.json"
    about = {}
    if summary.is_file():
        try:
            about = json.loads(summary.read_text()).get("about", {}) or {}
        except json.JSONDecodeError as e:
            raise ToolError(f"{summary}: not valid JSON ({e})") from e
    scene = override or about.get("scene")
    if scene is None:
        cfg = take.path / "config.toml"
        if cfg.is_file():
            import tomllib

            try:
                scene = tomllib.loads(cfg.read_text()).get("scene", {}).get("path")
            except tomllib.TOMLDecodeError:
                scene = None
    if scene is None:
        raise ToolError(
            f"{summary}: no key about.scene (expected the scene file the take was made in; "
            "pass it with --scene FILE)"
        )
    path = Path(scene)
    if not path.is_absolute() and not path.is_file():
        path = take.path / scene
    if not path.is_file():
        if override:
            raise ToolError(f"{scene}: no such scene file (given with --scene; expected the .glb/.gltf/.obj/.ply the take was made in)")
        raise ToolError(f"{scene}: no such scene file (named by {summary} about.scene; pass the file with --scene FILE)")
    up = about.get("scene_up_axis")
    if up is None:
        up = "y" if path.suffix.lower() in (".glb", ".gltf") else "z"
    if up not in ("y", "z"):
        raise ToolError(f"{summary}: key about.scene_up_axis: {up!r} (expected \"y\" or \"z\")")
    unit = about.get("scene_unit_m")
    unit = 1.0 if unit is None else float(unit)
    return path, up, unit


def load_scene_mesh(path: Path, up: str, unit: float):
    """Vertices (world: metres, z up) and triangles of the scene file, as src/scene/load/."""
    import trimesh

    try:
        loaded = trimesh.load(str(path), force="scene")
    except Exception as e:
        raise ToolError(f"{path}: cannot read the scene file ({type(e).__name__}: {e})") from e
    mesh = loaded.to_mesh() if hasattr(loaded, "to_mesh") else loaded.dump(concatenate=True)
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.faces, dtype=np.int32)
    if len(f) == 0:
        raise ToolError(f"{path}: no triangles")
    if up == "y":
        v = np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1)
    return v * unit, f


def scene_object_ids(take, camera: str, frames) -> tuple:
    """Segmentation ids of the scene file's objects where the scene file has them (not those
    people move: a chair pulled out, a thing picked up), and the names of those left out."""
    doc = camera_annotations(take, camera)
    agent_ids = {a.get("id") for f in frames for a in f.agents}
    moved = {m["name"] for f in doc.get("frames", []) for m in f.get("moved_scene_objects", [])}
    moved |= {o["scene_object"] for f in doc.get("frames", []) for o in f.get("objects", []) if o.get("scene_object")}
    keep, dropped = set(), []
    for e in doc.get("segmentation_ids", []):
        name, i = e["name"], e["id"]
        if (i >= 1000 or i in agent_ids or name == "egogen_ceiling" or name in moved
                or re.fullmatch(r"obstacle_\d+", name)):
            dropped.append(name)
        else:
            keep.add(i)
    return keep, dropped


# Cube faces: columns are the face's x, y, z axes in the (OpenCV) camera frame.
_FACES = {
    "front": np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1]], float).T,
    "right": np.array([[0, 0, -1], [0, 1, 0], [1, 0, 0]], float).T,
    "left": np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], float).T,
    "down": np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], float).T,
    "up": np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float).T,
}


def fisheye_rays(camera, w, h):
    """Per pixel (egogen centres at integers) the normalised ray (x/z, y/z) from the COLMAP
    camera, and whether it projects back onto its pixel within 0.01 px."""
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    px = np.stack([u.ravel() + 0.5, v.ravel() + 0.5], axis=1)
    xy = np.asarray(camera.cam_from_img(px), dtype=np.float64)
    ok = np.isfinite(xy).all(axis=1)
    back = np.full_like(px, np.nan)
    pts = np.concatenate([xy, np.ones((len(xy), 1))], axis=1)
    back[ok] = np.asarray(camera.img_from_cam(pts[ok]), dtype=np.float64)
    ok &= np.isfinite(back).all(axis=1)
    ok[ok] &= np.linalg.norm(back[ok] - px[ok], axis=1) < 0.01
    return xy.reshape(h, w, 2), ok.reshape(h, w)


def fisheye_pixels_of_rays(camera, rays: np.ndarray, w: int, h: int, ray_ok: np.ndarray) -> np.ndarray:
    """Where camera-frame rays (N x 3) land in the fisheye image: continuous pixels, egogen's
    centres at integers; NaN for a ray behind the camera, outside the image or the lens's
    valid field (`ray_ok`, from `fisheye_rays`), or one the lens folds back (a polynomial lens
    can bring rays past its field of view back into the image: the ray must come back from the
    pixel it lands on)."""
    at = np.full((len(rays), 2), np.nan)
    front = rays[:, 2] > 1e-6
    if not front.any():
        return at
    p = np.asarray(camera.img_from_cam(rays[front]), dtype=np.float64)
    good = np.isfinite(p).all(axis=1)
    xy = np.full_like(p, np.nan)
    xy[good] = np.asarray(camera.cam_from_img(p[good]), dtype=np.float64)
    r = rays[front][:, :2] / rays[front][:, 2:3]
    good &= np.isfinite(xy).all(axis=1)
    good[good] &= np.linalg.norm(xy[good] - r[good], axis=1) < 1e-3 * (1 + np.linalg.norm(r[good], axis=1) ** 2)
    q = p - 0.5  # egogen's pixel centres
    good &= (q[:, 0] > -0.5) & (q[:, 0] < w - 0.5) & (q[:, 1] > -0.5) & (q[:, 1] < h - 0.5)
    nearest = np.rint(np.nan_to_num(q)).astype(np.int64)
    near_flat = np.clip(nearest[:, 1], 0, h - 1) * w + np.clip(nearest[:, 0], 0, w - 1)
    good &= ray_ok.ravel()[near_flat]
    q[~good] = np.nan
    at[np.flatnonzero(front)] = q
    return at


def face_maps(camera, w, h, f_face: float, ray_ok: np.ndarray):
    """For each cube face: its size, and per face pixel where its ray lands in the fisheye
    image (continuous, egogen pixel centres at integers; NaN where it does not: outside the
    image or the lens), and the length of the face pixel's (x/z, y/z, 1) ray."""
    S = int(2 * math.ceil(f_face))
    c = (S - 1) / 2.0
    fx = S / 2.0
    u, v = np.meshgrid(np.arange(S, dtype=np.float64), np.arange(S, dtype=np.float64))
    local = np.stack([(u.ravel() - c) / fx, (v.ravel() - c) / fx, np.ones(S * S)], axis=1)
    local_len = np.linalg.norm(local, axis=1).reshape(S, S)
    maps = {}
    for name, R_cam_face in _FACES.items():
        at = fisheye_pixels_of_rays(camera, local @ R_cam_face.T, w, h, ray_ok)
        if np.isfinite(at).any():
            maps[name] = (R_cam_face, at.reshape(S, S, 2))
    return S, fx, c, local_len, maps


def sample_range(rng: np.ndarray, seg: np.ndarray, at: np.ndarray, spread: float = 0.05):
    """The range image (NaN: nothing to fuse) at continuous pixels `at` (..., 2): bilinear
    between the four pixels around each where they hold one surface (one object id, ranges
    within `spread` of the nearest), else the nearest pixel's: a face pixel's point then lies
    on its own ray, as egogen's depth lies on its pixel's ray."""
    h, w = rng.shape
    x, y = at[..., 0], at[..., 1]
    ok = np.isfinite(x) & np.isfinite(y)
    xs, ys = np.where(ok, x, 0.0), np.where(ok, y, 0.0)
    x0 = np.clip(np.floor(xs).astype(np.int64), 0, w - 2)
    y0 = np.clip(np.floor(ys).astype(np.int64), 0, h - 2)
    ax, ay = np.clip(xs - x0, 0, 1), np.clip(ys - y0, 0, 1)
    corners = [rng[y0, x0], rng[y0, x0 + 1], rng[y0 + 1, x0], rng[y0 + 1, x0 + 1]]
    ids = [seg[y0, x0], seg[y0, x0 + 1], seg[y0 + 1, x0], seg[y0 + 1, x0 + 1]]
    stack = np.stack(corners)
    lo, hi = np.min(stack, axis=0), np.max(stack, axis=0)
    one = np.isfinite(stack).all(axis=0) & (hi - lo <= spread * lo)
    for i in ids[1:]:
        one &= i == ids[0]
    bil = (1 - ay) * ((1 - ax) * corners[0] + ax * corners[1]) + ay * ((1 - ax) * corners[2] + ax * corners[3])
    nx = np.clip(np.rint(xs).astype(np.int64), 0, w - 1)
    ny = np.clip(np.rint(ys).astype(np.int64), 0, h - 1)
    out = np.where(one, bil, rng[ny, nx])
    return np.where(ok, out, np.nan)


def cmd_tsdf(args) -> dict:
    if not (math.isfinite(args.voxel_m) and args.voxel_m > 0):
        raise ToolError(f"--voxel-m {args.voxel_m}: expected a positive size in metres")
    if not (math.isfinite(args.max_depth_m) and args.max_depth_m > 0):
        raise ToolError(f"--max-depth-m {args.max_depth_m}: expected a positive depth in metres")
    try:
        import open3d as o3d
    except ImportError as e:
        raise ToolError(
            f"cannot import open3d ({e}); install it: pip install -r tools/vision_checks_requirements.txt"
            + (" (and the system's libusb-1.0, e.g. apt-get install libusb-1.0-0)" if "libusb" in str(e) else "")
        ) from e
    from scipy.spatial import cKDTree

    t0 = time.time()
    take = open_take(args.take)
    frames = camera_frames(take, args.camera, args.max_frames)
    chans = frame_groups(frames[0])
    depth_group = {"exact": "depth", "noisy": "depth_noisy"}[getattr(args, "depth", "exact")]
    if depth_group not in chans:
        raise ToolError(
            f"{frames[0].path}: no {depth_group}.Z channel (its channel groups: {', '.join(sorted(chans))}); expected a take rendered "
            + ("with the `depth` pass ([render] passes)" if depth_group == "depth"
               else f"with depth noise for {args.camera} ([render.depth_noise] cameras, docs/RENDERING.md)")
        )
    if "segmentation" not in chans:
        raise ToolError(
            f"{frames[0].path}: no segmentation.id channel (its channel groups: {', '.join(sorted(chans))}); expected a take "
            "rendered with the `segmentation` pass, which masks out the people"
        )
    has_position = "position" in chans
    scene_path, up, unit = take_scene(take, args.scene)
    V, F = load_scene_mesh(scene_path, up, unit)
    keep_ids, dropped = scene_object_ids(take, args.camera, frames)

    if (take.path / "colmap" / args.camera / "cameras.txt").is_file():
        model, w, h, params = read_colmap_camera_file(take, args.camera)
        cam_source = "colmap/cameras.txt"
    else:
        model, w, h, params = colmap_camera_from_annotations(take, args.camera)
        cam_source = "annotations (no COLMAP export)"
    camera = pycolmap_camera(model, w, h, params)
    xy, ray_ok = fisheye_rays(camera, w, h)
    dirs_cam = np.concatenate([xy, np.ones((h, w, 1))], axis=2)  # (x/z, y/z, 1)
    f_face = float(camera.mean_focal_length())
    S, fpx, cpx, face_len, faces = face_maps(camera, w, h, f_face, ray_ok)
    K = o3d.core.Tensor(np.array([[fpx, 0, cpx], [0, fpx, cpx], [0, 0, 1]], np.float64))
    # Open3D's tensor TSDF (VoxelBlockGrid); its surface is extracted as a mesh, which needs a
    # colour attribute: a black one.
    vbg = o3d.t.geometry.VoxelBlockGrid(
        attr_names=("tsdf", "weight", "color"),
        attr_dtypes=(o3d.core.float32, o3d.core.float32, o3d.core.float32),
        attr_channels=((1), (1), (3)),
        voxel_size=args.voxel_m,
        block_resolution=8,
        block_count=20000,
        device=o3d.core.Device("CPU:0"),
    )
    # The control: the same fusion (same faces, frames and pixels) of depth ray-cast from the
    # scene mesh itself: what the TSDF and its surface extraction give with perfect depth, the
    # floor of this measure.
    control = o3d.t.geometry.VoxelBlockGrid(
        attr_names=("tsdf", "weight", "color"),
        attr_dtypes=(o3d.core.float32, o3d.core.float32, o3d.core.float32),
        attr_channels=((1), (1), (3)),
        voxel_size=args.voxel_m,
        block_resolution=8,
        block_count=20000,
        device=o3d.core.Device("CPU:0"),
    )
    black = o3d.t.geometry.Image(o3d.core.Tensor(np.zeros((S, S, 3), np.float32)))
    fu, fv = np.meshgrid(np.arange(S, dtype=np.float64), np.arange(S, dtype=np.float64))
    face_local = np.stack([(fu - cpx) / fpx, (fv - cpx) / fpx, np.ones_like(fu)], axis=2).reshape(-1, 3)
    tmesh = o3d.t.geometry.TriangleMesh()
    tmesh.vertex.positions = o3d.core.Tensor(V.astype(np.float32))
    tmesh.triangle.indices = o3d.core.Tensor(F.astype(np.int32))
    rc = o3d.t.geometry.RaycastingScene()
    rc.add_triangles(tmesh)

    seen, d_err, pos_err, pos_pts = [], [], [], []
    n_used = n_bodies = n_ceiling = n_missed = integrated = 0
    n_ray_bad = int((~ray_ok).sum())
    for fr in frames:
        d = read_frame(fr, [depth_group, "valid", "segmentation"] + (["position"] if has_position else []))
        depth, seg = d[depth_group].astype(np.float64), d["segmentation"]
        valid = (d["valid"] > 0.5) & (depth > 0) & ray_ok
        scene_px = valid & np.isin(seg, list(keep_ids))
        n_bodies += int((valid & (seg >= 1000)).sum())
        n_ceiling += int((valid & ~scene_px & (seg < 1000)).sum())
        n_used += int(scene_px.sum())
        X_cam = dirs_cam * depth[..., None]  # planar depth: z of the point
        T = fr.T_world_cam
        R, t = T[:3, :3], T[:3, 3]
        Xw = X_cam[scene_px] @ R.T + t
        if has_position:
            P = d["position"][scene_px].astype(np.float64)
            pos_err.append(np.linalg.norm(Xw - P, axis=1))
            pos_pts.append(P[:: max(1, len(P) // 5000)])
        # The mesh through the same pixels.
        dirs = dirs_cam[scene_px]
        rng = np.linalg.norm(dirs, axis=1)
        unit_dirs = (dirs / rng[:, None]) @ R.T
        rays = np.concatenate([np.broadcast_to(t, unit_dirs.shape), unit_dirs], axis=1).astype(np.float32)
        hit = rc.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy().astype(np.float64)
        finite = np.isfinite(hit)
        n_missed += int((~finite).sum())
        d_err.append(np.abs(hit[finite] - (depth[scene_px] * rng)[finite]))
        seen.append(t + unit_dirs[finite] * hit[finite, None])
        # TSDF: every cube face as a pinhole depth image, each face pixel's range sampled where
        # its ray lands in the fisheye image.
        rng_img = np.where(scene_px, np.linalg.norm(X_cam, axis=2), np.nan)
        for R_cam_face, at in faces.values():
            r = sample_range(rng_img, seg, at)
            z = np.where(np.isfinite(r), r / face_len, 0.0).astype(np.float32)
            if not (z > 0).any():
                continue
            T_world_face = np.eye(4)
            T_world_face[:3, :3] = R @ R_cam_face
            T_world_face[:3, 3] = t
            ext = o3d.core.Tensor(np.linalg.inv(T_world_face))
            dimg = o3d.t.geometry.Image(o3d.core.Tensor(np.ascontiguousarray(z)))
            blocks = vbg.compute_unique_block_coordinates(dimg, K, ext, 1.0, args.max_depth_m, 4.0)
            vbg.integrate(blocks, dimg, black, K, ext, 1.0, args.max_depth_m, 4.0)
            integrated += 1
            d = face_local @ T_world_face[:3, :3].T
            d /= np.linalg.norm(d, axis=1)[:, None]
            cast = np.concatenate([np.broadcast_to(t, d.shape), d], axis=1).astype(np.float32)
            hit_m = rc.cast_rays(o3d.core.Tensor(cast))["t_hit"].numpy().reshape(S, S)
            z_mesh = np.where((z > 0) & np.isfinite(hit_m), hit_m / face_len, 0.0).astype(np.float32)
            if (z_mesh > 0).any():
                cimg = o3d.t.geometry.Image(o3d.core.Tensor(np.ascontiguousarray(z_mesh)))
                blocks = control.compute_unique_block_coordinates(cimg, K, ext, 1.0, args.max_depth_m, 4.0)
                control.integrate(blocks, cimg, black, K, ext, 1.0, args.max_depth_m, 4.0)

    # The fused surface: the vertices of the TSDF's zero crossing (marching cubes) where at least
    # one frame saw it (weight >= 1).
    fused = np.zeros((0, 3))
    if integrated:
        fused = vbg.extract_triangle_mesh(weight_threshold=0.5).vertex.positions.numpy().astype(np.float64)
    d_err = np.concatenate(d_err) if d_err else np.zeros(0)
    pos_err = np.concatenate(pos_err) if pos_err else None
    seen = np.concatenate(seen) if seen else np.zeros((0, 3))
    res = {
        "measure": "tsdf",
        "take": str(take.path),
        "camera": args.camera,
        "depth": depth_group + ".Z",
        "frames": len(frames),
        "colmap_camera": {"model": model, "width": w, "height": h, "params": params, "from": cam_source},
        "scene": {"path": str(scene_path), "up_axis": up, "unit_m": unit, "triangles": int(len(F))},
        "voxel_m": args.voxel_m,
        "sdf_trunc_m": 4 * args.voxel_m,
        "max_depth_m": args.max_depth_m,
        "cube_face_px": S,
        "cube_faces_used": sorted(faces),
        "pixels_fused": n_used,
        "pixels_people_masked": n_bodies,
        "pixels_other_masked": n_ceiling,
        "masked_objects": dropped,
        "pixels_ray_not_invertible": n_ray_bad,
        "depth_vs_mesh_median_abs_m": median(d_err),
        "depth_vs_mesh_within_2cm_share": float((d_err < 0.02).mean()) if len(d_err) else None,
        "rays_missing_mesh": n_missed,
        "depth_vs_position_pass_median_m": median(pos_err) if pos_err is not None else None,
        "depth_vs_position_pass_p99_m": float(np.percentile(pos_err, 99)) if pos_err is not None and len(pos_err) else None,
        "position_pass_to_mesh_median_m": None,
        "fused_points": int(len(fused)),
        "chamfer_m": None,
    }
    if pos_pts:
        pp = np.concatenate(pos_pts)
        if len(pp):
            pd = rc.compute_distance(o3d.core.Tensor(pp.astype(np.float32))).numpy().astype(np.float64)
            res["position_pass_to_mesh_median_m"] = float(np.median(pd))
            res["position_pass_to_mesh_p99_m"] = float(np.percentile(pd, 99))
    if integrated:
        floor = control.extract_triangle_mesh(weight_threshold=0.5).vertex.positions.numpy()
        if len(floor):
            fd = rc.compute_distance(o3d.core.Tensor(floor.astype(np.float32))).numpy().astype(np.float64)
            res["control_fused_to_mesh_mean_m"] = float(fd.mean())
            res["control_fused_to_mesh_median_m"] = float(np.median(fd))
            res["control_fused_within_2cm_share"] = float((fd < 0.02).mean())
    if len(fused) and len(seen):
        dist = rc.compute_distance(o3d.core.Tensor(fused.astype(np.float32))).numpy().astype(np.float64)
        ref = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(seen)).voxel_down_sample(args.voxel_m / 2)
        ref = np.asarray(ref.points)
        comp, _ = cKDTree(fused).query(ref, workers=-1)
        res.update(
            {
                "seen_mesh_points": int(len(ref)),
                "fused_to_mesh_mean_m": float(dist.mean()),
                "fused_to_mesh_median_m": float(np.median(dist)),
                "mesh_to_fused_mean_m": float(comp.mean()),
                "mesh_to_fused_median_m": float(np.median(comp)),
                "chamfer_m": float((dist.mean() + comp.mean()) / 2),
                "fused_within_2cm_share": float((dist < 0.02).mean()),
                "seen_mesh_within_2cm_share": float((comp < 0.02).mean()),
            }
        )
    res["seconds"] = time.time() - t0

    rows = [
        ("camera", f"{args.camera} ({model} {w}x{h}, {cam_source}), {len(frames)} frames, {depth_group}.Z"),
        ("scene mesh", f"{scene_path} ({len(F)} triangles, {up} up -> z up, x{unit:g} m)"),
        ("pixels fused", f"{n_used} (masked out: {n_bodies} people, {n_ceiling} ceiling/obstacles; {n_ray_bad} pixels without an invertible ray)"),
        ("depth vs mesh, per pixel", f"median |diff| {fmt(res['depth_vs_mesh_median_abs_m'], '.4f', ' m')}, within 2 cm {fmt(100 * res['depth_vs_mesh_within_2cm_share'] if res['depth_vs_mesh_within_2cm_share'] is not None else None, '.1f', ' %')}, rays missing the mesh {n_missed}"),
    ]
    if pos_err is not None:
        rows.append(("depth+pose vs position pass", f"median {fmt(res['depth_vs_position_pass_median_m'], '.2e', ' m')}, p99 {fmt(res['depth_vs_position_pass_p99_m'], '.2e', ' m')}"))
        rows.append(("position pass vs mesh", f"median {fmt(res['position_pass_to_mesh_median_m'], '.2e', ' m')}, p99 {fmt(res.get('position_pass_to_mesh_p99_m'), '.2e', ' m')}"))
    rows.append(("TSDF", f"voxel {args.voxel_m} m, truncation {4 * args.voxel_m:g} m, {len(faces)} cube faces of {S}x{S} px, {len(fused)} fused points"))
    if res["chamfer_m"] is not None:
        rows += [
            ("fused -> mesh", f"mean {res['fused_to_mesh_mean_m']:.4f} m, median {res['fused_to_mesh_median_m']:.4f} m"),
            ("seen mesh -> fused", f"mean {res['mesh_to_fused_mean_m']:.4f} m, median {res['mesh_to_fused_median_m']:.4f} m ({res['seen_mesh_points']} points)"),
            ("Chamfer (mean of both)", f"{res['chamfer_m']:.4f} m"),
            ("fused points within 2 cm", f"{100 * res['fused_within_2cm_share']:.1f} %"),
        ]
    if "control_fused_to_mesh_median_m" in res:
        rows.append((
            "control: mesh depth fused",
            f"fused -> mesh mean {res['control_fused_to_mesh_mean_m']:.4f} m, median {res['control_fused_to_mesh_median_m']:.4f} m, "
            f"within 2 cm {100 * res['control_fused_within_2cm_share']:.1f} % (depth ray-cast from the mesh: the measure's floor)",
        ))
    rows.append(("time", f"{res['seconds']:.1f} s"))
    print_table(f"tsdf: {take.path}", rows)
    if res["chamfer_m"] is None:
        print("  nothing fused: " + ("no scene pixel with depth in these frames" if not n_used else "the TSDF holds no surface"))
    return res


def cmd_rays(args) -> dict:
    """Ground truth on its own pixel: each pixel's surface point (`position`) reprojected with
    the exported camera lands how far from the pixel's centre, and how far the depth, unprojected
    along the pixel's exact ray, lies from that point."""
    t0 = time.time()
    take = open_take(args.take)
    frames = camera_frames(take, args.camera, args.max_frames)
    chans = frame_groups(frames[0])
    for group in ("depth", "position"):
        if group not in chans:
            raise ToolError(
                f"{frames[0].path}: no {group} channel (its channel groups: {', '.join(sorted(chans))}); "
                "expected a take rendered with the `depth` and `position` passes ([render] passes)"
            )
    if (take.path / "colmap" / args.camera / "cameras.txt").is_file():
        model, w, h, params = read_colmap_camera_file(take, args.camera)
    else:
        model, w, h, params = colmap_camera_from_annotations(take, args.camera)
    camera = pycolmap_camera(model, w, h, params)
    xy, ray_ok = fisheye_rays(camera, w, h)
    dirs_cam = np.concatenate([xy, np.ones((h, w, 1))], axis=2)
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    centre = np.stack([u + 0.5, v + 0.5], axis=2)
    off_px, gap_m = [], []
    for fr in frames:
        d = read_frame(fr, ["depth", "position", "valid"])
        depth = d["depth"].astype(np.float64)
        px = (d["valid"] > 0.5) & (depth > 0) & ray_ok
        T = fr.T_world_cam
        R, t = T[:3, :3], T[:3, 3]
        P_cam = (d["position"][px].astype(np.float64) - t) @ R  # R^T (p - t), row-wise
        back = np.asarray(camera.img_from_cam(P_cam), dtype=np.float64)
        off_px.append(np.linalg.norm(back - centre[px], axis=1))
        gap_m.append(np.linalg.norm(dirs_cam[px] * depth[px][:, None] - P_cam, axis=1))
    off = np.concatenate(off_px) if off_px else np.zeros(0)
    gap = np.concatenate(gap_m) if gap_m else np.zeros(0)
    ok = np.isfinite(off)
    q = lambda a, p: float(np.percentile(a, p)) if len(a) else None
    res = {
        "measure": "rays",
        "take": str(take.path),
        "camera": args.camera,
        "frames": len(frames),
        "size_px": [w, h],
        "surface_pixels": int(len(off)),
        "on_own_ray_share": float((off[ok] < 0.01).mean()) if ok.any() else None,
        "within_0_1px_share": float((off[ok] < 0.1).mean()) if ok.any() else None,
        "reprojection_px_median": q(off[ok], 50),
        "reprojection_px_p90": q(off[ok], 90),
        "reprojection_px_p99": q(off[ok], 99),
        "depth_vs_position_m_median": q(gap, 50),
        "depth_vs_position_m_p99": q(gap, 99),
        "seconds": time.time() - t0,
    }
    pct = lambda x: "-" if x is None else f"{100 * x:.1f} %"
    print_table(f"rays: {take.path} ({args.camera}, {w}x{h}, {len(frames)} frames)", [
        ("surface pixels", f"{res['surface_pixels']}"),
        ("position on its pixel's ray (< 0.01 px)", pct(res["on_own_ray_share"])),
        ("within 0.1 px", pct(res["within_0_1px_share"])),
        ("position reprojected vs pixel centre", f"median {fmt(res['reprojection_px_median'], '.4f', ' px')}, p90 {fmt(res['reprojection_px_p90'], '.4f', ' px')}, p99 {fmt(res['reprojection_px_p99'], '.4f', ' px')}"),
        ("depth along the ray vs position", f"median {fmt(res['depth_vs_position_m_median'] and 1000 * res['depth_vs_position_m_median'], '.3f', ' mm')}, p99 {fmt(res['depth_vs_position_m_p99'] and 1000 * res['depth_vs_position_m_p99'], '.3f', ' mm')}"),
        ("time", f"{res['seconds']:.1f} s"),
    ])
    return res


# ---------------------------------------------------------------------------------------------


def main(argv=None) -> int:
    ap = arguments.StrictParser(
        prog="vision_checks.py",
        description="Standard vision (SIFT, two-view geometry, SfM, TSDF) on a finished egogen take.",
    )
    ap.add_argument("--debug", action="store_true", help="show a traceback on an error")
    sub = ap.add_subparsers(dest="cmd", required=True)

    def common(p):
        p.add_argument("take", help="the take's folder (egogen-run's output)")
        p.add_argument("--camera", default="camera-rgb", help="camera name (default camera-rgb)")
        p.add_argument("--max-frames", type=int, default=None, help="only the first N frames")
        p.add_argument("--json", metavar="OUT", default=None, help="write the numbers to this JSON file")
        p.add_argument("--replace", action="store_true", help="overwrite an existing --json")

    def colmap_options(p):
        p.add_argument(
            "--rectify", action="store_true",
            help="resample the frames onto a pinhole camera of the same size and focal length first "
            "(as projectaria_tools' distort_by_calibration); COLMAP's defaults then take the camera as it is",
        )
        p.add_argument(
            "--threads", type=int, default=None,
            help="COLMAP's threads (default: every core); 1 makes a run repeat exactly",
        )
        p.add_argument(
            "--mask-people", action="store_true",
            help="keep features off the people (segmentation ids >= 1000, grown by 1/200 of the width): "
            "they move, SfM assumes a static scene; needs the segmentation pass",
        )

    p = sub.add_parser("features", help="SIFT and two-view geometry between consecutive frames")
    common(p)
    colmap_options(p)
    p = sub.add_parser("sfm", help="incremental SfM with the exported camera held fixed")
    common(p)
    colmap_options(p)
    p.add_argument(
        "--colmap-defaults", action="store_true",
        help="keep COLMAP's max_extra_param = 1 even where it rejects the (fixed) camera",
    )
    p = sub.add_parser("tsdf", help="TSDF fusion of the depth with the ground-truth poses against the scene mesh")
    common(p)
    p.add_argument("--voxel-m", type=float, default=0.02, help="TSDF voxel size (m), default 0.02")
    p.add_argument("--max-depth-m", type=float, default=10.0, help="depth beyond this is not fused (m), default 10")
    p.add_argument("--scene", default=None, help="the scene file, when the take's summary names none or it moved")
    p.add_argument(
        "--depth", choices=("exact", "noisy"), default="exact",
        help="fuse the exact depth (depth.Z, default) or the sensor-noise channel (depth_noisy.Z, [render.depth_noise])",
    )
    p = sub.add_parser("rays", help="ground truth on its own pixel: position reprojected, depth against position")
    common(p)
    args = ap.parse_args(argv)
    if args.debug:
        os.environ["VISION_CHECKS_DEBUG"] = "1"

    try:
        if args.json is not None:
            outputs.check_new(args.json, "--json", args.replace)
            outputs.check_outside(args.json, "--json", args.take, "the take")
        res = {"features": cmd_features, "sfm": cmd_sfm, "tsdf": cmd_tsdf, "rays": cmd_rays}[args.cmd](args)
        write_json(args.json, res, args.replace)
    except (ToolError, outputs.OutputError) as e:
        print(f"vision_checks {args.cmd}: error: {e}", file=sys.stderr)
        return 2
    except ImportError as e:
        print(f"vision_checks {args.cmd}: error: {e}; install: pip install -r tools/vision_checks_requirements.txt ./python", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except Exception as e:  # a bug or an unforeseen file: one line, --debug for the traceback
        if args.debug:
            raise
        print(f"vision_checks {args.cmd}: error: {type(e).__name__}: {e} (run with --debug for the traceback)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
