#!/usr/bin/env python3
"""Convert Sweet Home 3D's CC0 furniture library (or an opt-in CC-BY one) into egogen's
furniture catalogue.

Input: the Debian package sweethome3d-furniture_1.8-1_all.deb, or the library
BlendSwap-CC-0.sh3f taken from it (a zip: PluginFurnitureCatalog.properties plus one
folder of OBJ + MTL + textures per model).

Output (--out, e.g. assets/furniture):
  <id>.glb        one glTF 2.0 binary per model: y up, metres, scaled to exactly the
                  catalogue's width (x) x height (y) x depth (z), bounding box centred on
                  x and z, lowest point at y = 0, front facing +Z; one scene, one node,
                  one mesh, one primitive per material, textures embedded (<= 512 px).
  catalogue.json  the models' names, categories, tags, creators, sizes, elevations,
                  drop-on-top heights, triangle counts and file sizes.
  README.md       what ships and how it was made.

Sweet Home 3D conventions used (the front is checked on the seats, printed at the end):
  * the OBJ is y up; `modelRotation` (9 floats, row-major 3x3) is applied first
    (p' = M p), then the model is scaled non-uniformly so that its bounding box is
    width x height x depth (cm); its front faces +z;
  * `dropOnTopElevation` is in cm above the piece's bottom (Sweet Home 3D divides it by
    the height); absent means the top (the height), negative means "nothing is dropped
    on it" (null here).

Decimation: a triangle budget per model (triangle_budget), fast_simplification's
quadric decimation, every result checked against the source surface (decimate_shape);
textured primitives keep their UV seams where they can (decimate). See the README this
writes for the rules in words.

Everything is deterministic: same input, same bytes (no timestamps, fixed orders,
fast_simplification is deterministic).

Usage:
  python3 tools/furniture_catalogue.py /path/to/sweethome3d-furniture_1.8-1_all.deb \
      --out assets/furniture --replace
  python3 tools/furniture_catalogue.py /path/to/BlendSwap-CC-0.sh3f --out NEW_FOLDER
  python3 tools/furniture_catalogue.py --check assets/furniture   (verify only)
  python3 tools/furniture_catalogue.py sweethome3d-furniture_1.8-1_all.deb --library Scopia \
      --out ~/furniture/scopia     (an opt-in CC-BY library: see below)

Opt-in libraries (--library BlendSwap-CC-BY, Scopia, KatorLegaz, Reallusion; CC-BY-3.0, the
Debian package's `copyright` file): their ids are prefixed with the library's name, each model
gets the dwelling roles proposed for it (tools/furniture_roles.py: its name's words, category and size)
and only models with a role are converted unless --all-models; catalogue.json carries the
licence, its deed and the copyright line, which egogen writes into the ATTRIBUTION.md of every
dwelling, take and campaign that places one of its models.

An existing --out is refused unless --replace (the shipped catalogue, made again on purpose:
its files are overwritten, GLBs of ids no longer made removed).

Requirements: tools/furniture_catalogue_requirements.txt (numpy, scipy, pillow,
fast_simplification, trimesh for the check).
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import math
import os
import re
import struct
import sys
import tarfile
import zipfile
from dataclasses import dataclass, field

import numpy as np
from PIL import Image

import arguments
import outputs
from furniture_roles import proposed_roles

LIBRARY = "BlendSwap-CC-0"
SH3F_MEMBER = "usr/share/sweethome3d/furniture/{library}.sh3f"
SOURCE = "Debian sweethome3d-furniture 1.8-1, {library}.sh3f"
# The package's libraries and their licences, as its `copyright` file states them
# (/usr/share/doc/sweethome3d-furniture/copyright): (licence, its deed, copyright line).
LIBRARIES = {
    "BlendSwap-CC-0": ("CC0-1.0", "https://creativecommons.org/publicdomain/zero/1.0/",
                       "2014, Emmanuel PUYBARET eTeks <info@eteks.com> and other contributors"),
    "BlendSwap-CC-BY": ("CC-BY-3.0", "https://creativecommons.org/licenses/by/3.0/",
                        "The BlendSwap contributors"),
    "Scopia": ("CC-BY-3.0", "https://creativecommons.org/licenses/by/3.0/",
               "2010-2012, Scopia Visual Interfaces Systems, s.l. <http://www.scopia.es>"),
    "KatorLegaz": ("CC-BY-3.0-US", "https://creativecommons.org/licenses/by/3.0/us/",
                   "2003-2008, Andrew Kator & Jennifer Legaz"),
    "Reallusion": ("CC-BY-3.0-US", "https://creativecommons.org/licenses/by/3.0/us/",
                   "2008-2011, Reallusion <http://www.reallusion.com>"),
}
TOOL = "tools/furniture_catalogue.py"
EXCLUDED_CATEGORIES = ("Exterior", "Vehicles", "Characters", "Staircases")
EXCLUDED_NAMES = ("Shipping container",)
MAX_TEXTURE_PX = 512
JPEG_QUALITY = 85
CREASE_ANGLE_DEG = 80.0
MIN_PRIMITIVE_TRIANGLES = 12
DEFAULT_KD = (0.8, 0.8, 0.8)
CLUSTER_STEPS_M = (0.0005, 0.001, 0.002, 0.004, 0.008)
BUDGET_K, BUDGET_MIN, BUDGET_MAX = 1000, 200, 3500
# A decimated primitive is accepted at a level (min_multiple, f, share) once its target is
# at least min_multiple times its share of the budget, if at most `share` of the original
# surface (by area) lies farther than max(TOLERANCE_M, f * the box diagonal) from it.
TOLERANCE_M = 0.002
ACCEPT_LEVELS = ((1.0, 0.01, 0.02), (2.0, 0.02, 0.05), (3.0, 0.03, 0.08))
SEAM_FREE_EXCESS = 1000


# --------------------------------------------------------------------------- input


def read_ar_member(data: bytes, prefix: str) -> bytes:
    """The first member of an `ar` archive (a .deb) whose name starts with prefix."""
    if not data.startswith(b"!<arch>\n"):
        raise SystemExit("not an ar archive (.deb)")
    pos = 8
    while pos + 60 <= len(data):
        header = data[pos : pos + 60]
        name = header[0:16].decode("ascii").strip().rstrip("/")
        size = int(header[48:58].decode("ascii").strip())
        body = data[pos + 60 : pos + 60 + size]
        if name.startswith(prefix):
            return body
        pos += 60 + size + (size & 1)
    raise SystemExit(f"no {prefix}* member in the .deb")


def load_sh3f(path: str, library: str = LIBRARY) -> bytes:
    """The bytes of `<library>.sh3f`, from the .sh3f itself or from the .deb."""
    with open(path, "rb") as f:
        data = f.read()
    if data.startswith(b"!<arch>\n"):
        tar_bytes = read_ar_member(data, "data.tar")
        with tarfile.open(fileobj=io.BytesIO(tar_bytes), mode="r:*") as tar:
            for member in tar.getmembers():
                if member.name.lstrip("./") == SH3F_MEMBER.format(library=library):
                    extracted = tar.extractfile(member)
                    assert extracted is not None
                    return extracted.read()
        raise SystemExit(f"{SH3F_MEMBER.format(library=library)} not in the .deb's data archive")
    if not data.startswith(b"PK"):
        raise SystemExit("expected a .deb or a .sh3f (zip)")
    return data


def parse_properties(text: str) -> dict[str, str]:
    """Java .properties (latin-1 already decoded): continuations, escapes, comments."""
    out: dict[str, str] = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i].lstrip(" \t\f")
        i += 1
        if not line or line[0] in "#!":
            continue
        # Join continuation lines (an odd number of trailing backslashes).
        while (len(line) - len(line.rstrip("\\"))) % 2 == 1:
            line = line[:-1]
            if i >= len(lines):
                break
            line += lines[i].lstrip(" \t\f")
            i += 1
        # Split key / value at the first unescaped separator.
        k = 0
        while k < len(line):
            c = line[k]
            if c == "\\":
                k += 2
                continue
            if c in "=: \t\f":
                break
            k += 1
        key = line[:k]
        rest = line[k:].lstrip(" \t\f")
        if rest[:1] in ("=", ":"):
            rest = rest[1:].lstrip(" \t\f")
        out[_unescape(key)] = _unescape(rest)
    return out


def _unescape(s: str) -> str:
    if "\\" not in s:
        return s
    res = []
    i = 0
    while i < len(s):
        c = s[i]
        if c == "\\" and i + 1 < len(s):
            n = s[i + 1]
            if n == "u" and i + 6 <= len(s):
                res.append(chr(int(s[i + 2 : i + 6], 16)))
                i += 6
                continue
            res.append({"t": "\t", "n": "\n", "r": "\r", "f": "\f"}.get(n, n))
            i += 2
            continue
        res.append(c)
        i += 1
    return "".join(res)


def snake_id(folder: str) -> str:
    """Model folder name -> lower snake case ASCII id (bedsideTable2 -> bedside_table2)."""
    s = re.sub(r"([a-z0-9])([A-Z])", r"\1_\2", folder)
    s = re.sub(r"([A-Z]+)([A-Z][a-z])", r"\1_\2", s)
    s = re.sub(r"[^A-Za-z0-9]+", "_", s).strip("_").lower()
    s = re.sub(r"_+", "_", s)
    return s


@dataclass
class Entry:
    index: int
    id: str
    folder: str
    model: str  # zip path of the OBJ
    name: str
    category: str
    tags: list[str]
    creator: str
    width: float  # cm
    depth: float
    height: float
    elevation: float
    drop_on_top: float | None  # cm above the bottom, None = nothing dropped on it
    rotation: np.ndarray | None
    light: bool


def catalogue_entries(props: dict[str, str]) -> list[Entry]:
    indices = sorted({int(k.split("#", 1)[1]) for k in props if re.fullmatch(r"id#\d+", k)})
    entries = []
    for i in indices:
        g = lambda key, default=None: props.get(f"{key}#{i}", default)  # noqa: E731
        category = g("category")
        name = g("name")
        if category in EXCLUDED_CATEGORIES or name in EXCLUDED_NAMES:
            continue
        model = g("model").lstrip("/")
        folder = model.split("/")[-2]
        height = float(g("height"))
        drop = g("dropOnTopElevation")
        if drop is None:
            drop_cm: float | None = height  # Sweet Home 3D's default: the top
        else:
            drop_cm = float(drop)
            if drop_cm < 0:
                drop_cm = None
        rot = g("modelRotation")
        rotation = None
        if rot is not None:
            vals = [float(v) for v in rot.split()]
            if len(vals) != 9:
                raise SystemExit(f"modelRotation#{i}: expected 9 numbers")
            rotation = np.array(vals, dtype=np.float64).reshape(3, 3)
        tags = [t.strip() for t in (g("tags") or "").split(",")]
        tags = [t for t in tags if t and t != "Blend Swap"]
        entries.append(
            Entry(
                index=i,
                id=snake_id(folder),
                folder=folder,
                model=model,
                name=name,
                category=category,
                tags=tags,
                creator=g("creator") or "",
                width=float(g("width")),
                depth=float(g("depth")),
                height=height,
                elevation=float(g("elevation", "0")),
                drop_on_top=drop_cm,
                rotation=rotation,
                light=any(k.startswith("lightSource") and k.endswith(f"#{i}") for k in props),
            )
        )
    ids = [e.id for e in entries]
    if len(set(ids)) != len(ids):
        raise SystemExit("model ids are not unique")
    return entries


# --------------------------------------------------------------------------- OBJ / MTL


@dataclass
class Material:
    name: str
    kd: tuple[float, float, float] = DEFAULT_KD
    d: float = 1.0
    ns: float | None = None
    map_kd: str | None = None


@dataclass
class ObjData:
    v: np.ndarray  # (n, 3) float64
    vt: np.ndarray  # (m, 2) float64
    corner_v: np.ndarray  # (c,) int64, 0-based
    corner_vt: np.ndarray  # (c,) int64, -1 = none
    poly_start: np.ndarray  # (p + 1,) offsets into corners
    poly_mat: np.ndarray  # (p,) index into mat_names
    mat_names: list[str]
    mtllibs: list[str]
    line_v: np.ndarray  # vertex indices used by `l` elements


def parse_mtl(text: str) -> dict[str, Material]:
    mats: dict[str, Material] = {}
    cur: Material | None = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split(None, 1)
        key = parts[0]
        arg = parts[1].strip() if len(parts) > 1 else ""
        if key == "newmtl":
            cur = Material(arg)
            mats[arg] = cur
        elif cur is None:
            continue
        elif key == "Kd":
            vals = [float(x) for x in arg.split()[:3]]
            cur.kd = (vals[0], vals[1], vals[2]) if len(vals) == 3 else (vals[0],) * 3
        elif key == "d":
            cur.d = float(arg.split()[0])
        elif key == "Ns":
            cur.ns = float(arg.split()[0])
        elif key == "map_Kd":
            cur.map_kd = _map_path(arg)
    return mats


# Options of map_* statements and their argument counts (Wavefront MTL spec).
_MAP_OPTIONS = {"-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1,
                "-imfchan": 1, "-mm": 2, "-o": 3, "-s": 3, "-t": 3, "-texres": 1}


def _map_path(arg: str) -> str:
    """The file of a map_* statement: options skipped, the rest (which may hold spaces,
    "C:/Documents and Settings/...") kept."""
    rest = arg.strip()
    while True:
        parts = rest.split(None, 1)
        if not parts or parts[0] not in _MAP_OPTIONS:
            break
        n = _MAP_OPTIONS[parts[0]]
        rest = parts[1] if len(parts) > 1 else ""
        for _ in range(n):
            parts = rest.split(None, 1)
            if parts and (_is_number(parts[0]) or parts[0] in ("on", "off")):
                rest = parts[1] if len(parts) > 1 else ""
            else:
                break
    return rest.strip()


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def parse_obj(text: str) -> ObjData:
    v: list[list[float]] = []
    vt: list[list[float]] = []
    corner_v: list[int] = []
    corner_vt: list[int] = []
    poly_start = [0]
    poly_mat: list[int] = []
    mat_names: list[str] = []
    mat_index: dict[str, int] = {}
    mtllibs: list[str] = []
    line_v: list[int] = []
    cur_mat = -1

    def material(name: str) -> int:
        if name not in mat_index:
            mat_index[name] = len(mat_names)
            mat_names.append(name)
        return mat_index[name]

    for raw in text.splitlines():
        if not raw:
            continue
        if raw[0] in " \t":
            raw = raw.lstrip()
            if not raw:
                continue
        c0 = raw[0]
        if c0 == "v":
            c1 = raw[1:2]
            if c1 == " " or c1 == "\t":
                p = raw.split()
                v.append([float(p[1]), float(p[2]), float(p[3])])
            elif c1 == "t":
                p = raw.split()
                vt.append([float(p[1]), float(p[2]) if len(p) > 2 else 0.0])
            continue  # vn: normals are recomputed
        if c0 == "f":
            p = raw.split()[1:]
            if len(p) < 3:
                continue  # points / degenerate "faces" are not rendered
            nv = len(v)
            nt = len(vt)
            if cur_mat < 0:
                cur_mat = material("")
            for tok in p:
                s = tok.split("/")
                a = int(s[0])
                corner_v.append(a - 1 if a > 0 else nv + a)
                if len(s) > 1 and s[1]:
                    b = int(s[1])
                    corner_vt.append(b - 1 if b > 0 else nt + b)
                else:
                    corner_vt.append(-1)
            poly_start.append(len(corner_v))
            poly_mat.append(cur_mat)
            continue
        if c0 == "u" and raw.startswith("usemtl"):
            parts = raw.split(None, 1)
            cur_mat = material(parts[1].strip() if len(parts) > 1 else "")
            continue
        if c0 == "m" and raw.startswith("mtllib"):
            parts = raw.split(None, 1)
            if len(parts) > 1:
                mtllibs.append(parts[1].strip())
            continue
        if c0 == "l":
            nv = len(v)
            for tok in raw.split()[1:]:
                a = int(tok.split("/")[0])
                line_v.append(a - 1 if a > 0 else nv + a)
    return ObjData(
        v=np.array(v, dtype=np.float64).reshape(-1, 3),
        vt=np.array(vt, dtype=np.float64).reshape(-1, 2),
        corner_v=np.array(corner_v, dtype=np.int64),
        corner_vt=np.array(corner_vt, dtype=np.int64),
        poly_start=np.array(poly_start, dtype=np.int64),
        poly_mat=np.array(poly_mat, dtype=np.int64),
        mat_names=mat_names,
        mtllibs=mtllibs,
        line_v=np.array(line_v, dtype=np.int64),
    )


# --------------------------------------------------------------------------- triangulation


def _newell(pts: np.ndarray) -> np.ndarray:
    nxt = np.roll(pts, -1, axis=0)
    return np.array(
        [
            np.sum((pts[:, 1] - nxt[:, 1]) * (pts[:, 2] + nxt[:, 2])),
            np.sum((pts[:, 2] - nxt[:, 2]) * (pts[:, 0] + nxt[:, 0])),
            np.sum((pts[:, 0] - nxt[:, 0]) * (pts[:, 1] + nxt[:, 1])),
        ]
    )


def _ear_clip(pts3: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangulate one simple polygon (k >= 5 vertices, maybe concave) by ear clipping."""
    k = len(pts3)
    n = _newell(pts3)
    axis = int(np.argmax(np.abs(n)))
    keep = [a for a in range(3) if a != axis]
    p2 = pts3[:, keep]
    if n[axis] < 0:
        p2 = p2[:, ::-1]  # make the polygon counter-clockwise in its projection
    # Convex (the usual case): a fan.
    nxt = np.roll(p2, -1, axis=0)
    prv = np.roll(p2, 1, axis=0)
    cross = (p2[:, 0] - prv[:, 0]) * (nxt[:, 1] - p2[:, 1]) - (p2[:, 1] - prv[:, 1]) * (nxt[:, 0] - p2[:, 0])
    if np.all(cross >= 0):
        return [(0, i, i + 1) for i in range(1, k - 1)]
    idx = list(range(k))
    tris: list[tuple[int, int, int]] = []
    guard = 0
    while len(idx) > 3 and guard < 4 * k * k:
        m = len(idx)
        found = False
        for j in range(m):
            a, b, c = idx[j - 1], idx[j], idx[(j + 1) % m]
            pa, pb, pc = p2[a], p2[b], p2[c]
            cr = (pb[0] - pa[0]) * (pc[1] - pb[1]) - (pb[1] - pa[1]) * (pc[0] - pb[0])
            guard += 1
            if cr <= 0:
                continue
            others = [o for o in idx if o not in (a, b, c)]
            if others:
                q = p2[others]
                d1 = (pb[0] - pa[0]) * (q[:, 1] - pa[1]) - (pb[1] - pa[1]) * (q[:, 0] - pa[0])
                d2 = (pc[0] - pb[0]) * (q[:, 1] - pb[1]) - (pc[1] - pb[1]) * (q[:, 0] - pb[0])
                d3 = (pa[0] - pc[0]) * (q[:, 1] - pc[1]) - (pa[1] - pc[1]) * (q[:, 0] - pc[0])
                if np.any((d1 >= 0) & (d2 >= 0) & (d3 >= 0)):
                    continue
            tris.append((a, b, c))
            del idx[j]
            found = True
            break
        if not found:
            break
    if len(idx) == 3:
        tris.append((idx[0], idx[1], idx[2]))
    elif len(idx) > 3:  # not simple: fan the rest
        tris.extend((idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1))
    return tris


