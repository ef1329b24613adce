#!/usr/bin/env python3
"""Frame strip of a SIL run: stick figures (body origins joined to their parents) drawn from the
body positions apps/policy/pmg_policy_sil logs (<out>/frames<k>.csv), side view (x-z, walking
direction) and front view (y-z), one panel per time.

  python3 training/plot_frames.py OUT/frames0.csv --times 3.5 4.0 4.5 5.0 --out strip.png
"""
import argparse
import csv

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--times", type=float, nargs="+", required=True)
    ap.add_argument("--labels", nargs="*", default=None)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with open(a.csv) as f:
        rows = list(csv.reader(f))
    header = rows[0][1:]
    names = [h.split(":")[0] for h in header]
    parent = [int(h.split(":")[1]) for h in header]  # MuJoCo body ids; column i is body i + 1
    t = np.array([float(r[0]) for r in rows[1:]])
    pos = np.array([[list(map(float, c.split())) for c in r[1:]] for r in rows[1:]])  # (T, nbody-1, 3)
    fig, axes = plt.subplots(2, len(a.times), figsize=(1.9 * len(a.times), 5.2))
    for col, tq in enumerate(a.times):
        k = int(np.argmin(np.abs(t - tq)))
        p = pos[k]
        base = p[0]
        for view, (i, j) in enumerate([(0, 2), (1, 2)]):
            ax = axes[view, col]
            for b in range(len(names)):
                pb = parent[b] - 1
                if pb >= 0:
                    ax.plot([p[b, i] - base[i], p[pb, i] - base[i]], [p[b, j], p[pb, j]], "-", color="tab:blue", lw=1.5)
            ax.plot(p[:, i] - base[i], p[:, j], "o", ms=2, color="k")
            ax.axhline(0, color="0.5", lw=1)
            ax.set_xlim(-0.6, 0.6)
            ax.set_ylim(-0.05, 1.4)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            if view == 0:
                lab = a.labels[col] if a.labels and col < len(a.labels) else ""
                ax.set_title(f"t = {t[k]:.2f} s\n{lab}", fontsize=8)
        axes[0, 0].set_ylabel("side view (x-z)", fontsize=8)
        axes[1, 0].set_ylabel("front view (y-z)", fontsize=8)
    fig.suptitle("G1 in the MuJoCo 2.2 SIL driven by the trained policy (pmg_policy_sil)", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
