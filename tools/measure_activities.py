#!/usr/bin/env python3
"""Measures activities over seeds: for each scene and seed, `egogen synth` makes a take of 3
people wandering 60 s with the activity weights of configs/apartment_activities.toml (and, with
--walk-only, the same take walking only), then prints per scene the figures of
docs/ACTIVITIES.md "Measured": share of time per activity and phase, seats sat on, the seat fit
(median, max), how far the feet stay from the clip's, the body's sink into the seat, foot
contact (paper Eq. 12) of walking and of each activity, the fastest joint turn where activities
join the walk beside the clips' own, frames with the pelvis over a wall, activities skipped, and
what the pick-ups took (docs/ACTIVITIES.md "What is picked up": kinds, heights, the palm's gap
over the object's top, the deepest fingertip inside it).

    python3 tools/measure_activities.py --bin target/release/egogen \
        --scenes apartment small_house --seeds 0 1 2 3 4 5 --out out/measure_activities
    python3 tools/measure_activities.py ... --set 'blend_s = 0.8' --out out/measure_blend08
    python3 tools/measure_activities.py ... --scenes dwelling:5000 dwelling:5001 --seeds 0  # generated dwellings
    python3 tools/measure_activities.py ... --scenes path/to/dwelling_5000.glb --seeds 0      # any .glb file
    python3 tools/measure_activities.py ... --weights '{ walk = 1.0, stand = 1.0, sit = 2.0, pick_up = 3.0 }'
    python3 tools/measure_activities.py ... --policy assets/policy/dwellings/policy.safetensors  # other weights
"""

import json
import re
import statistics
import subprocess
import sys
from collections import Counter, defaultdict
from pathlib import Path

import arguments

ROOT = Path(__file__).resolve().parent.parent

CONFIG = """
[scene]
path = "{scene}"
[motion]
duration_s = {duration}
stop_when_done = false
wander_distance_m = [2.0, 5.0]
clearance_m = 0.4
seed = {seed}
{policy}[activities]
weights = {weights}
{extra}
[crowd]
count = 3
layout = "random"
steering = "policy"
wander = true
[output]
dir = "{out}"
"""

WEIGHTS = "{ walk = 1.0, stand = 1.0, sit = 2.0, pick_up = 1.0 }"


def take(bin_, scene, seed, duration, weights, out, extra="", policy=None):
    out.parent.mkdir(parents=True, exist_ok=True)
    if not (out / "summary.json").exists():
        config = out.with_suffix(".toml")
        config.write_text(
            CONFIG.format(
                scene=scene if scene.startswith("dwelling:") or scene.endswith(".glb")
                else ROOT / "assets/scenes" / f"{scene}.glb",
                duration=duration,
                seed=seed,
                weights=weights,
                extra=extra,
                policy=f'policy = "{Path(policy).resolve()}"\n' if policy else "",
                out=out.resolve(),
            )
        )
        subprocess.run([bin_, "synth", str(config), "--quiet"], check=True)
    return json.loads((out / "summary.json").read_text())


SEAT_KINDS = ("armchair", "sofa", "couch", "bed", "stool", "bench", "chair")


def folder_of(scene):
    """The takes' folder name of a scene: `dwelling:7` -> dwelling_7, `a/b/house.glb` -> house."""
    return Path(scene).stem if scene.endswith(".glb") else scene.replace(":", "_")


def seat_kind(name):
    """A seat's kind from its object's name: the first of SEAT_KINDS in it (`chair_7`,
    `IKEA_chair_PELLO.001` -> chair), else the name without a trailing number."""
    low = (name or "?").lower()
    return next((k for k in SEAT_KINDS if k in low), re.sub(r"[_.]\d+$", "", low))


