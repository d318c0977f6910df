"""Renders configs/appearance.toml for several seeds and writes one contact sheet of the
frame in each where the wearer sees the other person largest (its segmentation box, preferring
frames where that box is clear of the image border), with the
seed's skin tones, HDRI, lamp and headset offset printed beside it.

    python3 tools/appearance_sheet.py [--seeds 0 1 2 3 4 5] [--out out/appearance_seeds]
        [--sheet docs/appearance_seeds.png] [--replace]

Uses the release binaries (cargo build --release first); standard library only. A seed's take
already in --out is used as it is; the sheet is not overwritten without --replace.
"""
import json
import os
import subprocess

import arguments
import outputs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = arguments.StrictParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5])
    ap.add_argument("--config", default=os.path.join(ROOT, "configs/appearance.toml"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out/appearance_seeds"))
    ap.add_argument("--sheet", default=os.path.join(ROOT, "docs/appearance_seeds.png"))
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --sheet")
    args = ap.parse_args()
    outputs.check_new(args.sheet, "--sheet", args.replace)
    run = os.path.join(ROOT, "target/release/egogen-run")
    egogen = os.path.join(ROOT, "target/release/egogen")
    frames = []
    for seed in args.seeds:
        out = os.path.join(args.out, f"seed_{seed}")
        if not os.path.isdir(out):
            subprocess.run([run, args.config, "--seed", str(seed), "--out", out], check=True)
        with open(os.path.join(out, "cameras/camera-rgb/annotations.json")) as f:
            doc = json.load(f)

        size = doc["camera"]["resolution_px"]

        def area(frame):
            boxes = [a["bbox_xyxy"] for a in frame["agents"] if not a["wearer"] and a["bbox_xyxy"]]
            return max(((b[2] - b[0] + 1) * (b[3] - b[1] + 1) for b in boxes), default=0)

        def whole(frame):
            # The other person's box clear of the image border by 5 % (not cut off).
            m = [0.05 * size[0], 0.05 * size[1]]
            return any(
                b[0] > m[0] and b[1] > m[1] and b[2] < size[0] - m[0] and b[3] < size[1] - m[1]
                for a in frame["agents"]
                if not a["wearer"] and (b := a["bbox_xyxy"])
            )

        best = max(doc["frames"], key=lambda f: (whole(f), area(f)))
        hdri = doc["lighting"].get("world_hdri") or {}
        tones = ", ".join(f"{s['name']} {s['skin']['monk_skin_tone']}" for s in doc["skins"])
        wear = doc.get("headset_wear") or {}
        print(
            f"seed {seed}: frame {best['frame']} (other person {area(best)} px); Monk tones {tones}; "
            f"HDRI {hdri.get('name')} x{hdri.get('strength', 0):.2f}; "
            f"lamp {doc['lighting']['point_lights'][0]['watts']:.0f} W; "
            f"wear {[round(1000 * t, 1) for t in wear.get('translation_m', [])]} mm"
        )
        frames.append(os.path.join(out, "cameras/camera-rgb", best["file"]))
    with outputs.writing(args.sheet, args.replace) as tmp:
        subprocess.run([egogen, "inspect", *frames, "--pass", "rgb", "--exposure", "auto",
                        "--preview", tmp],
                       check=True, stdout=subprocess.DEVNULL)
    print("wrote", args.sheet)


main()
