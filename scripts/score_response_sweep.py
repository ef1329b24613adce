#!/usr/bin/env python3
"""Scores pmg_policy_sil runs of a random command sweep (scripts/make_response_sweep.py) against
issue 12's velocity band, per axis and per command, and lists the upsets and falls.

Usage: scripts/score_response_sweep.py SUMMARY.json [SUMMARY.json ...]

For each summary: per velocity axis (heading frame), of the sweep's commands (segments named r###)
that command that axis (|u| >= 0.05), how many are achieved within the band
    |achieved - command| <= max(0.15 |command|, tol),  tol = 0.05 m/s (v_x, v_y), 0.08 rad/s (w)
(segment means over the last 60 % of the segment and over seeds), the RMSE of achieved - command
over every command, the commands with every axis in band, the segments a seed fell in, and each
seed's upsets: a segment more than UPSET off its command on some axis.
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fit_command_response import AXES, UPSET  # noqa: E402  (what an upset is, one definition)
from plot_segments import VEL_ABS, VEL_REL  # noqa: E402  (the band, one definition)


def score(path):
    with open(path) as f:
        d = json.load(f)
    band = {a: [0, 0] for a in AXES}
    err = {a: [] for a in AXES}
    every = [0, 0]
    fallen = []
    for s in d["segments"]:
        if not s["name"].startswith("r"):
            continue
        c, v = s["command"], s["achieved"]
        if s.get("fallen", 0):
            fallen.append(s["name"])
        ok_all = True
        for a in AXES:
            if v[a] is None:
                ok_all = False
                continue
            e = v[a] - c[a]
            err[a].append(e)
            if abs(c[a]) >= 0.05:
                ok = abs(e) <= max(VEL_REL * abs(c[a]), VEL_ABS[a])
                band[a][0] += ok
                band[a][1] += 1
                ok_all = ok_all and ok
        every[0] += ok_all
        every[1] += 1
    cmd = {s["name"]: s["command"] for s in d["segments"]}
    upsets = []
    for run in d.get("runs", []):
        for s in run.get("segments", []):
            c = cmd[s["name"]]
            if any(s["achieved"][a] is None for a in AXES) or all(abs(c[a]) < 0.05 for a in AXES):
                continue
            if max(abs(s["achieved"][a] - c[a]) for a in AXES) > UPSET:
                upsets.append(f"seed {run['seed']} {s['name']} command ({c['vx']}, {c['vy']}, {c['wz']}) achieved "
                              f"({s['achieved']['vx']:.2f}, {s['achieved']['vy']:.2f}, {s['achieved']['wz']:.2f})")
    print(f"== {path}")
    for a in AXES:
        rmse = math.sqrt(sum(e * e for e in err[a]) / max(1, len(err[a])))
        print(f"{a}: in band {band[a][0]}/{band[a][1]}, RMSE {rmse:.4f}")
    print(f"commands with every axis in band: {every[0]}/{every[1]}")
    print(f"segments with a fall: {len(fallen)} {' '.join(fallen)}")
    print(f"upsets (more than {UPSET} off on some axis): {len(upsets)}")
    for u in upsets:
        print(f"  {u}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for p in sys.argv[1:]:
        score(p)
