#!/usr/bin/env python3
"""The velocity estimate's bias per battery, from summary.json files alone (no per-tick CSVs needed).

Usage: scripts/estimate_bias.py BATTERY_DIR [BATTERY_DIR ...]

For each BATTERY_DIR (scripts/evaluate_candidate.py's output) and each of its batteries (grid, mirror, table1,
posture_walks, probe_heights, crouched_backward), over the segments with a velocity command (|v_x|, |v_y| or |w| of at
least 0.05 at the end): the mean of estimate − achieved for v_x and v_y [m/s, heading frame] (summary.json's pooled
`estimate` and `achieved`, each a mean over the segment's last 60 % and its seeds), the largest in magnitude, and the
mean share of the window in which the velocity feedback was held (the estimator's gate rejecting leg odometry).
docs/controller.md "The accelerometer aliased into the velocity estimate".
"""
import json
import os
import statistics
import sys

BATTERIES = ("grid", "mirror", "table1", "posture_walks", "probe_heights", "crouched_backward")


def main(dirs):
    if not dirs:
        print(__doc__)
        return 2
    for d in dirs:
        print(d)
        for b in BATTERIES:
            path = os.path.join(d, b, "summary.json")
            if not os.path.exists(path):
                continue
            with open(path) as f:
                s = json.load(f)
            ex, ey, held = [], [], []
            for g in s["segments"]:
                c, e, a = g["command"], g["estimate"], g["achieved"]
                if max(abs(c["vx"]), abs(c["vy"]), abs(c["wz"])) < 0.05 or e["vx"] is None or a["vx"] is None:
                    continue
                ex.append(e["vx"] - a["vx"])
                ey.append(e["vy"] - a["vy"])
                held.append(g["feedback_held_fraction"])
            if not ex:
                continue
            print(f"  {b:18s} v_x {statistics.mean(ex):+.3f} (largest {max(ex, key=abs):+.3f})  "
                  f"v_y {statistics.mean(ey):+.3f} (largest {max(ey, key=abs):+.3f})  held {statistics.mean(held):.2f}  "
                  f"({len(ex)} walks)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
