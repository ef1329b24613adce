#!/usr/bin/env python3
"""Runaways per seed: the seeds whose robot moved well beyond its command in a segment.

Usage: scripts/seed_runaways.py [--segments GLOB] [--json OUT] DIR [DIR ...]

Reads every seed<N>.csv (pmg_policy_sil --out DIR; one row per 100 Hz tick) under each DIR, and for each
seed and each segment takes the mean over the last 60 % of the segment's ticks (the window of
pmg_policy_sil's summary.json) of the commanded (vx_cmd, vy_cmd, wz_cmd) and achieved (vx, vy, wz)
velocities, in the robot's heading frame [m/s, rad/s]. A segment runs away on an axis when
    |achieved| - |command| > max(RUNAWAY_REL |command|, RUNAWAY_ABS[axis])
with the achieved value not against a nonzero command (scripts/segment_band.py's rule, there applied to
the means over seeds; here to each seed, since a runaway in one seed of twelve vanishes in the mean).
A stop (command 0) that runs on beyond 0.2 m/s is a runaway. Only the first episode (`episode` 0) is
read: after a fall, pmg_policy_sil --restart-after-fall starts the schedule again, and those rows are
not the schedule's timing. A seed falls when its first episode reaches the latched damping mode (a fall
or a fault) or a second episode follows. A segment the seed did not reach is not counted; the seed's
fall is reported.

--segments GLOB (fnmatch, e.g. 'stand_*') restricts the count to the matching segment names.
Prints, per matching segment, the seeds that ran away with their window means, then the count of
seeds with at least one runaway. --json writes {"seeds": N, "runaway_seeds": [...], "segments": {name:
[{"seed", "axis", "command", "achieved"}]}, "falls": [seed...]}. Exit status 2 when a DIR has no seed CSV
or a CSV lacks a needed column (the file and the column named).
"""
import argparse
import csv
import fnmatch
import glob
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from segment_band import is_runaway  # noqa: E402

WINDOW = 0.6  # the last 60 % of a segment's ticks, as pmg_policy_sil's summary.json
AXES = ("vx", "vy", "wz")
NEEDED = ("segment", "episode", "mode") + AXES + tuple(a + "_cmd" for a in AXES)


def seed_segments(path):
    """The first episode's segments of one seed CSV, in order: [(name, {axis: (command, achieved)})],
    and whether that episode fell (rows of a later episode follow it)."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in NEEDED if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f"{path}: no column {missing[0]!r} (expected pmg_policy_sil's seed CSV)")
        blocks, fell = [], False
        for row in reader:
            if row["episode"] != "0":
                fell = True
                break
            if row["mode"] == "damping":  # the latched damping mode: a fall or a fault ended the episode
                fell = True
            if row["mode"] != "active":
                continue
            if not blocks or blocks[-1][0] != row["segment"]:
                blocks.append((row["segment"], []))
            blocks[-1][1].append(row)
    out = []
    for name, rows in blocks:
        window = rows[int(len(rows) * (1.0 - WINDOW)):]
        if not window:
            continue
        means = {}
        for a in AXES:
            cmd = sum(float(r[a + "_cmd"]) for r in window) / len(window)
            vals = [float(r[a]) for r in window if not math.isnan(float(r[a]))]
            if vals:
                means[a] = (cmd, sum(vals) / len(vals))
        out.append((name, means))
    return out, fell


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("dirs", nargs="+", help="pmg_policy_sil --out folders holding seed<N>.csv")
    p.add_argument("--segments", default="*", help="fnmatch pattern on segment names (default: all)")
    p.add_argument("--json", help="write the result here")
    args = p.parse_args(argv)
    files = []
    for d in args.dirs:
        found = sorted(glob.glob(os.path.join(d, "seed*.csv")))
        if not found:
            print(f"{d}: no seed<N>.csv (expected a pmg_policy_sil --out folder)", file=sys.stderr)
            return 2
        files += found
    result = {"seeds": 0, "runaway_seeds": [], "segments": {}, "falls": []}
    for path in files:
        m = re.search(r"seed(\d+)\.csv$", path)
        if not m:
            continue
        seed = int(m.group(1))
        try:
            segs, fell = seed_segments(path)
        except ValueError as e:
            print(e, file=sys.stderr)
            return 2
        result["seeds"] += 1
        if fell:
            result["falls"].append(seed)
        for name, means in segs:
            if not fnmatch.fnmatch(name, args.segments):
                continue
            for axis, cmd, ach in [(a, c, v) for a, (c, v) in means.items() if is_runaway(a, c, v)]:
                result["segments"].setdefault(name, []).append(
                    {"seed": seed, "axis": axis, "command": round(cmd, 4), "achieved": round(ach, 4)})
                if seed not in result["runaway_seeds"]:
                    result["runaway_seeds"].append(seed)
    result["runaway_seeds"].sort()
    result["falls"].sort()
    for name, hits in sorted(result["segments"].items()):
        print(f"{name}: {len(hits)} runaway(s): " +
              ", ".join(f"seed {h['seed']} {h['axis']} {h['achieved']:+.3f} of {h['command']:+.3f}" for h in hits))
    print(f"seeds with a runaway in '{args.segments}': {len(result['runaway_seeds'])} of {result['seeds']}"
          f" ({', '.join(map(str, result['runaway_seeds'])) or 'none'}); seeds that fell: "
          f"{', '.join(map(str, result['falls'])) or 'none'}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
