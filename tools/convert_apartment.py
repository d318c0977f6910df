#!/usr/bin/env python3
"""Convert MORSE's furnished apartment scene to ``assets/scenes/apartment.glb``.

Source: ``/usr/share/morse/data/environments/apartment.blend`` from the Debian
package ``morse-simulator-data`` (version 1.4-8, source package morse-simulator;
BSD-3-Clause, (c) LAAS-CNRS / ONERA / ISAE-SUPAERO, see assets/NOTICE).  The file is
a gzip-compressed Blender 2.65 file (sha256 checked below).

Requirements
------------
* apt:  ``apt-get install -y morse-simulator-data``
* pip:  Blender as a Python module, in a Python 3.11 virtual environment::

      python3.11 -m venv .venv-bpy
      .venv-bpy/bin/pip install bpy==4.5.15      # pulls numpy 1.26.4

  (numpy is the only other module used; no other pip package is needed.)

  assimp (``assimp export apartment.blend out.glb``) was tried and rejected: it
  silently drops the object ``IKEAShelf_mesh``, ignores Blender's hide flags,
  keeps z-up and emits bogus procedural-texture URIs.

Usage (from the repository root)::

    .venv-bpy/bin/python tools/convert_apartment.py \
        [--blend /usr/share/morse/data/environments/apartment.blend] \
        [--out assets/scenes/apartment.glb] [--replace]

``--replace`` overwrites an existing ``--out`` (the shipped file, converted again on
purpose); without it an existing file is refused before anything is read.

Runs in ~1-2 s.  Re-running with the same inputs and bpy version gives byte-identical
output (checked with bpy 4.5.15).

What it does
------------
1. Opens the .blend with bpy (Python auto-run disabled).
2. Drops everything that is not the apartment:
   * ``Plane``: the 21.8 m x 21.8 m ground plane at z = -0.017 m (no material);
   * ``IKEAShelf_bb``: a hidden (hide_render) collision bounding box of the shelf;
   * the four light objects ``Lamp``, ``Lamp.001``..``Lamp.003`` (and any camera).
   What remains is the wall mesh ``C6_plein_ext_P`` and 29 furniture objects: 28
   mesh objects plus the ``IKEAShelf`` empty whose three mesh children
   ``IKEAShelf_mesh``, ``.001``, ``.002`` are the shelf modules.
3. Adds ``floor``: one rectangle at z = 0 (the bottom of the walls, on which the
   furniture stands) spanning the x/y bounding box of everything kept plus a 0.5 m
   margin, with material ``floor`` = Blender's default grey (0.8), as the original
   ground plane had no material.
4. Renames every mesh datablock after its object, so that glTF node names *and*
   mesh names are the MORSE object names (used for segmentation).
5. Exports GLB with Blender's glTF exporter: +Y up (the exporter maps Blender
   (x, y, z) to glTF (x, z, -y)), metres, base colours only (the file has no UV
   maps, so its two packed wood textures cannot be used), no lights/cameras/
   animations/extras, loose edges dropped.
6. Reads the GLB back (plain numpy, independent of Blender), converts glTF y-up to
   the z-up world with world = (x, -z_gltf, y_gltf) and checks that the floor is
   horizontal with its normal pointing to +z at z = 0 and the walls span
   z = 0 .. 2.5 m; prints the bounding box and object list.
"""
from __future__ import annotations

import hashlib
import json
import os
import struct
import sys
import tempfile
import time

import numpy as np

import arguments
import outputs

DEFAULT_BLEND = "/usr/share/morse/data/environments/apartment.blend"
BLEND_SHA256 = "b11a03abfb96aea78c8534fcc24f5dc409be66bdc78951bc7f01f9b08aefef9a"
BPY_VERSION_PREFIX = (4, 5)

# Objects of the .blend that are not part of the apartment (besides lights/cameras).
DROP_OBJECTS = {
    "Plane": "21.8 m x 21.8 m ground plane at z=-0.017 m (replaced by 'floor')",
    "IKEAShelf_bb": "hidden collision bounding box of IKEAShelf",
}
WALLS = "C6_plein_ext_P"
FLOOR_NAME = "floor"
FLOOR_MARGIN = 0.5  # metres around the x/y bounding box of walls + furniture
FLOOR_COLOR = (0.8, 0.8, 0.8, 1.0)  # Blender's default material colour
COPYRIGHT = ("Derived from MORSE apartment.blend (c) 2009-2010 LAAS-CNRS / ONERA, "
             "2011-2012 LAAS-CNRS, 2015-2016 ISAE-SUPAERO; BSD-3-Clause, see assets/NOTICE")


def sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


