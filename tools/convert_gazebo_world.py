#!/usr/bin/env python3
"""Convert a Gazebo SDF world of COLLADA models to one textured GLB scene egogen reads.

Written for the AWS RoboMaker residential worlds (MIT-0; see assets/NOTICE), whose worlds
place static models (``<model><include><uri>model://NAME</uri></include><pose>…``) and
whose models are links with COLLADA visuals. Used for the held-out evaluation dwelling
``assets/scenes/small_house.glb``::

    git clone https://github.com/aws-robotics/aws-robomaker-small-house-world SRC
    git -C SRC checkout dd44be6
    python3 -m venv /tmp/convert
    /tmp/convert/bin/pip install trimesh==5.2.0 pycollada==0.9.3 pillow==13.0.0 numpy==2.4.6
    /tmp/convert/bin/python tools/convert_gazebo_world.py SRC/worlds/small_house.world \
        --models SRC/models --out assets/scenes/small_house.glb --replace --copyright "Derived from \
    aws-robotics/aws-robomaker-small-house-world (c) 2019 Amazon.com, Inc. or its affiliates; \
    MIT-0, see assets/NOTICE"

About 10 s; the same inputs give the same bytes (two runs compared by sha256). A full clone
may hold textures the snapshot converted here lacked (assets/NOTICE names them), and then
gives a file that differs in those materials.

What it does:

1. Reads the world: every ``<model>`` that includes a model (its pose = the model's
   ``<pose>`` after the include's), and every ``<include>`` directly in the world. Poses are
   SDF's ``x y z roll pitch yaw`` (R = Rz(yaw)·Ry(pitch)·Rx(roll)). Lights, physics and the
   GUI camera are ignored.
2. Reads each included model's ``model.sdf``: its links' visuals with a mesh (uri, scale,
   model, link and visual poses), or a box, sphere or cylinder (with its ``<diffuse>``
   colour), and the same of every ``<model>`` nested in it (placed after its parent);
   collision geometry is ignored. A mesh that is not COLLADA,
   or a model or mesh file that is missing, is an error naming the file (``--skip-model``
   leaves a model out by its world name).
3. Reads every visual with pycollada (through trimesh), honouring the file's ``<unit>`` and
   ``<up_axis>`` as Gazebo does. The RoboMaker files give ids with spaces and '#', which
   break references; they are renamed in memory first (the source is never written).
   Blender's own COLLADA importer reads none of these files (it resolves the scene to the
   node that shares its id), so it is not used.
4. Writes each world model as one glTF node named after the world's model name
   (``Bed_01_001``; a nested model as ``outer::nested``), one mesh with a primitive per material: one segmentation id and one
   name in egogen's id table per piece of furniture. Textures are scaled to at most
   ``--max-texture-px`` (default 512) on their longer side and stored as JPEG (quality
   ``--jpeg-quality``, default 85), each once; a texture missing from the source tree (a
   snapshot without some of its large files) is dropped with a message and its material
   keeps its base colour.
5. ``--floor-margin-m M`` adds a grey floor rectangle named ``floor`` at the lowest point,
   M metres beyond the footprint, for worlds that stand on Gazebo's ground plane.
6. GLB, +Y up, metres (egogen reads it z-up); written to ``OUT.partial`` and renamed.

The output is a derivative of the source world: keep its licence and attribution with it.
"""
from __future__ import annotations

import hashlib
import io
import json
import os
import re
import struct
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

import arguments
import outputs


def fail(msg: str):
    print(f"convert_gazebo_world: {msg}", file=sys.stderr)
    sys.exit(1)


def parse_pose(text: str | None, where: str) -> tuple[float, ...]:
    if text is None or not text.strip():
        return (0.0,) * 6
    parts = text.split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 6:
        fail(f"{where}: <pose> must hold 6 numbers (x y z roll pitch yaw), got {text!r}")
    return values


def pose_matrix(pose: tuple[float, ...]) -> np.ndarray:
    """SDF pose → 4×4: R = Rz(yaw) · Ry(pitch) · Rx(roll), then the translation."""
    x, y, z, roll, pitch, yaw = pose
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rz @ ry @ rx
    m[:3, 3] = (x, y, z)
    return m


