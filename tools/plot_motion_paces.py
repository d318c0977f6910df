"""Histograms of primitive pace (horizontal pelvis speed) and turn (heading change per 0.5 s
primitive), side by side for several sets, from the JSON files that
`egogen motion stats --json` and `egogen motion eval --pace-json` write.

    python tools/plot_motion_paces.py --out docs/motion_paces.png [--replace] \
        "old training set=old_stats.json:train" "new training set=new_stats.json:train" \
        "random-latent chains=eval_paces.json:random_chains"

Each argument is `LABEL=FILE:KEY`, KEY a set in that file (`train`, `held_out`,
`train_primitives`, `random_chains`). Needs numpy and matplotlib (pip install matplotlib).
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import arguments  # noqa: E402
import outputs  # noqa: E402


def load(spec):
    if "=" not in spec or ":" not in spec.split("=", 1)[1]:
        sys.exit(f"error: {spec!r}: expected LABEL=FILE:KEY")
    label, rest = spec.split("=", 1)
    path, key = rest.rsplit(":", 1)
    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"error: {path}: {e}")
    if key not in doc or "speed_m_s" not in doc[key]:
        sys.exit(f"error: {path}: no set {key!r} with speed_m_s (keys: {sorted(doc)})")
    return label, np.asarray(doc[key]["speed_m_s"]), np.abs(np.asarray(doc[key]["turn_deg"]))


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sets", nargs="+", help="LABEL=FILE:KEY")
    ap.add_argument("--out", required=True, help="output PNG (must not exist)")
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace)
    sets = [load(s) for s in args.sets]
    fig, (ax_v, ax_t) = plt.subplots(1, 2, figsize=(12, 4.2))
    v_bins = np.arange(0.0, 2.51, 0.1)
    t_bins = np.arange(0.0, 90.1, 2.5)
    for label, v, t in sets:
        ax_v.hist(np.clip(v, 0, 2.5), bins=v_bins, density=True, histtype="step", linewidth=1.8,
                  label=f"{label} (n={len(v)}, median {np.median(v):.2f} m/s)")
        ax_t.hist(np.clip(t, 0, 90), bins=t_bins, density=True, histtype="step", linewidth=1.8,
                  label=f"{label} (median {np.median(t):.1f}°)")
    ax_v.axvspan(1.2, 1.4, color="0.85", zorder=0, label="human walking pace 1.2–1.4 m/s")
    ax_v.set_xlabel("pelvis speed over a primitive (m/s; last bin ≥ 2.4)")
    ax_v.set_ylabel("density")
    ax_v.legend(fontsize=8, loc="upper left")
    ax_t.set_xlabel("|heading change| over a primitive (degrees per 0.45 s; last bin ≥ 90)")
    ax_t.set_ylabel("density")
    ax_t.set_yscale("log")
    ax_t.legend(fontsize=8)
    fig.tight_layout()
    with outputs.writing(args.out, args.replace) as tmp:
        fig.savefig(tmp, dpi=110, format=outputs.format_of(args.out))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
