"""Colour quality against time from `cargo bench --bench render_quality`'s JSON: PSNR and SSIM
of each setting against the high-sample reference, over the colour render's seconds per frame,
one panel pair per camera; plain path tracing and OpenImageDenoise (with its accurate and its
fast prefilter) as lines labelled with their sample counts, adaptive sampling as separate
points, the shipped setting circled.

    python tools/plot_render_quality.py target/render_quality_0.25.json --out docs/render_quality.png [--replace]

Needs numpy and matplotlib (pip install matplotlib).
"""
import json

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import arguments  # noqa: E402
import outputs  # noqa: E402


def main():
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("json", help="render_quality_<scale>.json written by the bench")
    ap.add_argument("--out", required=True, help="PNG to write")
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --out")
    ap.add_argument("--shipped", default="4,fast",
                    help="samples[,accurate|fast] to circle (no prefilter: plain path tracing)")
    args = ap.parse_args()
    outputs.check_new(args.out, "--out", args.replace)
    outputs.check_outside(args.out, "--out", args.json, "the bench's JSON")
    rows = json.load(open(args.json))
    for r in rows:  # JSON of earlier runs: no prefilter recorded, Cycles' default (accurate)
        r.setdefault("denoise_prefilter", "accurate" if r["denoise"] else None)
    shipped_samples, *rest = args.shipped.split(",")
    shipped = (int(shipped_samples), rest[0] if rest else None)
    cameras = sorted({r["camera"] for r in rows}, key=lambda c: [r["camera"] for r in rows].index(c))
    fig, axes = plt.subplots(2, len(cameras), figsize=(5.5 * len(cameras), 7.5), squeeze=False)
    for col, camera in enumerate(cameras):
        mine = [r for r in rows if r["camera"] == camera]
        size = f'{mine[0]["width"]}×{mine[0]["height"]}'
        for row, (key, label) in enumerate([("psnr_db", "PSNR (dB)"), ("ssim", "SSIM")]):
            ax = axes[row][col]
            for prefilter, colour, name in [(None, "tab:blue", "path tracing"),
                                            ("accurate", "tab:orange", "+ OIDN, accurate prefilter"),
                                            ("fast", "tab:red", "+ OIDN, fast prefilter")]:
                line = sorted(
                    (r for r in mine
                     if r["denoise_prefilter"] == prefilter and r["adaptive_threshold"] == 0),
                    key=lambda r: r["samples"],
                )
                xs = [r["colour_seconds_per_frame"] for r in line]
                ys = [r[key] for r in line]
                ax.plot(xs, ys, "o-", color=colour, label=name)
                for r in line:
                    ax.annotate(str(r["samples"]), (r["colour_seconds_per_frame"], r[key]),
                                textcoords="offset points", xytext=(4, -10), fontsize=8, color=colour)
            adaptive = [r for r in mine if r["adaptive_threshold"] > 0]
            for r in adaptive:
                ax.plot(r["colour_seconds_per_frame"], r[key], "s", color="tab:green")
                ax.annotate(f'{r["samples"]}, adaptive {r["adaptive_threshold"]}'
                            + (" + OIDN" if r["denoise"] else ""),
                            (r["colour_seconds_per_frame"], r[key]), textcoords="offset points",
                            xytext=(4, 4), fontsize=7, color="tab:green")
            for r in mine:
                if (r["samples"], r["denoise_prefilter"]) == shipped and r["adaptive_threshold"] == 0:
                    ax.plot(r["colour_seconds_per_frame"], r[key], "o", ms=14, mfc="none",
                            mec="black", label="shipped")
            ax.set_xscale("log")
            ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            ax.set_xlabel("colour render call, seconds (one frame, 2 cores)")
            ax.set_ylabel(label)
            ax.set_title(f"{camera} {size}")
            ax.grid(True, alpha=0.3)
            if row == 0:
                ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    with outputs.writing(args.out, args.replace) as tmp:
        fig.savefig(tmp, dpi=110, format=outputs.format_of(args.out))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
