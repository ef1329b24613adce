#!/usr/bin/env python3
"""Robots fallen by the floor friction they drew, from segment_robots.py summaries of eval_mjx.py --randomized
rollouts (docs/controller.md "Slippery floors").

  python3 training/falls_by_friction.py A.json [B.json ...] [--bins 0.4,0.6,0.8,1.0,1.25]

A robot counts as fallen when segment_robots.py marks it fallen by the end of the schedule (the last segment's
"fallen_by_end").
Prints, per summary, the robots and the share fallen in each friction bin [lo, hi) (the last bin closed).
With the same --seed, eval_mjx.py draws the same robots for every actor, so the rows compare actor to actor.
"""
import argparse
import bisect
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from segment_robots import segments  # noqa: E402


def fallen_by_bin(summary, bins):
    """(robots per bin, fallen per bin) of one segment_robots.py summary dict."""
    fallen_by_end = segments(summary)[-1][1]["fallen_by_end"]
    robots, fallen = [0] * (len(bins) - 1), [0] * (len(bins) - 1)
    for i, mu in enumerate(summary["drawn_friction"]):
        if not bins[0] <= mu <= bins[-1]:
            raise ValueError(f"robot {i}: friction {mu} outside the bins {bins}")
        k = min(bisect.bisect_right(bins, mu), len(bins) - 1) - 1  # [lo, hi), the last bin closed
        robots[k] += 1
        fallen[k] += bool(fallen_by_end[i])
    return robots, fallen


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("summaries", nargs="+", help="segment_robots.py summarize outputs (JSON)")
    ap.add_argument("--bins", default="0.4,0.6,0.8,1.0,1.25", help="friction bin edges (default: the training's range)")
    args = ap.parse_args(argv)
    bins = [float(x) for x in args.bins.split(",")]
    if len(bins) < 2 or any(b <= a for a, b in zip(bins, bins[1:])):
        ap.error(f"--bins {args.bins}: expected two or more increasing edges")
    print("summary: " + ", ".join(f"[{a:g}, {b:g})" for a, b in zip(bins, bins[1:])) + ": fallen / robots (share)")
    for path in args.summaries:
        with open(path) as f:
            robots, fallen = fallen_by_bin(json.load(f), bins)
        print(f"{path}: {sum(fallen)} of {sum(robots)}; " +
              ", ".join(f"{k}/{n} ({k / n:.2f})" if n else "0/0" for k, n in zip(fallen, robots)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
