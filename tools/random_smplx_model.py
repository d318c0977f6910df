"""Deterministic random-valued body model with the official SMPL-X shapes.

10 475 vertices, 400 shape/expression directions, 486 pose correctives, 55 joints. Every value
comes from a counter-based hash (SplitMix64), so Rust (tests/common/random_model.rs) rebuilds the
same file bit for bit without any fixture. Used to check skinning against `smplx` on a model with
official sizes, which cannot be shipped.
"""
import numpy as np

V = 10475
F = 20908
NUM_DIRS = 400
POSE_FEATURES = 486
PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 15, 15, 15,
           20, 25, 26, 20, 28, 29, 20, 31, 32, 20, 34, 35, 20, 37, 38,
           21, 40, 41, 21, 43, 44, 21, 46, 47, 21, 49, 50, 21, 52, 53]

M64 = np.uint64(0xFFFFFFFFFFFFFFFF)


def splitmix64(x):
    x = np.asarray(x, dtype=np.uint64)
    with np.errstate(over="ignore"):
        z = x + np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def uniform(stream, index):
    """U(stream, i) in [0, 1): top 53 bits of splitmix64((stream << 40) + i), exact in f64."""
    key = (np.uint64(stream) << np.uint64(40)) + np.asarray(index, dtype=np.uint64)
    return (splitmix64(key) >> np.uint64(11)).astype(np.float64) * (2.0 ** -53)


def build():
    v3 = np.arange(V * 3, dtype=np.uint64)
    v_template = (uniform(1, v3) - 0.5).reshape(V, 3)
    shapedirs = 0.02 * (uniform(2, np.arange(V * 3 * NUM_DIRS, dtype=np.uint64)) - 0.5)
    shapedirs = shapedirs.reshape(V, 3, NUM_DIRS)
    posedirs = 0.01 * (uniform(3, np.arange(V * 3 * POSE_FEATURES, dtype=np.uint64)) - 0.5)
    posedirs = posedirs.reshape(V, 3, POSE_FEATURES)
    j_regressor = np.zeros((55, V))
    for j in range(55):
        for m in range(8):
            v = int(np.floor(uniform(4, 8 * j + m) * V))
            j_regressor[j, v] += 0.125
    weights = np.zeros((V, 55))
    idx = np.arange(V * 4, dtype=np.uint64)
    joints = np.floor(uniform(5, idx) * 55).astype(np.int64).reshape(V, 4)
    raw = (0.1 + uniform(6, idx)).reshape(V, 4)
    total = ((raw[:, 0] + raw[:, 1]) + raw[:, 2]) + raw[:, 3]
    for m in range(4):
        np.add.at(weights, (np.arange(V), joints[:, m]), raw[:, m] / total)
    i = np.arange(F)
    f = np.stack([i % V, (i + 1) % V, (i + 2) % V], axis=1).astype(np.uint32)
    kintree = np.stack([np.array(PARENTS, dtype=np.int64), np.arange(55, dtype=np.int64)])
    return dict(
        v_template=v_template, f=f, shapedirs=shapedirs, posedirs=posedirs,
        J_regressor=j_regressor, weights=weights, kintree_table=kintree,
        hands_componentsl=np.eye(45), hands_componentsr=np.eye(45),
        hands_meanl=np.zeros(45), hands_meanr=np.zeros(45),
        lmk_faces_idx=np.zeros(51, dtype=np.int64), lmk_bary_coords=np.full((51, 3), 1 / 3),
        dynamic_lmk_faces_idx=np.zeros((79, 17), dtype=np.int64),
        dynamic_lmk_bary_coords=np.full((79, 17, 3), 1 / 3),
    )
