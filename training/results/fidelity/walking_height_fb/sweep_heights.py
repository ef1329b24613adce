#!/usr/bin/env python3
"""Per walk segment of a 72-seed sweep (sweep.sh's six summaries): the commanded height, the achieved
height (mean over the segments' windows and seeds) and its error, the height command after feedback,
and how many seed-segments miss issue 12's 0.015 m. Usage: sweep_heights.py SWEEP_DIR [SWEEP_DIR ...]"""
import glob
import json
import sys

for d in sys.argv[1:]:
    rows, cmds = {}, {}
    for f in sorted(glob.glob(f"{d}/seeds*/summary.json")):
        s = json.load(open(f))
        cmds.update({seg["name"]: seg["command"]["height"] for seg in s["segments"]})
        for run in s["runs"]:
            for seg in run["segments"]:
                rows.setdefault(seg["name"], []).append(seg)
    print(f"== {d}")
    print(f"{'segment':16s} {'cmd':>6s} {'achieved':>8s} {'error':>7s} {'misses':>7s}")
    for name, segs in rows.items():
        ach = [x["achieved"]["height"] for x in segs if x.get("achieved") and x["achieved"].get("height") is not None]
        cmd = cmds[name]
        if not ach:
            continue
        m = sum(ach) / len(ach)
        miss = sum(abs(a - cmd) > 0.015 for a in ach)
        print(f"{name:16s} {cmd:6.3f} {m:8.3f} {m - cmd:+7.3f} {miss:4d}/{len(ach)}")