# --------------------------------------------------------------------------------------
# Blender part
# --------------------------------------------------------------------------------------
def build_and_export(blend: str, out: str) -> None:
    import bpy  # noqa: WPS433 (Blender as a Python module)

    if tuple(bpy.app.version[:2]) != BPY_VERSION_PREFIX:
        sys.exit(f"need bpy {BPY_VERSION_PREFIX[0]}.{BPY_VERSION_PREFIX[1]}.x, "
                 f"got {bpy.app.version_string}")

    bpy.ops.wm.open_mainfile(filepath=blend, load_ui=False, use_scripts=False)
    scene = bpy.context.scene
    assert scene.unit_settings.scale_length == 1.0, "blend units are not metres"

    # 1. drop what is not the apartment
    dropped = []
    for ob in sorted(bpy.data.objects, key=lambda o: o.name):
        reason = DROP_OBJECTS.get(ob.name)
        if reason is None and ob.type not in ("MESH", "EMPTY"):
            reason = f"{ob.type.lower()} object"
        if reason is None and ob.type == "MESH" and ob.hide_render:
            reason = "hidden for rendering"
        if reason is not None:
            dropped.append((ob.name, reason))
    for name, _ in dropped:
        bpy.data.objects.remove(bpy.data.objects[name], do_unlink=True)
    for name, reason in dropped:
        print(f"dropped {name}: {reason}")

    kept = [ob for ob in scene.objects]
    meshes = [ob for ob in kept if ob.type == "MESH"]
    assert WALLS in {ob.name for ob in meshes}, "wall mesh not found"

    # 2. mesh datablock names := object names
    for ob in meshes:
        assert ob.data.users == 1, f"{ob.name}: shared mesh data"
        ob.data.name = ob.name

    # 3. footprint of walls + furniture, floor rectangle at the walls' bottom
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    wall_zmin = None
    for ob in meshes:
        m = np.array(ob.matrix_world)
        v = np.array([vt.co for vt in ob.data.vertices], dtype=np.float64)
        w = v @ m[:3, :3].T + m[:3, 3]
        lo = np.minimum(lo, w.min(0))
        hi = np.maximum(hi, w.max(0))
        if ob.name == WALLS:
            wall_zmin = float(w[:, 2].min())
    floor_z = round(wall_zmin, 4) + 0.0  # 0.0 for this file (+0.0: no "-0.0")
    x0, y0 = (float(np.round(c - FLOOR_MARGIN, 4)) for c in lo[:2])
    x1, y1 = (float(np.round(c + FLOOR_MARGIN, 4)) for c in hi[:2])
    me = bpy.data.meshes.new(FLOOR_NAME)
    # counter-clockwise seen from above -> normal +z
    me.from_pydata([(x0, y0, floor_z), (x1, y0, floor_z), (x1, y1, floor_z), (x0, y1, floor_z)],
                   [], [(0, 1, 2, 3)])
    me.update()
    mat = bpy.data.materials.new(FLOOR_NAME)
    mat.use_nodes = False
    mat.diffuse_color = FLOOR_COLOR
    mat.roughness = 0.5
    mat.metallic = 0.0
    me.materials.append(mat)
    floor = bpy.data.objects.new(FLOOR_NAME, me)
    scene.collection.objects.link(floor)
    print(f"floor rectangle x [{x0}, {x1}] y [{y0}, {y1}] z {floor_z}")

    # 4. export
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    bpy.ops.export_scene.gltf(
        filepath=os.path.abspath(out),
        check_existing=False,
        export_format="GLB",
        export_copyright=COPYRIGHT,
        export_yup=True,
        export_apply=True,
        export_materials="EXPORT",
        export_image_format="NONE",
        export_texcoords=True,
        export_normals=True,
        export_tangents=False,
        export_vertex_color="NONE",
        export_attributes=False,
        use_mesh_edges=False,
        use_mesh_vertices=False,
        export_cameras=False,
        export_lights=False,
        export_extras=False,
        export_animations=False,
        export_skins=False,
        export_morph=False,
        use_selection=False,
        use_visible=False,
        use_renderable=False,
    )


# --------------------------------------------------------------------------------------
# Read-back check (numpy only)
# --------------------------------------------------------------------------------------
_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
_DTYPE = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
          5125: np.uint32, 5126: np.float32}
# glTF (y-up) -> egogen world (z-up): world = (x, -z, y)
GLTF_TO_ZUP = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=np.float64)


def read_glb(path: str):
    data = open(path, "rb").read()
    magic, version, _ = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2, "not a glTF 2 GLB"
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A
    gltf = json.loads(data[20:20 + jlen])
    blen, btype = struct.unpack_from("<II", data, 20 + jlen)
    assert btype == 0x004E4942
    return gltf, data[28 + jlen:28 + jlen + blen]


def _accessor(gltf, binary, idx):
    acc = gltf["accessors"][idx]
    bv = gltf["bufferViews"][acc["bufferView"]]
    n = _NCOMP[acc["type"]]
    dt = np.dtype(_DTYPE[acc["componentType"]])
    off = bv.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = bv.get("byteStride", n * dt.itemsize)
    assert stride == n * dt.itemsize, "interleaved buffers not handled"
    a = np.frombuffer(binary, dt, acc["count"] * n, off)
    return a.reshape(acc["count"], n) if n > 1 else a