def print_sit_share(sits, sit_skips):
    """Of the sits drawn where seats exist (skips for no seat or every seat taken left out), the
    share done, overall and by seat kind (a skip's kind read from its reason's seat name)."""
    seatless = ("the scene has no seat", "every seat on this floor is taken",
                "every free seat on this floor was walked", "the take ended")
    drawn = [r for r in sit_skips if not r.startswith(seatless)]
    if not sits and not drawn:
        return
    done = Counter(seat_kind(r["seat"]) for r in sits)
    missed = Counter()
    for reason in drawn:
        m = re.search(r"(?:seat of|sitting on) (\S+?)(?:,| |$|\))", reason)
        missed[seat_kind(m.group(1)) if m else "?"] += 1
    total = len(sits) + len(drawn)
    pulled = sum(1 for r in sits if r.get("chair_pulled_m"))
    print(f"sits drawn where seats exist: {total}, done {len(sits)} ({100 * len(sits) / total:.0f} %; "
          f"{pulled} on chairs pulled out from their tables); by seat: "
          + ", ".join(f"{k} {done[k]}/{done[k] + missed[k]}" for k in sorted(set(done) | set(missed))))


def frames_of(segments, frames):
    """Frames per (activity, phase); the rest walking."""
    counts = Counter()
    for s in segments:
        counts[(s["activity"], s["phase"])] += s["end_frame"] - s["start_frame"]
    counts[("walk", "")] = frames - sum(counts.values())
    return counts


