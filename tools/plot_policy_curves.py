"""Training curves of the locomotion policy from the JSON-lines log `egogen train policy`
writes: mean episode return, success share, episode length (primitives) and KL(π ‖ N(0, I)),
per update (thin) and for the validation episodes (dots), against environment steps, with
the stage boundary marked.

    python tools/plot_policy_curves.py assets/policy/train_log.jsonl --out docs/policy_curves.png [--replace]

Needs numpy and matplotlib (pip install matplotlib).
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import arguments  # noqa: E402
import outputs  # noqa: E402

PANELS = [
    ("episode_return", "episode_return", "episode return"),
    ("success_rate", "success_rate", "success (pelvis within 0.1 m)"),
    ("episode_length", None, "episode length (primitives)"),
    ("kl_prior", "kl_prior", "KL(π ‖ N(0, I))"),
]


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("log")
    ap.add_argument("--out", required=True)
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace)
    outputs.check_outside(args.out, "--out", args.log, "the log")
    rows = []
    try:
        with open(args.log) as f:
            for n, line in enumerate(f, 1):
                try:
                    rows.append(json.loads(line))
                except json.JSONDecodeError as e:
                    sys.exit(f"error: {args.log}:{n}: not JSON: {e}")
    except OSError as e:
        sys.exit(f"error: {args.log}: {e}")
    if not rows:
        sys.exit(f"error: {args.log}: no updates")
    steps = np.array([r["env_steps"] for r in rows], dtype=float)
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.5), sharex=True)
    stages = [r["stage"] for r in rows]
    boundaries = [steps[i] for i in range(1, len(rows)) if stages[i] != stages[i - 1]]
    for ax, (key, vkey, title) in zip(axes.flat, PANELS):
        y = np.array([r[key] for r in rows], dtype=float)
        ok = np.array([r["episodes"] > 0 for r in rows])
        ax.plot(steps[ok] / 1e6, y[ok], lw=0.6, color="tab:blue", alpha=0.7, label="training episodes")
        if vkey:
            v = [(r["env_steps"], r["validation"][vkey]) for r in rows if "validation" in r]
            if v:
                vx, vy = zip(*v)
                ax.plot(np.array(vx) / 1e6, vy, "o-", ms=3, color="tab:red", label="validation (64 episodes)")
        for b in boundaries:
            ax.axvline(b / 1e6, color="gray", ls="--", lw=1)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    for ax in axes[1]:
        ax.set_xlabel("environment steps (millions); dashed: pretrain → finetune")
    wall = rows[-1]["wall_s"]
    fig.suptitle(f"{len(rows)} updates, {int(steps[-1]):,} steps, {wall / 60:.0f} min", fontsize=10)
    fig.tight_layout()
    with outputs.writing(args.out, args.replace) as tmp:
        fig.savefig(tmp, dpi=110, format=outputs.format_of(args.out))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
