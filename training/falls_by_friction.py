#!/usr/bin/env python3
"""Robots fallen by the floor friction they drew, from segment_robots.py summaries of eval_mjx.py --randomized
rollouts (docs/controller.md "Slippery floors").

  python3 training/falls_by_friction.py A.json [B.json ...] [--bins 0.4,0.6,0.8,1.0,1.25]

A robot counts as fallen when some segment has no value for it (it was down before that segment's window).
Prints, per summary, the robots and the share fallen in each friction bin [lo, hi) (the last bin closed).
With the same --seed, eval_mjx.py draws the same robots for every actor, so the rows compare actor to actor.
"""
import argparse
import json
import sys


def fallen_by_bin(summary, bins):
    """(robots per bin, fallen per bin) of one segment_robots.py summary dict."""
    friction = summary["drawn_friction"]
    segments = [v for k, v in summary.items() if not k.startswith("drawn_")]
    robots, fallen = [0] * (len(bins) - 1), [0] * (len(bins) - 1)
    for i, mu in enumerate(friction):
        k = next((j for j in range(len(bins) - 1) if bins[j] <= mu < bins[j + 1] or (j == len(bins) - 2 and mu == bins[-1])), None)
        if k is None:
            raise ValueError(f"robot {i}: friction {mu} outside the bins {bins}")
        robots[k] += 1
        fallen[k] += any(seg["vx"][i] is None for seg in segments)
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
