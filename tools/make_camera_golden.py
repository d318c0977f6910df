"""Golden Fisheye624 projections from projectaria-tools (the independent oracle).

Reads tests/fixtures/aria_gen1_device_calibration.json with projectaria-tools' own loader and,
for camera-rgb (2880x2880 and rescaled to 1408x1408), camera-slam-left and camera-slam-right,
writes tests/fixtures/fisheye624_golden.json holding:
  - the calibration projectaria-tools derives (params, image size, valid radius, max angle,
    T_Cpf_Camera from its CAD extrinsics),
  - camera-frame points and `CameraCalibration.project` of each (pixel, or null outside the
    valid field of view): the optical axis, angles down to 1e-12 rad, random directions up to
    0.2 rad beyond the maximum angle, points just inside / outside the valid-radius circle and
    the image corners, and points behind the camera,
  - pixels (a grid over the image, the principal point, the valid circle) and
    `CameraCalibration.unproject` of each (unit ray, or null).
Points whose projection lies within 1e-6 px of a boundary (image edge, valid circle) or whose
angle is within 1e-9 rad of the maximum are flagged `near_boundary`: rounding may decide them
either way.

Run (PyPI projectaria-tools 2.3.0, numpy):
    python3 -m venv .venv-aria && .venv-aria/bin/pip install projectaria-tools==2.3.0
    .venv-aria/bin/python tools/make_camera_golden.py --replace   # [--out PATH] (a new file)
"""
import hashlib
import math
import os
from importlib.metadata import version

import numpy as np
from projectaria_tools.core import calibration

import arguments
import outputs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIXTURE = os.path.join(ROOT, "tests", "fixtures", "aria_gen1_device_calibration.json")
OUT = os.path.join(ROOT, "tests", "fixtures", "fisheye624_golden.json")
N_RANDOM = 120
GRID = 9
SEED = 624


def theta_of(p):
    return math.atan2(math.hypot(p[0], p[1]), p[2])


def near_boundary(cam, p):
    """Whether rounding could flip the valid-FOV decision for point p."""
    if p[2] <= 0:
        return False
    if abs(theta_of(p) - cam.get_max_solid_angle()) < 1e-9:
        return True
    px = cam.project_no_checks(np.array(p))
    w, h = cam.get_image_size()
    margins = [px[0] + 0.5, px[1] + 0.5, w - 0.5 - px[0], h - 0.5 - px[1]]
    r = cam.get_valid_radius()
    if r is not None:
        margins.append(r - np.linalg.norm(px - cam.get_principal_point()))
    return min(abs(m) for m in margins) < 1e-6


def direction(theta, phi):
    return [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]


def points_for(cam, rng):
    max_t = cam.get_max_solid_angle()
    w, h = cam.get_image_size()
    pp = cam.get_principal_point()
    pts = [[0.0, 0.0, z] for z in (0.05, 1.0, 7.5)]
    for t in (1e-12, 1e-9, 1e-6, 1e-3):
        for phi in (0.3, 2.1, 4.0):
            pts.append([1.5 * c for c in direction(t, phi)])
    for _ in range(N_RANDOM):
        t = rng.uniform(0.0, max_t + 0.2)
        phi = rng.uniform(0.0, 2 * math.pi)
        depth = math.exp(rng.uniform(math.log(0.1), math.log(20.0)))
        pts.append([depth * c for c in direction(t, phi)])
    # The cone of the maximum angle.
    for phi in np.linspace(0.0, 2 * math.pi, 8, endpoint=False):
        for t in (max_t - 1e-6, max_t + 1e-6):
            pts.append(direction(t, phi))
    # The valid circle (clipped to the image) and the image corners, from projectaria's rays.
    edge_pixels = []
    r = cam.get_valid_radius()
    if r is not None:
        for phi in np.linspace(0.0, 2 * math.pi, 16, endpoint=False):
            for s in (1 - 1e-6, 1 + 1e-6):
                edge_pixels.append(pp + s * r * np.array([math.cos(phi), math.sin(phi)]))
    for cx, cy in ((-0.5, -0.5), (w - 0.5, -0.5), (-0.5, h - 0.5), (w - 0.5, h - 0.5)):
        for d in (1.0, -1e-3):
            edge_pixels.append(np.array([cx + d * (1 if cx < 0 else -1), cy + d * (1 if cy < 0 else -1)]))
    for px in edge_pixels:
        ray = cam.unproject_no_checks(px)
        if ray[2] > 0 and theta_of(ray) < math.pi / 2 - 1e-3:
            ray = ray / np.linalg.norm(ray)
            pts.append(list(2.0 * ray))
    # Behind and beside the camera.
    pts += [[0.0, 0.0, -1.0], [0.3, -0.2, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 1e-9]]
    # Round inputs to 12 significant digits: the stored decimal is the exact input.
    return [[float(f"{c:.12g}") for c in p] for p in pts]


