#!/usr/bin/env python3
"""A contact sheet of generated dwellings: for each seed, the dwelling from above (its walkable
map with the seats found, `egogen scene inspect`) beside what its first person's Aria RGB camera
sees on the take's first frame (`egogen-run`, two people, 1/2 size, upright).

    python3 tools/dwelling_sheet.py --seeds 0 1 2 3 4 5 6 7 --work /tmp/dwelling_sheet \\
        --out docs/dwellings_sheet.png [--replace] [--egogen target/release/egogen]
        [--egogen-run target/release/egogen-run] [--with-catalogue DIR ...]

`--with-catalogue` adds opt-in furniture libraries (`egogen scene generate --with-catalogue`);
where the dwellings place CC-BY models, their attributions are joined into
`<out stem>.attribution.md` beside the sheet, which must travel with it.

Needs Pillow. Each take renders in about a minute on two cores.
"""
import argparse
import os
import subprocess
import sys

import arguments
import outputs

RUN = """[body]

[motion]
source = "agents"
duration_s = 0.5
seed = {seed}

[crowd]
count = 2
layout = "random"

[output]
dir = "{out}"

[scene]
path = "{scene}"

[render]
cameras = ["camera-rgb"]
resolution_scale = 0.5
every_n_frames = 40
samples = 16
"""


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr[-3000:]}")


def main():
    ap = arguments.StrictParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, nargs="+", required=True)
    ap.add_argument("--work", required=True, help="folder for the dwellings and takes (must not exist)")
    ap.add_argument("--out", required=True, help="sheet PNG (must not exist)")
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    ap.add_argument("--egogen", default="target/release/egogen")
    ap.add_argument("--egogen-run", default="target/release/egogen-run")
    ap.add_argument("--columns", type=int, default=2)
    ap.add_argument("--with-catalogue", action="append", default=[], metavar="DIR",
                    help="an opt-in furniture library to add (repeatable)")
    a = ap.parse_args()
    outputs.check_new(a.work, "--work", None, folder=True, parents=True)
    outputs.check_new(a.out, "--out", a.replace)
    outputs.check_outside(a.out, "--out", a.work, "--work")
    attribution_out = os.path.splitext(a.out)[0] + ".attribution.md"
    if a.with_catalogue:
        outputs.check_new(attribution_out, "--out's attribution", a.replace)
    added = [arg for d in a.with_catalogue for arg in ("--with-catalogue", d)]
    attributions = []
    from PIL import Image, ImageDraw
    os.makedirs(a.work)
    tiles = []
    size = 360
    for seed in a.seeds:
        d = os.path.join(a.work, f"seed_{seed}")
        run([a.egogen, "scene", "generate", "--seed", str(seed), "--out", d] + added)
        attribution = os.path.join(d, "dwelling.attribution.md")
        if os.path.exists(attribution):
            with open(attribution, encoding="utf-8") as f:
                attributions.append((seed, f.read()))
        glb = os.path.abspath(os.path.join(d, "dwelling.glb"))
        run([a.egogen, "scene", "inspect", glb, "--out", os.path.join(d, "map.png"), "--agents", "0"])
        cfg = os.path.join(d, "take.toml")
        with open(cfg, "w") as f:
            f.write(RUN.format(seed=seed, out=os.path.abspath(os.path.join(d, "take")), scene=glb))
        run([a.egogen_run, cfg])
        frame = os.path.join(d, "take", "images", "camera-rgb", "frame_00000.png")
        top = Image.open(os.path.join(d, "map.png")).convert("RGB")
        top.thumbnail((size, size))
        eye = Image.open(frame).convert("RGB").rotate(-90, expand=True).resize((size, size))
        tile = Image.new("RGB", (2 * size + 30, size + 24), "white")
        tile.paste(top, ((size - top.width) // 2 + 10, 20 + (size - top.height) // 2))
        tile.paste(eye, (size + 20, 20))
        ImageDraw.Draw(tile).text((10, 4), f"dwelling:{seed} from above (walkable map, seats) and from the wearer's eye", fill=(0, 0, 0))
        tiles.append(tile)
        print(f"seed {seed} done", flush=True)
    cols = a.columns
    rows = (len(tiles) + cols - 1) // cols
    w, h = tiles[0].size
    sheet = Image.new("RGB", (cols * w, rows * h), "white")
    for k, t in enumerate(tiles):
        sheet.paste(t, ((k % cols) * w, (k // cols) * h))
    with outputs.writing(a.out, a.replace) as tmp:
        sheet.save(tmp, format="PNG")
    print(f"wrote {a.out}")
    if attributions:
        outputs.write_text(attribution_out, joined_attribution(a.out, attributions), a.replace)
        print(f"wrote {attribution_out}")


def joined_attribution(picture, attributions):
    """One attribution for the sheet: the dwellings' `dwelling.attribution.md` files (each a
    header paragraph, then per library a `## ` heading, a paragraph and a table of models),
    every library once with every model it lent any of them once."""
    header, sections = None, {}
    for _, text in attributions:
        head, *libs = text.split("\n## ")
        header = header or head
        for lib in libs:
            lines = lib.rstrip("\n").split("\n")
            rows = [l for l in lines if l.startswith("| `")]
            top = [l for l in lines if not l.startswith("| `")]
            got = sections.setdefault(top[0], (top, set()))
            got[1].update(rows)
    seeds = " ".join(str(seed) for seed, _ in attributions)
    out = header.rstrip("\n") + f"\n\nThe picture `{os.path.basename(picture)}` shows dwellings {seeds}.\n"
    for _, (top, rows) in sorted(sections.items()):
        out += "\n## " + "\n".join(top) + "\n" + "\n".join(sorted(rows)) + "\n"
    return out


if __name__ == "__main__":
    main()