def model_dir_of(uri: str, models: str, where: str, skip_missing: bool) -> str | None:
    m = re.fullmatch(r"model://([^/]+)(/.*)?", uri.strip())
    if not m:
        if skip_missing:
            print(f"  {where}: uri {uri!r} is not model://NAME: skipped (--skip-missing-models)")
            return None
        fail(f"{where}: uri {uri!r} is not model://NAME (--skip-missing-models leaves it out)")
    path = os.path.join(models, m.group(1))
    if not os.path.isdir(path):
        if skip_missing:
            print(f"  {where}: model directory {path} not found: skipped (--skip-missing-models)")
            return None
        fail(f"{where}: model directory {path} not found (is --models the world's models folder? "
             "--skip-missing-models leaves such models out)")
    return path


def resolve_mesh_uri(uri: str, models: str, sdf_path: str) -> str:
    uri = uri.strip()
    if uri.startswith("model://"):
        return os.path.join(models, uri[len("model://"):])
    if uri.startswith("file://"):
        return uri[len("file://"):]
    return os.path.join(os.path.dirname(sdf_path), uri)


def numbers(text: str | None, count: int, where: str) -> list[float]:
    try:
        values = [float(s) for s in (text or "").split()]
    except ValueError:
        values = []
    if len(values) != count:
        fail(f"{where}: expected {count} numbers, got {text!r}")
    return values


def sdf_shape(visual: ET.Element, where: str):
    """A visual's box, sphere or cylinder as a trimesh with its ``<diffuse>`` colour, or None."""
    import trimesh

    geometry = visual.find("geometry")
    kinds = [c.tag for c in geometry] if geometry is not None else []
    name = f"{where} visual {visual.get('name')!r}"
    if "box" in kinds:
        mesh = trimesh.creation.box(extents=numbers(geometry.findtext("box/size"), 3, f"{name} <size>"))
    elif "sphere" in kinds:
        mesh = trimesh.creation.icosphere(
            subdivisions=3, radius=numbers(geometry.findtext("sphere/radius"), 1, f"{name} <radius>")[0])
    elif "cylinder" in kinds:
        mesh = trimesh.creation.cylinder(
            radius=numbers(geometry.findtext("cylinder/radius"), 1, f"{name} <radius>")[0],
            height=numbers(geometry.findtext("cylinder/length"), 1, f"{name} <length>")[0], sections=32)
    else:
        print(f"  {name} is {kinds}, not a mesh, box, sphere or cylinder: skipped")
        return None
    diffuse = visual.findtext("material/diffuse")
    color = tuple(numbers(diffuse, 4, f"{name} <diffuse>")) if diffuse else (0.8, 0.8, 0.8, 1.0)
    return mesh, color


def model_parts(model_dir: str, models: str, name: str) -> list[tuple[str, list[tuple[object, np.ndarray]]]]:
    """The model's parts, each (node name, visuals): the model's own links under ``name``, then
    each nested ``<model>`` as ``name::nested`` (its pose after its parent's). A visual is a
    COLLADA path, or a shape with its colour, with its placement in the world model."""
    sdf_path = os.path.join(model_dir, "model.sdf")
    if not os.path.isfile(sdf_path):
        fail(f"{model_dir}: model.sdf not found")
    try:
        root = ET.parse(sdf_path).getroot()
    except ET.ParseError as e:
        fail(f"{sdf_path}: not valid XML ({e})")
    model = root.find("model")
    if model is None:
        fail(f"{sdf_path}: no <model> element")
    parts: list[tuple[str, list]] = []

    def walk(model: ET.Element, parent: np.ndarray, node: str) -> None:
        model_pose = parent @ pose_matrix(parse_pose(model.findtext("pose"), f"{sdf_path} {node}"))
        visuals = []
        for link in model.findall("link"):
            link_pose = pose_matrix(parse_pose(link.findtext("pose"), f"{sdf_path} link"))
            for visual in link.findall("visual"):
                placed = model_pose @ link_pose @ pose_matrix(
                    parse_pose(visual.findtext("pose"), f"{sdf_path} visual"))
                visuals += link_visual(visual, placed, models, sdf_path)
        if visuals:
            parts.append((node, visuals))
        for nested in model.findall("model"):
            walk(nested, model_pose, f"{node}::{nested.get('name') or len(parts)}")

    walk(model, np.eye(4), name)
    return parts


