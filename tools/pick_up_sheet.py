#!/usr/bin/env python3
"""A contact sheet of a wearer's RGB frames around a pick-up: each frame turned upright (Aria's
RGB camera is mounted sideways), the picked-up object's box from the camera's annotations
drawn in red. docs/pick_up_scene_thing.png was made so (docs/ACTIVITIES.md "What is picked
up"): a held-out dwelling with things left on its floors, its take rendered, then

    python3 tools/pick_up_sheet.py OUT/cameras/camera-rgb --frames 620 660 700 720 740 760 \\
        --out docs/pick_up_scene_thing.png

Needs numpy, Pillow and OpenEXR (`pip install numpy pillow OpenEXR`).
"""

import argparse
import json
from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image, ImageDraw


def upright(camera: Path, frame: int, boxes) -> Image.Image:
    """Frame `frame` of `camera` in sRGB, turned upright, with `boxes` (pixels, as annotated)."""
    with OpenEXR.File(str(camera / f"frame_{frame:05d}.exr")) as exr:
        rgb = exr.channels()["rgb"].pixels[..., :3].astype(np.float64)
    rgb = np.clip(rgb, 0.0, None)
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1 / 2.4) - 0.055)
    img = Image.fromarray((np.clip(srgb, 0, 1) * 255 + 0.5).astype(np.uint8)).rotate(-90)
    draw = ImageDraw.Draw(img)
    draw.text((6, 6), f"frame {frame}", fill=(255, 255, 255))
    h = img.size[1]
    for x0, y0, x1, y1 in boxes:
        # Turned a quarter clockwise: (x, y) -> (h - 1 - y, x).
        draw.rectangle([h - 1 - y1 - 2, x0 - 2, h - 1 - y0 + 2, x1 + 2], outline=(230, 30, 30), width=2)
    return img


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("camera", type=Path, help="a rendered camera's folder (frames and annotations.json)")
    ap.add_argument("--frames", type=int, nargs="+", required=True)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    annotations = json.loads((args.camera / "annotations.json").read_text())
    boxes = {
        f["frame"]: [o["bbox_xyxy"] for o in f.get("objects", []) if o.get("bbox_xyxy")]
        for f in annotations["frames"]
    }
    missing = [f for f in args.frames if f not in boxes]
    if missing:
        ap.error(f"{args.camera / 'annotations.json'}: no rendered frame {missing}")
    tiles = [upright(args.camera, f, boxes[f]) for f in args.frames]
    w, h = tiles[0].size
    cols = min(3, len(tiles))
    sheet = Image.new("RGB", (w * cols, h * ((len(tiles) + cols - 1) // cols)))
    for k, tile in enumerate(tiles):
        sheet.paste(tile, ((k % cols) * w, (k // cols) * h))
    sheet.save(args.out, optimize=True)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
