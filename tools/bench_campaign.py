#!/usr/bin/env python3
"""Campaign against a loop of single runs, side by side in one run (docs/CAMPAIGNS.md).

    cargo build --release && python3 tools/bench_campaign.py [--takes 6] [--workers 2] [--out DIR]
    python3 tools/bench_campaign.py --backend slurm --against OTHER_EGOGEN_RUN [--out DIR]

Makes the same takes twice on this machine: once as one campaign (`egogen-run CAMPAIGN.toml`,
all takes' shards in one pool), once as a shell-style loop of `egogen-run RUN.toml --seed …
--scene … --crowd-count …` (each take's own pool, started and drained in turn). Then a second
campaign of as many other takes, budgeted with `--throughput-from` the first, to compare the
budget's estimate with its wall time. Prints one table (wall seconds, worker utilisation from
the pool reports, frames) and writes it as JSON beside the runs (in --out, which must not
exist; a new temporary folder without it).

With `--against BIN`, only the campaign is made, by this checkout's `egogen-run` and by BIN
(another build), alternating, to compare two versions of the pool (e.g. `--backend slurm` on
the single-node cluster of `tools/slurm_single_node.sh`).
"""

import json
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import arguments
import outputs

ROOT = Path(__file__).resolve().parent.parent
BIN = ROOT / "target/release/egogen-run"

RUN = """
[body]
[motion]
source = "agents"
duration_s = 2.0
[crowd]
count = 2
layout = "random"
wander = true
[output]
dir = "single"
mesh_every_n_frames = 0
[render]
cameras = ["camera-slam-left"]
resolution_scale = 0.25
every_n_frames = 4
samples = 4
frames_per_shard = 5
passes = ["colour", "depth", "segmentation"]
colmap = false
[supervisor]
workers = {workers}
[supervisor.slurm]
cpus_per_task = 1
mem_gb = 1.0
poll_interval_s = 0.5
"""

CAMPAIGN = """
[campaign]
run = "run.toml"
out = "{out}"
takes = {takes}
first_seed = {first_seed}
scenes = ["{apartment}"]
floor_plans = [5]
crowd_count = [1, 3]
min_free_disk_gb = 0.0
"""


def run(cmd, log):
    t = time.monotonic()
    with open(log, "w") as f:
        subprocess.run([str(c) for c in cmd], check=True, stderr=f, stdout=f)
    return time.monotonic() - t


def utilisation(reports):
    busy = wall = 0.0
    for r in reports:
        rep = json.loads(Path(r).read_text())
        places = rep["wall_seconds"] * rep["workers"]
        # Slurm tasks' run times, for pool reports that did not sum them themselves.
        attempts = sum(a["seconds"] for sh in rep["shards"] for a in sh["attempts"])
        busy += rep["utilisation"] * places or attempts
        wall += places
    return busy / wall if wall else 0.0


