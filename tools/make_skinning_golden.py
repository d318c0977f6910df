"""Golden skinning data from the `smplx` package (the independent oracle).

Writes tests/fixtures/skinning_golden_default.npz (our shipped neutral model) and
tests/fixtures/skinning_golden_random.npz (the random model with official SMPL-X shapes, see
random_smplx_model.py). Each holds the inputs (betas, expression, full 165-value poses, transl)
and smplx's outputs in float64: all 55 joints, all vertices for the first FULL_POSES bodies,
and a fixed vertex subset for every body (float64; the full-mesh bodies, all near the origin,
are stored as float32, rounding < 1e-7 m).

Run (needs torch + smplx 0.1.28):  python tools/make_skinning_golden.py [default] [random] --replace
(the shipped files are not overwritten without --replace).
"""
import os
import sys
import tempfile

import numpy as np
import smplx
import torch

sys.path.insert(0, os.path.dirname(__file__))
import arguments  # noqa: E402
import outputs  # noqa: E402
import random_smplx_model  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIX = os.path.join(ROOT, "tests", "fixtures")
N_RANDOM = 100
FULL_POSES = 6
SUBSET = 600


def poses_and_shapes(rng, n_betas, n_expr):
    """≥ 100 random bodies plus extremes: angles near 0 and π, ±5σ betas, far translations."""
    bodies = []
    for i in range(N_RANDOM):
        pose = rng.normal(0, 0.4, 165)
        pose[:3] = rng.normal(0, 1.5, 3)
        betas = rng.normal(0, 1.5, n_betas)
        expr = rng.normal(0, 1.0, n_expr)
        transl = rng.normal(0, 1.0, 3)
        bodies.append((pose, betas, expr, transl))

    def axis(k):
        a = rng.normal(size=3)
        return a / np.linalg.norm(a)

    extremes = []
    for angle in [0.0, 1e-12, 1e-8, 1e-5, 1e-3, np.pi - 1e-3, np.pi - 1e-6, np.pi, np.pi + 1e-6, 2.5, 4.0]:
        pose = np.concatenate([angle * axis(j) for j in range(55)])
        extremes.append((pose, np.zeros(n_betas), np.zeros(n_expr), np.zeros(3)))
    for sign in [5.0, -5.0]:
        extremes.append((rng.normal(0, 0.4, 165), np.full(n_betas, sign), np.zeros(n_expr), np.zeros(3)))
        b = np.zeros(n_betas)
        b[0] = sign
        extremes.append((np.zeros(165), b, np.zeros(n_expr), np.zeros(3)))
    extremes.append((rng.normal(0, 0.4, 165), rng.normal(0, 1, n_betas), np.zeros(n_expr),
                     np.array([1000.0, -2000.0, 500.0])))
    return extremes[:FULL_POSES] + bodies + extremes[FULL_POSES:]


def run_smplx(model_dir, n_betas, n_expr, bodies):
    model = smplx.SMPLX(model_dir, gender="neutral", ext="npz", use_pca=False, flat_hand_mean=True,
                        num_betas=n_betas, num_expression_coeffs=n_expr, use_face_contour=False,
                        dtype=torch.float64)
    pose = torch.tensor(np.stack([b[0] for b in bodies]))
    betas = torch.tensor(np.stack([b[1] for b in bodies]))
    expr = torch.tensor(np.stack([b[2] for b in bodies]))
    transl = torch.tensor(np.stack([b[3] for b in bodies]))
    with torch.no_grad():
        out = model(global_orient=pose[:, :3], body_pose=pose[:, 3:66], jaw_pose=pose[:, 66:69],
                    leye_pose=pose[:, 69:72], reye_pose=pose[:, 72:75], left_hand_pose=pose[:, 75:120],
                    right_hand_pose=pose[:, 120:165], betas=betas, expression=expr, transl=transl,
                    return_verts=True)
    return pose.numpy(), betas.numpy(), expr.numpy(), transl.numpy(), out.vertices.numpy(), out.joints[:, :55].numpy()


def write(name, model_dir, n_betas, n_expr, seed, replace):
    rng = np.random.default_rng(seed)
    bodies = poses_and_shapes(rng, n_betas, n_expr)
    pose, betas, expr, transl, verts, joints = run_smplx(model_dir, n_betas, n_expr, bodies)
    subset = np.sort(rng.choice(verts.shape[1], SUBSET, replace=False)).astype(np.int64)
    path = os.path.join(FIX, name)
    with outputs.writing(path, replace) as tmp, open(tmp, "wb") as f:
        np.savez_compressed(f, poses=pose, betas=betas, expression=expr, transl=transl, joints=joints,
                            subset=subset, vertices_subset=verts[:, subset],
                            vertices_full=verts[:FULL_POSES].astype(np.float32))
    print(f"wrote {path}: {len(bodies)} bodies, {verts.shape[1]} vertices, {os.path.getsize(path)} bytes")


def main():
    which, replace = arguments.switch(sys.argv[1:], "--replace")
    which = which or ["default", "random"]
    unknown = [a for a in which if a not in ("default", "random")]
    if unknown:
        sys.exit(f"usage: make_skinning_golden.py [default] [random] [--replace] (not {' '.join(unknown)})")
    outputs.check_new_all([os.path.join(FIX, f"skinning_golden_{w}.npz") for w in which],
                          "golden", replace, parents=True)
    os.makedirs(FIX, exist_ok=True)
    if "default" in which:
        write("skinning_golden_default.npz", os.path.join(ROOT, "assets", "body"), 10, 10, seed=1,
              replace=replace)
    if "random" in which:
        with tempfile.TemporaryDirectory() as tmp:
            np.savez(os.path.join(tmp, "SMPLX_NEUTRAL.npz"), **random_smplx_model.build())
            write("skinning_golden_random.npz", tmp, 300, 100, seed=2, replace=replace)


if __name__ == "__main__":
    main()
