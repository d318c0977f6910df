"""Skinning speed, egogen vs the `smplx` package, in one run on the same machine.

Runs `cargo bench --bench skinning` (criterion), then times smplx (torch, CPU, float32 and
float64) on the same model with the same batch sizes, and prints a Markdown table of frames/s
and ratios (paste it into docs/BENCHMARKS.md).

    python tools/bench_skinning.py            # needs torch + smplx 0.1.28
"""
import json
import os
import subprocess
import sys
import time

import numpy as np
import smplx
import torch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODEL_DIR = os.path.join(ROOT, "assets", "body")


def criterion_ns(name, group="skinning"):
    path = os.path.join(ROOT, "target", "criterion", group, name, "new", "estimates.json")
    with open(path) as f:
        return json.load(f)["median"]["point_estimate"]


def time_smplx(batch, dtype, repeats):
    model = smplx.SMPLX(MODEL_DIR, gender="neutral", ext="npz", use_pca=False, flat_hand_mean=True,
                        num_betas=10, num_expression_coeffs=10, dtype=dtype, batch_size=batch)
    rng = np.random.default_rng(0)
    pose = torch.tensor(rng.normal(0, 0.3, (batch, 165)), dtype=dtype)
    betas = torch.tensor(rng.normal(0, 1, (batch, 10)), dtype=dtype)
    kw = dict(global_orient=pose[:, :3], body_pose=pose[:, 3:66], jaw_pose=pose[:, 66:69],
              leye_pose=pose[:, 69:72], reye_pose=pose[:, 72:75], left_hand_pose=pose[:, 75:120],
              right_hand_pose=pose[:, 120:165], betas=betas)
    with torch.no_grad():
        for _ in range(3):
            model(**kw)
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            model(**kw)
            times.append(time.perf_counter() - t)
    return float(np.median(times))


def main():
    subprocess.run(["cargo", "bench", "--locked", "--bench", "skinning"], cwd=ROOT, check=True)
    ours = {k: criterion_ns(k) * 1e-9 for k in ["full_single", "pose_cached_shape", "joints_only", "joints_markers_cpf"]}
    ours["full_batch_64"] = criterion_ns("full_batch/64") * 1e-9
    threads = torch.get_num_threads()
    rows = []
    for dtype, label in [(torch.float32, "float32"), (torch.float64, "float64")]:
        s1 = time_smplx(1, dtype, 200)
        s64 = time_smplx(64, dtype, 20)
        rows.append((label, s1, s64))
    print(f"\nMachine: {os.cpu_count()} cores, torch {torch.__version__} ({threads} threads), smplx {smplx.__version__ if hasattr(smplx, '__version__') else '0.1.28'}")
    print("\n| case | egogen (f64) frames/s | smplx f32 frames/s | smplx f64 frames/s | egogen / smplx f32 | egogen / smplx f64 |")
    print("|---|---|---|---|---|---|")
    f32, f64 = rows
    def line(name, ours_s, per_frame_ours, s32, s64):
        o = per_frame_ours / ours_s
        print(f"| {name} | {o:,.0f} | {1/s32:,.0f} | {1/s64:,.0f} | {o*s32:.1f}× | {o*s64:.1f}× |")
    line("single frame, full (shape + pose + LBS)", ours["full_single"], 1, f32[1], f64[1])
    line("batch of 64, full", ours["full_batch_64"], 64, f32[2] / 64, f64[2] / 64)
    print(f"| single frame, shape cached (sequence) | {1/ours['pose_cached_shape']:,.0f} | – | – | {f32[1]/ours['pose_cached_shape']:.1f}× | {f64[1]/ours['pose_cached_shape']:.1f}× |")
    for key, name in [("joints_only", "joints + transforms only (fast path)"),
                      ("joints_markers_cpf", "joints + 67 markers + CPF (motion-loop fast path)")]:
        print(f"| {name} | {1/ours[key]:,.0f} | – | – | {f32[1]/ours[key]:.0f}× | {f64[1]/ours[key]:.0f}× |")

    w = criterion_ns("full_single_with_correctives", "official_shaped") * 1e-9
    wo = criterion_ns("full_single_zero_correctives", "official_shaped") * 1e-9
    print(f"\nOfficial SMPL-X sizes (10 475 vertices, 300+100 dirs, random values), single frame: "
          f"with the 31 425×486 pose-corrective product {w*1e3:.2f} ms, skipped (all zero) {wo*1e3:.2f} ms "
          f"({w/wo:.1f}× faster when skipped)")

if __name__ == "__main__":
    sys.exit(main())
