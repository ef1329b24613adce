#!/usr/bin/env python3
"""Per-segment comparison of several actors from pmg_policy_sil summaries: the achieved pelvis
height against the commanded one, and achieved/commanded velocity per axis, with issue 12's bands.

Usage: scripts/plot_segment_compare.py OUT.png LABEL=summary.json [LABEL=summary.json ...]
       [--segments a,b,...] [--title TEXT]

Segments: every segment with a velocity command of at least 0.05 on an axis, in the order of the
first summary, unless --segments names them. Values are the summaries' per-segment means (last 60 %
of each segment, over the seeds that did not fall). Bands: height within 0.015 m of the command;
velocity within ±15 % (or 0.05 m/s / 0.08 rad/s, drawn as ±15 %). Prints the table it draws:
segment, then per actor the achieved height [m] and the ratios v_x, v_y, ω ("-" where the axis is
not commanded).
"""
import argparse
import json
import sys

AXES = (("vx", "v_x"), ("vy", "v_y"), ("wz", "ω"))
MIN_COMMAND = 0.05


def read_segments(path):
    """[(name, command, achieved)] from a pmg_policy_sil summary.json."""
    try:
        with open(path) as f:
            doc = json.load(f)
        segs = [(s["name"], s["command"], s["achieved"]) for s in doc["segments"]]
    except (OSError, ValueError, KeyError, TypeError) as e:
        sys.exit(f"{path}: not a pmg_policy_sil summary with 'segments' ({e})")
    if not segs:
        sys.exit(f"{path}: no segments")
    return segs


def ratio(command, achieved, axis):
    c = command[axis]
    return achieved[axis] / c if abs(c) >= MIN_COMMAND else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("summaries", nargs="+", help="LABEL=summary.json")
    ap.add_argument("--segments", default=None, help="comma-separated segment names (default: the walking ones)")
    ap.add_argument("--title", default="Per segment: achieved height and velocity against the command")
    args = ap.parse_args()

    series = []
    for spec in args.summaries:
        if "=" not in spec:
            sys.exit(f"{spec}: expected LABEL=summary.json")
        label, path = spec.split("=", 1)
        segments = read_segments(path)
        series.append((label, {n: (c, a) for n, c, a in segments}, [n for n, _, _ in segments]))
    first = series[0]
    if args.segments:
        segs = [s for s in args.segments.split(",") if s]
    else:
        segs = [n for n in first[2] if any(abs(first[1][n][0][a]) >= MIN_COMMAND for a, _ in AXES)]
    missing = [(label, s) for label, t, _ in series for s in segs if s not in t]
    if missing:
        sys.exit(f"segment '{missing[0][1]}' is not in the summary of '{missing[0][0]}'")
    if not segs:
        sys.exit("no walking segment in the first summary")

    # The table.
    print("segment".ljust(14) + "".join(f"{label:>30}" for label, _, _ in series))
    print(" " * 14 + "".join(f"{'height   v_x   v_y     ω':>30}" for _ in series))
    for s in segs:
        row = s.ljust(14)
        for _, t, _ in series:
            c, a = t[s]
            cells = [f"{a['height']:.3f}"] + [("-" if ratio(c, a, ax) is None else f"{ratio(c, a, ax):.2f}") for ax, _ in AXES]
            row += f"{'  '.join(f'{x:>5}' for x in cells):>30}"
        print(row)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_h, ax_v) = plt.subplots(2, 1, figsize=(11, 7.5), sharex=True)
    n = len(series)
    w = 0.8 / n
    for i, (label, t, _) in enumerate(series):
        xs = [j + (i - (n - 1) / 2) * w for j in range(len(segs))]
        ax_h.bar(xs, [t[s][1]["height"] - t[s][0]["height"] for s in segs], width=w, label=label)
        # Velocity: one marker per commanded axis.
        for k, (axis, name) in enumerate(AXES):
            vals = [ratio(t[s][0], t[s][1], axis) for s in segs]
            ax_v.scatter([x for x, v in zip(xs, vals) if v is not None], [v for v in vals if v is not None],
                         marker="os^"[k], color=f"C{i}", s=28, label=f"{label} {name}")
    ax_h.axhspan(-0.015, 0.015, color="0.88", zorder=0, label="±0.015 m")
    ax_h.axhline(0, color="k", lw=0.6)
    ax_h.set_ylabel("achieved − commanded height [m]")
    ax_h.legend(fontsize=8, ncol=n + 1, loc="upper right")
    ax_v.axhspan(0.85, 1.15, color="0.88", zorder=0)
    ax_v.axhline(1.0, color="k", lw=0.6)
    ax_v.set_ylabel("achieved / commanded (○ v_x, □ v_y, △ ω)")
    ax_v.set_xticks(range(len(segs)))
    ax_v.set_xticklabels(segs, rotation=30, ha="right")
    ax_v.legend(fontsize=7, ncol=n, loc="upper center", bbox_to_anchor=(0.5, -0.35))
    ax_h.set_title(args.title)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110, bbox_inches="tight")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
