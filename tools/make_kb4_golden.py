"""Golden Kannala-Brandt (KB4) projections from OpenCV's cv::fisheye (the independent oracle).

Writes tests/fixtures/kb4_golden.json: for two KB4 cameras (fx, fy, cx, cy, k1..k4), camera-
frame points in front of the camera (z > 0, angles from 0 to 80 degrees, including 1e-12 rad)
with `cv2.fisheye.projectPoints` of each, and pixels up to 80 degrees off-axis with `cv2.fisheye.undistortPoints`
(tight termination: 100 iterations or 1e-15) turned into unit rays.

OpenCV divides by z, so only z > 0 is covered; egogen's field-of-view limits are not
OpenCV's and are not tested here.

Run (numpy, PyPI opencv-python-headless):
    .venv-aria/bin/pip install opencv-python-headless
    .venv-aria/bin/python tools/make_kb4_golden.py --replace   # [--out PATH] (a new file)
"""
import math
import os

import cv2
import numpy as np

import arguments
import outputs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "tests", "fixtures", "kb4_golden.json")
SEED = 4

CAMERAS = [
    # A RealSense-T265-like calibration and a strongly distorted one.
    {"name": "t265-like", "fx": 285.72, "fy": 286.92, "cx": 418.38, "cy": 399.27,
     "k": [-0.00616, 0.04307, -0.04012, 0.00686], "size": [848, 800]},
    {"name": "strong", "fx": 410.0, "fy": 405.5, "cx": 322.1, "cy": 241.7,
     "k": [0.12, -0.05, 0.011, -0.0009], "size": [640, 480]},
]


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=OUT, help="the golden file (default: the shipped one)")
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace)
    rng = np.random.default_rng(SEED)
    out = {"generator": "tools/make_kb4_golden.py", "oracle": f"OpenCV {cv2.__version__} cv2.fisheye",
           "cameras": []}
    for cam in CAMERAS:
        K = np.array([[cam["fx"], 0, cam["cx"]], [0, cam["fy"], cam["cy"]], [0, 0, 1.0]])
        D = np.array(cam["k"], dtype=np.float64)
        pts = [[0.0, 0.0, 1.0]]
        for t in (1e-12, 1e-6):
            pts.append([math.sin(t), 0.0, math.cos(t)])
        for _ in range(60):
            t = rng.uniform(0.0, math.radians(80.0))
            phi = rng.uniform(0.0, 2 * math.pi)
            d = rng.uniform(0.2, 10.0)
            pts.append([d * math.sin(t) * math.cos(phi), d * math.sin(t) * math.sin(phi), d * math.cos(t)])
        pts = [[float(f"{c:.12g}") for c in p] for p in pts]
        proj, _ = cv2.fisheye.projectPoints(np.array([pts]), np.zeros(3), np.zeros(3), K, D)
        w, h = cam["size"]
        # Pixels up to 80 degrees from the axis (OpenCV's rays are only meaningful below 90).
        t80 = math.radians(80.0)
        td80 = t80 * (1 + sum(k * t80 ** (2 * i + 2) for i, k in enumerate(cam["k"])))
        pix = []
        while len(pix) < 40:
            u, v = float(rng.uniform(0, w - 1)), float(rng.uniform(0, h - 1))
            if math.hypot((u - cam["cx"]) / cam["fx"], (v - cam["cy"]) / cam["fy"]) < td80:
                pix.append([u, v])
        pix = [[cam["cx"], cam["cy"]]] + [[float(f"{c:.12g}") for c in p] for p in pix]
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-15)
        und = cv2.fisheye.undistortPoints(np.array([pix]), K, D, criteria=crit)
        rays = []
        for a, b in und[0]:
            v = np.array([a, b, 1.0])
            rays.append([float(c) for c in v / np.linalg.norm(v)])
        out["cameras"].append({**cam, "points": pts, "pixels": proj[0].tolist(),
                               "query_pixels": pix, "rays": rays})
    outputs.write_json(args.out, out, args.replace, indent=None, separators=(",", ":"))
    print(f"wrote {args.out}: {os.path.getsize(args.out)} bytes")


if __name__ == "__main__":
    main()
