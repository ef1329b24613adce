#!/usr/bin/env python3
"""Plot the shipped clip set: dynamic clips as joint angles over the phase with the contact
schedule, static clips as joint angles over the command value.

Usage: scripts/motion_plot_clips.py [config/clips/g1] [out_dir]   (default out_dir: <clips>/plots)
Writes dynamic_clips.png and static_clips.png. The default clip folder is the shipped set of pmg's
data directory ($PMG_DATA_DIR, else the folder above this script: the checkout or <prefix>/share/pmg).
"""
import glob
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

JOINTS = ["left_hip_pitch_joint", "left_hip_roll_joint", "left_knee_joint", "left_ankle_pitch_joint",
          "right_hip_pitch_joint", "right_knee_joint", "waist_yaw_joint", "left_shoulder_pitch_joint"]


def default_clip_dir():
    data_dir = os.environ.get("PMG_DATA_DIR") or os.path.join(os.path.dirname(os.path.realpath(__file__)), "..")
    return os.path.normpath(os.path.join(data_dir, "config", "clips", "g1"))


def main():
    if len(sys.argv) > 1 and sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return
    clip_dir = sys.argv[1] if len(sys.argv) > 1 else default_clip_dir()
    out_dir = sys.argv[2] if len(sys.argv) > 2 else os.path.join(clip_dir, "plots")
    os.makedirs(out_dir, exist_ok=True)
    clips = [yaml.safe_load(open(f)) for f in sorted(glob.glob(os.path.join(clip_dir, "*.yaml")))]
    dyn = [c for c in clips if c["kind"] == "dynamic"]
    sta = [c for c in clips if c["kind"] == "static"]
    if dyn:
        fig, axes = plt.subplots(len(dyn), 1, figsize=(10, 2.6 * len(dyn)), squeeze=False)
        for ax, c in zip(axes[:, 0], dyn):
            q = np.array(c["q"])
            n = len(q)
            phi = np.arange(n + 1) / n
            names = c["joint_names"]
            for j in JOINTS:
                col = names.index(j)
                ax.plot(phi, np.append(q[:, col], q[0, col]), label=j.replace("_joint", ""))
            for side, y0 in (("left", -1.45), ("right", -1.6)):
                mu, sg = c["contact"][side]["mu"], c["contact"][side]["sigma"]
                for a in (mu - sg, mu - sg + 1, mu - sg - 1):
                    ax.broken_barh([(a, 2 * sg)], (y0, 0.1), color="k" if side == "left" else "0.5")
            ax.set_xlim(0, 1)
            ax.set_ylim(-1.7, 1.6)
            ax.set_ylabel("q [rad]")
            ax.set_title(f'{c["name"]}: {c["axis"]} {c["direction"]:+d}, x̄ = {c["nominal_scale"]:.2f}, T = {c["period"]:.2f} s, '
                         f'{c["metadata"]["provenance"]} ({os.path.basename(c["metadata"]["source_file"]) or "-"})', fontsize=9)
        axes[0, 0].legend(ncol=4, fontsize=7, loc="upper right")
        axes[-1, 0].set_xlabel("phase φ (bars: contact, black = left foot, grey = right foot)")
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, "dynamic_clips.png"), dpi=80)
    if sta:
        fig, axes = plt.subplots(1, len(sta), figsize=(6 * len(sta), 4), squeeze=False)
        for ax, c in zip(axes[0], sta):
            q = np.array(c["q"])
            v = np.array(c["values"])
            names = c["joint_names"]
            for j in JOINTS + ["waist_pitch_joint", "waist_roll_joint", "left_ankle_roll_joint"]:
                ax.plot(v, q[:, names.index(j)], label=j.replace("_joint", ""))
            ax.axvline(c["neutral"], color="k", ls=":", lw=1)
            unit = "m" if c["axis"] == "height" else "rad"
            ax.set_xlabel(f'{c["axis"]} command [{unit}] (dotted: neutral)')
            ax.set_ylabel("q [rad]")
            ax.set_title(f'{c["name"]} ({os.path.basename(c["metadata"]["source_file"]) or c["metadata"]["provenance"]})', fontsize=9)
        axes[0, 0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, "static_clips.png"), dpi=80)


if __name__ == "__main__":
    main()