def main():
    ap = arguments.StrictParser()
    ap.add_argument("--takes", type=int, default=6)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=None, help="folder for the runs (must not exist)")
    ap.add_argument("--backend", choices=["local", "slurm"], default="local")
    ap.add_argument("--against", type=Path, default=None)
    a = ap.parse_args()
    if a.out:
        outputs.check_new(a.out, "--out", None, folder=True, parents=True)
    backend = ["--backend", a.backend]
    work = a.out or Path(tempfile.mkdtemp(prefix="egogen-bench-campaign-"))
    work.mkdir(parents=True, exist_ok=True)
    (work / "run.toml").write_text(RUN.format(workers=a.workers))
    apartment = ROOT / "assets/scenes/apartment.glb"
    for name, first in [("campaign", 0), ("budgeted", 1000)]:
        (work / f"{name}.toml").write_text(
            CAMPAIGN.format(out=name, takes=a.takes, first_seed=first, apartment=apartment)
        )

    if a.against:
        return compare(a, work, backend)

    campaign_s = run([BIN, work / "campaign.toml", *backend], work / "campaign.log")
    state = json.loads((work / "campaign/campaign.json").read_text())
    frames = sum(t["frames"] for t in state["takes"])
    camp_util = utilisation((work / "campaign/logs").glob("start_*/pool_report.json"))

    loop_s = 0.0
    loop_reports = []
    for t in state["takes"]:
        out = work / "loop" / t["id"]
        cmd = [BIN, work / "run.toml", "--out", out, "--seed", str(t["seed"]), "--scene", t["scene"], *backend]
        if "crowd_count" in t:
            cmd += ["--crowd-count", str(t["crowd_count"])]
        loop_s += run(cmd, work / f"loop_{t['id']}.log")
        loop_reports += list(out.glob("logs/start_*/pool_report.json"))
    loop_util = utilisation(loop_reports)

    dry = subprocess.run(
        [BIN, work / "budgeted.toml", "--dry-run", "--throughput-from", work / "campaign", *backend],
        capture_output=True, text=True, check=True,
    ).stderr
    m = re.search(r"([0-9.]+) min on", dry)
    estimate_s = float(m.group(1)) * 60 if m else float("nan")
    budgeted_s = run([BIN, work / "budgeted.toml", *backend], work / "budgeted.log")
    budgeted_util = utilisation((work / "budgeted/logs").glob("start_*/pool_report.json"))

    result = {
        "takes": a.takes,
        "workers": a.workers,
        "frames": frames,
        "campaign_wall_s": round(campaign_s, 1),
        "campaign_utilisation": round(camp_util, 3),
        "loop_wall_s": round(loop_s, 1),
        "loop_utilisation": round(loop_util, 3),
        "loop_over_campaign": round(loop_s / campaign_s, 2),
        "budget_estimate_s": round(estimate_s, 1),
        "budgeted_wall_s": round(budgeted_s, 1),
        "budgeted_utilisation": round(budgeted_util, 3),
        "budget_error": round(estimate_s / budgeted_s - 1, 3),
    }
    outputs.write_json(work / "bench_campaign.json", result)
    print(f"{'':28}{'wall s':>9}{'utilisation':>13}")
    print(f"{'campaign':28}{campaign_s:9.1f}{camp_util:13.0%}")
    print(f"{'loop of single runs':28}{loop_s:9.1f}{loop_util:13.0%}")
    print(f"loop / campaign: {loop_s / campaign_s:.2f}x ({a.takes} takes, {frames} frames, {a.workers} workers)")
    print(f"budget of another {a.takes} takes: estimated {estimate_s:.0f} s, took {budgeted_s:.0f} s "
          f"({100 * (estimate_s / budgeted_s - 1):+.0f} %)")
    print(f"details: {work}")


def compare(a, work, backend):
    """The same campaign by this checkout's binary and by `a.against`, alternating."""
    rows = []
    for rnd in range(2):
        for name, binary in [("this", BIN), ("against", a.against)]:
            out = f"{name}_{rnd}"
            (work / f"{out}.toml").write_text(
                CAMPAIGN.format(out=out, takes=a.takes, first_seed=0,
                                apartment=ROOT / "assets/scenes/apartment.glb")
            )
            wall = run([binary, work / f"{out}.toml", *backend], work / f"{out}.log")
            util = utilisation((work / out / "logs").glob("start_*/pool_report.json"))
            rows.append((name, rnd, wall, util))
            print(f"{name:8} round {rnd}: {wall:7.1f} s, utilisation {util:.0%}", flush=True)
    outputs.write_json(work / "bench_campaign_compare.json", [
        {"binary": n, "round": r, "wall_s": round(w, 1), "utilisation": round(u, 3)}
        for n, r, w, u in rows])
    for name in ["this", "against"]:
        w = [r[2] for r in rows if r[0] == name]
        u = [r[3] for r in rows if r[0] == name]
        print(f"{name:8} mean {sum(w) / len(w):7.1f} s, utilisation {sum(u) / len(u):.0%}")
    print(f"details: {work}")


if __name__ == "__main__":
    sys.exit(main())
