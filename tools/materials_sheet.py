"""Renders one take of a config with each `[render.materials]` mode (keep, fill, all; seed 0)
and with fill at two more material seeds (the motion, lighting and skins stay those of the
config: only `render.materials.seed` changes), and writes a contact sheet of the same RGB
frame of each, left to right: keep, fill, all, fill seed 1, fill seed 2 (`--variants`).

    python3 tools/materials_sheet.py [--config configs/default.toml] [--duration 2]
        [--frame 40] [--out out/materials_sheet] [--sheet docs/materials_apartment.png] [--replace]

Uses the release binaries (cargo build --release first); standard library only. The variant
configs are written beside the config (paths in it are relative to its folder) and removed. A
variant's take already in --out is used as it is; the sheet is not overwritten without --replace.
"""
import json
import os
import re
import subprocess
import sys

import arguments
import outputs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VARIANTS = [("keep", 0), ("fill", 0), ("all", 0), ("fill", 1), ("fill", 2)]


def with_materials(text, mode, seed):
    """The config's text with its `[render.materials]` table replaced by this one."""
    text = re.sub(r"(?ms)^\[render\.materials\][^\[]*", "", text)
    return text.rstrip() + f'\n\n[render.materials]\nmode = "{mode}"\nseed = {seed}\n'


def main():
    ap = arguments.StrictParser()
    ap.add_argument("--config", default=os.path.join(ROOT, "configs/default.toml"))
    ap.add_argument("--duration", type=float, default=2.0, help="seconds of motion")
    ap.add_argument("--frame", type=int, default=40, help="the motion frame shown")
    ap.add_argument("--camera", default="camera-rgb")
    ap.add_argument("--variants", nargs="+", default=[f"{m}:{s}" for m, s in VARIANTS],
                    help="MODE:SEED of each column (default: keep:0 fill:0 all:0 fill:1 fill:2)")
    ap.add_argument("--out", default=os.path.join(ROOT, "out/materials_sheet"))
    ap.add_argument("--sheet", default=os.path.join(ROOT, "docs/materials_apartment.png"))
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --sheet")
    args = ap.parse_args()
    outputs.check_new(args.sheet, "--sheet", args.replace)
    run = os.path.join(ROOT, "target/release/egogen-run")
    egogen = os.path.join(ROOT, "target/release/egogen")
    with open(args.config) as f:
        text = f.read()
    frames = []
    variants = [(v.split(":")[0], int(v.split(":")[1])) for v in args.variants]
    for mode, seed in variants:
        out = os.path.join(args.out, f"{mode}_{seed}")
        if not os.path.isdir(out):
            variant = os.path.join(os.path.dirname(os.path.abspath(args.config)),
                                   f".materials_sheet_{mode}_{seed}.toml")
            with open(variant, "w") as f:
                f.write(with_materials(text, mode, seed))
            try:
                subprocess.run([run, variant, "--duration", str(args.duration), "--out", out],
                               check=True)
            finally:
                os.remove(variant)
        cam = os.path.join(out, "cameras", args.camera)
        with open(os.path.join(cam, "annotations.json")) as f:
            doc = json.load(f)
        frame = next((fr for fr in doc["frames"] if fr["frame"] == args.frame), None)
        if frame is None:
            sys.exit(f"{cam}/annotations.json: no frame {args.frame}")
        drawn = doc.get("materials", [])
        patterns = sorted({m["pattern"] for m in drawn})
        print(f"{mode} seed {seed}: {len(drawn)} objects drawn ({', '.join(patterns) or 'none'})")
        frames.append(os.path.join(cam, frame["file"]))
    with outputs.writing(args.sheet, args.replace) as tmp:
        subprocess.run([egogen, "inspect", *frames, "--pass", "rgb", "--exposure", "auto",
                        "--preview", tmp], check=True, stdout=subprocess.DEVNULL)
    print("wrote", args.sheet)


if __name__ == "__main__":
    main()