def pixels_for(cam):
    w, h = cam.get_image_size()
    pp = cam.get_principal_point()
    pix = [list(pp)]
    for u in np.linspace(-0.5, w - 0.5, GRID):
        for v in np.linspace(-0.5, h - 0.5, GRID):
            pix.append([u, v])
    r = cam.get_valid_radius()
    if r is not None:
        for phi in np.linspace(0.0, 2 * math.pi, 12, endpoint=False):
            pix.append(list(pp + (r - 1e-3) * np.array([math.cos(phi), math.sin(phi)])))
    return [[float(f"{c:.12g}") for c in p] for p in pix]


def camera_entry(dc, label, rgb_1408, rng):
    cam = dc.get_camera_calib(label)
    if rgb_1408:
        cam = cam.rescale(np.array([1408, 1408]), 0.5, np.array([32.0, 32.0]))
    t_cpf_cam = dc.get_transform_cpf_sensor(label).to_matrix()
    pts = points_for(cam, rng)
    pixels, near = [], []
    for p in pts:
        px = cam.project(np.array(p))
        pixels.append(None if px is None else [float(px[0]), float(px[1])])
        near.append(near_boundary(cam, p))
    query = pixels_for(cam)
    rays = []
    for q in query:
        ray = cam.unproject(np.array(q))
        rays.append(None if ray is None else [float(c) for c in ray / np.linalg.norm(ray)])
    return {
        "label": label,
        "rgb_1408": rgb_1408,
        "params": [float(c) for c in cam.get_projection_params()],
        "image_size": [int(c) for c in cam.get_image_size()],
        "valid_radius": cam.get_valid_radius(),
        "max_solid_angle": cam.get_max_solid_angle(),
        "cpf_from_cam_rows": [[float(c) for c in row] for row in t_cpf_cam[:3]],
        "points": pts,
        "pixels": pixels,
        "near_boundary": [i for i, n in enumerate(near) if n],
        "query_pixels": query,
        "rays": rays,
    }


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=OUT, help="the golden file (default: the shipped one)")
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace)
    outputs.check_outside(args.out, "--out", FIXTURE, "the calibration")
    with open(FIXTURE, "rb") as f:
        raw = f.read()
    dc = calibration.device_calibration_from_json_string(raw.decode())
    rng = np.random.default_rng(SEED)
    cams = [
        camera_entry(dc, "camera-rgb", False, rng),
        camera_entry(dc, "camera-rgb", True, rng),
        camera_entry(dc, "camera-slam-left", False, rng),
        camera_entry(dc, "camera-slam-right", False, rng),
    ]
    out = {
        "generator": "tools/make_camera_golden.py",
        "oracle": f"projectaria-tools {version('projectaria-tools')} (PyPI)",
        "fixture": "tests/fixtures/aria_gen1_device_calibration.json",
        "fixture_sha256": hashlib.sha256(raw).hexdigest(),
        "cameras": cams,
    }
    outputs.write_json(args.out, out, args.replace, indent=None, separators=(",", ":"))
    n_pts = sum(len(c["points"]) for c in cams)
    n_pix = sum(len(c["query_pixels"]) for c in cams)
    n_valid = sum(p is not None for c in cams for p in c["pixels"])
    print(f"wrote {args.out}: {n_pts} points ({n_valid} inside the valid FOV), {n_pix} pixels, "
          f"{os.path.getsize(args.out)} bytes")


if __name__ == "__main__":
    main()
