"""What drawn materials cost: renders one config's take with each `[render.materials]` mode in
turn, `--repeats` rounds interleaved (keep, fill, all, keep, fill, all, …: a slow spell of the
machine hits every mode alike), and prints per camera the seconds per frame of the colour's
path tracing, the ground truth's path tracing and the whole attempt (the pool report's
stages, docs/RENDERING.md "Where a frame's time goes"), median over the rounds, and each
against `keep`.

    python3 tools/bench_materials.py [--config configs/default.toml] [--duration 1]
        [--repeats 3] [--modes keep fill all] [--out out/bench_materials] [--replace]

Uses the release binary (cargo build --release first); standard library only. The variant
configs are written beside the config (paths in it are relative to its folder) and removed.
"""
import json
import os
import shutil
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import arguments  # noqa: E402
import outputs  # noqa: E402
from materials_sheet import with_materials  # noqa: E402


def per_camera(report):
    """camera -> (frames, attempt seconds, {stage: seconds})."""
    out = {}
    for shard in report["shards"]:
        frames, seconds, stages = out.setdefault(shard["camera"], [0, 0.0, {}])
        for a in shard["attempts"]:
            out[shard["camera"]][0] += a["finished"]
            out[shard["camera"]][1] += a["seconds"]
            for k, v in a["stages"].items():
                stages[k] = stages.get(k, 0.0) + v
    return out


def main():
    ap = arguments.StrictParser()
    ap.add_argument("--config", default=os.path.join(ROOT, "configs/default.toml"))
    ap.add_argument("--duration", type=float, default=1.0, help="seconds of motion per take")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--modes", nargs="+", default=["keep", "fill", "all"])
    ap.add_argument("--out", default=os.path.join(ROOT, "out/bench_materials"),
                    help="folder for the takes (must not exist)")
    ap.add_argument("--replace", action="store_true",
                    help="use an existing --out, its takes of these modes and rounds made anew")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace, folder=True, parents=True)
    run = os.path.join(ROOT, "target/release/egogen-run")
    with open(args.config) as f:
        text = f.read()
    folder = os.path.dirname(os.path.abspath(args.config))
    # mode -> camera -> {measure: [seconds per frame, one per round]}
    results = {}
    for r in range(args.repeats):
        for mode in args.modes:
            out = os.path.join(args.out, f"{mode}_{r}")
            shutil.rmtree(out, ignore_errors=True)
            variant = os.path.join(folder, f".bench_materials_{mode}.toml")
            with open(variant, "w") as f:
                f.write(with_materials(text, mode, 0))
            try:
                subprocess.run([run, variant, "--duration", str(args.duration), "--out", out],
                               check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            finally:
                os.remove(variant)
            with open(os.path.join(out, "logs/start_01/pool_report.json")) as f:
                report = json.load(f)
            for cam, (frames, seconds, stages) in per_camera(report).items():
                m = results.setdefault(mode, {}).setdefault(cam, {})
                for name, value in [
                    ("colour path tracing", stages.get("colour_path_tracing", 0.0)),
                    ("ground truth path tracing", stages.get("ground_truth_path_tracing", 0.0)),
                    ("attempt", seconds),
                ]:
                    m.setdefault(name, []).append(value / frames)
            print(f"round {r + 1}/{args.repeats}: {mode} done", file=sys.stderr)
    base = results[args.modes[0]]
    print(f"{args.config}, {args.duration} s of motion, {args.repeats} rounds interleaved; "
          "seconds per frame, median (min–max), and × keep")
    print()
    print("| camera | mode | colour path tracing | ground truth path tracing | attempt |")
    print("|---|---|---|---|---|")
    for cam in sorted(base):
        for mode in args.modes:
            cells = []
            for name in ["colour path tracing", "ground truth path tracing", "attempt"]:
                v = results[mode][cam][name]
                med = statistics.median(v)
                ratio = med / statistics.median(base[cam][name]) if base[cam][name] else float("nan")
                cells.append(f"{med:.3f} ({min(v):.3f}–{max(v):.3f}) ×{ratio:.2f}")
            print(f"| {cam} | {mode} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
