#!/usr/bin/env python3
"""The stride adaptation of the reference (docs/gco.md "Stride adaptation"), as sole traces.

Reads two `pmg_gco_eval --out-dir` folders written for the same command and --trace, one without and
one with `stride_adaptation` (controller key, or --stride-adaptation), and plots the reference's soles
with GCO (u') in the world frame: the path seen from above (stance samples bold), the sole height,
and the stance-foot speed, side by side.
Usage: python3 scripts/plot_stride_adaptation.py DIR_WITHOUT DIR_WITH --out docs/img/stride_adaptation.png
       [--title "command ..."]
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gco_plot import read_trace, shade_stance  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("without", help="pmg_gco_eval --out-dir folder without the stride adaptation")
    ap.add_argument("with_", metavar="with", help="the same with it")
    ap.add_argument("--out", required=True, help="PNG to write")
    ap.add_argument("--title", default="", help="first line of the figure title (the command)")
    a = ap.parse_args()
    traces = []
    for d in (a.without, a.with_):
        path = os.path.join(d, "gco_trace.csv")
        if not os.path.exists(path):
            sys.exit(f"{path}: missing (run pmg_gco_eval --out-dir {d} --trace VX VY WZ)")
        traces.append(read_trace(path))
    colors = {"left": "tab:blue", "right": "tab:red"}
    titles = ("reference as generated (GCO on)", "with the stride adaptation (GCO on)")
    fig, axes = plt.subplots(3, 2, figsize=(12, 10))
    for col, data in enumerate(traces):
        for foot in ("left", "right"):
            d = data[("with_gco", foot)]
            t, c = d["t"], d["contact"]
            axes[0][col].plot(d["x"], d["y"], color=colors[foot], lw=0.6, alpha=0.5)
            axes[0][col].plot([x if k else float("nan") for x, k in zip(d["x"], c)],
                              [y if k else float("nan") for y, k in zip(d["y"], c)], color=colors[foot], lw=2.5,
                              label=f"{foot} sole in stance")
            axes[1][col].plot(t, [1e3 * z for z in d["z"]], color=colors[foot])
            axes[2][col].plot(t, [1e3 * s if k else float("nan") for s, k in zip(d["speed"], c)], color=colors[foot])
            for ax in axes[1:, col]:
                shade_stance(ax, t, c, colors[foot])
        axes[0][col].set_title(titles[col])
        axes[0][col].set_xlabel("sole x in world [m]")
        axes[0][col].set_ylabel("sole y in world [m]")
        axes[0][col].set_aspect("equal", adjustable="datalim")
        axes[0][col].legend(loc="best", fontsize=8)
        axes[1][col].set_ylabel("sole height [mm]")
        axes[1][col].axhline(0.0, color="k", lw=0.5)
        axes[2][col].set_ylabel("stance-foot speed [mm/s]")
        axes[2][col].set_xlabel("time [s]")
        for ax in axes[:, col]:
            ax.grid(alpha=0.3)
    for row in (1, 2):
        lo = min(axes[row][0].get_ylim()[0], axes[row][1].get_ylim()[0])
        hi = max(axes[row][0].get_ylim()[1], axes[row][1].get_ylim()[1])
        for col in range(2):
            axes[row][col].set_ylim(lo, hi)
    fig.suptitle((a.title + "\n" if a.title else "") +
                 "G1 reference soles, pelvis moved by u' (shaded: stance, c_f = 1). A still stance foot draws a dot "
                 "from above and a flat height.")
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
