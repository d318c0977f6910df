"""Convert a SAMP motion capture `.pkl` into the SAMP-style `.npz` egogen reads.

SAMP (licence-gated; not shipped) stores a pickle with `pose_est_fullposes` (N, 165),
`pose_est_trans` (N, 3), `shape_est_betas` and `mocap_framerate`. egogen reads `.npz` only
(no pickle parsing in Rust), so this copies those arrays, unchanged, into an `.npz`.

    python tools/samp_pkl_to_npz.py IN.pkl OUT.npz [--replace]
"""
import pickle
import sys

import numpy as np

import arguments
import outputs

KEYS = ["pose_est_fullposes", "pose_est_trans", "shape_est_betas", "mocap_framerate"]


def main(argv):
    args, replace = arguments.switch(argv[1:], "--replace")
    if len(args) != 2:
        sys.exit(__doc__)
    src, dst = args
    outputs.check_new(dst, "OUT.npz", replace)
    outputs.check_outside(dst, "OUT.npz", src, "IN.pkl")
    with open(src, "rb") as f:
        data = pickle.load(f, encoding="latin1")
    missing = [k for k in KEYS if k not in data]
    if missing:
        sys.exit(f"{src}: missing SAMP keys {missing} (found {sorted(data)})")
    poses = np.asarray(data["pose_est_fullposes"], dtype=np.float64)
    if poses.ndim != 2 or poses.shape[1] != 165:
        sys.exit(f"{src}: `pose_est_fullposes` has shape {poses.shape}, expected (N, 165)")
    with outputs.writing(dst, replace) as tmp, open(tmp, "wb") as f:
        np.savez(f, pose_est_fullposes=poses,
                 pose_est_trans=np.asarray(data["pose_est_trans"], dtype=np.float64),
                 shape_est_betas=np.asarray(data["shape_est_betas"], dtype=np.float64),
                 mocap_framerate=np.float64(data["mocap_framerate"]))
    print(f"wrote {dst}: {poses.shape[0]} frames")


if __name__ == "__main__":
    main(sys.argv)
