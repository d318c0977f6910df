"""Builds the skin detail map and the eye mask that ship in assets/body/textures/ from a skin
albedo in MakeHuman's UV layout (the body model's own, docs/BODY_MODEL.md):

- `egogen_skin_detail.jpg`: the albedo's relative lightness, linear luminance over its mean on
  the skin, halved (so 0.5 = the skin's mean, 1.0 = twice as light), grey, 1024²: the skin's
  tone (drawn per agent, docs/RENDERING.md "Skin") is multiplied by twice it, so the face's
  features, creases and freckles show on every tone without the albedo's own colour.
- `egogen_eyes.jpg`: the two eye sockets (painted plain red in MakeHuman's skins: the two red
  islands of equal size; the largest red island, the inside of the mouth, is left out), a mask
  for the `eyes` skin region; the detail map holds 0.5 there.

    python3 tools/build_skin_detail.py ALBEDO [--out assets/body/textures] [--replace]

The shipped files come from `young_lightskinned_female_diffuse_fix_nosehole-albedo.jpg` of
akjava/makehuman-godot3-simple-pbr (MIT; MakeHuman's CC0 skin retouched), assets/NOTICE.
Needs numpy, scipy and Pillow (tools/vision_checks_requirements.txt installs them).
"""
import os
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

import arguments
import outputs

SIZE = 1024
NAMES = ["egogen_skin_detail.jpg", "egogen_eyes.jpg"]


def srgb_to_linear(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def main():
    ap = arguments.StrictParser()
    ap.add_argument("albedo")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__))), "assets/body/textures"))
    ap.add_argument("--replace", action="store_true",
                    help="overwrite the maps in --out (the shipped ones, rebuilt on purpose)")
    args = ap.parse_args()
    outputs.check_new_all([os.path.join(args.out, n) for n in NAMES], "--out", args.replace,
                          parents=True)
    for name in NAMES:
        outputs.check_outside(os.path.join(args.out, name), "--out", args.albedo, "the albedo")
    srgb = np.asarray(Image.open(args.albedo).convert("RGB"), dtype=np.float64) / 255.0
    red = srgb[..., 0] - srgb[..., 1] > 0.35
    labels, n = ndimage.label(red)
    sizes = ndimage.sum(red, labels, range(1, n + 1))
    order = np.argsort(sizes)[::-1]
    if n < 3 or not 0.8 < sizes[order[2]] / sizes[order[1]] < 1.25:
        sys.exit(f"{args.albedo}: expected the mouth and two eye sockets painted red "
                 f"(red islands of {sorted(sizes.astype(int))[::-1][:4]} px)")
    eyes = np.isin(labels, [order[1] + 1, order[2] + 1])
    lin = srgb_to_linear(srgb)
    lum = 0.2126 * lin[..., 0] + 0.7152 * lin[..., 1] + 0.0722 * lin[..., 2]
    skin = (lum > 0.05) & ~red
    detail = np.clip(lum / lum[skin].mean(), 0.0, 2.0) / 2.0
    detail[ndimage.binary_dilation(red, iterations=2)] = 0.5
    eyes = ndimage.binary_dilation(eyes, iterations=2).astype(np.float64)
    os.makedirs(args.out, exist_ok=True)
    for name, plane in zip(NAMES, [detail, eyes]):
        img = Image.fromarray(np.round(plane * 255).astype(np.uint8), "L")
        with outputs.writing(os.path.join(args.out, name), args.replace) as tmp:
            img.resize((SIZE, SIZE), Image.LANCZOS).save(tmp, format="JPEG", quality=92)
        print("wrote", os.path.join(args.out, name))
    print(f"skin mean linear luminance {lum[skin].mean():.3f}; eye sockets {int(eyes.sum())} px")


if __name__ == "__main__":
    main()
