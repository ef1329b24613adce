#!/usr/bin/env python3
"""How far the velocity feedback's estimate is from the simulator's truth, per pmg_policy_sil run.

Usage: scripts/estimate_error.py OUT_DIR [OUT_DIR ...]

Over every active tick of every seed<k>.csv in each directory (pmg_policy_sil with the velocity
feedback on): the RMS of vx_est - vx, vy_est - vy [m/s] and wz_est - wz [rad/s] (the estimate against
the simulated pelvis velocity, heading frame), and the share of ticks off by more than 0.3 m/s, 0.3 m/s
and 0.5 rad/s (docs/controller.md "What the velocity estimate gets wrong").
"""
import csv
import glob
import math
import sys

LIMITS = (0.3, 0.3, 0.5)


def stats(paths):
    n, se, big = 0, [0.0] * 3, [0] * 3
    for p in paths:
        with open(p) as f:
            for r in csv.DictReader(f):
                if r["mode"] != "active":
                    continue
                truth = [float(r[k]) for k in ("vx", "vy", "wz")]
                est = [float(r[k]) for k in ("vx_est", "vy_est", "wz_est")]
                if any(math.isnan(x) for x in est + truth):
                    continue
                n += 1
                for i in range(3):
                    e = est[i] - truth[i]
                    se[i] += e * e
                    big[i] += abs(e) > LIMITS[i]
    return n, [math.sqrt(s / n) for s in se] if n else [math.nan] * 3, [100.0 * b / n for b in big] if n else [math.nan] * 3


def main(dirs):
    for d in dirs:
        paths = sorted(glob.glob(f"{d}/seed*.csv"))
        if not paths:
            sys.exit(f"{d}: no seed<k>.csv")
        n, rms, big = stats(paths)
        print(f"{d}: {n} ticks; RMS v_x {rms[0]:.3f} m/s, v_y {rms[1]:.3f} m/s, yaw rate {rms[2]:.3f} rad/s; "
              f"off by more than 0.3 / 0.3 / 0.5: {big[0]:.2f} % / {big[1]:.2f} % / {big[2]:.2f} % of ticks")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
