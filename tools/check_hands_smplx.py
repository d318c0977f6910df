"""Checks a rendered take's hands against the `smplx` package (the independent oracle): every
person's SMPL-X parameters as a camera's annotations write them (`smplx`: betas, body and
hand poses with `use_pca=False`, translation), posed by `smplx` 0.1.28 in float64, give the
hand landmarks the same annotations list (`hands[].landmarks_3d`, world, m): the wrist, the
15 finger joints and the palm's centre (midway between the wrist and the middle finger's
knuckle) from smplx's joints, each fingertip from the smplx vertex that is its landmark on the
first frame checked.

Run (needs torch + smplx 0.1.28 + numpy):
    python tools/check_hands_smplx.py TAKE [--camera camera-rgb] [--model assets/body] [--every 1]
Prints the largest distance per landmark group and exits 1 when one exceeds --tolerance-m
(default 1e-6).
"""
import json
import os
import sys

import numpy as np
import smplx
import torch

sys.path.insert(0, os.path.dirname(__file__))
import arguments  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Each finger's three SMPL-X joints (from the palm out), thumb to little finger, of the left
# hand (the right's are 15 on): src/body/hand_landmarks.rs.
FINGER_JOINTS = [[37, 38, 39], [25, 26, 27], [28, 29, 30], [34, 35, 36], [31, 32, 33]]
WRISTS = [20, 21]


def mps_joints(joints, hand):
    """The 16 landmarks of MPS order 5..20 (wrist, finger joints, palm centre) from smplx's
    joints (N × 55 × 3) of one hand: N × 16 × 3."""
    off = 15 * hand
    finger = lambda f, k: joints[:, FINGER_JOINTS[f][k] + off]  # noqa: E731
    points = [joints[:, WRISTS[hand]], finger(0, 1), finger(0, 2)]
    for f in range(1, 5):
        points += [finger(f, k) for k in range(3)]
    points.append(0.5 * (joints[:, WRISTS[hand]] + finger(2, 0)))
    return np.stack(points, axis=1)


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("take", help="a rendered take's folder (cameras/<camera>/annotations.json)")
    ap.add_argument("--camera", default="camera-rgb")
    ap.add_argument("--model", default=os.path.join(ROOT, "assets", "body"),
                    help="folder holding SMPLX_NEUTRAL.npz (default: the shipped body model)")
    ap.add_argument("--every", type=int, default=1, help="check every n-th annotated frame")
    ap.add_argument("--tolerance-m", type=float, default=1e-6)
    args = ap.parse_args()
    path = os.path.join(args.take, "cameras", args.camera, "annotations.json")
    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"{path}: cannot read the annotations: {e}")
    if args.every < 1:
        sys.exit(f"--every: {args.every}, expected a whole number ≥ 1")
    by_person = {}
    for frame in doc["frames"][::args.every]:
        for a in frame["agents"]:
            if a.get("hands"):
                by_person.setdefault(a["name"], []).append(a)
    if not by_person:
        sys.exit(f"{path}: no person has hand landmarks (finger motion off?)")
    worst = {"joints": 0.0, "palm": 0.0, "tips": 0.0}
    checked = 0
    for name, rows in by_person.items():
        p = rows[0]["smplx"]
        model = smplx.SMPLX(args.model, gender="neutral", ext="npz", use_pca=False,
                            flat_hand_mean=True, num_betas=len(p["betas"]),
                            num_expression_coeffs=10, use_face_contour=False,
                            dtype=torch.float64)
        t = lambda key: torch.tensor(np.array([r["smplx"][key] for r in rows], dtype=np.float64))  # noqa: E731
        with torch.no_grad():
            out = model(betas=t("betas"), global_orient=t("global_orient"), body_pose=t("body_pose"),
                        jaw_pose=t("jaw_pose"), leye_pose=t("leye_pose"), reye_pose=t("reye_pose"),
                        left_hand_pose=t("left_hand_pose"), right_hand_pose=t("right_hand_pose"),
                        transl=t("transl"), return_verts=True,
                        expression=torch.zeros((len(rows), 10), dtype=torch.float64))
        joints, verts = out.joints[:, :55].numpy(), out.vertices.numpy()
        for hand in (0, 1):
            ours = np.array([r["hands"][hand]["landmarks_3d"] for r in rows], dtype=np.float64)
            theirs = mps_joints(joints, hand)
            err = np.linalg.norm(ours[:, 5:] - theirs, axis=2)
            worst["joints"] = max(worst["joints"], float(err[:, :15].max()))
            worst["palm"] = max(worst["palm"], float(err[:, 15].max()))
            # Each fingertip's vertex: the one at its landmark on the first frame.
            tips = [int(np.argmin(np.linalg.norm(verts[0] - ours[0, k], axis=1))) for k in range(5)]
            err = np.linalg.norm(ours[:, :5] - verts[:, tips], axis=2)
            worst["tips"] = max(worst["tips"], float(err.max()))
        checked += len(rows)
    print(f"{checked} person-frames of {len(by_person)} people ({path}): largest distance to smplx — "
          f"wrist and finger joints {worst['joints']:.2e} m, palm centre {worst['palm']:.2e} m, "
          f"fingertips {worst['tips']:.2e} m")
    if max(worst.values()) > args.tolerance_m:
        sys.exit(f"more than {args.tolerance_m} m apart")


if __name__ == "__main__":
    main()
