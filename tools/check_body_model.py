#!/usr/bin/env python3
"""Sanity checks of assets/body/SMPLX_*.npz with the reference ``smplx`` loader.

Needs ``torch`` and ``smplx==0.1.28`` (not needed to *build* the model):

    python3 tools/check_body_model.py [--dir assets/body] [--gender neutral]

Checks: the file loads in smplx.SMPLX; zero pose reproduces v_template; a 90 deg
left-knee bend moves only the left lower leg and foot backwards/up; the eye joints lie
inside the head in front of the head joint; plausible stature (neutral 1.6-1.8 m); betas +-3 change
stature / volume; array dtypes and shapes.
"""
import sys

import numpy as np

import arguments


def main():
    ap = arguments.StrictParser()
    ap.add_argument("--dir", default="assets/body")
    ap.add_argument("--gender", default="neutral", choices=["neutral", "male", "female"])
    args = ap.parse_args()

    import torch
    import smplx

    path = f"{args.dir}/SMPLX_{args.gender.upper()}.npz"
    raw = np.load(path, allow_pickle=False)
    print(f"{path}:")
    for k in raw.files:
        print(f"  {k:26s} {str(raw[k].shape):16s} {raw[k].dtype}")
    ok = True

    def check(cond, msg):
        nonlocal ok
        print(("  PASS " if cond else "  FAIL ") + msg)
        ok &= bool(cond)

    m = smplx.SMPLX(args.dir, gender=args.gender, ext="npz", use_pca=False,
                    flat_hand_mean=True, num_betas=10, num_expression_coeffs=10,
                    dtype=torch.float64)
    vt = raw["v_template"]
    f = raw["f"].astype(np.int64)
    with torch.no_grad():
        out0 = m(return_verts=True)
    v0 = out0.vertices[0].numpy()
    j0 = out0.joints[0].numpy()
    check(np.abs(v0 - vt).max() < 1e-6,  # smplx casts the npz arrays through float32
          f"zero pose == v_template (max diff {np.abs(v0 - vt).max():.2e})")
    jr = raw["J_regressor"] @ vt
    check(np.abs(j0[:55] - jr).max() < 1e-6, "joints[:55] == J_regressor @ v_template")
    stature = vt[:, 1].max() - vt[:, 1].min()
    lo, hi = {"neutral": (1.6, 1.8), "male": (1.65, 1.85), "female": (1.5, 1.75)}[args.gender]
    check(lo <= stature <= hi, f"stature {stature:.3f} m in [{lo}, {hi}]")
    print(f"  soles y = {vt[:, 1].min():.4f}, pelvis joint = {jr[0].round(4)}")

    # Eyes inside the head, in front of the head joint, symmetric.
    head, le, re = jr[15], jr[23], jr[24]
    hv = vt[raw["weights"][:, 15] > 0.5]
    inside = all(hv[:, a].min() < e[a] < hv[:, a].max() for e in (le, re) for a in range(3))
    check(inside and le[0] > 0.015 and re[0] < -0.015 and le[2] > head[2] and abs(le[1] - re[1]) < 1e-3,
          f"eye joints L {le.round(4)} R {re.round(4)} inside head bbox, in front of head joint {head.round(4)}")
    # Distance of eye joints to nearest surface vertex (eyeball radius ~12 mm).
    dmin = np.linalg.norm(vt - le, axis=1).min()
    print(f"  left eye joint -> nearest body vertex {1000 * dmin:.1f} mm")

    # Left knee bent 90 deg (flexion = rotation about +x for SMPL-X).
    body_pose = torch.zeros(1, 63, dtype=torch.float64)
    body_pose[0, 3 * (4 - 1) + 0] = np.pi / 2  # joint 4 = left_knee; body_pose starts at joint 1
    with torch.no_grad():
        out = m(body_pose=body_pose)
    v1 = out.vertices[0].numpy()
    j1 = out.joints[0].numpy()
    moved = np.linalg.norm(v1 - vt, axis=1) > 1e-6
    lw = raw["weights"]
    below = lw[:, [4, 7, 10]].sum(1) > 0.5  # left knee / ankle / foot dominated
    check(moved[below].all() and not moved[lw[:, [5, 8, 11]].sum(1) > 0.99].any(),
          f"knee bend moves {moved.sum()} verts, all left-shin verts, no right-leg verts")
    ankle = j1[7]
    knee = j1[4]
    d = ankle - knee
    check(abs(d[1]) < 0.05 and d[2] < -0.3,
          f"left ankle after 90 deg knee flexion is behind the knee: knee->ankle {d.round(3)}")

    # Betas change stature / volume.
    def vol(v):
        a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
        return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6

    print(f"  volume at betas=0: {vol(vt) * 1000:.1f} L")
    for k in range(10):
        res = []
        for s in (-3.0, 3.0):
            betas = torch.zeros(1, 10, dtype=torch.float64)
            betas[0, k] = s
            with torch.no_grad():
                v = m(betas=betas).vertices[0].numpy()
            res.append((v[:, 1].max() - v[:, 1].min(), vol(v) * 1000))
        print(f"  beta{k} -3/+3: stature {res[0][0]:.3f}/{res[1][0]:.3f} m, volume {res[0][1]:.1f}/{res[1][1]:.1f} L")
        if k == 0:
            check(res[1][0] - res[0][0] > 0.2, "beta0 +-3 changes stature by > 20 cm")
    print("ALL PASS" if ok else "SOME CHECKS FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
