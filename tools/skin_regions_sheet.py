"""Close-ups of the skins a run recorded: face and hand of the rest body under one area light,
each skin's material built by blender_scripts/render_shard.py itself from what the annotations
record (base tone, the regions tinted through the body model's masks, the detail map), side by
side.

    ~/.cache/egogen/bpy-4.5/bin/python tools/skin_regions_sheet.py ANNOTATIONS.json [...]
        [--model assets/body/SMPLX_NEUTRAL.npz] [--out docs/skin_regions.png] [--replace]
        [--size 256] [--views face,hand] [--samples 64] [--detail recorded|off|both]

Views: `face` (three-quarter, head and ears), `hand` (the left hand's back), `closeup` (the
eyes, brows and nose, frontal: what the detail map adds is seen best here).

Runs in the Python that has Blender's `bpy` (egogen installs it there on first render).
Skins are taken in order from every file given, duplicates (same tone) once.
"""
import importlib.util
import json
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # also under `blender --python`
import arguments  # noqa: E402
import outputs  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def shard_script():
    spec = importlib.util.spec_from_file_location(
        "render_shard", os.path.join(ROOT, "blender_scripts/render_shard.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def skins_of(paths):
    seen, skins = set(), []
    for path in paths:
        with open(path) as f:
            doc = json.load(f)
        for entry in doc.get("skins", []):
            tone = entry["skin"]["monk_skin_tone"]
            if tone not in seen:
                seen.add(tone)
                skins.append(entry)
    return skins


def look_at(obj, target):
    obj.rotation_euler = (Vector(target) - obj.location).to_track_quat("-Z", "Y").to_euler()


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("annotations", nargs="+")
    ap.add_argument("--model", default=os.path.join(ROOT, "assets/body/SMPLX_NEUTRAL.npz"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs/skin_regions.png"))
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--views", default="face,hand", help="comma-separated: face, hand, closeup")
    ap.add_argument("--samples", type=int, default=64)
    ap.add_argument("--detail", choices=("recorded", "off", "both"), default="recorded",
                    help="the detail map as recorded, none, or each skin without and with it side by side")
    args = ap.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else None)
    outputs.check_new(args.out, "--out", args.replace)

    rs = shard_script()
    skins = skins_of(args.annotations)
    if not skins:
        sys.exit(f"no skins recorded in {args.annotations}")
    model = np.load(args.model)
    if "vt" not in model:
        sys.exit(f"{args.model}: no `vt`/`ft` (UVs); regions cannot be shown")
    textures = os.path.join(os.path.dirname(os.path.abspath(args.model)), "textures")
    v, f = model["v_template"], model["f"].astype(np.int64)
    corner_uvs = model["vt"][model["ft"].astype(np.int64)].reshape(-1, 2).astype(np.float32)
    zup = np.stack([v[:, 0], -v[:, 2], v[:, 1]], 1)  # model y-up, z forward -> Blender z-up
    joints = model["J_regressor"] @ zup
    head, hand = joints[15] + np.array([0.0, 0.0, 0.02]), joints[20] + np.array([0.13, 0.0, 0.0])
    eyes = joints[15] + np.array([0.0, -0.08, 0.025])
    known = {  # (target, camera offset, lens mm)
        "face": (head, (0.12, -0.42, 0.03), 70.0),
        "hand": (hand, (-0.02, -0.12, 0.30), 50.0),
        "closeup": (eyes, (0.05, -0.36, 0.02), 85.0),
    }
    names = [v.strip() for v in args.views.split(",") if v.strip()]
    unknown = [v for v in names if v not in known]
    if unknown or not names:
        sys.exit(f"--views {args.views}: expected some of {', '.join(known)}")
    views = [known[v] for v in names]

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.samples = args.samples
    scene.cycles.device = "CPU"
    scene.render.resolution_x = scene.render.resolution_y = args.size
    scene.render.image_settings.file_format = "PNG"
    scene.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("world")
    world.color = (0.25, 0.25, 0.25)
    scene.world = world
    mesh = bpy.data.meshes.new("body")
    mesh.from_pydata(zup.tolist(), [], f.tolist())
    mesh.update()
    for poly in mesh.polygons:
        poly.use_smooth = True
    rs.add_uv_layer(mesh, corner_uvs, args.model)
    body = bpy.data.objects.new("body", mesh)
    scene.collection.objects.link(body)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    lamp = bpy.data.objects.new("lamp", bpy.data.lights.new("lamp", "AREA"))
    lamp.data.size = 1.0
    scene.collection.objects.link(lamp)

    tiles = []
    for k, entry in enumerate(skins):
        regions = [{"paint": r, "mask": os.path.join(textures, r["mask"])}
                   for r in entry.get("regions", [])]
        detail = entry.get("detail")
        if detail:
            detail = os.path.join(textures, detail)
            if not os.path.isfile(detail):
                sys.exit(f"{detail}: no such file (the detail map the annotations name, skins[].detail)")
        variants = {"recorded": [detail], "off": [None], "both": [None, detail]}[args.detail]
        for d, with_detail in enumerate(variants):
            body.data.materials.clear()
            body.data.materials.append(rs.skin_material(f"skin_{k}_{d}", entry["skin"], regions, with_detail))
            column = []
            for target, offset, lens in views:
                camera.location = Vector(target) + Vector(offset)
                camera.data.lens = lens
                look_at(camera, target)
                lamp.location = camera.location + Vector((0.6, -0.2, 0.7))
                lamp.data.energy = 20.0
                look_at(lamp, target)
                path = os.path.join(bpy.app.tempdir, f"skin_{k}_{d}_{len(column)}.png")
                scene.render.filepath = path
                bpy.ops.render.render(write_still=True)
                image = bpy.data.images.load(path)
                column.append(np.array(image.pixels[:], dtype=np.float32).reshape(
                    args.size, args.size, 4))
            # Blender's pixel rows run bottom-up: the first view goes on top.
            tiles.append(np.concatenate(column[::-1], 0))
            print(f"{entry['name']}: Monk tone {entry['skin']['monk_skin_tone']}, "
                  f"{len(regions)} regions, detail {os.path.basename(with_detail) if with_detail else 'none'}",
                  flush=True)
    sheet = np.concatenate(tiles, 1)
    out = bpy.data.images.new("sheet", sheet.shape[1], sheet.shape[0], alpha=True)
    out.pixels = sheet.ravel()
    out.file_format = "PNG"
    with outputs.writing(args.out, args.replace) as tmp:
        out.filepath_raw = os.path.abspath(tmp)
        out.save()
    print(f"wrote {args.out} ({len(skins)} skins)")


if __name__ == "__main__":
    main()
