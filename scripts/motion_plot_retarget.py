#!/usr/bin/env python3
"""Plot a few frames of a retargeting: the human skeleton (scaled by the leg-length ratio, drawn
0.8 m to the left), the robot-proportioned keypoint targets and the robot keypoints.

Usage: scripts/motion_plot_retarget.py retarget.csv out.png [--frames 0,10,20,30] [--title T]
The CSV comes from `build/bin/pmg_retarget <mocap> --csv retarget.csv`. Two rows of panels: side
view (x-z) and front view (y-z) in the pelvis heading frame; human target skeleton dashed orange, robot solid blue; the
feet in contact are marked with a black square; the human skeleton (grey) is drawn beside them. Also prints the mean error per keypoint [m].
"""
import argparse
import csv
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

BONES = [("pelvis", "left_hip"), ("left_hip", "left_knee"), ("left_knee", "left_ankle"), ("left_ankle", "left_toe"),
         ("pelvis", "right_hip"), ("right_hip", "right_knee"), ("right_knee", "right_ankle"),
         ("right_ankle", "right_toe"), ("pelvis", "left_shoulder"), ("pelvis", "right_shoulder"),
         ("left_shoulder", "right_shoulder"), ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
         ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist")]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("out")
    ap.add_argument("--frames", default="")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    pts = defaultdict(dict)
    contact = {}
    with open(a.csv) as f:
        for r in csv.DictReader(f):
            k = int(r["frame"])
            pts[(k, r["source"])][r["keypoint"]] = np.array([float(r["x"]), float(r["y"]), float(r["z"])])
            contact[k] = (r["contact_left"] == "1", r["contact_right"] == "1")
    n = max(k for k, _ in pts) + 1
    frames = [int(x) for x in a.frames.split(",")] if a.frames else list(np.linspace(0, n - 1, 4).astype(int))
    err = defaultdict(list)
    for k in range(n):
        for name, p in pts[(k, "robot")].items():  # error of the robot against its targets
            err[name].append(np.linalg.norm(p - pts[(k, "target")][name]))
    for name in sorted(err):
        print(f"{name:16s} mean {np.mean(err[name]):.3f} m  max {np.max(err[name]):.3f} m")
    fig, axes = plt.subplots(2, len(frames), figsize=(4.2 * len(frames), 7), squeeze=False)
    for c, k in enumerate(frames):
        # View in the robot's heading frame: x along the pelvis heading (perpendicular to the
        # right-hip -> left-hip line), origin under the pelvis.
        R = pts[(k, "robot")]
        lat = R["left_hip"] - R["right_hip"]
        psi = np.arctan2(-lat[0], lat[1])
        rot = np.array([[np.cos(psi), np.sin(psi), 0], [-np.sin(psi), np.cos(psi), 0], [0, 0, 1]])
        origin = R["pelvis"] * np.array([1, 1, 0])
        for src in ("human", "target", "robot"):
            if (k, src) not in pts:
                continue
            pts[(k, src + "_H")] = {name: rot @ (p - origin) for name, p in pts[(k, src)].items()}
        centre = np.zeros(3)
        for row, (i, lab) in enumerate([(0, "x"), (1, "y")]):
            ax = axes[row][c]
            for src, style, off in (("human", dict(color="0.45", lw=2), -0.8),
                                    ("target", dict(color="tab:orange", ls="--", lw=2), 0.0),
                                    ("robot", dict(color="tab:blue", lw=2.5), 0.0)):
                if (k, src + "_H") not in pts:
                    continue
                P = pts[(k, src + "_H")]
                for b0, b1 in BONES:
                    ax.plot([P[b0][i] - centre[i] + off, P[b1][i] - centre[i] + off], [P[b0][2], P[b1][2]], **style)
            for side, foot in ((0, "left_ankle"), (1, "right_ankle")):
                if contact[k][side]:
                    p = pts[(k, "robot_H")][foot]
                    ax.plot([p[i] - centre[i]], [p[2]], "ks", ms=6)
            ax.axhline(0.0, color="0.6", lw=1)
            ax.set_aspect("equal")
            ax.set_xlim(-1.3, 0.6)
            ax.set_ylim(-0.05, 1.5)
            ax.set_xlabel(f"{lab}_H [m] (heading frame)")
            if c == 0:
                ax.set_ylabel(("side view" if row == 0 else "front view") + "  z [m]")
            if row == 0:
                ax.set_title(f"frame {k}")
    fig.suptitle(a.title or a.csv + "  (grey: human x scale, left; orange dashed: targets; blue: G1)")
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)


if __name__ == "__main__":
    main()