def _local_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    r = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r * np.array(node.get("scale", [1, 1, 1]))[None, :]
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def world_triangles(path: str):
    """{node name: (positions (N,3), normals (N,3), triangles (M,3))} in z-up world."""
    gltf, binary = read_glb(path)
    out = {}

    def walk(idx, parent):
        node = gltf["nodes"][idx]
        m = parent @ _local_matrix(node)
        if "mesh" in node:
            pos, nrm, tri = [], [], []
            base = 0
            for prim in gltf["meshes"][node["mesh"]]["primitives"]:
                assert prim.get("mode", 4) == 4, "non-triangle primitive"
                p = _accessor(gltf, binary, prim["attributes"]["POSITION"]).astype(np.float64)
                q = _accessor(gltf, binary, prim["attributes"]["NORMAL"]).astype(np.float64)
                i = _accessor(gltf, binary, prim["indices"]).astype(np.int64).reshape(-1, 3)
                pw = p @ m[:3, :3].T + m[:3, 3]
                nw = q @ np.linalg.inv(m[:3, :3])  # inverse-transpose
                nw /= np.linalg.norm(nw, axis=1, keepdims=True)
                pos.append(pw @ GLTF_TO_ZUP.T)
                nrm.append(nw @ GLTF_TO_ZUP.T)
                tri.append(i + base)
                base += len(p)
            out[node["name"]] = (np.concatenate(pos), np.concatenate(nrm), np.concatenate(tri))
        for c in node.get("children", []):
            walk(c, m)

    for root in gltf["scenes"][gltf.get("scene", 0)]["nodes"]:
        walk(root, np.eye(4))
    return gltf, out


def check(path: str) -> dict:
    gltf, objs = world_triangles(path)
    floor_p, floor_n, floor_t = objs[FLOOR_NAME]
    fz = floor_p[:, 2]
    assert np.ptp(fz) < 1e-6, "floor not horizontal"
    a, b, c = (floor_p[floor_t[:, k]] for k in range(3))
    geo_n = np.cross(b - a, c - a)
    geo_n /= np.linalg.norm(geo_n, axis=1, keepdims=True)
    assert np.all(geo_n[:, 2] > 0.999) and np.all(floor_n[:, 2] > 0.999), "floor normal not +z"
    wz = objs[WALLS][0][:, 2]
    assert abs(wz.min() - fz[0]) < 1e-4 and abs(wz.max() - fz[0] - 2.5) < 1e-3, "walls not 2.5 m upright"
    allp = np.concatenate([p for p, _, _ in objs.values()])
    furn = np.concatenate([p for n, (p, _, _) in objs.items() if n not in (FLOOR_NAME, WALLS)])
    bottoms = {n: float(p[:, 2].min()) for n, (p, _, _) in objs.items()}
    top_names = [gltf["nodes"][i]["name"] for i in gltf["scenes"][0]["nodes"]]
    return {
        "bbox_min": [round(float(v), 4) for v in allp.min(0)],
        "bbox_max": [round(float(v), 4) for v in allp.max(0)],
        "furniture_walls_bbox_min": [round(float(v), 4) for v in
                                     np.concatenate([furn, objs[WALLS][0]]).min(0)],
        "floor_z": round(float(fz[0]), 6),
        "walls_z": [round(float(wz.min()), 4) + 0.0, round(float(wz.max()), 4) + 0.0],
        "mesh_nodes": len(objs),
        "triangles": int(sum(len(t) for _, _, t in objs.values())),
        "materials": len(gltf.get("materials", [])),
        "top_level_nodes": top_names,
        "floating_bottoms_gt_1cm": {n: round(z, 4) for n, z in bottoms.items()
                                    if z - fz[0] > 0.01 and z < 0.1},
    }


def main() -> None:
    ap = arguments.StrictParser(description=__doc__.split("\n")[0])
    ap.add_argument("--blend", default=DEFAULT_BLEND)
    ap.add_argument("--out", default=os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "assets", "scenes", "apartment.glb"))
    ap.add_argument("--skip-sha256", action="store_true",
                    help="accept an apartment.blend whose hash differs from morse-simulator-data 1.4-8")
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace, parents=True)
    outputs.check_outside(args.out, "--out", args.blend, "the .blend")

    t0 = time.time()
    digest = sha256(args.blend)
    if digest != BLEND_SHA256 and not args.skip_sha256:
        sys.exit(f"{args.blend}: sha256 {digest} != expected {BLEND_SHA256} "
                 "(morse-simulator-data 1.4-8); use --skip-sha256 to override")
    out = os.path.normpath(args.out)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with outputs.writing(out, args.replace) as partial:
        # Exported under its own name (the exporter goes by the extension), then checked.
        with tempfile.TemporaryDirectory(dir=os.path.dirname(os.path.abspath(out))) as tmp:
            glb = os.path.join(tmp, os.path.basename(out))
            build_and_export(args.blend, glb)
            summary = check(glb)
            os.replace(glb, partial)
    summary["bytes"] = os.path.getsize(out)
    summary["sha256"] = sha256(out)
    summary["seconds"] = round(time.time() - t0, 2)
    print(json.dumps(summary, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
