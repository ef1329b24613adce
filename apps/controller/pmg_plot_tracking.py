#!/usr/bin/env python3
"""Tracking plot of a pmg_controller run: reference vs. measured joint angles of the leg joints
(like the PMG paper's tracking figure), from its LCM event log (or the CSV of pmg_log_export).

    pmg_plot_tracking.py run.lcmlog tracking.png [--robot ROBOT.yaml]
    pmg_plot_tracking.py run.csv tracking.png
An event log is first converted with pmg_log_export, found next to this script (build/bin or
<prefix>/bin); --robot goes to it (default: the G1 config of pmg's data directory).
"""
import argparse
import os
import subprocess
import sys
import tempfile

LEG = ["hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll"]


def load(path: str, robot):
    import numpy as np

    if path.endswith(".csv"):
        return np.genfromtxt(path, delimiter=",", names=True)
    exporter = os.path.join(os.path.dirname(os.path.realpath(__file__)), "pmg_log_export")
    with tempfile.TemporaryDirectory() as tmp:
        csv_path = os.path.join(tmp, "run.csv")
        cmd = [exporter, "--log", path, "--csv", csv_path] + (["--robot", robot] if robot else [])
        rc = subprocess.run(cmd).returncode
        if rc not in (0, 2):  # 2: truncated log, the complete events were exported (warning printed)
            sys.exit(f"pmg_plot_tracking.py: {' '.join(cmd)} failed (exit code {rc})")
        return np.genfromtxt(csv_path, delimiter=",", names=True)


def main(log_path: str, png_path: str, robot=None) -> int:
    # Imported here, not at the top: --help needs neither matplotlib nor numpy (nor their caches).
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    data = load(log_path, robot)
    t = data["t"]
    fig, axes = plt.subplots(len(LEG), 2, figsize=(13, 12), sharex=True)
    rms_all = []
    for col, side in enumerate(["left", "right"]):
        for row, joint in enumerate(LEG):
            name = f"{side}_{joint}_joint"
            q, q_ref = data["q_" + name], data["q_ref_" + name]
            active = data["mode"] == 2
            rms = float(np.sqrt(np.mean((q - q_ref)[active] ** 2))) if active.any() else float("nan")
            rms_all.append(rms)
            ax = axes[row, col]
            ax.plot(t, q_ref, "k--", lw=1.0, label="reference (PMG)")
            ax.plot(t, q, "C0", lw=1.2, label="measured")
            ax.set_ylabel(f"{side} {joint}\n[rad]", fontsize=8)
            ax.set_title(f"RMS error {rms:.4f} rad", fontsize=8, loc="right")
            ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    # Shade the command segments on the top row.
    for ax in axes[0]:
        ax2 = ax.twinx()
        ax2.plot(t, data["vx"], "C2", lw=0.8, alpha=0.6, label="v_x cmd [m/s]")
        ax2.plot(t, data["wz"], "C3", lw=0.8, alpha=0.6, label="ω cmd [rad/s]")
        ax2.set_ylim(-1.2, 1.2)
        ax2.legend(loc="lower right", fontsize=7)
    axes[0, 0].legend(loc="upper left", fontsize=7)
    fig.suptitle(f"G1 leg joint tracking in the MuJoCo 2.2 SIL ({os.path.basename(log_path)}), mean RMS {np.nanmean(rms_all):.4f} rad")
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)
    print(f"{png_path}: leg tracking RMS per joint [rad]: " + " ".join(f"{r:.4f}" for r in rms_all))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("log", help="pmg_controller event log (.lcmlog) or pmg_log_export CSV (.csv)")
    parser.add_argument("png", help="output PNG")
    parser.add_argument("--robot", help="robot config YAML for the export of an event log (joint names)")
    args = parser.parse_args()
    sys.exit(main(args.log, args.png, args.robot))
