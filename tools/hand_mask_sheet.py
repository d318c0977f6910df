#!/usr/bin/env python3
"""A strip of rendered frames, each twice: its colour, then the same with every person's
hand masks drawn over it (`segmentation.part`: left hand green, right hand red, left forearm
blue, right forearm yellow) and held objects (segmentation ids from 2000) purple; turned
upright (the Aria RGB camera is mounted sideways) and shrunk to `--tile-px`. The frames are of
one take (`TAKE --frames ...`) or of several (`--shots TAKE:FRAME ...`).

    python3 tools/hand_mask_sheet.py TAKE --frames 120 160 200 --out docs/hand_masks.png
        [--camera camera-rgb] [--tile-px 352] [--replace]
    python3 tools/hand_mask_sheet.py --shots walk:320 sit:250 other:500 --out sheet.png

The take must have the `colour` and `segmentation` passes. Needs numpy, OpenEXR and Pillow, and
egogen's reader (`pip install ./python`, or run from the checkout).
"""

import sys
from pathlib import Path

import arguments
import outputs

PART_COLOURS = {1: (40, 220, 60), 2: (230, 50, 40), 3: (120, 200, 255), 4: (255, 200, 60)}
HELD_COLOUR = (170, 60, 255)
HELD_ID_BASE = 2000


def tiles(take: Path, camera: str, frames: list) -> list:
    import numpy as np

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "python"))
    from egogen import reader

    found = {}
    for frame in reader.Take(take).frames(camera):
        if frame.index in frames:
            found[frame.index] = frame.read(["rgb", "segmentation", "body_part"])
    missing = [f for f in frames if f not in found]
    if missing:
        raise SystemExit(f"{take}: {camera} has no rendered frame {missing[0]}")
    out = []
    for f in frames:
        px = found[f]
        rgb = np.clip(px["rgb"], 0.0, None)
        # Exposure: the 99th percentile of the luminance to 0.9, then sRGB.
        lum = rgb @ np.array([0.2126, 0.7152, 0.0722])
        k = 0.9 / max(float(np.percentile(lum[lum > 0], 99)) if (lum > 0).any() else 1.0, 1e-6)
        x = np.clip(rgb * k, 0.0, 1.0)
        img = (np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055) * 255).astype(np.uint8)
        over = img.copy()
        masks = [(px["body_part"] == p, c) for p, c in PART_COLOURS.items()]
        masks.append((px["segmentation"] >= HELD_ID_BASE, HELD_COLOUR))
        for m, c in masks:
            over[m] = (0.35 * img[m] + 0.65 * np.array(c)).astype(np.uint8)
        out.extend([img, over])
    return out


def main() -> None:
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("take", type=Path, nargs="?")
    ap.add_argument("--frames", type=int, nargs="+")
    ap.add_argument("--shots", nargs="+", metavar="TAKE:FRAME", help="frames of several takes")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--camera", default="camera-rgb")
    ap.add_argument("--tile-px", type=int, default=352)
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    a = ap.parse_args()
    if (a.take is None) == (a.shots is None) or (a.take is None) != (a.frames is None):
        ap.error("give TAKE --frames F ..., or --shots TAKE:FRAME ...")
    shots = [(a.take, a.frames)] if a.take else []
    for s in a.shots or []:
        take, _, frame = s.rpartition(":")
        if not take or not frame.isdigit():
            ap.error(f"--shots: `{s}`, expected TAKE:FRAME (a folder, a colon, a frame number)")
        shots.append((Path(take), [int(frame)]))
    outputs.check_new(a.out, "--out", a.replace)
    for take, _ in shots:
        outputs.check_outside(a.out, "--out", take, "the take")
    from PIL import Image

    images = [Image.fromarray(t).rotate(-90).resize((a.tile_px, a.tile_px), Image.LANCZOS)
              for take, frames in shots for t in tiles(take, a.camera, frames)]
    gap = 4
    sheet = Image.new("RGB", (len(images) * (a.tile_px + gap) - gap, a.tile_px), (255, 255, 255))
    for i, im in enumerate(images):
        sheet.paste(im, (i * (a.tile_px + gap), 0))
    tmp = a.out.with_name(a.out.name + ".partial.png")
    sheet.save(tmp, optimize=True)
    tmp.replace(a.out)
    print(f"{a.out}: {len(images) // 2} frames of {', '.join(str(t) for t, _ in shots)} ({a.camera})")


if __name__ == "__main__":
    main()
