#!/usr/bin/env python3
"""Summarises `egogen scene generate --count N --summary FILE` (one JSON line per dwelling):
generation time, tries, rooms, floor area, pieces, catalogue models, and how the seat finder
does against the catalogue (a seating piece is a sofa, armchair, chair, stool or bed), as a
Markdown table; with --png, histograms of area, pieces, models and rooms per dwelling.

    egogen scene generate --seed 0 --count 1000 --check-only --summary dwellings.jsonl
    python3 tools/dwelling_survey.py dwellings.jsonl [--png dwellings_histograms.png [--replace]]
"""
import argparse
import collections
import json
import statistics
import sys

import arguments
import outputs


def quantile(values, q):
    s = sorted(values)
    return s[round((len(s) - 1) * q)]


def histogram(draw, box, values, title, bins=12):
    from PIL import ImageDraw  # noqa: F401 (draw is an ImageDraw)
    x0, y0, x1, y1 = box
    lo, hi = min(values), max(values)
    width = (hi - lo) / bins if hi > lo else 1.0
    counts = [0] * bins
    for v in values:
        counts[min(int((v - lo) / width), bins - 1)] += 1
    top = max(counts)
    bw = (x1 - x0) / bins
    for i, c in enumerate(counts):
        h = (y1 - y0 - 40) * c / top
        draw.rectangle([x0 + i * bw + 2, y1 - 20 - h, x0 + (i + 1) * bw - 2, y1 - 20], fill=(70, 110, 170))
    draw.text((x0, y0), title, fill=(0, 0, 0))
    draw.text((x0, y1 - 15), f"{lo:.4g}", fill=(0, 0, 0))
    draw.text((x1 - 40, y1 - 15), f"{hi:.4g}", fill=(0, 0, 0))


def main():
    ap = arguments.StrictParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("summary")
    ap.add_argument("--png")
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --png")
    a = ap.parse_args()
    if a.png:
        outputs.check_new(a.png, "--png", a.replace)
        outputs.check_outside(a.png, "--png", a.summary, "the summary")
    try:
        rows = [json.loads(line) for line in open(a.summary) if line.strip()]
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"{a.summary}: {e}")
    if not rows:
        sys.exit(f"{a.summary}: no dwellings")
    n = len(rows)
    secs = [r["seconds"] for r in rows]
    tries = collections.Counter(r["tries"] for r in rows)
    draws = sum(r["tries"] for r in rows)
    area = [r["area_m2"] for r in rows]
    pieces = [r["pieces"] for r in rows]
    per_models = [len(set(r["models"])) for r in rows]
    rooms = [len(r["rooms"]) for r in rows]
    used = set(m for r in rows for m in r["models"])
    w = sum(r["seating_with_seat"] for r in rows)
    wo = sum(r["seating_without_seat"] for r in rows)
    other = sum(r["other_with_seat"] + r["built_with_seat"] for r in rows)
    print(f"| over {n} seeds | |")
    print("|---|---|")
    print(f"| generation time per dwelling, one core (median, p95, max) | {statistics.median(secs):.3f}, {quantile(secs, 0.95):.3f}, {max(secs):.3f} s |")
    print(f"| dwellings made | {n} (each passes the checks; {n / draws:.0%} of the {draws} draws passed, the rest drawn again) |")
    print(f"| made on the first draw | {tries[1] / n:.0%} |")
    print(f"| rooms (min–max; counts) | {min(rooms)}–{max(rooms)}; " + ", ".join(f"{k}: {v}" for k, v in sorted(collections.Counter(rooms).items())) + " |")
    print(f"| floor area (p5, median, p95) | {quantile(area, 0.05):.1f}, {statistics.median(area):.1f}, {quantile(area, 0.95):.1f} m² |")
    print(f"| pieces per dwelling (p5, median, p95) | {quantile(pieces, 0.05)}, {statistics.median(pieces):g}, {quantile(pieces, 0.95)} |")
    print(f"| catalogue models per dwelling (p5, median, p95); used over all | {quantile(per_models, 0.05)}, {statistics.median(per_models):g}, {quantile(per_models, 0.95)}; {len(used)} |")
    print(f"| seat finder against the catalogue: precision, recall | {w / max(w + other, 1):.3f}, {w / max(w + wo, 1):.3f} ({w} of {w + wo} seating pieces with a seat found; {other} other objects with one) |")
    if a.png:
        from PIL import Image, ImageDraw
        img = Image.new("RGB", (1200, 300), "white")
        d = ImageDraw.Draw(img)
        histogram(d, (10, 10, 290, 290), area, "floor area (m2)")
        histogram(d, (310, 10, 590, 290), pieces, "pieces per dwelling")
        histogram(d, (610, 10, 890, 290), per_models, "catalogue models per dwelling")
        histogram(d, (910, 10, 1190, 290), rooms, "rooms", bins=max(rooms) - min(rooms) + 1)
        with outputs.writing(a.png, a.replace) as tmp:
            img.save(tmp, format="PNG")
        print(f"\nwrote {a.png}")


if __name__ == "__main__":
    main()