def link_visual(visual: ET.Element, placed: np.ndarray, models: str, sdf_path: str) -> list:
    """A visual as [(COLLADA path or (shape, colour), placement)], or [] when it is skipped."""
    mesh = visual.find("geometry/mesh")
    if mesh is None:
        shape = sdf_shape(visual, sdf_path)
        return [(shape, placed)] if shape is not None else []
    uri = mesh.findtext("uri")
    if not uri:
        fail(f"{sdf_path}: visual {visual.get('name')!r} has a <mesh> without <uri>")
    path = resolve_mesh_uri(uri, models, sdf_path)
    if not path.lower().endswith(".dae"):
        fail(f"{sdf_path}: visual mesh {uri} is not COLLADA (.dae); only COLLADA is read")
    if not os.path.isfile(path):
        fail(f"{sdf_path}: visual mesh {path} not found")
    scale_text = mesh.findtext("scale") or "1 1 1"
    try:
        scale = [float(s) for s in scale_text.split()]
    except ValueError:
        scale = []
    if len(scale) != 3:
        fail(f"{sdf_path}: <scale> must hold 3 numbers, got {scale_text!r}")
    return [(path, placed @ np.diag([*scale, 1.0]))]


def world_models(world_path: str, models: str, skip: set[str], skip_missing: bool):
    """(name, model directory, pose) for each model the world places, in file order."""
    try:
        root = ET.parse(world_path).getroot()
    except (ET.ParseError, OSError) as e:
        fail(f"{world_path}: cannot read the world ({e})")
    world = root.find("world")
    if world is None:
        fail(f"{world_path}: no <world> element")
    placed = []
    for model in world.findall("model"):
        name = model.get("name")
        if not name:
            fail(f"{world_path}: a <model> without a name")
        include = model.find("include")
        if include is None:
            print(f"  model {name!r} defines its own links: skipped (only included models are read)")
            continue
        where = f"{world_path} model {name!r}"
        pose = pose_matrix(parse_pose(model.findtext("pose"), where)) @ pose_matrix(
            parse_pose(include.findtext("pose"), where))
        placed.append((name, model_dir_of(include.findtext("uri") or "", models, where, skip_missing),
                       pose))
    for include in world.findall("include"):
        uri = include.findtext("uri") or ""
        name = include.findtext("name") or uri.rstrip("/").split("/")[-1]
        where = f"{world_path} include {name!r}"
        placed.append((name, model_dir_of(uri, models, where, skip_missing),
                       pose_matrix(parse_pose(include.findtext("pose"), where))))
    names = [n for n, _, _ in placed]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        fail(f"{world_path}: model names used twice: {dup}")
    unknown = skip - set(names)
    if unknown:
        fail(f"--skip-model {sorted(unknown)}: no such model in {world_path}")
    return [p for p in placed if p[0] not in skip and p[1] is not None]