def main():
    ap = arguments.StrictParser()
    ap.add_argument("--bin", default=str(ROOT / "target/release/egogen"))
    ap.add_argument("--scenes", nargs="+", default=["apartment", "small_house"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 3, 4, 5])
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--walk-only", action="store_true", help="also the same takes walking only")
    ap.add_argument("--weights", default=WEIGHTS, help=f"[activities] weights (default {WEIGHTS})")
    ap.add_argument("--set", action="append", default=[],
                    help="another [activities] key, e.g. --set 'blend_s = 0.8' (the knobs' trades)")
    ap.add_argument("--out", default=str(ROOT / "out/measure_activities"))
    ap.add_argument("--policy", help="policy weights the takes walk with (default: the shipped policy)")
    ap.add_argument("--pool", metavar="NAME",
                    help="report the scenes' takes together under NAME (e.g. 50 generated dwellings)")
    args = ap.parse_args()
    out = Path(args.out)
    groups = [(args.pool, args.scenes)] if args.pool else [(s, [s]) for s in args.scenes]
    for scene, scenes in groups:
        counts, records, skipped, held, picked = Counter(), [], Counter(), [], 0
        sit_skips = []
        contact_walk, off_floor, agents = [], 0, 0
        walk_only_contact = []
        goals = goals_given = 0
        for scene_file, seed in ((f, seed) for f in scenes for seed in args.seeds):
            s = take(args.bin, scene_file, seed, args.duration, args.weights,
                     out / folder_of(scene_file) / f"seed{seed}", "\n".join(args.set), args.policy)
            goals += s.get("totals", {}).get("goals_reached", 0)
            goals_given += s.get("totals", {}).get("goals", 0)
            for a in s["agents"]:
                agents += 1
                counts += frames_of(a.get("activity_segments", []), s["frames"])
                records += a.get("activities", [])
                skipped.update(k["reason"].split(" (")[0] for k in a.get("skipped_activities", []))
                sit_skips += [k["reason"] for k in a.get("skipped_activities", []) if k["activity"] == "sit"]
                contact_walk.append(a["contact"])
                held += a.get("held_objects", [])
                picked += any(r["activity"] == "pick_up" for r in a.get("activities", []))
                off_floor += a["pelvis_off_floor_frames"]
            if args.walk_only:
                w = take(args.bin, scene_file, seed, args.duration, "{ walk = 1.0 }",
                         out / folder_of(scene_file) / f"seed{seed}_walk", policy=args.policy)
                walk_only_contact += [a["contact"] for a in w["agents"]]
        total = sum(counts.values())
        takes = len(args.seeds) * len(scenes)
        print(f"## {scene}: {takes} takes x {agents // takes} people x {args.duration:g} s"
              + (f" ({'; '.join(args.set)})" if args.set else ""))
        print(f"goals reached: {goals} of {goals_given} ({100 * goals / max(goals_given, 1):.1f} %; "
              f"{goals / agents:.1f} per person)")
        by_activity = defaultdict(int)
        for (a, _), n in counts.items():
            by_activity[a] += n
        print("time share: " + ", ".join(
            f"{a} {100 * n / total:.1f} %" for a, n in sorted(by_activity.items(), key=lambda x: -x[1])))
        print("  by phase: " + ", ".join(
            f"{a}/{p} {100 * n / total:.1f} %" for (a, p), n in sorted(counts.items()) if p))
        done = Counter(r["activity"] for r in records)
        print("done: " + ", ".join(f"{k} {v}" for k, v in sorted(done.items())))
        sits = [r for r in records if r["activity"] == "sit"]
        if sits:
            fit = [abs(r["seat_fit_m"]) for r in sits]
            print(f"sits: {len(sits)} on {len(set(r['seat'] for r in sits))} seats "
                  f"({', '.join(sorted(set(r['seat'] for r in sits)))}); clips "
                  f"{dict(Counter(r['clip'] for r in sits))}")
            print(f"  seat fit |m|: median {statistics.median(fit):.3f}, max {max(fit):.3f}; "
                  f"feet off the clip's: max {max(r['foot_miss_m'] for r in sits) * 1000:.2f} mm; "
                  f"sink into the seat: median {statistics.median(r['seat_penetration_m'] for r in sits) * 1000:.1f} mm, "
                  f"max {max(r['seat_penetration_m'] for r in sits) * 1000:.1f} mm")
            gaps = [r["seat_gap_m"] * 1000 for r in sits if "seat_gap_m" in r]
            if gaps:
                print(f"  seated over the seat (buttocks and thighs, mm; - into it): median "
                      f"{statistics.median(gaps):.1f}, min {min(gaps):.1f}, max {max(gaps):.1f}")
            turns = [abs(r["turn_deg"]) for r in sits]
            print(f"  turn before sitting: median {statistics.median(turns):.0f} deg, max {max(turns):.0f} deg")
        print_sit_share(sits, sit_skips)
        # Contact of whole activities only (one cut short by the take's end scores its partial turn).
        whole = [r for r in records if r["end_frame"] < s["frames"]]
        print(f"foot contact (Eq. 12): walking {statistics.mean(contact_walk):.3f}"
              + (f" (walking only: {statistics.mean(walk_only_contact):.3f})" if walk_only_contact else "")
              + "; " + ", ".join(
                  f"{k} {statistics.mean(r['contact'] for r in whole if r['activity'] == k):.3f}"
                  for k in sorted(set(r["activity"] for r in whole))))
        for k in sorted(set(r["activity"] for r in records)):
            rs = [r for r in records if r["activity"] == k]
            clip = [r["clip_joint_speed_rad_s"] for r in rs if r.get("clip_joint_speed_rad_s")]
            print(f"fastest joint turn at the joins, {k}: max {max(r['join_joint_speed_rad_s'] for r in rs):.2f} rad/s, "
                  f"median {statistics.median(r['join_joint_speed_rad_s'] for r in rs):.2f}"
                  + (f" (in the clip itself: {max(clip):.2f})" if clip else ""))
        if picked:
            pick_ups = sum(r["activity"] == "pick_up" for r in records)
            walked_to = [r for r in records if r["activity"] == "pick_up" and r.get("object")]
            print(f"picked up: {pick_ups} pick-ups by {picked} people; {len(held)} objects taken"
                  f" ({sum('scene_object' in o for o in held)} of them the scene's own, of"
                  f" {len(walked_to)} pick-ups that walked to one)")
        if held:
            gaps = [o["palm_gap_m"] * 100 for o in held]
            heights = [o["size_m"][2] * 100 for o in held]
            print("  kinds: " + ", ".join(f"{v} {k}" for k, v in Counter(o.get("kind") or "scene thing" for o in held).most_common())
                  + f"; heights {min(heights):.1f}–{max(heights):.1f} cm")
            print(f"  palm over the top: {min(gaps):.1f}–{max(gaps):.1f} cm (median {statistics.median(gaps):.1f}); "
                  f"deepest fingertip inside: {max(o['fingertip_depth_m'] for o in held) * 1000:.1f} mm")
        print(f"pelvis over a wall (frames): {off_floor}")
        print("skipped: " + (", ".join(f"{v} x {k}" for k, v in skipped.most_common()) or "none"))
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
