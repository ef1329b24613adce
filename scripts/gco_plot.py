#!/usr/bin/env python3
"""Plots of the Ground-aware Command Optimization (GCO) evaluation (docs/gco.md).

Reads the CSV files written by `build/bin/pmg_gco_eval --out-dir DIR`:
  DIR/gco_trace.csv  -> docs/gco_fig5.png  (PMG Fig. 5 style: sole trajectories in the world frame
                                            with and without GCO; stance phases shaded)
  DIR/gco_grid.csv   -> docs/gco_grid.png  (mean stance-foot speed and slip per stance over the
                                            command grid, without vs. with GCO)
Usage: python3 scripts/gco_plot.py DIR [--out docs]
"""
import argparse
import csv
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_trace(path):
    data = defaultdict(lambda: defaultdict(list))
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            d = data[(r["variant"], r["foot"])]
            for k in ("t", "x", "y", "z", "speed"):
                d[k].append(float(r[k]))
            d["contact"].append(int(r["contact"]))
    return data


def shade_stance(ax, t, contact, color):
    start = None
    for i, c in enumerate(contact):
        if c and start is None:
            start = t[i]
        if (not c or i == len(contact) - 1) and start is not None:
            ax.axvspan(start, t[i], color=color, alpha=0.08, lw=0)
            start = None


def plot_trace(trace_csv, out_png):
    data = read_trace(trace_csv)
    fig, axes = plt.subplots(3, 2, figsize=(12, 9), sharex="col")
    colors = {"left": "tab:blue", "right": "tab:red"}
    titles = {"without_gco": "PMG template without GCO", "with_gco": "PMG template with GCO (u')"}
    for col, variant in enumerate(("without_gco", "with_gco")):
        for foot in ("left", "right"):
            d = data[(variant, foot)]
            if not d["t"]:
                continue
            t = d["t"]
            axes[0][col].plot(t, d["x"], color=colors[foot], label=f"{foot} sole")
            axes[1][col].plot(t, [1e3 * z for z in d["z"]], color=colors[foot])
            axes[2][col].plot(t, [1e3 * s if c else float("nan") for s, c in zip(d["speed"], d["contact"])],
                              color=colors[foot])
            for ax in axes[:, col]:
                shade_stance(ax, t, d["contact"], colors[foot])
        axes[0][col].set_title(titles[variant])
        axes[0][col].set_ylabel("sole x in world [m]")
        axes[1][col].set_ylabel("sole height [mm]")
        axes[2][col].set_ylabel("stance-foot speed [mm/s]")
        axes[2][col].set_xlabel("time [s]")
        axes[1][col].axhline(0.0, color="k", lw=0.5)
        axes[0][col].legend(loc="upper left")
        for ax in axes[:, col]:
            ax.grid(alpha=0.3)
    # Same y range on both columns so the slip/float is comparable.
    for row in range(3):
        lo = min(axes[row][0].get_ylim()[0], axes[row][1].get_ylim()[0])
        hi = max(axes[row][0].get_ylim()[1], axes[row][1].get_ylim()[1])
        for col in range(2):
            axes[row][col].set_ylim(lo, hi)
    fig.suptitle("G1 sole trajectories over a few gait cycles (shaded: stance, c_f = 1). "
                 "Flat x segments = stationary stance feet.")
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    print("wrote", out_png)


def plot_grid(grid_csv, out_png):
    rows = list(csv.DictReader(open(grid_csv, newline="")))
    rows = [r for r in rows if int(r["stances"]) > 0]
    if not rows:
        return
    labels = [f"{float(r['vx']):+.1f},{float(r['vy']):+.1f},{float(r['wz']):+.1f}" for r in rows]
    # One bar pair per velocity command (posture variants averaged).
    agg = defaultdict(lambda: [0.0, 0.0, 0.0, 0.0, 0])
    for lab, r in zip(labels, rows):
        a = agg[lab]
        a[0] += 1e3 * float(r["speed_without"])
        a[1] += 1e3 * float(r["speed_with"])
        a[2] += 1e3 * float(r["slip_without"])
        a[3] += 1e3 * float(r["slip_with"])
        a[4] += 1
    keys = list(agg.keys())
    vals = [[agg[k][i] / agg[k][4] for k in keys] for i in range(4)]
    fig, axes = plt.subplots(2, 1, figsize=(max(8, 0.5 * len(keys)), 7), sharex=True)
    xs = range(len(keys))
    w = 0.4
    axes[0].bar([x - w / 2 for x in xs], vals[0], w, label="without GCO", color="tab:gray")
    axes[0].bar([x + w / 2 for x in xs], vals[1], w, label="with GCO", color="tab:green")
    axes[0].set_ylabel("mean stance-foot speed [mm/s]")
    axes[0].legend()
    axes[1].bar([x - w / 2 for x in xs], vals[2], w, color="tab:gray")
    axes[1].bar([x + w / 2 for x in xs], vals[3], w, color="tab:green")
    axes[1].set_ylabel("mean slip per stance [mm]")
    axes[1].set_xticks(list(xs))
    axes[1].set_xticklabels(keys, rotation=60, ha="right", fontsize=8)
    axes[1].set_xlabel("command (v_x [m/s], v_y [m/s], yaw rate [rad/s]); posture variants averaged")
    for ax in axes:
        ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    print("wrote", out_png)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir", help="folder with gco_trace.csv / gco_grid.csv (pmg_gco_eval --out-dir)")
    ap.add_argument("--out", default="docs", help="output folder for the PNGs")
    a = ap.parse_args()
    trace = os.path.join(a.dir, "gco_trace.csv")
    grid = os.path.join(a.dir, "gco_grid.csv")
    if os.path.exists(trace):
        plot_trace(trace, os.path.join(a.out, "gco_fig5.png"))
    if os.path.exists(grid):
        plot_grid(grid, os.path.join(a.out, "gco_grid.png"))


if __name__ == "__main__":
    main()