def triangulate(obj: ObjData) -> tuple[np.ndarray, np.ndarray]:
    """Triangles as corner indices (t, 3) and their material index (t,)."""
    starts = obj.poly_start[:-1]
    sizes = np.diff(obj.poly_start)
    out_c: list[np.ndarray] = []
    out_m: list[np.ndarray] = []
    order: list[np.ndarray] = []  # polygon index of each triangle, to keep file order
    # Triangles.
    sel = np.nonzero(sizes == 3)[0]
    if len(sel):
        c = starts[sel][:, None] + np.arange(3)[None, :]
        out_c.append(c)
        out_m.append(obj.poly_mat[sel])
        order.append(sel)
    # Quads: split along the diagonal that keeps both halves facing the quad's normal.
    sel = np.nonzero(sizes == 4)[0]
    if len(sel):
        c = starts[sel][:, None] + np.arange(4)[None, :]
        p = obj.v[obj.corner_v[c]]  # (q, 4, 3)
        nrm = np.zeros((len(sel), 3))
        for i in range(4):
            a, b = p[:, i], p[:, (i + 1) % 4]
            nrm += np.cross(a, b)
        n1 = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        n2 = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])
        fan_ok = (np.einsum("ij,ij->i", n1, nrm) >= 0) & (np.einsum("ij,ij->i", n2, nrm) >= 0)
        t1 = np.where(fan_ok[:, None], c[:, [0, 1, 2]], c[:, [0, 1, 3]])
        t2 = np.where(fan_ok[:, None], c[:, [0, 2, 3]], c[:, [1, 2, 3]])
        out_c.append(np.stack([t1, t2], axis=1).reshape(-1, 3))
        out_m.append(np.repeat(obj.poly_mat[sel], 2))
        order.append(np.repeat(sel, 2))
    # Larger polygons.
    sel = np.nonzero(sizes >= 5)[0]
    big_c: list[tuple[int, int, int]] = []
    big_m: list[int] = []
    big_o: list[int] = []
    for pi in sel:
        s, k = int(starts[pi]), int(sizes[pi])
        pts = obj.v[obj.corner_v[s : s + k]]
        for a, b, cc in _ear_clip(pts):
            big_c.append((s + a, s + b, s + cc))
            big_m.append(int(obj.poly_mat[pi]))
            big_o.append(int(pi))
    if big_c:
        out_c.append(np.array(big_c, dtype=np.int64))
        out_m.append(np.array(big_m, dtype=np.int64))
        order.append(np.array(big_o, dtype=np.int64))
    if not out_c:
        return np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    corners = np.concatenate(out_c)
    mats = np.concatenate(out_m)
    o = np.argsort(np.concatenate(order), kind="stable")  # file order of polygons
    return corners[o], mats[o]


