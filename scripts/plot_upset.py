#!/usr/bin/env python3
"""Plots what the upset guard does in one pmg_policy_sil run against the same run without it.

Usage: scripts/plot_upset.py OFF_DIR ON_DIR SEED T0 T1 OUT.png

For the window [T0, T1] s of seed SEED (pmg_policy_sil --upset-guard off / on, the same script):
per run, the commanded v_x (script), the command after the feedback (vx_fb: what the generator got),
and the achieved v_x, v_y [m/s] and yaw rate [rad/s] in the robot's heading frame, the guard's hold
shaded, and the fall (the run's end) marked.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(d, seed, t0, t1):
    with open(f"{d}/seed{seed}.csv") as f:
        return [r for r in csv.DictReader(f) if t0 <= float(r["t"]) <= t1]


def main(off_dir, on_dir, seed, t0, t1, out):
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for ax, d, title in ((axes[0], off_dir, "guard off"), (axes[1], on_dir, "guard on")):
        rs = load(d, seed, t0, t1)
        t = [float(r["t"]) for r in rs]
        col = lambda k: [float(r[k]) for r in rs]  # noqa: E731
        ax.plot(t, col("vx_cmd"), "k--", lw=1, label="v_x commanded")
        ax.plot(t, col("vx_fb"), "k-", lw=1, label="v_x to the generator")
        ax.plot(t, col("vx"), label="v_x achieved")
        ax.plot(t, col("vy"), label="v_y achieved")
        ax.plot(t, col("wz"), lw=0.8, alpha=0.7, label="yaw rate achieved [rad/s]")
        if "upset_hold" in rs[0]:
            hold = [float(r["upset_hold"]) > 0 for r in rs]
            if any(hold):
                ax.fill_between(t, -4, 4, where=hold, color="orange", alpha=0.2, label="guard holds")
        if t[-1] < t1 - 0.05:
            ax.axvline(t[-1], color="r", lw=2, label="fall")
        ax.set_ylim(-4, 4)
        ax.set_ylabel("m/s, rad/s")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=7, ncol=3)
    axes[1].legend(loc="upper left", fontsize=7, ncol=3)
    axes[1].set_xlabel("script time [s]")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 7:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5]), sys.argv[6])
