#!/usr/bin/env python3
"""Trace plot of one pmg_teleop_bench trial (issue 14): pelvis, working hand and object over time,
with the operator's phases shaded; a box trial adds the left hand and the grip (the contact normal
force of each hand on the box).

    python3 scripts/plot_teleop_trial.py out/bench_wipe/trial_0.csv [--out trial_0.png]
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    rows = list(csv.DictReader(open(a.csv)))
    t = [float(r["t"]) for r in rows]
    col = lambda k: [float(r[k]) for r in rows]  # noqa: E731
    grip = "grip_left_n" in rows[0]
    fig, ax = plt.subplots(4 if grip else 3, 1, figsize=(10, 10 if grip else 8), sharex=True)
    for i, axis in enumerate("xyz"):
        ax[i].plot(t, col("pelvis_" + axis), label="pelvis")
        ax[i].plot(t, col("hand_" + axis), label="right hand (wrist)" if grip else "working hand (wrist)")
        if grip:
            ax[i].plot(t, col("left_hand_" + axis), label="left hand (wrist)")
        ax[i].plot(t, col("obj_" + axis), label="object")
        ax[i].set_ylabel(f"{axis} in W [m]")
        ax[i].grid(alpha=0.3)
    start = 0
    for k in range(1, len(rows) + 1):
        if k == len(rows) or rows[k]["phase"] != rows[start]["phase"]:
            for x in ax:
                x.axvspan(t[start], t[k - 1], alpha=0.06 * (1 + (start % 2)), color="gray")
            ax[0].text(t[start], ax[0].get_ylim()[1], rows[start]["phase"], fontsize=8, va="top")
            start = k
    if grip:
        ax[3].plot(t, col("grip_left_n"), label="left arm (wrist links and hand) on the box")
        ax[3].plot(t, col("grip_right_n"), label="right arm (wrist links and hand) on the box")
        if "grip_left_hand_n" in rows[0]:
            ax[3].plot(t, col("grip_left_hand_n"), "--", color="C0", label="left rubber hand alone")
            ax[3].plot(t, col("grip_right_hand_n"), "--", color="C1", label="right rubber hand alone")
        if "box_tilt" in rows[0]:
            tw = ax[3].twinx()
            tw.plot(t, col("box_tilt"), ":", color="k", label="box tilt")
            tw.set_ylabel("box tilt [rad]")
            tw.legend(fontsize=8, loc="upper left")
        ax[3].set_ylabel("contact normal force [N]")
        ax[3].grid(alpha=0.3)
        ax[3].legend(fontsize=8, loc="upper right")
    ax[0].legend(fontsize=8, loc="lower right")
    ax[-1].set_xlabel("t [s]")
    fig.suptitle(a.csv)
    fig.tight_layout()
    out = a.out or a.csv.replace(".csv", ".png")
    fig.savefig(out, dpi=90)
    print("wrote", out)


if __name__ == "__main__":
    main()
