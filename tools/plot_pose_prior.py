"""Histograms of pose-prior scores (mean negative log-density per joint value over a
primitive's frames) for held-out mocap, primitives decoded from random latents and held-out
mocap with one joint bent by 90°, with the prior's plausibility limit, from the files that
`egogen policy pose-prior --out PRIOR --scores-json SCORES` writes.

    python tools/plot_pose_prior.py --prior assets/policy/pose_prior.json \
        --scores scores.json --out docs/pose_prior_scores.png [--replace]

Scores above 6 are drawn in the last bin. Needs numpy and matplotlib (pip install matplotlib).
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import arguments  # noqa: E402
import outputs  # noqa: E402

GROUPS = [
    ("held_out_mocap", "held-out mocap"),
    ("random_latent", "random latents (training seeds)"),
    ("bent_joint", "held-out mocap, one joint bent 90°"),
]
CLIP = 6.0


def read_json(path, what):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"error: {path}: cannot read {what}: {e}")


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--prior", required=True)
    ap.add_argument("--scores", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace)
    prior = read_json(args.prior, "a pose prior")
    scores = read_json(args.scores, "pose-prior scores")
    limit = prior.get("plausible_max_nll")
    if limit is None:
        sys.exit(f"error: {args.prior}: no field plausible_max_nll")
    bins = np.linspace(-2.5, CLIP, 60)
    fig, axes = plt.subplots(len(GROUPS), 1, figsize=(7, 6.5), sharex=True)
    for ax, (key, label) in zip(axes, GROUPS):
        if key not in scores:
            sys.exit(f"error: {args.scores}: no field {key}")
        v = np.asarray([x if x is not None else np.inf for x in scores[key]], dtype=float)
        above = np.mean(v > limit)
        ax.hist(np.clip(v, bins[0], CLIP - 1e-9), bins=bins, color="tab:blue")
        ax.axvline(limit, color="tab:red", lw=1.5)
        ax.set_title(f"{label}: {len(v)} primitives, {100 * above:.1f} % above the limit", fontsize=9)
        ax.set_ylabel("primitives")
    axes[-1].set_xlabel(
        f"mean −ln p(θ)/63 over the primitive (red: limit at training quantile "
        f"{prior.get('plausible_quantile', '?')}; ≥ {CLIP:g} in the last bin)"
    )
    fig.tight_layout()
    with outputs.writing(args.out, args.replace) as tmp:
        fig.savefig(tmp, dpi=110, format=outputs.format_of(args.out))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