# --------------------------------------------------------------------------- geometry


def corner_normals(p: np.ndarray, f: np.ndarray, crease_deg: float) -> np.ndarray:
    """Per-corner normals (3t, 3): corner-angle weighted average of the normals of the
    faces around the corner's vertex that lie within crease_deg of the corner's face."""
    t = len(f)
    a, b, c = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
    fn = np.cross(b - a, c - a)
    ln = np.linalg.norm(fn, axis=1)
    fnu = np.divide(fn, ln[:, None], out=np.zeros_like(fn), where=ln[:, None] > 0)
    ang = np.empty((t, 3))
    for k in range(3):
        e1 = p[f[:, (k + 1) % 3]] - p[f[:, k]]
        e2 = p[f[:, (k + 2) % 3]] - p[f[:, k]]
        ang[:, k] = np.arctan2(np.linalg.norm(np.cross(e1, e2), axis=1), np.einsum("ij,ij->i", e1, e2))
    cv = f.ravel()
    cw = ang.ravel()
    sc = np.argsort(cv, kind="stable")
    sv = cv[sc]
    _, gstart, gcount = np.unique(sv, return_index=True, return_counts=True)
    gid = np.repeat(np.arange(len(gcount)), gcount)
    k = gcount[gid]
    total = int(k.sum())
    a_pos = np.repeat(np.arange(3 * t), k)
    block_start = np.repeat(np.cumsum(k) - k, k)
    off = np.arange(total) - block_start
    b_pos = gstart[gid[a_pos]] + off
    ca, cb = sc[a_pos], sc[b_pos]
    fa, fb = ca // 3, cb // 3
    dot = np.einsum("ij,ij->i", fnu[fa], fnu[fb])
    m = dot >= math.cos(math.radians(crease_deg)) - 1e-9
    ca, fb, w = ca[m], fb[m], cw[cb[m]]
    out = np.zeros((3 * t, 3))
    for d in range(3):
        out[:, d] = np.bincount(ca, weights=fnu[fb, d] * w, minlength=3 * t)
    ln = np.linalg.norm(out, axis=1)
    own = np.repeat(fnu, 3, axis=0)
    bad = ln < 1e-12
    out = np.divide(out, ln[:, None], out=np.zeros_like(out), where=~bad[:, None])
    out[bad] = own[bad]
    still = np.linalg.norm(out, axis=1) < 0.5
    out[still] = (0.0, 1.0, 0.0)
    return out


def closest_point_barycentric(pt: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray):
    """Closest points on triangles (a, b, c) to points pt (all (n, 3)); returns
    (squared distance, barycentric weights (n, 3)). Ericson, Real-Time Collision
    Detection 5.1.5, vectorised."""
    ab, ac, ap = b - a, c - a, pt - a
    d1 = np.einsum("ij,ij->i", ab, ap)
    d2 = np.einsum("ij,ij->i", ac, ap)
    bp = pt - b
    d3 = np.einsum("ij,ij->i", ab, bp)
    d4 = np.einsum("ij,ij->i", ac, bp)
    cp = pt - c
    d5 = np.einsum("ij,ij->i", ab, cp)
    d6 = np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    n = len(pt)
    bary = np.zeros((n, 3))
    done = np.zeros(n, dtype=bool)

    def setw(mask, w):
        nonlocal done
        mask = mask & ~done
        bary[mask] = w[mask] if w.ndim == 2 else w
        done |= mask

    with np.errstate(divide="ignore", invalid="ignore"):
        setw((d1 <= 0) & (d2 <= 0), np.array([1.0, 0, 0]))
        setw((d3 >= 0) & (d4 <= d3), np.array([0, 1.0, 0]))
        v = d1 / (d1 - d3)
        setw((vc <= 0) & (d1 >= 0) & (d3 <= 0), np.stack([1 - v, v, 0 * v], 1))
        setw((d6 >= 0) & (d5 <= d6), np.array([0, 0, 1.0]))
        w = d2 / (d2 - d6)
        setw((vb <= 0) & (d2 >= 0) & (d6 <= 0), np.stack([1 - w, 0 * w, w], 1))
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        setw((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0), np.stack([0 * w, 1 - w, w], 1))
        denom = 1.0 / (va + vb + vc)
        v = vb * denom
        w = vc * denom
        setw(np.ones(n, dtype=bool), np.stack([1 - v - w, v, w], 1))
    bary = np.nan_to_num(bary, nan=1.0 / 3.0)
    q = bary[:, :1] * a + bary[:, 1:2] * b + bary[:, 2:] * c
    return np.einsum("ij,ij->i", q - pt, q - pt), bary


