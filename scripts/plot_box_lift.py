#!/usr/bin/env python3
"""The box's lift in pmg_teleop_bench trials side by side (issue 14): from the start of each trial's
lift phase, the box's centre above where it started (`obj_z`, frame W) [m], its tilt (`box_tilt`)
[rad] and the operator's torso pitch command (`cmd_pitch`, + bends forward) [rad], one line per
NAME=CSV. Shows whether the legs (the torso standing up) or the arms alone raise the box, and how far
it turns in the grip while it leaves the table.

    python3 scripts/plot_box_lift.py v6=OUT6/trial_5.csv v7=OUT7/trial_5.csv --out lift.png [--seconds 6]
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def lift_series(path, seconds):
    rows = list(csv.DictReader(open(path)))
    need = ("t", "phase", "obj_z", "box_tilt", "cmd_pitch")
    if not rows or any(k not in rows[0] for k in need):
        sys.exit(f"{path}: expected a pmg_teleop_bench --task box trial CSV with columns {', '.join(need)}")
    start = next((r for r in rows if r["phase"] == "lift"), None)
    if start is None:
        sys.exit(f"{path}: no lift phase (the box was never gripped)")
    t0, z0 = float(start["t"]), float(rows[0]["obj_z"])
    sel = [r for r in rows if 0.0 <= float(r["t"]) - t0 <= seconds]
    return ([float(r["t"]) - t0 for r in sel], [float(r["obj_z"]) - z0 for r in sel], [float(r["box_tilt"]) for r in sel],
            [float(r["cmd_pitch"]) for r in sel])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="NAME=CSV")
    ap.add_argument("--out", required=True)
    ap.add_argument("--seconds", type=float, default=6.0, help="how long after the lift's start to plot [s]")
    a = ap.parse_args()
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for spec in a.runs:
        name, _, path = spec.partition("=")
        if not path:
            sys.exit(f"{spec}: expected NAME=CSV")
        t, z, tilt, pitch = lift_series(path, a.seconds)
        ax[0].plot(t, z, label=name)
        ax[1].plot(t, tilt, label=name)
        ax[2].plot(t, pitch, label=name)
    ax[0].axhline(0.05, color="gray", lw=0.8, ls=":")
    ax[0].set_ylabel("box centre above its start [m]")
    ax[1].set_ylabel("box tilt [rad]")
    ax[2].set_ylabel("torso pitch command [rad]")
    ax[2].set_xlabel("time since the lift began [s]")
    for x in ax:
        x.grid(alpha=0.3)
        x.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
