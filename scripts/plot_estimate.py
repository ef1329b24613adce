#!/usr/bin/env python3
"""The velocity feedback's v_x estimate against the simulator's truth over time, one panel per run.

Usage: scripts/plot_estimate.py OUT.png DIR[=LABEL] [DIR[=LABEL] ...] [--seed K]

Reads DIR/seed<K>.csv (pmg_policy_sil with the velocity feedback on) and plots, against script time [s]:
the user's command (vx_cmd), the command after the feedback and feed-forward (vx_fb), the simulated
pelvis velocity (vx, heading frame), the estimate (vx_est) and the leg-odometry sample before the gate
(vx_leg), dots where the gate rejected it (leg_rejected). All in m/s. docs/controller.md "A swing foot
inside the stance band" shows one.
"""
import argparse
import csv
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    with open(path) as f:
        rows = [r for r in csv.DictReader(f) if r["mode"] == "active"]
    col = {k: [float(r[k]) for r in rows] for k in ("t", "vx_cmd", "vx_fb", "vx", "vx_est", "vx_leg", "leg_rejected")}
    return col


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("runs", nargs="+", help="DIR or DIR=LABEL")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    fig, axes = plt.subplots(len(a.runs), 1, figsize=(10, 3.2 * len(a.runs)), sharex=True, squeeze=False)
    for ax, run in zip(axes[:, 0], a.runs):
        d, _, label = run.partition("=")
        c = load(f"{d}/seed{a.seed}.csv")
        rej = [(t, v) for t, v, r in zip(c["t"], c["vx_leg"], c["leg_rejected"]) if r > 0.5 and not math.isnan(v)]
        ax.plot(c["t"], c["vx_leg"], color="0.8", lw=0.7, label="leg-odometry sample")
        if rej:
            ax.plot(*zip(*rej), ".", color="0.6", ms=2, label="rejected by the gate")
        ax.plot(c["t"], c["vx_cmd"], "k--", lw=1.2, label="command")
        ax.plot(c["t"], c["vx_fb"], color="tab:orange", lw=1.2, label="command after the feedback")
        ax.plot(c["t"], c["vx"], color="tab:blue", lw=1.5, label="pelvis (simulator)")
        ax.plot(c["t"], c["vx_est"], color="tab:red", lw=1.2, label="estimate")
        ax.set_ylim(-0.6, 1.4)
        ax.set_ylabel("v_x [m/s]")
        ax.set_title(label or d, fontsize=10)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="upper left", fontsize=8, ncol=3)
    axes[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(a.out)


if __name__ == "__main__":
    main()
