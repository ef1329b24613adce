#!/usr/bin/env python3
"""Ablation of the generator's blending (issue 12, docs/policy.md "Command fidelity").

Reference side: pmg_gco_eval --envelope --out-dir grids (one per blending), the cycle-mean
stance-implied velocity against the command, per axis. SIL side: pmg_policy_sil summaries
(per-segment achieved / commanded) of several policy + blending + GCO combinations.

  scripts/plot_blending_ablation.py --grid paper=/tmp/abl/gco_grid_paper.csv \
      --grid consistent=/tmp/abl/gco_grid_consistent.csv \
      --sil "paper+GCO (shipped)=/tmp/before/envelope" --sil "consistent+GCO=/tmp/after/envelope" \
      --out docs/img/blending_ablation.png
"""
import argparse
import csv
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

AXES = ("vx", "vy", "wz")
UNITS = {"vx": "m/s", "vy": "m/s", "wz": "rad/s"}
TOL = {"vx": 0.03, "vy": 0.03, "wz": 0.05}


def named(spec):
    name, _, path = spec.partition("=")
    if not path:
        raise SystemExit(f"expected NAME=PATH, got {spec!r}")
    return name, path


def read_grid(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no rows")
    cmd = np.array([[float(r[a]) for a in AXES] for r in rows])
    imp = np.array([[float(r["cycle_implied_" + a]) for a in AXES] for r in rows])
    within = np.array([int(r["within_target"]) for r in rows])
    return cmd, imp, within


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grid", action="append", default=[], help="NAME=gco_grid.csv of pmg_gco_eval --envelope")
    ap.add_argument("--sil", action="append", default=[], help="NAME=pmg_policy_sil output folder (summary.json)")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    grids = [(n, read_grid(p)) for n, p in map(named, args.grid)]
    sils = []
    for n, d in map(named, args.sil):
        with open(os.path.join(d, "summary.json")) as f:
            sils.append((n, json.load(f)))

    fig, axs = plt.subplots(2, 3, figsize=(15, 8.5))
    # Top: reference-implied / commanded per axis (scatter over the envelope grid).
    for k, a in enumerate(AXES):
        ax = axs[0][k]
        for n, (cmd, imp, within) in grids:
            m = np.abs(cmd[:, k]) > 1e-9
            err = np.mean(np.abs(imp[:, k] - cmd[:, k]))
            ok = np.mean(np.abs(imp[:, k] - cmd[:, k]) <= np.maximum(0.1 * np.abs(cmd[:, k]), TOL[a]))
            ax.scatter(cmd[m, k], imp[m, k], s=5, alpha=0.35,
                       label=f"{n}: mean |err| {err:.3f}, {100 * ok:.0f} % within target")
        lim = [min(cmd[:, k].min() for _, (cmd, _, _) in grids), max(cmd[:, k].max() for _, (cmd, _, _) in grids)]
        x = np.linspace(lim[0], lim[1], 10)
        ax.plot(x, x, "k-", lw=1)
        ax.fill_between(x, x - np.maximum(0.1 * np.abs(x), TOL[a]), x + np.maximum(0.1 * np.abs(x), TOL[a]),
                        color="g", alpha=0.15, label="target ±10 %")
        ax.set_xlabel(f"commanded {a} [{UNITS[a]}]")
        ax.set_ylabel(f"reference-implied {a} [{UNITS[a]}]")
        ax.set_title(f"reference (generator) over the envelope grid: {a}")
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    # Bottom: SIL achieved / commanded per segment.
    for k, a in enumerate(AXES):
        ax = axs[1][k]
        for n, s in sils:
            xs, ys = [], []
            for seg in s.get("segments", []):
                c, ach = seg["command"][a], seg["achieved"][a]
                if c is None or ach is None or abs(c) < 0.05:
                    continue
                xs.append(c)
                ys.append(ach)
            if xs:
                xs, ys = np.array(xs), np.array(ys)
                ok = np.mean(np.abs(ys - xs) <= np.maximum(0.15 * np.abs(xs), 0.05 if a != "wz" else 0.08))
                ax.scatter(xs, ys, s=18, alpha=0.7, label=f"{n}: {100 * ok:.0f} % within ±15 %")
        ax.axline((0, 0), slope=1, color="k", lw=1)
        ax.set_xlabel(f"commanded {a} [{UNITS[a]}]")
        ax.set_ylabel(f"achieved {a} in the SIL [{UNITS[a]}]")
        ax.set_title(f"SIL, per segment (last 60 %): {a}")
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    fig.suptitle("Blending ablation: the paper's convex blending vs command-consistent blending (issue 12)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
