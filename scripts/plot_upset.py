#!/usr/bin/env python3
"""Plots what the upset guard does in one pmg_policy_sil run against the same run without it.

Usage: scripts/plot_upset.py OFF_DIR ON_DIR SEED T0 T1 OUT.png [--titles "TOP,BOTTOM"] [--yaw]

For the window [T0, T1] s of seed SEED (pmg_policy_sil --upset-guard off / on, the same script):
per run, the commanded v_x (script), the command after the feedback (vx_fb: what the generator got),
and the achieved v_x, v_y [m/s] and yaw rate [rad/s] in the robot's heading frame, the guard's hold
shaded, and the fall marked: the run's end, or with --restart-after-fall the first tick in damping
(the rows after it, the restarted robot, are left out). --titles names the two runs otherwise (e.g. two
floors: any two runs of one script and seed); --yaw draws the yaw rate's command and its command after
the feedback instead of v_x's, and shades the ticks with neither foot on the floor.
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(d, seed, t0, t1):
    """The rows of @p d/seed@p seed.csv in [t0, t1] up to the first tick in damping (a fall), and whether there was one."""
    rows = []
    with open(f"{d}/seed{seed}.csv") as f:
        for r in csv.DictReader(f):
            if not t0 <= float(r["t"]) <= t1:
                continue
            if r.get("mode") == "damping" and rows:
                return rows, True
            rows.append(r)
    return rows, False


def main(off_dir, on_dir, seed, t0, t1, out, titles=("guard off", "guard on"), yaw=False):
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for ax, d, title in ((axes[0], off_dir, titles[0]), (axes[1], on_dir, titles[1])):
        rs, fell = load(d, seed, t0, t1)
        t = [float(r["t"]) for r in rs]
        col = lambda k: [float(r[k]) for r in rs]  # noqa: E731
        if yaw:
            ax.plot(t, col("wz_cmd"), "k--", lw=1, label="yaw rate commanded")
            ax.plot(t, col("wz_fb"), "k-", lw=1, label="yaw rate to the generator")
            flight = [r["contact_l"] == "0" and r["contact_r"] == "0" for r in rs]
            if any(flight):
                ax.fill_between(t, -4, 4, where=flight, step="mid", color="grey", alpha=0.3, label="no foot down")
        else:
            ax.plot(t, col("vx_cmd"), "k--", lw=1, label="v_x commanded")
            ax.plot(t, col("vx_fb"), "k-", lw=1, label="v_x to the generator")
        ax.plot(t, col("vx"), label="v_x achieved")
        ax.plot(t, col("vy"), label="v_y achieved")
        ax.plot(t, col("wz"), lw=0.8, alpha=0.7, label="yaw rate achieved [rad/s]")
        if "upset_hold" in rs[0]:
            hold = [float(r["upset_hold"]) > 0 for r in rs]
            if any(hold):
                ax.fill_between(t, -4, 4, where=hold, color="orange", alpha=0.2, label="guard holds")
        if fell or t[-1] < t1 - 0.05:
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
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("off_dir")
    ap.add_argument("on_dir")
    ap.add_argument("seed", type=int)
    ap.add_argument("t0", type=float)
    ap.add_argument("t1", type=float)
    ap.add_argument("out")
    ap.add_argument("--titles", default="guard off,guard on", help="the two panels' titles, comma-separated")
    ap.add_argument("--yaw", action="store_true", help="the yaw rate's command and feedback, and the flight phases")
    a = ap.parse_args()
    names = a.titles.split(",")
    if len(names) != 2:
        ap.error(f"--titles {a.titles!r}: expected two titles separated by a comma")
    main(a.off_dir, a.on_dir, a.seed, a.t0, a.t1, a.out, tuple(names), a.yaw)