def weld(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique rows in order of first appearance: (first index of each, inverse)."""
    _, first, inv = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return first[order], rank[inv]


@dataclass
class Prim:
    material: int  # index into the model's material list
    pos: np.ndarray  # (n, 3) float64 vertices
    uv: np.ndarray | None  # (n, 2) per vertex, or None
    tri: np.ndarray  # (t, 3) int64
    decimated: bool = False


def _own_mapping(n: int, tri: np.ndarray, collapses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Replay fast_simplification's collapse list (i1 merged into i0): the new index of
    every input vertex (-1: unreferenced) and the input triangles so mapped, degenerate
    ones dropped, in input order (which is what simplify() returns)."""
    parent = np.arange(n)
    for i0, i1 in np.asarray(collapses, dtype=np.int64).reshape(-1, 2):
        parent[i1] = i0
    root = parent
    while True:
        nxt = root[root]
        if np.array_equal(nxt, root):
            break
        root = nxt
    t = root[tri]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    t = t[keep]
    used = np.unique(t)
    rank = np.full(n, -1, dtype=np.int64)
    rank[used] = np.arange(len(used))
    mapping = np.where(rank[root] >= 0, rank[root], -1)
    return mapping, rank[t]


def _qem(p: np.ndarray, tri: np.ndarray, target: int, preserve_border: bool):
    """fast_simplification to target triangles: (points, triangles, mapping of the input
    vertices to the output ones), or None where it fails."""
    import fast_simplification

    if len(tri) <= target:
        return None
    pts, faces, collapses = fast_simplification.simplify(
        np.ascontiguousarray(p, dtype=np.float64),
        np.ascontiguousarray(tri, dtype=np.int32),
        target_count=int(target),
        agg=7.0,
        return_collapses=True,
        preserve_border=preserve_border,
    )
    pts = np.asarray(pts, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    mapping, mapped = _own_mapping(len(p), np.asarray(tri, dtype=np.int64), collapses)
    if not np.array_equal(mapped, faces) or not np.all(np.isfinite(pts)) or len(pts) != mapping.max() + 1:
        return None
    return pts, faces, mapping


def _cluster(p: np.ndarray, tri: np.ndarray, h: float):
    """Vertex clustering on a grid of h metres: (points, triangles, mapping)."""
    cell = np.floor((p - p.min(axis=0)) / h).astype(np.int64)
    _, cid = weld(cell)
    n = int(cid.max()) + 1
    cnt = np.bincount(cid, minlength=n).astype(np.float64)
    q = np.stack([np.bincount(cid, weights=p[:, d], minlength=n) / cnt for d in range(3)], axis=1)
    t = cid[tri]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    t = t[keep]
    # Drop triangles repeated with the same corners (same orientation).
    _, first = np.unique(t, axis=0, return_index=True)
    t = t[np.sort(first)]
    return q, t, cid


def surface_distances(p0: np.ndarray, t0: np.ndarray, p1: np.ndarray, t1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distances from the original triangles' centres (p0, t0) to the decimated surface
    (p1, t1), with the original triangles' areas as weights. The nearest decimated
    triangle is sought among those owning the 24 nearest of their corners, edge midpoints
    and centres."""
    from scipy.spatial import cKDTree

    a0, b0, c0 = p0[t0[:, 0]], p0[t0[:, 1]], p0[t0[:, 2]]
    w = 0.5 * np.linalg.norm(np.cross(b0 - a0, c0 - a0), axis=1)
    q = (a0 + b0 + c0) / 3.0
    if not len(t1):
        return np.full(len(q), np.inf), w
    a, b, c = p1[t1[:, 0]], p1[t1[:, 1]], p1[t1[:, 2]]
    samples = np.concatenate([a, b, c, (a + b) / 2, (b + c) / 2, (c + a) / 2, (a + b + c) / 3])
    owner = np.tile(np.arange(len(t1)), 7)
    tree = cKDTree(samples)
    k = min(24, len(samples))
    d = np.zeros(len(q))
    for s in range(0, len(q), 16384):
        qs = q[s : s + 16384]
        _, idx = tree.query(qs, k=k)
        cand = owner[idx.reshape(len(qs), k)].ravel()
        d2, _ = closest_point_barycentric(np.repeat(qs, k, axis=0), a[cand], b[cand], c[cand])
        d[s : s + 16384] = np.sqrt(d2.reshape(len(qs), k).min(axis=1))
    return d, w


def far_share(d: np.ndarray, w: np.ndarray, tol: float) -> float:
    """Share of the surface (by area) farther than tol."""
    total = w.sum()
    return float(w[d > tol].sum() / total) if total > 0 else 0.0


def _compact(r):
    """Drop points no triangle uses from a (points, triangles, mapping) result."""
    pts, faces, m = r
    used = np.unique(faces)
    if len(used) == len(pts):
        return r
    rank = np.full(len(pts), -1, dtype=np.int64)
    rank[used] = np.arange(len(used))
    return pts[used], rank[faces], np.where(m >= 0, rank[np.maximum(m, 0)], -1)


def decimate_shape(p: np.ndarray, tri: np.ndarray, target: int, diag: float, borders=(False, True), weld_uv: np.ndarray | None = None):
    """Quadric decimation of a mesh to about target triangles, checked against the
    original surface by ACCEPT_LEVELS: at first the result must keep all but 2 % of the
    original surface (by area) within max(2 mm, 1 % of the model's box diagonal diag) of
    it, and all but 2 % of its own surface within as much of the original, else the
    target is raised by half again, until the decimation would remove under
    10 %; past twice and four times the target, looser levels are accepted too.
    Tried at each target, smallest passing result first: the mesh as given and welded by
    coordinates (by coordinates and weld_uv where given), each with open borders free to
    collapse and kept (fast_simplification's preserve_border; free borders let flat open
    parts shrink); where the decimation stops well short of its target (thin tubes,
    near-coincident unwelded vertices) also after clustering the vertices on grids of
    CLUSTER_STEPS_M (not coarser than tol). Returns (points, triangles, mapping of the
    input vertices) or None (left as it is)."""
    keys = p if weld_uv is None else np.concatenate([p, weld_uv], axis=1)
    wf, wid = weld(keys)
    topologies = [(p, tri, np.arange(len(p)))]
    if len(wf) < len(p):
        tw = wid[tri]
        keep = (tw[:, 0] != tw[:, 1]) & (tw[:, 1] != tw[:, 2]) & (tw[:, 0] != tw[:, 2])
        topologies.append((p[wf], tw[keep], wid))
    tol = max(TOLERANCE_M, ACCEPT_LEVELS[0][1] * diag)
    target = max(int(target), MIN_PRIMITIVE_TRIANGLES + 1)
    t = target
    while t < 0.9 * len(tri):
        cands = []
        for tp, tt, tmap in topologies:
            short = True
            for pb in borders:
                r = _qem(tp, tt, t, pb)
                if r is not None:
                    cands.append((r[0], r[1], r[2][tmap]))
                    short = short and len(r[1]) > 1.2 * t
            if short and False not in borders:
                continue
            if short:
                for h in CLUSTER_STEPS_M:
                    if h > tol:
                        break
                    q, ct, cmap = _cluster(tp, tt, h)
                    if len(ct) <= MIN_PRIMITIVE_TRIANGLES:
                        break
                    rc = _qem(q, ct, t, False)
                    pts, faces, m2 = _compact(rc if rc is not None else (q, ct, np.arange(len(q))))
                    cands.append((pts, faces, m2[cmap][tmap]))
                    if len(faces) <= 1.2 * t:
                        break
        cands.sort(key=lambda c: len(c[1]))  # stable: earlier candidates first among equals
        levels = [lv for lv in ACCEPT_LEVELS if t >= lv[0] * target]
        for c in cands:
            if len(c[1]) > 1.2 * t or len(c[1]) >= len(tri):
                break  # stuck well above this target: judged when the target gets there
            if len(c[1]) < MIN_PRIMITIVE_TRIANGLES:
                continue
            d, w = surface_distances(p, tri, c[0], c[1])  # lost surface
            ok = [lv for lv in levels if far_share(d, w, max(TOLERANCE_M, lv[1] * diag)) <= lv[2]]
            if ok:
                d, w = surface_distances(c[0], c[1], p, tri)  # surface that was not there
                if any(far_share(d, w, max(TOLERANCE_M, f * diag)) <= share for _, f, share in ok):
                    return c
        t = int(t * 1.5) + 1
    return None


def _barycentric(q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of the projections of q on the triangles' planes
    (unclamped: points outside a triangle extrapolate its UV map linearly)."""
    v0, v1, v2 = b - a, c - a, q - a
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = d00 * d11 - d01 * d01
    ok = np.abs(den) > 1e-30
    den = np.where(ok, den, 1.0)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    out = np.stack([1.0 - v - w, v, w], axis=1)
    if not ok.all():
        _, clamped = closest_point_barycentric(q[~ok], a[~ok], b[~ok], c[~ok])
        out[~ok] = clamped
    return out


def _uv_by_charts(prim: Prim, pts: np.ndarray, tri: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """UVs for a textured primitive decimated without regard to its seams: each new
    triangle takes the UV chart (connected part of the original position+UV mesh) of the
    original triangle nearest its centre, and each of its corners the UV of the nearest
    original triangle of that chart (extrapolated linearly). Returns per-vertex arrays
    (points, uv, triangles), vertices split where corners disagree."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    t0 = prim.tri
    n0 = len(prim.pos)
    adj = coo_matrix((np.ones(2 * len(t0)), (np.concatenate([t0[:, 0], t0[:, 1]]), np.concatenate([t0[:, 1], t0[:, 2]]))), shape=(n0, n0))
    _, vchart = connected_components(adj, directed=False)
    chart = vchart[t0[:, 0]]
    a, b, c = prim.pos[t0[:, 0]], prim.pos[t0[:, 1]], prim.pos[t0[:, 2]]
    tree = cKDTree((a + b + c) / 3.0)

    def nearest(q: np.ndarray, allowed_chart: np.ndarray | None, k: int) -> np.ndarray:
        k = min(k, len(t0))
        _, cand = tree.query(q, k=k)
        cand = cand.reshape(len(q), k)
        qq = np.repeat(q, k, axis=0)
        cf = cand.ravel()
        d2, _ = closest_point_barycentric(qq, a[cf], b[cf], c[cf])
        d2 = d2.reshape(len(q), k)
        if allowed_chart is not None:
            d2 = np.where(chart[cand] == allowed_chart[:, None], d2, np.inf)
        best = np.argmin(d2, axis=1)  # first of equals: nearest centroid
        found = np.isfinite(d2[np.arange(len(q)), best])
        return np.where(found, cand[np.arange(len(q)), best], -1)

    centre = pts[tri].mean(axis=1)
    owner = nearest(centre, None, 16)
    corner_q = pts[tri].reshape(-1, 3)
    corner_chart = np.repeat(chart[owner], 3)
    src = nearest(corner_q, corner_chart, 32)
    src = np.where(src >= 0, src, np.repeat(owner, 3))
    st = t0[src]
    w = _barycentric(corner_q, prim.pos[st[:, 0]], prim.pos[st[:, 1]], prim.pos[st[:, 2]])
    uv = w[:, :1] * prim.uv[st[:, 0]] + w[:, 1:2] * prim.uv[st[:, 1]] + w[:, 2:] * prim.uv[st[:, 2]]
    cvid = tri.ravel()
    keys = np.concatenate([cvid[:, None].astype(np.float64), uv], axis=1)
    first, inv = weld(keys)
    return pts[cvid[first]], uv[first], inv.reshape(-1, 3)


def decimate(prim: Prim, target: int, diag: float) -> tuple[Prim, str]:
    """Decimate a primitive to about target triangles. Untextured: decimate_shape.
    Textured: first with its UV seams and open borders kept (the mesh is welded by
    position and UV, so seams are borders; preserve_border), each moved vertex taking the
    UV of the closest point of the original surface it replaced; where the seams stop that
    short (over twice the target and over SEAM_FREE_EXCESS triangles too many), the
    primitive is decimated as a shape and its UVs re-projected by chart (_uv_by_charts).
    Every result is checked against the original surface (decimate_shape). Returns the
    primitive and how it was done."""
    if len(prim.tri) <= target:
        return prim, "kept"
    if prim.uv is None:
        r = decimate_shape(prim.pos, prim.tri, target, diag)
        if r is None or len(r[1]) >= len(prim.tri):
            return prim, "kept"
        return Prim(prim.material, r[0], None, r[1], decimated=True), "qem"
    r = decimate_shape(prim.pos, prim.tri, target, diag, borders=(True,), weld_uv=prim.uv)
    seam_prim = prim
    if r is not None and len(r[1]) < len(prim.tri):
        new_pts, new_tri, mapping = r
        # Candidate original triangles of each new vertex: those around the original
        # vertices merged into it.
        cj = mapping[prim.tri.ravel()]
        ct = np.repeat(np.arange(len(prim.tri)), 3)
        ok = cj >= 0
        pairs = np.unique(np.stack([cj[ok], ct[ok]], 1), axis=0)
        j, t = pairs[:, 0], pairs[:, 1]
        tri_o = prim.tri[t]
        d2, bary = closest_point_barycentric(new_pts[j], prim.pos[tri_o[:, 0]], prim.pos[tri_o[:, 1]], prim.pos[tri_o[:, 2]])
        best = np.lexsort((t, d2, j))  # per vertex: nearest, then lowest triangle index
        jb = j[best]
        first = np.ones(len(jb), dtype=bool)
        first[1:] = jb[1:] != jb[:-1]
        sel = best[first]
        uv = np.zeros((len(new_pts), 2))
        tri_s = prim.tri[t[sel]]
        w = bary[sel]
        uv[j[sel]] = w[:, :1] * prim.uv[tri_s[:, 0]] + w[:, 1:2] * prim.uv[tri_s[:, 1]] + w[:, 2:] * prim.uv[tri_s[:, 2]]
        seam_prim = Prim(prim.material, new_pts, uv, new_tri, decimated=True)
    n_seam = len(seam_prim.tri)
    if n_seam <= 2 * target or n_seam - target <= SEAM_FREE_EXCESS:
        return seam_prim, ("seams kept" if seam_prim is not prim else "kept")
    # Decimate the shape (welded by position) and re-project the UVs by chart.
    wf, wid = weld(prim.pos)
    pw = prim.pos[wf]
    tw = wid[prim.tri]
    keep = (tw[:, 0] != tw[:, 1]) & (tw[:, 1] != tw[:, 2]) & (tw[:, 0] != tw[:, 2])
    r = decimate_shape(pw, tw[keep], target, diag, borders=(False, True))
    if r is None or len(r[1]) >= n_seam:
        return seam_prim, "seams kept"
    pts, uv, tri = _uv_by_charts(prim, r[0], r[1])
    return Prim(prim.material, pts, uv, tri, decimated=True), "uv re-projected"


# --------------------------------------------------------------------------- budget


def triangle_budget(width_cm: float, depth_cm: float) -> int:
    """clamp(round(BUDGET_K * sqrt(footprint / 0.25 m^2)), BUDGET_MIN, BUDGET_MAX)."""
    area = (width_cm / 100.0) * (depth_cm / 100.0)
    return int(min(BUDGET_MAX, max(BUDGET_MIN, round(BUDGET_K * math.sqrt(area / 0.25)))))


def allocate(counts: list[int], budget: int) -> list[int]:
    """Per-primitive targets: proportional shares of the budget, never below
    MIN_PRIMITIVE_TRIANGLES (nor above the primitive's own count)."""
    total = sum(counts)
    targets = []
    for c in counts:
        share = round(budget * c / total) if total else c
        targets.append(min(c, max(MIN_PRIMITIVE_TRIANGLES, share)))
    return targets


# --------------------------------------------------------------------------- textures


def encode_texture(data: bytes) -> tuple[bytes, str, int, int, str]:
    """(bytes, mime, width, height, alpha) with the longer side at most MAX_TEXTURE_PX
    (Lanczos); JPEGs stay JPEGs (quality JPEG_QUALITY, or their own bytes where those are
    smaller and no scaling is needed), PNGs PNGs, anything else becomes a PNG.
    alpha: "opaque", "mask" (alpha mostly 0 or 255: a cut-out) or "blend"."""
    im = Image.open(io.BytesIO(data))
    im.load()
    fmt = im.format
    w, h = im.size
    alpha = "opaque"
    if im.mode in ("RGBA", "LA", "PA") or (im.mode == "P" and "transparency" in im.info):
        a = np.asarray(im.convert("RGBA"))[..., 3]
        if a.min() < 255:
            mid = np.mean((a > 8) & (a < 247))  # anti-aliased edges of a cut-out, or glass
            alpha = "mask" if mid < 0.25 else "blend"
    scale = MAX_TEXTURE_PX / max(w, h)
    if scale >= 1.0 and fmt == "PNG":
        return data, "image/png", w, h, alpha
    if scale >= 1.0 and fmt == "JPEG":
        # Small enough: stored at quality JPEG_QUALITY where that is smaller, else as is.
        buf = io.BytesIO()
        im.convert("RGB" if im.mode not in ("RGB", "L") else im.mode).save(buf, format="JPEG", quality=JPEG_QUALITY)
        out = buf.getvalue() if len(buf.getvalue()) < len(data) else data
        return out, "image/jpeg", w, h, alpha
    if scale < 1.0:
        nw, nh = max(1, round(w * scale)), max(1, round(h * scale))
    else:
        nw, nh = w, h
    buf = io.BytesIO()
    if fmt == "JPEG":
        if im.mode not in ("RGB", "L"):
            im = im.convert("RGB")
        im = im.resize((nw, nh), Image.Resampling.LANCZOS) if (nw, nh) != (w, h) else im
        im.save(buf, format="JPEG", quality=JPEG_QUALITY)
        return buf.getvalue(), "image/jpeg", nw, nh, alpha
    if im.mode not in ("RGB", "RGBA", "L", "LA"):
        im = im.convert("RGBA" if alpha != "opaque" else "RGB")
    im = im.resize((nw, nh), Image.Resampling.LANCZOS) if (nw, nh) != (w, h) else im
    im.save(buf, format="PNG", optimize=True)
    return buf.getvalue(), "image/png", nw, nh, alpha


# --------------------------------------------------------------------------- GLB


class GlbBuilder:
    def __init__(self) -> None:
        self.bin = bytearray()
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def _view(self, data: bytes, target: int | None) -> int:
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.bin.extend(data)
        self.views.append(view)
        return len(self.views) - 1

    def accessor(self, arr: np.ndarray, kind: str, minmax: bool = False) -> int:
        if kind == "SCALAR":
            data = np.ascontiguousarray(arr, dtype="<u4")
            ctype, target, count = 5125, 34963, len(data)
        else:
            data = np.ascontiguousarray(arr, dtype="<f4")
            ctype, target, count = 5126, 34962, len(data)
        acc = {"bufferView": self._view(data.tobytes(), target), "componentType": ctype, "count": int(count), "type": kind}
        if minmax:
            acc["min"] = [float(x) for x in data.min(axis=0)]
            acc["max"] = [float(x) for x in data.max(axis=0)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def image_view(self, data: bytes) -> int:
        return self._view(data, None)

    def finish(self, doc: dict) -> bytes:
        while len(self.bin) % 4:
            self.bin.append(0)
        doc["accessors"] = self.accessors
        doc["bufferViews"] = self.views
        doc["buffers"] = [{"byteLength": len(self.bin)}]
        js = json.dumps(doc, separators=(",", ":"), ensure_ascii=True).encode("ascii")
        js += b" " * ((4 - len(js) % 4) % 4)
        total = 12 + 8 + len(js) + 8 + len(self.bin)
        out = bytearray()
        out += struct.pack("<III", 0x46546C67, 2, total)
        out += struct.pack("<II", len(js), 0x4E4F534A) + js
        out += struct.pack("<II", len(self.bin), 0x004E4942) + bytes(self.bin)
        return bytes(out)


# --------------------------------------------------------------------------- model


@dataclass
class Result:
    glb: bytes
    triangles: int
    source_triangles: int
    notes: list[str] = field(default_factory=list)
    front: tuple[float, float] | None = None  # (mean z of high vertices / depth, fraction at z < 0)
    budget: int = 0
    reprojected: int = 0  # textured primitives decimated across their UV seams


def convert_model(zf: zipfile.ZipFile, e: Entry) -> Result:
    notes: list[str] = []
    obj_dir = e.model.rsplit("/", 1)[0]
    obj = parse_obj(zf.read(e.model).decode("latin-1"))
    names = set(zf.namelist())
    mats: dict[str, Material] = {}
    for lib in obj.mtllibs:
        path = f"{obj_dir}/{lib}"
        if path in names:
            mats.update(parse_mtl(zf.read(path).decode("latin-1")))
        else:
            notes.append(f"missing mtllib {lib}")

    corners, tri_mat = triangulate(obj)
    source_triangles = len(corners)

    # modelRotation, then the exact box (Sweet Home 3D computes the bounds from the
    # geometry it draws: faces and lines).
    v = obj.v if e.rotation is None else obj.v @ e.rotation.T
    used = np.unique(np.concatenate([obj.corner_v[corners.ravel()], obj.line_v]))
    lo, hi = v[used].min(axis=0), v[used].max(axis=0)
    used_f = np.unique(obj.corner_v[corners.ravel()])
    flo, fhi = v[used_f].min(axis=0), v[used_f].max(axis=0)
    if np.any(np.abs(flo - lo) > 1e-9) or np.any(np.abs(fhi - hi) > 1e-9):
        notes.append("lines widen the bounds")
    size = np.array([e.width, e.height, e.depth]) / 100.0
    ext = hi - lo
    s = np.where(ext > 1e-12, size / np.where(ext > 1e-12, ext, 1.0), 1.0)
    vt_all = (v - lo) * s
    vt_all[:, 0] -= size[0] / 2.0
    vt_all[:, 2] -= size[2] / 2.0
    aniso = float(np.max(s) / np.min(s)) if np.all(ext > 1e-12) else float("inf")

    # Triangles whose corners share a position are dropped. The primitives keep the
    # OBJ's own vertex sharing (welding coincident vertices of separate parts makes
    # non-manifold edges that the decimation handles badly).
    _, pid = weld(obj.v)
    # Build one primitive per material, in order of first use.
    prims: list[Prim] = []
    gltf_mats: list[tuple[Material, str | None]] = []
    for mi, mname in enumerate(obj.mat_names):
        sel = np.nonzero(tri_mat == mi)[0]
        if not len(sel):
            continue
        mat = mats.get(mname)
        if mat is None:
            mat = Material(mname or "default")
            notes.append(f"material {mname!r} undefined: default colour")
        c = corners[sel]
        cv = obj.corner_v[c]
        tex = None
        if mat.map_kd:
            tex = resolve_texture(names, obj_dir, mat.map_kd)
            if tex is None:
                notes.append(f"texture {mat.map_kd!r} of {mat.name!r} missing: base colour only")
        cvt = obj.corner_vt[c]
        if tex is not None and np.all(cvt < 0):
            notes.append(f"material {mat.name!r} has a texture but no UVs: base colour only")
            tex = None
        p_id = pid[cv]
        keep = (p_id[:, 0] != p_id[:, 1]) & (p_id[:, 1] != p_id[:, 2]) & (p_id[:, 0] != p_id[:, 2])
        # The same triangle twice (the back of a two-sided surface): once is enough, the
        # materials are double sided.
        _, once = np.unique(np.sort(p_id, axis=1), axis=0, return_index=True)
        dup = np.ones(len(p_id), dtype=bool)
        dup[once] = False
        keep &= ~dup
        cv, cvt = cv[keep], cvt[keep]
        if not len(cv):
            continue
        if tex is not None:
            uv_c = np.where(cvt[..., None] >= 0, obj.vt[np.maximum(cvt, 0)] if len(obj.vt) else 0.0, 0.0)
            keys = np.concatenate([cv.reshape(-1, 1).astype(np.float64), uv_c.reshape(-1, 2)], axis=1)
            first, inv = weld(keys)
            pos = vt_all[cv.ravel()[first]]
            uv = uv_c.reshape(-1, 2)[first]
        else:
            first, inv = weld(cv.reshape(-1, 1))
            pos = vt_all[cv.ravel()[first]]
            uv = None
        prims.append(Prim(len(gltf_mats), pos, uv, inv.reshape(-1, 3)))
        gltf_mats.append((mat, tex))

    # Front convention check (before decimation): the vertices above 60 % of the height.
    allp = np.concatenate([p.pos for p in prims])
    hi_mask = allp[:, 1] > 0.6 * size[1]
    front = None
    if hi_mask.any():
        zs = allp[hi_mask, 2]
        front = (float(zs.mean() / size[2]), float(np.mean(zs < 0)))

    # Decimation to the budget.
    budget = triangle_budget(e.width, e.depth)
    diag = float(np.linalg.norm(size))
    reprojected = 0
    counts = [len(p.tri) for p in prims]
    if sum(counts) > budget:
        # Textured primitives first (their seams may stop them short of the target);
        # the untextured ones then share what is left of the budget.
        targets = allocate(counts, budget)
        for i, p in enumerate(prims):
            if p.uv is not None and counts[i] > targets[i]:
                prims[i], how = decimate(p, targets[i], diag)
                if how == "uv re-projected":
                    reprojected += 1
                    notes.append(f"{gltf_mats[p.material][0].name!r}: decimated across its UV seams, UVs re-projected")
        tex_now = sum(len(p.tri) for p in prims if p.uv is not None)
        untex = [i for i, p in enumerate(prims) if p.uv is None]
        left = max(0, budget - tex_now)
        ucounts = [counts[i] for i in untex]
        if ucounts and sum(ucounts) > left:
            utargets = allocate(ucounts, left)
            for i, t in zip(untex, utargets):
                if counts[i] > t:
                    prims[i], _ = decimate(prims[i], t, diag)
        now = sum(len(p.tri) for p in prims)
        if now > 1.1 * budget:
            notes.append(f"over the budget of {budget}")

    # The exact box again (decimation moves vertices).
    allp = np.concatenate([p.pos for p in prims])
    lo2, hi2 = allp.min(axis=0), allp.max(axis=0)
    ext2 = hi2 - lo2
    s2 = np.where(ext2 > 1e-12, size / np.where(ext2 > 1e-12, ext2, 1.0), 1.0)
    for p in prims:
        q = (p.pos - lo2) * s2
        q[:, 0] -= size[0] / 2.0
        q[:, 2] -= size[2] / 2.0
        p.pos = q

    # GLB.
    g = GlbBuilder()
    doc: dict = {
        "asset": {"version": "2.0", "generator": "egogen tools/furniture_catalogue.py"},
        "scene": 0,
        "scenes": [{"name": e.id, "nodes": [0]}],
        "nodes": [{"name": e.id, "mesh": 0}],
    }
    images: list[dict] = []
    textures: list[dict] = []
    tex_index: dict[str, tuple[int, str]] = {}
    materials: list[dict] = []
    for mat, tex in gltf_mats:
        kd = [min(1.0, max(0.0, float(x))) for x in mat.kd]
        alpha = min(1.0, max(0.0, float(mat.d)))
        rough = 0.8 if mat.ns is None else min(1.0, max(0.2, 1.0 - mat.ns / 1000.0))
        pbr: dict = {
            "baseColorFactor": [round(kd[0], 6), round(kd[1], 6), round(kd[2], 6), round(alpha, 6)],
            "metallicFactor": 0.0,
            "roughnessFactor": round(rough, 6),
        }
        m: dict = {"name": mat.name or "default", "pbrMetallicRoughness": pbr, "doubleSided": True}
        mode = "blend" if alpha < 1.0 else "opaque"
        if tex is not None:
            if tex not in tex_index:
                data, mime, _, _, talpha = encode_texture(zf.read(tex))
                images.append({"bufferView": g.image_view(data), "mimeType": mime, "name": tex.rsplit("/", 1)[-1]})
                textures.append({"sampler": 0, "source": len(images) - 1})
                tex_index[tex] = (len(textures) - 1, talpha)
            ti, talpha = tex_index[tex]
            pbr["baseColorTexture"] = {"index": ti, "texCoord": 0}
            if mode == "opaque" and talpha != "opaque":
                mode = talpha
        if mode == "blend":
            m["alphaMode"] = "BLEND"
        elif mode == "mask":
            m["alphaMode"] = "MASK"
            m["alphaCutoff"] = 0.5
        materials.append(m)
    primitives = []
    total_tris = 0
    for p in prims:
        # Normals over the position-welded triangles (UV seams do not crease).
        wf, wid = weld(p.pos)
        n = corner_normals(p.pos[wf], wid[p.tri], CREASE_ANGLE_DEG)
        q = np.round(n * 1e5).astype(np.int64)
        cvid = p.tri.ravel()
        first, inv = weld(np.concatenate([cvid[:, None], q], axis=1))
        pos = p.pos[cvid[first]].astype(np.float32)
        nrm = n[first]
        nrm = (nrm / np.linalg.norm(nrm, axis=1, keepdims=True)).astype(np.float32)
        attrs = {"POSITION": g.accessor(pos, "VEC3", minmax=True), "NORMAL": g.accessor(nrm, "VEC3")}
        if p.uv is not None:
            uv = p.uv[cvid[first]].copy()
            uv[:, 1] = 1.0 - uv[:, 1]  # OBJ's v runs up, glTF's down
            attrs["TEXCOORD_0"] = g.accessor(uv.astype(np.float32), "VEC2")
        idx = g.accessor(inv.astype(np.uint32), "SCALAR")
        primitives.append({"attributes": attrs, "indices": idx, "material": p.material, "mode": 4})
        total_tris += len(p.tri)
    doc["meshes"] = [{"name": e.id, "primitives": primitives}]
    doc["materials"] = materials
    if textures:
        doc["samplers"] = [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}]
        doc["images"] = images
        doc["textures"] = textures
    if aniso > 1.25:
        notes.append(f"non-uniform scale ratio {aniso:.2f}")
    return Result(g.finish(doc), total_tris, source_triangles, notes, front, budget, reprojected)


def resolve_texture(names: set[str], obj_dir: str, ref: str) -> str | None:
    ref = ref.replace("\\", "/").strip()
    cand = f"{obj_dir}/{ref}"
    if cand in names:
        return cand
    base = ref.rsplit("/", 1)[-1].lower()
    for n in sorted(names):
        if n.startswith(obj_dir + "/") and n.rsplit("/", 1)[-1].lower() == base:
            return n
    return None


# --------------------------------------------------------------------------- check


def parse_glb(data: bytes) -> tuple[dict, bytes]:
    magic, version, total = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2 and total == len(data)
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A
    doc = json.loads(data[20 : 20 + jlen])
    off = 20 + jlen
    blen, btype = struct.unpack_from("<II", data, off)
    assert btype == 0x004E4942
    return doc, data[off + 8 : off + 8 + blen]


def check_folder(out: str) -> list[str]:
    """Load every GLB back and check it against catalogue.json. Returns failures."""
    import trimesh

    with open(os.path.join(out, "catalogue.json"), encoding="utf-8") as f:
        raw = f.read()
    cat = json.loads(raw)
    fails: list[str] = []
    if raw != json.dumps(cat, sort_keys=True, indent=1, ensure_ascii=False) + "\n":
        fails.append("catalogue.json: not sorted keys / indent 1 / trailing newline")
    ids = [m["id"] for m in cat["models"]]
    if ids != sorted(set(ids)):
        fails.append("catalogue.json: ids not unique and sorted")
    glbs = sorted(n for n in os.listdir(out) if n.endswith(".glb"))
    if glbs != sorted(m["file"] for m in cat["models"]):
        fails.append("GLB files and catalogue entries differ")
    for m in cat["models"]:
        path = os.path.join(out, m["file"])
        data = open(path, "rb").read()
        try:
            doc, binc = parse_glb(data)
            assert len(data) == m["bytes"], "bytes"
            assert len(doc["scenes"]) == 1 and doc["scenes"][0]["nodes"] == [0], "scene"
            assert len(doc["nodes"]) == 1 and doc["nodes"][0] == {"name": m["id"], "mesh": 0}, "node"
            assert len(doc["meshes"]) == 1 and len(doc["buffers"]) == 1, "mesh/buffer"
            assert doc["buffers"][0]["byteLength"] == len(binc), "buffer length"
            assert "extensionsUsed" not in doc, "extensions"
            tris = 0
            for pr in doc["meshes"][0]["primitives"]:
                assert pr["mode"] == 4
                acc = doc["accessors"][pr["indices"]]
                assert acc["componentType"] == 5125 and acc["type"] == "SCALAR"
                tris += acc["count"] // 3
                textured = "baseColorTexture" in doc["materials"][pr["material"]]["pbrMetallicRoughness"]
                assert set(pr["attributes"]) == ({"POSITION", "NORMAL", "TEXCOORD_0"} if textured else {"POSITION", "NORMAL"})
                for name in pr["attributes"].values():
                    assert doc["accessors"][name]["componentType"] == 5126
                counts = {doc["accessors"][a]["count"] for a in pr["attributes"].values()}
                assert len(counts) == 1, "attribute counts"
                nacc = doc["accessors"][pr["attributes"]["NORMAL"]]
                bv = doc["bufferViews"][nacc["bufferView"]]
                nrm = np.frombuffer(binc, dtype="<f4", count=nacc["count"] * 3, offset=bv["byteOffset"]).reshape(-1, 3)
                assert np.all(np.abs(np.linalg.norm(nrm, axis=1) - 1) < 1e-3), "unit normals"
                pacc = doc["accessors"][pr["attributes"]["POSITION"]]
                bv = doc["bufferViews"][pacc["bufferView"]]
                pos = np.frombuffer(binc, dtype="<f4", count=pacc["count"] * 3, offset=bv["byteOffset"]).reshape(-1, 3)
                assert pacc["min"] == [float(x) for x in pos.min(axis=0)] and pacc["max"] == [float(x) for x in pos.max(axis=0)], "min/max"
            for bv in doc["bufferViews"]:
                assert bv["byteOffset"] % 4 == 0
            assert len(doc.get("samplers", [])) == (1 if doc.get("images") else 0), "one sampler"
            assert tris == m["triangles"], f"triangles {tris} != {m['triangles']}"
            for im in doc.get("images", []):
                bv = doc["bufferViews"][im["bufferView"]]
                img = Image.open(io.BytesIO(binc[bv["byteOffset"] : bv["byteOffset"] + bv["byteLength"]]))
                img.load()
                assert max(img.size) <= MAX_TEXTURE_PX, "texture size"
                assert {"JPEG": "image/jpeg", "PNG": "image/png"}[img.format] == im["mimeType"], "mime"
            scene = trimesh.load(io.BytesIO(data), file_type="glb", force="scene")
            assert len(scene.geometry) == len(doc["meshes"][0]["primitives"]), "trimesh: one geometry per primitive"
            lo, hi = scene.bounds
            w, d, h = m["size_m"]
            want_lo = np.array([-w / 2, 0, -d / 2])
            want_hi = np.array([w / 2, h, d / 2])
            assert np.all(np.abs(lo - want_lo) <= 1e-3) and np.all(np.abs(hi - want_hi) <= 1e-3), f"bounds {lo} {hi}"
            ttris = sum(len(g.faces) for g in scene.geometry.values())
            assert ttris == m["triangles"], f"trimesh triangles {ttris}"
        except AssertionError as err:
            fails.append(f"{m['id']}: {err}")
    return fails


# --------------------------------------------------------------------------- main


def write_readme(out: str, cat: dict, base_bytes: int, stats: dict, replace: bool) -> int:
    """Write README.md; returns the folder's total size (GLBs, catalogue.json, README)."""
    import textwrap

    models = cat["models"]
    tris = sum(m["triangles"] for m in models)
    src = sum(m["source_triangles"] for m in models)
    cats: dict[str, int] = {}
    for m in models:
        cats[m["category"]] = cats.get(m["category"], 0) + 1
    cat_line = ", ".join(f"{k} {v}" for k, v in sorted(cats.items()))
    times = {2.0: "twice", 3.0: "three times", 4.0: "four times"}
    levels = " and ".join(
        f"to {share * 100:g} % beyond {f * 100:g} % of the diagonal once the target is {times.get(mult, f'{mult:g} times')} "
        "the primitive's share of the budget"
        for mult, f, share in ACCEPT_LEVELS[1:]
    )

    def text(total: int) -> str:
        paragraphs = [
            f"{len(models)} pieces of indoor furniture and household objects ({cat_line}): one glTF 2.0 "
            "binary `<id>.glb` each, and `catalogue.json` (name, category, tags, creator, size, "
            "elevation, drop-on-top height, light, triangle counts, file size; sorted by id).",
            "Source: the library `BlendSwap-CC-0.sh3f` (version 1.8) of the Debian package "
            "`sweethome3d-furniture` 1.8-1, Sweet Home 3D's additional furniture: Blend Swap models "
            f"cleaned and converted to OBJ by Emmanuel Puybaret / eTeks (sha256 {cat['source_sha256']}). "
            "Licence: CC0 1.0 (public domain); see `assets/NOTICE`. The models' creators are in "
            "`catalogue.json`. Left out: the categories Exterior, Vehicles, Characters and Staircases, "
            "and the shipping container.",
            "Each GLB: y up, metres; the OBJ, turned by the catalogue's `modelRotation` where it has "
            "one, is scaled (non-uniformly, as Sweet Home 3D does) to exactly the catalogue's width (x) "
            "x height (y) x depth (z), its bounding box centred on x and z with its lowest point at "
            "y = 0, its front facing +Z (Sweet Home 3D's convention). One scene, one node (named `<id>`, "
            "no transform), one mesh, one primitive per material (POSITION, NORMAL, TEXCOORD_0 where "
            "textured, 32-bit indices). Materials: base colour Kd (alpha d: BLEND below 1; MASK for "
            "cut-out PNGs), metallic 0, roughness clamp(1 - Ns / 1000, 0.2, 1), double sided, the "
            f"MTL's texture embedded (at most {MAX_TEXTURE_PX} px; JPEG at quality {JPEG_QUALITY}, or "
            f"PNG). Normals are recomputed (smooth up to {CREASE_ANGLE_DEG:g} degrees). Textures the "
            "MTLs name but the library lacks leave their materials untextured.",
            "`elevation_m`: the height above the floor Sweet Home 3D puts the piece at. "
            "`drop_on_top_m`: where things put on the piece rest, above its lowest point (the "
            "catalogue's `dropOnTopElevation`, in cm there; absent there: the top; negative there: "
            "null, nothing is put on it).",
            f"Triangle budget per model: clamp(round({BUDGET_K} * sqrt(footprint_m2 / 0.25)), "
            f"{BUDGET_MIN}, {BUDGET_MAX}) (a 50 x 50 cm chair {triangle_budget(50, 50)}, a 1.4 x 2 m bed "
            f"{triangle_budget(140, 200)}, a cup {triangle_budget(8, 8)}), shared among its materials by "
            f"their triangle counts, never a primitive below {MIN_PRIMITIVE_TRIANGLES} triangles. "
            "Models above it are decimated with fast_simplification (quadric edge collapse), every "
            "result checked against the source: at most 2 % of either surface (by area) may lie "
            "farther than max(2 mm, 1 % of the box diagonal) from the other, else the target rises by "
            f"half again; the check loosens {levels}; a primitive that passes none stays whole. "
            "Textured primitives keep their UV seams; where that stops one at over twice its target "
            f"and over {SEAM_FREE_EXCESS} triangles above it, its shape is decimated freely and its UVs "
            "taken from the nearest source "
            f"surface of the same UV chart ({stats['reprojected']} primitives). Result: {tris} "
            f"triangles (source {src}); {stats['over']} of the {len(models)} models end above their "
            "budget.",
            f"Size: {total} bytes ({total / 1e6:.2f} MB) for this folder.",
        ]
        body = "\n\n".join(textwrap.fill(p, width=88, break_on_hyphens=False) for p in paragraphs)
        return (
            "# Furniture catalogue (Sweet Home 3D, Blend Swap CC0)\n\n"
            + body
            + "\n\nRemake (byte-identical; Python packages in `tools/furniture_catalogue_requirements.txt`):\n\n"
            "    python3 tools/furniture_catalogue.py sweethome3d-furniture_1.8-1_all.deb --out assets/furniture --replace\n\n"
            "(or the extracted `BlendSwap-CC-0.sh3f` as the argument). Check only:\n\n"
            "    python3 tools/furniture_catalogue.py --check assets/furniture\n"
        )

    total = base_bytes
    for _ in range(10):  # the size printed is part of the file: iterate to a fixed point
        body = text(total).encode("utf-8")
        if base_bytes + len(body) == total:
            break
        total = base_bytes + len(body)
    outputs.write_bytes(os.path.join(out, "README.md"), body, replace)
    return total


def write_opt_in_readme(out: str, cat: dict, base_bytes: int, replace: bool) -> int:
    """README.md of an opt-in (CC-BY) library's catalogue; returns the folder's size."""
    import textwrap

    paragraphs = [
        f"{len(cat['models'])} models of Sweet Home 3D's `{cat['library']}` library (Debian "
        f"`sweethome3d-furniture` 1.8-1, sha256 {cat['source_sha256']}), converted as the shipped "
        "catalogue is (assets/furniture/README.md), each with the parts it plays in a dwelling "
        "(`roles`, proposed from its name, category and size by tools/furniture_catalogue.py; "
        "edit them to taste).",
        f"Licence: {cat['licence']} ({cat['licence_url']}), copyright {cat['copyright']}; each "
        "model's creator is in catalogue.json. Use it with `egogen scene generate "
        "--with-catalogue THIS_FOLDER` (or a campaign's `dwelling_catalogues`): every dwelling "
        "that places one of its models gets an ATTRIBUTION.md naming the models, their "
        "creators, the licence and the changes made, and so does every take or campaign made "
        "in one. Keep it with whatever you publish.",
    ]
    body = (
        f"# Furniture catalogue (Sweet Home 3D, {cat['library']}, opt-in)\n\n"
        + "\n\n".join(textwrap.fill(p, width=88, break_on_hyphens=False) for p in paragraphs)
        + "\n"
    ).encode("utf-8")
    outputs.write_bytes(os.path.join(out, "README.md"), body, replace)
    return base_bytes + len(body)


def main() -> int:
    ap = arguments.StrictParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("source", nargs="?", help="sweethome3d-furniture_*.deb or a library's .sh3f")
    ap.add_argument("--library", default=LIBRARY, choices=sorted(LIBRARIES),
                    help="which of the package's libraries (default: the CC0 one egogen ships); "
                    "the others are CC-BY: an opt-in catalogue for `egogen scene generate --with-catalogue`")
    ap.add_argument("--all-models", action="store_true",
                    help="an opt-in library: convert every model, not only those with a role")
    ap.add_argument("--out", default="assets/furniture", help="output folder")
    ap.add_argument("--check", metavar="DIR", help="only check an existing output folder")
    ap.add_argument("--only", nargs="*", help="convert only these ids (for testing; writes no catalogue)")
    ap.add_argument("--replace", action="store_true",
                    help="write into an existing --out (the shipped catalogue, made again on purpose)")
    args = ap.parse_args()

    if args.check:
        fails = check_folder(args.check)
        for f in fails:
            print("FAIL", f)
        print(f"check: {len(fails)} failure(s)")
        return 1 if fails else 0
    if not args.source:
        ap.error("source is required")
    outputs.check_new(args.out, "--out", args.replace, folder=True, parents=True)

    shipped = args.library == LIBRARY
    sh3f = load_sh3f(args.source, args.library)
    sha = hashlib.sha256(sh3f).hexdigest()
    zf = zipfile.ZipFile(io.BytesIO(sh3f))
    props = parse_properties(zf.read("PluginFurnitureCatalog.properties").decode("latin-1"))
    entries = catalogue_entries(props)
    roles: dict[str, list[str]] = {}
    if not shipped:
        # An opt-in library's ids carry its name (they join the shipped catalogue's), and it
        # holds the models that play a part in a dwelling unless --all-models.
        prefix = snake_id(args.library) + "_"
        for e in entries:
            e.id = prefix + e.id
            roles[e.id] = proposed_roles(e.name, e.category, e.width, e.depth, e.height, e.elevation, e.light)
        if not args.all_models:
            entries = [e for e in entries if roles[e.id]]
    if args.only:
        entries = [e for e in entries if e.id in args.only]
    entries.sort(key=lambda e: e.id)
    os.makedirs(args.out, exist_ok=True)
    print(f"{len(entries)} models from {args.library} (sha256 {sha})")

    models = []
    fronts = []
    stats = {"over": 0, "reprojected": 0}
    for e in entries:
        r = convert_model(zf, e)
        fname = f"{e.id}.glb"
        outputs.write_bytes(os.path.join(args.out, fname), r.glb, args.replace)
        models.append(
            {
                "id": e.id,
                "name": e.name,
                "category": e.category,
                "tags": e.tags,
                "creator": e.creator,
                "size_m": [round(e.width / 100, 4), round(e.depth / 100, 4), round(e.height / 100, 4)],
                "elevation_m": round(e.elevation / 100, 4),
                "drop_on_top_m": None if e.drop_on_top is None else round(e.drop_on_top / 100, 4),
                "light": e.light,
                "file": fname,
                "triangles": r.triangles,
                "source_triangles": r.source_triangles,
                "bytes": len(r.glb),
            }
        )
        if not shipped:
            models[-1]["roles"] = roles[e.id]
        stats["over"] += r.triangles > r.budget
        stats["reprojected"] += r.reprojected
        if "Seat" in e.tags or "chair" in e.name.lower() or "Chair" in e.tags:
            fronts.append((e.id, r.front))
        note = ("  [" + "; ".join(r.notes) + "]") if r.notes else ""
        print(f"{e.id:28s} {r.source_triangles:8d} -> {r.triangles:6d} tris {len(r.glb):9d} B{note}")

    if args.only:
        return 0
    # Remove GLBs this run did not write (stale ids).
    keep = {m["file"] for m in models}
    for n in sorted(os.listdir(args.out)):
        if n.endswith(".glb") and n not in keep:
            os.remove(os.path.join(args.out, n))
    licence, deed, copyright_line = LIBRARIES[args.library]
    cat = {
        "library": args.library,
        "licence": licence,
        "source": SOURCE.format(library=args.library),
        "source_sha256": sha,
        "tool": TOOL,
        "models": models,
    }
    if not shipped:
        cat["licence_url"] = deed
        cat["copyright"] = copyright_line
    outputs.write_text(os.path.join(args.out, "catalogue.json"),
                       json.dumps(cat, sort_keys=True, indent=1, ensure_ascii=False) + "\n", args.replace)
    base = sum(m["bytes"] for m in models) + os.path.getsize(os.path.join(args.out, "catalogue.json"))
    if shipped:
        total = write_readme(args.out, cat, base, stats, args.replace)
    else:
        total = write_opt_in_readme(args.out, cat, base, args.replace)

    print("\nfront check (vertices above 60 % of the height; front = +z, so the back rest at z < 0):")
    for mid, fr in fronts:
        if fr is None:
            continue
        print(f"  {mid:28s} mean z / depth {fr[0]:+.3f}, share at z < 0 {fr[1]:.2f}")
    tris = sum(m["triangles"] for m in models)
    src = sum(m["source_triangles"] for m in models)
    print(
        f"\n{len(models)} models, {tris} triangles (source {src}), {stats['over']} above their budget, "
        f"{stats['reprojected']} textured primitives with re-projected UVs; folder {total} bytes"
    )
    fails = check_folder(args.out)
    for f in fails:
        print("FAIL", f)
    print(f"check: {len(fails)} failure(s)")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
