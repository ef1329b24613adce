#!/usr/bin/env python3
"""Does the robot stop when told? The mean achieved speed FROM..TO s into each named stop segment,
per seed, of a pmg_policy_sil run (docs/controller.md "Bent velocity envelope").

For each SEGMENT: the mean of the achieved velocity along the axis the segment's name implies
(v_y for names with "side", ω for names with "turn", else v_x; --axis names one for all) over [--from-s, --to-s) s after the
segment's first tick, in every seedN.csv of OUT_DIR. Prints one row per seed (nan: the seed fell
before the segment, or the segment is shorter than --from-s) and, per segment, how many seeds moved faster than --threshold (absolute).

  python3 scripts/stop_speed.py OUT_DIR SEGMENT [SEGMENT ...] [--from-s 1] [--to-s 3] [--threshold 0.3] [--axis vx|vy|wz]
Exit status 2 (with a message naming it) when OUT_DIR has no seedN.csv or a segment is in none of them.
"""
import argparse
import csv
import glob
import math
import os
import re
import sys


def axis_of(segment):
    return "vy" if "side" in segment else ("wz" if "turn" in segment else "vx")


def mean_speed(rows, segment, t_from, t_to, axis=None):
    seg = [r for r in rows if r["segment"] == segment]
    if not seg:
        return math.nan
    t0 = float(seg[0]["t"])
    key = axis or axis_of(segment)
    vals = [float(r[key]) for r in seg if t_from <= float(r["t"]) - t0 < t_to]
    return sum(vals) / len(vals) if vals else math.nan


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("segments", nargs="+")
    ap.add_argument("--from-s", type=float, default=1.0)
    ap.add_argument("--to-s", type=float, default=3.0)
    ap.add_argument("--threshold", type=float, default=0.3)
    ap.add_argument("--axis", choices=("vx", "vy", "wz"), help="the velocity for every segment (default: from each name)")
    a = ap.parse_args(argv)
    files = sorted(glob.glob(os.path.join(a.out_dir, "seed*.csv")),
                   key=lambda p: int(re.findall(r"seed(\d+)\.csv$", p)[0]))
    if not files:
        print(f"stop_speed: {a.out_dir}: no seedN.csv (a pmg_policy_sil --out directory expected)", file=sys.stderr)
        return 2
    table, seen = [], set()
    for path in files:
        with open(path) as f:
            rows = list(csv.DictReader(f))
        seen.update(r["segment"] for r in rows)
        table.append((os.path.basename(path)[:-4], [mean_speed(rows, s, a.from_s, a.to_s, a.axis) for s in a.segments]))
    for s in a.segments:
        if s not in seen:
            print(f"stop_speed: segment {s!r} is in none of {a.out_dir}/seed*.csv", file=sys.stderr)
            return 2
    print("seed    " + " ".join(f"{s[:22]:>22s}" for s in a.segments))
    for name, vals in table:
        print(f"{name:8s}" + " ".join(f"{v:22.3f}" for v in vals))
    counts = [sum(1 for _, v in table if not math.isnan(v[i]) and abs(v[i]) > a.threshold) for i in range(len(a.segments))]
    ran = [sum(1 for _, v in table if not math.isnan(v[i])) for i in range(len(a.segments))]
    print(f"faster than {a.threshold:g} {a.from_s:g}-{a.to_s:g} s in: " +
          ", ".join(f"{s} {c} of {n}" for s, c, n in zip(a.segments, counts, ran)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
