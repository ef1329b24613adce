#!/usr/bin/env python3
"""Checks pmg_policy_sil runs of the shipped full-PMG policy on the whole preset command sequence
(config/policies/eval_commands.yaml: stand, forward, backward, sideways, turns, combined, squat,
bend, lean; ctest pmg_policy_sil_full_sequence, label sil): no run falls, every run reaches the
end, the mean Table I errors stay below bounds about 1.5x what 5 seeds measured (training/README.md:
LinVel 0.122 m/s, YawVel 0.169 rad/s, Roll 0.042 rad, Pitch 0.050 rad, Height 0.005 m), the robot
really walks backward (mean v_x < -0.08 m/s over the last 3 s of the backward segment, commanded
-0.3 m/s after a 0.5 m/s forward segment; measured -0.12 to -0.23 m/s) and really squats (pelvis
below 0.70 m in the squat segment, commanded 0.66 m).  Usage: check_sil_sequence.py OUT_DIR
"""
import csv
import json
import sys

import numpy as np

BOUNDS = {"lin_vel": 0.18, "yaw_vel": 0.25, "roll": 0.07, "pitch": 0.08, "height": 0.012}


def _last(x, t, seg, name, seconds):
    """Mean of x over the last `seconds` of segment `name` (nan if the run never got there)."""
    sel = seg == name
    if not sel.any():
        return float("nan")
    return float(x[sel & (t >= t[sel].max() - seconds)].mean())


def main(out):
    with open(f"{out}/summary.json") as f:
        summary = json.load(f)
    ok = True
    for run in summary["runs"]:
        seed = run["seed"]
        with open(f"{out}/seed{seed}.csv") as f:
            rows = list(csv.DictReader(f))
        seg = np.array([r["segment"] for r in rows])
        vx = np.array([float(r["vx"]) for r in rows])
        h = np.array([float(r["height"]) for r in rows])
        t = np.array([float(r["t"]) for r in rows])
        checks = {"no fall": not run["fell"], "ran the whole sequence": t[-1] >= summary["duration_s"] - 0.02,
                  "walks backward (mean v_x < -0.08 m/s, last 3 s)": _last(vx, t, seg, "backward", 3.0) < -0.08,
                  "squats (pelvis < 0.70 m)": (seg == "squat").any() and h[seg == "squat"].min() < 0.70}
        for k, b in BOUNDS.items():
            checks[f"{k} {run[k]:.4f} < {b}"] = run[k] < b
        for k, good in checks.items():
            print(f"seed {seed}: " + ("ok   " if good else "FAIL ") + k)
            ok &= bool(good)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
