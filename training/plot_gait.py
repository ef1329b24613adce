#!/usr/bin/env python3
"""Achieved over commanded speed against the share of time in flight, per walking segment, for eval_mjx.py
rollouts (their .npz: segment_command, segment_achieved, segment_gait). A walk that follows PMG's gait
has no flight; an actor that runs its command away does so with both feet off the floor.

  python3 training/plot_gait.py --out docs/img/crouched_backward_flight.png "default=wh6g.npz" "V20e=v20e.npz" ...

--axis vx|vy|wz picks the velocity axis (default vx); segments whose command on it is below 0.05 in
magnitude (stops, stands) are left out. Heights below --crouched (default 0.76 m) are drawn filled."""
import argparse

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

AXES = {"vx": 0, "vy": 1, "wz": 2}


def points(path, axis, crouched):
    """(flight share, achieved / commanded, crouched?) of each walking segment of one rollout."""
    z = np.load(path, allow_pickle=True)
    c, a, g = z["segment_command"], z["segment_achieved"], z["segment_gait"]
    out = []
    for ci, ai, gi in zip(c, a, g):
        if abs(ci[axis]) < 0.05 or not np.isfinite(ai[axis]) or not np.isfinite(gi[0]):
            continue
        out.append((gi[0], ai[axis] / ci[axis], ci[5] < crouched))
    return np.array(out, float).reshape(-1, 3)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", metavar="LABEL=NPZ")
    ap.add_argument("--out", required=True)
    ap.add_argument("--axis", choices=sorted(AXES), default="vx")
    ap.add_argument("--crouched", type=float, default=0.76, metavar="H")
    args = ap.parse_args(argv)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for k, item in enumerate(args.runs):
        label, path = item.split("=", 1)
        p = points(path, AXES[args.axis], args.crouched)
        color = f"C{k}"
        ax.scatter(p[p[:, 2] > 0, 0], p[p[:, 2] > 0, 1], color=color, label=f"{label} (crouched)")
        ax.scatter(p[p[:, 2] == 0, 0], p[p[:, 2] == 0, 1], facecolors="none", edgecolors=color,
                   label=f"{label} (standing)")
    ax.axhspan(0.85, 1.15, color="0.9", zorder=0, label="issue 12 band (±15 %)")
    ax.set_xlabel("share of the window with neither foot on the floor")
    ax.set_ylabel(f"achieved / commanded {args.axis}")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