def collada_text(path: str) -> tuple[str, float, np.ndarray]:
    """The file's text with ids of spaces and '#' renamed, its unit (metres) and up-axis turn."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read()
    ids = set(re.findall(r'\b(?:id|sid)="([^"]*)"', text))
    for old in sorted((i for i in ids if re.search(r"[\s#]", i)), key=len, reverse=True):
        text = text.replace(old, re.sub(r"[\s#]", "_", old))
    here = os.path.dirname(os.path.abspath(path))

    def absolute(m: re.Match) -> str:  # images by absolute path: the text is read from memory
        if "." not in m.group(2) or os.path.isabs(m.group(2)):
            return m.group(0)
        image = os.path.normpath(os.path.join(here, m.group(2)))
        beside = os.path.join(os.path.dirname(here), "materials", "textures", os.path.basename(image))
        if not os.path.isfile(image) and os.path.isfile(beside):
            image = beside  # a path into an install tree; the model keeps its own copy
        return m.group(1) + image + m.group(3)

    text = re.sub(r"(<init_from>)([^<]*)(</init_from>)", absolute, text)
    unit = re.search(r'<unit\b[^>]*\bmeter="([^"]+)"', text)
    try:
        meter = float(unit.group(1)) if unit else 1.0
    except ValueError:
        fail(f"{path}: <unit meter={unit.group(1)!r}> is not a number")
    up = re.search(r"<up_axis>\s*([XYZ])_UP\s*</up_axis>", text)
    turn = np.eye(4)
    if up and up.group(1) == "Y":  # Y up → Z up: (x, y, z) → (x, -z, y)
        turn[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    elif up and up.group(1) == "X":  # X up → Z up
        turn[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    return text, meter, turn


class Glb:
    """A GLB being written: one buffer, nodes of named meshes, JPEG textures stored once."""

    def __init__(self, max_px: int, quality: int):
        self.bin = bytearray()
        self.json = {"asset": {"version": "2.0", "generator": "egogen tools/convert_gazebo_world.py"},
                     "scenes": [{"nodes": []}], "scene": 0, "nodes": [], "meshes": [],
                     "accessors": [], "bufferViews": [], "materials": [], "textures": [],
                     "images": [], "samplers": [{"wrapS": 10497, "wrapT": 10497}]}
        self.max_px, self.quality = max_px, quality
        self.textures: dict[str, int] = {}
        self.materials: dict[tuple, int] = {}

    def _view(self, data: bytes, target: int | None = None) -> int:
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.bin.extend(data)
        self.json["bufferViews"].append(view)
        return len(self.json["bufferViews"]) - 1

    def _accessor(self, array: np.ndarray, kind: str, target: int, bounds: bool = False) -> int:
        component = 5125 if array.dtype == np.uint32 else 5126
        acc = {"bufferView": self._view(array.tobytes(), target), "componentType": component,
               "count": int(array.shape[0]), "type": kind}
        if bounds:
            acc["min"] = array.min(0).tolist()
            acc["max"] = array.max(0).tolist()
        self.json["accessors"].append(acc)
        return len(self.json["accessors"]) - 1

    def _texture(self, image) -> int:
        from PIL import Image

        image = image.convert("RGB")
        key = hashlib.sha256(image.tobytes() + repr(image.size).encode()).hexdigest()
        if key not in self.textures:
            w, h = image.size
            if max(w, h) > self.max_px:
                f = self.max_px / max(w, h)
                image = image.resize((max(1, round(w * f)), max(1, round(h * f))), Image.LANCZOS)
            out = io.BytesIO()
            image.save(out, "JPEG", quality=self.quality)
            self.json["images"].append({"bufferView": self._view(out.getvalue()),
                                        "mimeType": "image/jpeg"})
            self.json["textures"].append({"sampler": 0, "source": len(self.json["images"]) - 1})
            self.textures[key] = len(self.json["textures"]) - 1
        return self.textures[key]

    def material(self, name: str, color, image) -> int:
        texture = self._texture(image) if image is not None else None
        rgba = tuple(round(float(c), 4) for c in color)
        key = (rgba, texture)
        if key not in self.materials:
            pbr = {"baseColorFactor": list(rgba), "metallicFactor": 0.0, "roughnessFactor": 0.8}
            if texture is not None:
                pbr["baseColorTexture"] = {"index": texture}
            self.json["materials"].append({"name": name, "pbrMetallicRoughness": pbr,
                                           "doubleSided": True})
            self.materials[key] = len(self.json["materials"]) - 1
        return self.materials[key]

    def node(self, name: str, primitives: list[tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray, int]]):
        """One node and mesh: primitives of (z-up positions, normals, uvs or None, faces, material)."""
        prims = []
        for pos, nrm, uv, faces, mat in primitives:
            to_y_up = lambda a: np.stack([a[:, 0], a[:, 2], -a[:, 1]], axis=1)  # noqa: E731
            attrs = {"POSITION": self._accessor(to_y_up(pos).astype(np.float32), "VEC3", 34962, True),
                     "NORMAL": self._accessor(to_y_up(nrm).astype(np.float32), "VEC3", 34962)}
            if uv is not None:
                flipped = np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1).astype(np.float32)
                attrs["TEXCOORD_0"] = self._accessor(flipped, "VEC2", 34962)
            indices = self._accessor(faces.astype(np.uint32).reshape(-1), "SCALAR", 34963)
            prims.append({"attributes": attrs, "indices": indices, "material": mat})
        self.json["meshes"].append({"name": name, "primitives": prims})
        self.json["nodes"].append({"name": name, "mesh": len(self.json["meshes"]) - 1})
        self.json["scenes"][0]["nodes"].append(len(self.json["nodes"]) - 1)

    def write(self, path: str, copyright: str, replace: bool) -> None:
        if copyright:
            self.json["asset"]["copyright"] = copyright
        self.json["buffers"] = [{"byteLength": len(self.bin)}]
        for key in ("textures", "images"):
            if not self.json[key]:
                del self.json[key]
        doc = json.dumps(self.json, separators=(",", ":")).encode()
        doc += b" " * (-len(doc) % 4)
        while len(self.bin) % 4:
            self.bin.append(0)
        total = 12 + 8 + len(doc) + 8 + len(self.bin)
        with outputs.writing(path, replace) as tmp:
            with open(tmp, "wb") as f:
                f.write(struct.pack("<III", 0x46546C67, 2, total))
                f.write(struct.pack("<II", len(doc), 0x4E4F534A) + doc)
                f.write(struct.pack("<II", len(self.bin), 0x004E4942) + bytes(self.bin))


class _AbsolutePaths:
    """Reads a texture by the absolute path ``collada_text`` gave it (trimesh's own file
    resolver refuses paths outside the scratch copy's folder)."""

    def get(self, name: str) -> bytes:
        with open(name, "rb") as f:
            return f.read()


def visual_primitives(path: str, placed: np.ndarray, glb: Glb, missing: set[str]):
    import trimesh

    text, meter, turn = collada_text(path)
    # pycollada finds images by path only when it reads a file: a scratch copy, never the source.
    with tempfile.TemporaryDirectory() as scratch:
        copy = os.path.join(scratch, "visual.dae")
        with open(copy, "w", encoding="utf-8") as f:
            f.write(text)
        try:
            scene = trimesh.load(copy, force="scene", resolver=_AbsolutePaths())
        except Exception as e:  # noqa: BLE001 (any reader failure names the file)
            fail(f"{path}: not a COLLADA file pycollada reads ({e})")
    for full in re.findall(r"<init_from>([^<]+\.(?:png|jpg|jpeg|PNG|JPG))</init_from>", text):
        if not os.path.isfile(full) and full not in missing:
            missing.add(full)
            print(f"  texture {full} is missing from the source: its material keeps its base colour")
    to_world = placed @ np.diag([meter, meter, meter, 1.0]) @ turn
    prims = []
    for mesh in scene.dump(concatenate=False):
        if len(mesh.faces) == 0:
            continue
        mesh = mesh.copy()
        mesh.apply_transform(to_world)
        visual = mesh.visual
        material = getattr(visual, "material", None)
        image = uv = None
        color = (0.8, 0.8, 0.8, 1.0)
        name = "default"
        if material is not None:
            pbr = material.to_pbr() if hasattr(material, "to_pbr") else material
            if pbr.baseColorFactor is not None:
                color = tuple(np.asarray(pbr.baseColorFactor, dtype=np.float64).reshape(-1)[:4] / 255.0)
            image = pbr.baseColorTexture
            name = pbr.name or name
            if image is not None and getattr(visual, "uv", None) is not None:
                uv = np.asarray(visual.uv, dtype=np.float64)
            else:
                image = None
        prims.append((np.asarray(mesh.vertices), np.asarray(mesh.vertex_normals),
                      uv, np.asarray(mesh.faces), glb.material(name, color, image)))
    return prims


def check(path: str) -> None:
    """Reads the GLB back (numpy only) and prints what egogen will see, z-up."""
    with open(path, "rb") as f:
        data = f.read()
    if struct.unpack_from("<I", data, 0)[0] != 0x46546C67:
        fail(f"{path}: not a GLB file")
    jlen = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + jlen])
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    tris = 0
    for mesh in gltf["meshes"]:
        for prim in mesh["primitives"]:
            acc = gltf["accessors"][prim["attributes"]["POSITION"]]
            lo = np.minimum(lo, [acc["min"][0], -acc["max"][2], acc["min"][1]])
            hi = np.maximum(hi, [acc["max"][0], -acc["min"][2], acc["max"][1]])
            tris += gltf["accessors"][prim["indices"]]["count"] // 3
    print(f"{path}: {len(gltf['nodes'])} objects, {tris} triangles, "
          f"{len(gltf.get('images', []))} images, {os.path.getsize(path) / 1e6:.1f} MB; "
          f"z-up bounds {np.round(lo, 3).tolist()} .. {np.round(hi, 3).tolist()}")


