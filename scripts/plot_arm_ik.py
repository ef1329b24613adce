#!/usr/bin/env python3
"""Arm IK tracking plot (docs/img/arm_ik_tracking.png): the pose stream generated from the G1's own
forward kinematics of a smooth arm trajectory, solved by pmg::teleop::ArmIk at its 100 Hz settings.

    build/bin/pmg_arm_ik_bench --ticks 2000 --csv /tmp/arm_ik_stream.csv
    scripts/plot_arm_ik.py /tmp/arm_ik_stream.csv docs/img/arm_ik_tracking.png

Panels: hand position and orientation error per tick (both arms); the left arm's joints from the IK
against the known answer q* (the configuration with the same hand pose at which the IK's null-space
pull toward the nominal pose is stationary) and against the generating trajectory q_a (which differs
from q* along the elbow swivel: the pose does not determine it); |q - q*| per joint, both arms.
The CSV columns are written by bench/teleop/ik/arm_ik_bench.cpp (--csv).
"""
import argparse
import sys

JOINTS = ["shoulder pitch", "shoulder roll", "shoulder yaw", "elbow", "wrist roll", "wrist pitch", "wrist yaw"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", help="CSV from pmg_arm_ik_bench --csv")
    parser.add_argument("png", help="output image")
    args = parser.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    try:
        d = np.genfromtxt(args.csv, delimiter=",", names=True)
    except OSError as e:
        sys.exit(f"plot_arm_ik.py: {args.csv}: {e}")
    needed = ["t"] + [f"{s}_{k}" for s in ("left", "right") for k in ("ep", "eo")]
    needed += [f"{s}_{k}{j}" for s in ("left", "right") for k in ("q", "qstar", "qa") for j in range(7)]
    missing = [c for c in needed if d.dtype.names is None or c not in d.dtype.names]
    if missing or d.size < 2:
        sys.exit(f"plot_arm_ik.py: {args.csv}: not a pmg_arm_ik_bench --csv file (missing {missing[:3]}...)")
    t = d["t"]

    fig = plt.figure(figsize=(12, 10), constrained_layout=True)
    grid = fig.add_gridspec(4, 2, height_ratios=[1, 1, 2.2, 1])
    ax_p = fig.add_subplot(grid[0, 0])
    ax_o = fig.add_subplot(grid[0, 1])
    for side, style in (("left", "-"), ("right", "--")):
        ax_p.plot(t, 1e3 * d[f"{side}_ep"], style, lw=0.8, label=side)
        ax_o.plot(t, 1e3 * d[f"{side}_eo"], style, lw=0.8, label=side)
    ax_p.set_ylabel("hand position error [mm]")
    ax_o.set_ylabel("hand orientation error [mrad]")
    for ax in (ax_p, ax_o):
        ax.set_xlabel("t [s]")
        ax.legend(loc="upper right", fontsize=8)
        ax.grid(alpha=0.3)
    ax_p.set_title(f"pose error: max {1e3 * max(d['left_ep'].max(), d['right_ep'].max()):.3f} mm")
    ax_o.set_title(f"max {1e3 * max(d['left_eo'].max(), d['right_eo'].max()):.3f} mrad")

    ax_q = fig.add_subplot(grid[1:3, :])
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j in range(7):
        c = colors[j % len(colors)]
        ax_q.plot(t, d[f"left_qa{j}"], ":", color=c, lw=0.8, alpha=0.6)
        ax_q.plot(t, d[f"left_qstar{j}"], "-", color=c, lw=2.5, alpha=0.35)
        ax_q.plot(t, d[f"left_q{j}"], "-", color=c, lw=0.9, label=JOINTS[j])
    ax_q.set_ylabel("left arm joints [rad]")
    ax_q.set_xlabel("t [s]")
    ax_q.set_title("left arm: IK (thin) vs known answer q* (wide, pale) vs generating trajectory q_a (dotted)")
    ax_q.legend(loc="upper right", ncol=4, fontsize=8)
    ax_q.grid(alpha=0.3)

    ax_e = fig.add_subplot(grid[3, :])
    worst = 0.0
    for side, style in (("left", "-"), ("right", "--")):
        err = np.max([np.abs(d[f"{side}_q{j}"] - d[f"{side}_qstar{j}"]) for j in range(7)], axis=0)
        worst = max(worst, err.max())
        ax_e.plot(t, err, style, lw=0.8, label=f"{side}: max over joints |q - q*|")
    ax_e.set_ylabel("[rad]")
    ax_e.set_xlabel("t [s]")
    ax_e.set_title(f"joint error against the known answer: max {worst:.4f} rad")
    ax_e.legend(loc="upper right", fontsize=8)
    ax_e.grid(alpha=0.3)
    fig.suptitle("pmg::teleop::ArmIk on a pose stream from the G1's own forward kinematics (100 Hz, both arms)")
    fig.savefig(args.png, dpi=110)
    print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
