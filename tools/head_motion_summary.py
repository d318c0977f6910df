#!/usr/bin/env python3
"""Tables of `egogen motion head-stats --json` records (tools/head_motion_survey.sh): per group
of sources (each variant's takes, the CMU clips, the Aria wearer) the median and range over
its people or clips of each statistic. Stdlib only.

Usage: python3 tools/head_motion_summary.py STATS.json
"""
import json
import math
import sys

STATS = [
    ("head acc median", lambda r: r["head_acceleration"]["all"]["p50"], "m/s²"),
    ("head acc p95", lambda r: r["head_acceleration"]["all"]["p95"], "m/s²"),
    ("join frames / inside median", lambda r: r["head_acceleration"]["join_ratio_median"], "×"),
    ("join frames / inside p95", lambda r: r["head_acceleration"]["join_ratio_p95"], "×"),
    ("pelvis acc p95", lambda r: (r.get("pelvis_acceleration") or {}).get("all", {}).get("p95"), "m/s²"),
    ("pelvis join frames / inside median", lambda r: (r.get("pelvis_acceleration") or {}).get("join_ratio_median"), "×"),
    ("pelvis join frames / inside p95", lambda r: (r.get("pelvis_acceleration") or {}).get("join_ratio_p95"), "×"),
    ("angular speed median", lambda r: r["angular_speed"]["p50"], "rad/s"),
    ("angular speed p95", lambda r: r["angular_speed"]["p95"], "rad/s"),
    ("yaw sway RMS", lambda r: r["yaw_sway_rms_deg"], "°"),
    ("heading to the path 2 m ahead, median", lambda r: r["path_ahead_deg"]["p50"], "°"),
    ("vertical bob RMS", lambda r: r["bob_rms_mm"], "mm"),
    ("step frequency", lambda r: r["step_hz"], "Hz"),
    ("IMU specific force p99", lambda r: r["imu"]["specific_force"]["p99"], "m/s²"),
    ("IMU specific force max", lambda r: r["imu"]["specific_force"]["max"], "m/s²"),
    ("IMU gyro p99", lambda r: r["imu"]["gyro"]["p99"], "rad/s"),
]


def group(label):
    if "aria_mps" in label:
        return "Aria wearer (MPS)"
    if "/assets/motion/cmu/" in label:
        return "CMU walking clips"
    for variant in ("decoded", "shipped"):
        if f"/{variant}/" in label:
            return "default take, " + variant if "/default:" in label else "six takes, " + variant
    return "other"


def cell(values):
    v = sorted(x for x in values if x is not None and math.isfinite(x))
    if not v:
        return "–"
    med = v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])
    if len(v) == 1:
        return f"{med:.2f}"
    return f"{med:.2f} ({v[0]:.2f}–{v[-1]:.2f})"


def main():
    records = json.load(open(sys.argv[1]))
    # CMU: the clips that walk at least 1.5 s.
    groups = {}
    for r in records:
        g = group(r["label"])
        if g == "CMU walking clips" and r["walking_s"] < 1.5:
            continue
        groups.setdefault(g, []).append(r)
    order = [g for g in ("default take, decoded", "default take, shipped", "six takes, decoded",
                         "six takes, shipped", "CMU walking clips", "Aria wearer (MPS)") if g in groups]
    print("| statistic | " + " | ".join(f"{g} ({len(groups[g])})" for g in order) + " |")
    print("|---|" + "---|" * len(order))
    for name, get, unit in STATS:
        print(f"| {name} ({unit}) | " + " | ".join(cell(get(r) for r in groups[g]) for g in order) + " |")


if __name__ == "__main__":
    main()
