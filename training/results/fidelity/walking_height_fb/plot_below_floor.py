#!/usr/bin/env python3
"""docs/img/walking_below_floor.png: the crouched probe's nine walks at 0.66 m (the walking floor), pelvis height
above the command (means over the last 60 % of each walk and over seeds 36-47), without and with
posture_feedback.walking_below_floor_m, for each actor given. Issue 12's band (0.015 m) shaded.
Usage: plot_below_floor.py OUT.png NAME WITHOUT_SUMMARY WITH_SUMMARY [NAME WITHOUT WITH ...]
(the probe_heights/summary.json files of evaluate_candidate.py's batteries)."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def walks_at_floor(path, floor=0.66):
    with open(path) as f:
        d = json.load(f)
    out = []
    for s in d["segments"]:
        c, a = s["command"], s["achieved"]
        if abs(c["vx"]) + abs(c["vy"]) + abs(c["wz"]) > 0 and abs(c["height"] - floor) < 1e-6:
            out.append((s["name"].replace("_0.66", ""), a["height"] - c["height"]))
    return out


def main():
    out, rest = sys.argv[1], sys.argv[2:]
    if len(rest) % 3 or not rest:
        sys.exit(__doc__)
    actors = [rest[k:k + 3] for k in range(0, len(rest), 3)]
    fig, axs = plt.subplots(1, len(actors), figsize=(6.5 * len(actors), 4.2), sharey=True, squeeze=False)
    for ax, (name, without, with_) in zip(axs[0], actors):
        a, b = walks_at_floor(without), walks_at_floor(with_)
        assert [n for n, _ in a] == [n for n, _ in b], "the two summaries must be the same battery"
        x = np.arange(len(a))
        ax.axhspan(-0.015, 0.015, color="0.9", label="issue 12's band (±0.015 m)")
        ax.bar(x - 0.2, [v for _, v in a], 0.4, label="the command never below the floor (first summary)")
        ax.bar(x + 0.2, [v for _, v in b], 0.4, label="walking height feedback, the command allowed 0.04 m below it")
        ax.set_xticks(x)
        ax.set_xticklabels([n for n, _ in a], rotation=40, ha="right", fontsize=8)
        ax.set_title(f"{name}: the probe's walks at the 0.66 m floor", fontsize=10)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.grid(axis="y", alpha=0.3)
    axs[0][0].set_ylabel("pelvis height − command [m]")
    axs[0][0].set_ylim(-0.035, None)
    axs[0][0].legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
