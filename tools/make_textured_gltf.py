#!/usr/bin/env python3
"""A small textured glTF room: the one tests/scene_formats.rs renders and docs/RENDERING.md shows.

    python3 tools/make_textured_gltf.py DIR [--replace]

Writes DIR/room.gltf, DIR/room.bin and DIR/checker.png (none of them may exist, unless
--replace; DIR is made if missing): an 8 x 8 m floor carrying a 4 x 4
texel red-and-blue checker (repeated four times across it) and a 0.2 m wall at x = 3 m, 2.5 m
tall, one mesh of two primitives with two materials (green on the face towards -x, grey on the
rest). glTF is y up. Standard library only. docs/RENDERING.md renders it with
`egogen-run` to show a textured glTF with several materials.
"""

import json
import struct
import sys
import zlib
from pathlib import Path

import arguments
import outputs

FILES = ["checker.png", "room.bin", "room.gltf"]


def png(path, w, h, rows, replace):
    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    raw = b"".join(b"\0" + bytes(v for px in row for v in px) for row in rows)
    outputs.write_bytes(
        path,
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw))
        + chunk(b"IEND", b""),
        replace,
    )


def main():
    args, replace = arguments.switch(sys.argv[1:], "--replace")
    if len(args) != 1:
        sys.exit("usage: make_textured_gltf.py DIR [--replace]")
    out = Path(args[0])
    outputs.check_new_all([out / f for f in FILES], "DIR", replace, parents=True)
    out.mkdir(parents=True, exist_ok=True)
    png(out / "checker.png", 4, 4,
        [[(230, 20, 20) if (x + y) % 2 == 0 else (20, 20, 230) for x in range(4)] for y in range(4)],
        replace)
    v = [(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)]
    for z in (0.0, 2.5):
        v += [(3.0, -4, z), (3.2, -4, z), (3.2, 4, z), (3.0, 4, z)]
    floor = [(1, 2, 3, 4)]
    wall = [(5, 8, 7, 6), (9, 10, 11, 12), (5, 6, 10, 9), (6, 7, 11, 10), (7, 8, 12, 11), (8, 5, 9, 12)]
    near = [q for q in wall if all(v[i - 1][0] == 3.0 for i in q)]
    rest = [q for q in wall if q not in near]
    gl = lambda p: (float(p[0]), float(p[2]), float(-p[1]))  # z up -> y up

    def tris(quads, base):
        return [i - 1 - base for q in quads for i in (q[0], q[1], q[2], q[0], q[2], q[3])]

    floor_pos, wall_pos = [gl(p) for p in v[:4]], [gl(p) for p in v[4:]]
    arrays = [
        struct.pack(f"<{12}f", *[c for p in floor_pos for c in p]),
        struct.pack("<8f", 0, 0, 4, 0, 4, 4, 0, 4),
        struct.pack(f"<{6}H", *tris(floor, 0)),
        struct.pack(f"<{24}f", *[c for p in wall_pos for c in p]),
        struct.pack(f"<{6 * len(near)}H", *tris(near, 4)),
        struct.pack(f"<{6 * len(rest)}H", *tris(rest, 4)),
    ]
    binary, views = b"", []
    for a in arrays:
        views.append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(a)})
        binary += a + b"\0" * (-len(a) % 4)
    outputs.write_bytes(out / "room.bin", binary, replace)
    bounds = lambda ps: ([min(p[k] for p in ps) for k in range(3)], [max(p[k] for p in ps) for k in range(3)])
    (flo, fhi), (wlo, whi) = bounds(floor_pos), bounds(wall_pos)
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "floor", "mesh": 0}, {"name": "wall", "mesh": 1}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]},
            {"primitives": [
                {"attributes": {"POSITION": 3}, "indices": 4, "material": 1},
                {"attributes": {"POSITION": 3}, "indices": 5, "material": 2},
            ]},
        ],
        "materials": [
            {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}},
            {"name": "green", "pbrMetallicRoughness": {"baseColorFactor": [0.05, 0.8, 0.05, 1.0], "metallicFactor": 0.0}},
            {"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}},
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497, "magFilter": 9728}],
        "images": [{"uri": "checker.png"}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": flo, "max": fhi},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
            {"bufferView": 3, "componentType": 5126, "count": 8, "type": "VEC3", "min": wlo, "max": whi},
            {"bufferView": 4, "componentType": 5123, "count": 6 * len(near), "type": "SCALAR"},
            {"bufferView": 5, "componentType": 5123, "count": 6 * len(rest), "type": "SCALAR"},
        ],
        "bufferViews": views,
        "buffers": [{"uri": "room.bin", "byteLength": len(binary)}],
    }
    outputs.write_text(out / "room.gltf", json.dumps(doc, indent=2), replace)
    print(f"wrote {out / 'room.gltf'}")


if __name__ == "__main__":
    main()
