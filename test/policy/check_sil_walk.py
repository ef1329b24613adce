#!/usr/bin/env python3
"""Checks a short pmg_policy_sil run of the shipped policy (ctest pmg_policy_sil_walks, label sil):
the robot stands for 3 s, then walks forward on a 0.5 m/s command without falling, with a mean
forward velocity in [0.25, 0.75] m/s over the last 3 s, yaw rate error < 0.4 rad/s and the pelvis
above 0.65 m.  Usage: check_sil_walk.py OUT_DIR
"""
import csv
import json
import sys

import numpy as np


def main(out):
    with open(f"{out}/summary.json") as f:
        summary = json.load(f)
    run = summary["runs"][0]
    with open(f"{out}/seed0.csv") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows])
    vx = np.array([float(r["vx"]) for r in rows])
    h = np.array([float(r["height"]) for r in rows])
    sel = t >= t[-1] - 3.0
    checks = {
        "no fall": not run["fell"],
        "ran the whole sequence": t[-1] >= summary["duration_s"] - 0.02,
        "forward velocity in [0.25, 0.75] m/s": 0.25 <= vx[sel].mean() <= 0.75,
        "yaw rate error < 0.4 rad/s": run["yaw_vel"] < 0.4,
        "pelvis above 0.65 m": h.min() > 0.65,
    }
    print(f"mean v_x over the last 3 s: {vx[sel].mean():.3f} m/s; min pelvis height {h.min():.3f} m; "
          f"summary {run}")
    for k, ok in checks.items():
        print(("ok   " if ok else "FAIL ") + k)
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
