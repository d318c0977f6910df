"""A large scan to measure scene loading and rendering on: a binary PLY of 1.04 M triangles,
a 30 x 30 m floor grid with 3 mm of height noise (0.9 M triangles) inside four 2.5 m walls,
vertex colours and Replica-style per-face object ids (floor 1, walls 2-5).

    python tools/make_big_scan.py OUT.ply [--replace]    (numpy)
"""
import sys

import numpy as np

import arguments
import outputs

args, replace = arguments.switch(sys.argv[1:], "--replace")
if len(args) != 1:
    sys.exit("usage: make_big_scan.py OUT.ply [--replace]")
out = outputs.check_new(args[0], "OUT.ply", replace)

n = 670                      # grid vertices per side -> 2*(n-1)^2 triangles
xs = np.linspace(-15, 15, n)
X, Y = np.meshgrid(xs, xs)
rng = np.random.default_rng(0)
Z = rng.normal(0, 0.003, X.shape)
v = np.stack([X.ravel(), Y.ravel(), Z.ravel()], 1)
idx = np.arange(n * n).reshape(n, n)
a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
ids = np.ones(len(tris), np.int32)
# Four walls, each a 300 x 60 grid of quads split into triangles.
walls = []
wid = []
for k, (x0, y0, x1, y1) in enumerate([(-15, -15, 15, -15), (15, -15, 15, 15), (15, 15, -15, 15), (-15, 15, -15, -15)]):
    m, h = 300, 60
    t = np.linspace(0, 1, m); s = np.linspace(0, 2.5, h)
    T, S = np.meshgrid(t, s)
    wv = np.stack([x0 + (x1 - x0) * T.ravel(), y0 + (y1 - y0) * T.ravel(), S.ravel()], 1)
    base = len(v) + sum(len(w) for w in walls)
    wi = np.arange(m * h).reshape(h, m) + base
    a, b, c, d = wi[:-1, :-1].ravel(), wi[:-1, 1:].ravel(), wi[1:, 1:].ravel(), wi[1:, :-1].ravel()
    walls.append(wv)
    tris = np.concatenate([tris, np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    ids = np.concatenate([ids, np.full(2 * len(a), k + 2, np.int32)])
v = np.concatenate([v] + walls)
col = np.tile(np.array([[180, 160, 140]], np.uint8), (len(v), 1))
with outputs.writing(out, replace) as tmp, open(tmp, "wb") as f:
    f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\n"
             f"property uchar red\nproperty uchar green\nproperty uchar blue\nelement face {len(tris)}\n"
             "property list uchar int vertex_indices\nproperty int object_id\nend_header\n").encode())
    vd = np.zeros(len(v), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("r", "u1"), ("g", "u1"), ("b", "u1")])
    vd["x"], vd["y"], vd["z"] = v[:, 0], v[:, 1], v[:, 2]
    vd["r"], vd["g"], vd["b"] = col[:, 0], col[:, 1], col[:, 2]
    f.write(vd.tobytes())
    fd = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", 3), ("o", "<i4")])
    fd["n"] = 3; fd["i"] = tris; fd["o"] = ids
    f.write(fd.tobytes())
print(len(v), "vertices", len(tris), "triangles")