def main() -> None:
    ap = arguments.StrictParser(description=__doc__.split("\n")[0])
    ap.add_argument("world", help="the Gazebo .world file")
    ap.add_argument("--models", required=True, help="folder holding the model://NAME folders")
    ap.add_argument("--out", required=True, help="GLB to write (not overwritten unless --replace)")
    ap.add_argument("--skip-model", action="append", default=[], metavar="NAME",
                    help="leave out a model by its world name (repeatable)")
    ap.add_argument("--skip-missing-models", action="store_true",
                    help="leave out models whose folder is not under --models (e.g. Gazebo Fuel "
                         "models a world downloads) instead of stopping")
    ap.add_argument("--floor-margin-m", type=float, default=None, metavar="M",
                    help="add a floor rectangle (node 'floor') under everything, M metres beyond "
                         "its footprint, at its lowest point: for worlds whose floor is "
                         "Gazebo's ground plane")
    ap.add_argument("--max-texture-px", type=int, default=512)
    ap.add_argument("--jpeg-quality", type=int, default=85)
    ap.add_argument("--copyright", default="")
    ap.add_argument("--replace", action="store_true",
                    help="overwrite an existing --out (e.g. the shipped GLB, converted again on purpose)")
    args = ap.parse_args()
    try:
        outputs.check_new(args.out, "--out", args.replace, parents=True)
        outputs.check_outside(args.out, "--out", args.models, "--models")
        outputs.check_outside(args.out, "--out", args.world, "the world file")
    except outputs.OutputError as e:
        fail(str(e))
    if args.max_texture_px < 1:
        fail("--max-texture-px must be at least 1")
    if not 1 <= args.jpeg_quality <= 100:
        fail("--jpeg-quality must be within 1..100")
    try:
        import trimesh  # noqa: F401
        import PIL  # noqa: F401
    except ImportError as e:
        fail(f"needs trimesh, pycollada and pillow ({e}); see this file's docstring")

    placed = world_models(args.world, args.models, set(args.skip_model), args.skip_missing_models)
    print(f"{len(placed)} models placed by {args.world}")
    glb = Glb(args.max_texture_px, args.jpeg_quality)
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    missing: set[str] = set()
    parts = [(node, pose, visuals) for name, model_dir, pose in placed
             for node, visuals in model_parts(model_dir, args.models, name)]
    for i, (name, pose, visuals) in enumerate(parts):
        prims = []
        for source, local in visuals:
            if isinstance(source, str):
                prims += visual_primitives(source, pose @ local, glb, missing)
            else:
                shape, color = source
                shape = shape.copy()
                shape.apply_transform(pose @ local)
                prims.append((np.asarray(shape.vertices), np.asarray(shape.vertex_normals), None,
                              np.asarray(shape.faces), glb.material(f"{name}_colour", color, None)))
        if not prims:
            print(f"  {name}: no mesh: skipped")
            continue
        for prim in prims:
            lo, hi = np.minimum(lo, prim[0].min(0)), np.maximum(hi, prim[0].max(0))
        glb.node(name, prims)
        print(f"  [{i + 1}/{len(parts)}] {name}: {sum(len(p[3]) for p in prims)} triangles")
    if args.floor_margin_m is not None:
        if not np.isfinite(lo).all():
            fail("--floor-margin-m: the world has no geometry to lay a floor under")
        m = args.floor_margin_m
        (x0, y0), (x1, y1), z = lo[:2] - m, hi[:2] + m, lo[2]
        corners = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]])
        up = np.tile([0.0, 0.0, 1.0], (4, 1))
        grey = glb.material("floor", (0.8, 0.8, 0.8, 1.0), None)
        glb.node("floor", [(corners, up, None, np.array([[0, 1, 2], [0, 2, 3]]), grey)])
        print(f"  floor: x [{x0:.2f}, {x1:.2f}] y [{y0:.2f}, {y1:.2f}] at z {z:.3f}")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    glb.write(args.out, args.copyright, args.replace)
    check(args.out)


if __name__ == "__main__":
    main()
