#!/usr/bin/env python3
"""Bar chart of the pelvis pitch per walking segment for several actors, from the tables that
scripts/pelvis_pitch.py prints (segment, torso, pelvis, waist pitch [rad]).

Usage: scripts/plot_pelvis_pitch.py OUT.png LABEL=TABLE.txt [LABEL=TABLE.txt ...]
       [--segments a,b,...]

Segments: the walking segments of config/policies/eval_envelope.yaml by default. Pelvis pitch:
forward (nose down) positive, the seed mean over each segment's last 60 %. A dashed band marks
±0.05 rad.
"""
import argparse
import sys

WALKING = ("fwd_0.50,fwd_1.00,back_0.50,left_0.4,right_0.4,turn_l_0.8,arc_l,arc_r_fast,back_arc,"
           "diag_turn,crouch_walk,crouch_turn")


def read_table(path):
    """{segment: (torso, pelvis, waist)} from a pelvis_pitch.py table."""
    rows = {}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) != 4:
                continue
            try:
                rows[parts[0]] = tuple(float(x) for x in parts[1:])
            except ValueError:
                continue  # the header
    if not rows:
        sys.exit(f"{path}: no rows 'segment torso pelvis waist' (scripts/pelvis_pitch.py output)")
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("tables", nargs="+", help="LABEL=TABLE.txt")
    ap.add_argument("--segments", default=WALKING)
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    series = []
    for spec in args.tables:
        if "=" not in spec:
            sys.exit(f"{spec}: expected LABEL=TABLE.txt")
        label, path = spec.split("=", 1)
        series.append((label, read_table(path)))
    segs = [s for s in args.segments.split(",") if s and any(s in t for _, t in series)]
    if not segs:
        sys.exit("none of the segments is in the tables")
    fig, ax = plt.subplots(figsize=(11, 4.2))
    w = 0.8 / len(series)
    for i, (label, t) in enumerate(series):
        xs = [j + (i - (len(series) - 1) / 2) * w for j in range(len(segs))]
        ax.bar(xs, [t[s][1] if s in t else float("nan") for s in segs], width=w, label=label)
    ax.axhspan(-0.05, 0.05, color="0.85", zorder=0, label="±0.05 rad")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xticks(range(len(segs)))
    ax.set_xticklabels(segs, rotation=30, ha="right")
    ax.set_ylabel("pelvis pitch [rad] (forward +)")
    ax.set_title("Pelvis pitch while walking (envelope grid; torso upright in every actor)")
    ax.legend(fontsize=8, ncol=len(series) + 1, loc="upper center", bbox_to_anchor=(0.5, -0.3))
    fig.tight_layout()
    fig.savefig(args.out, dpi=110, bbox_inches="tight")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
