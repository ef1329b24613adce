#!/usr/bin/env python3
"""Regenerate every motion plot of the shipped clip set (config/clips/g1/plots/*.png).

Usage: scripts/motion_plots.py [--build build] [--clips config/clips/g1]
Runs <build>/bin/pmg_make_clips into a temporary folder (for the per-clip retargeting CSVs; the
shipped clip files are not touched), then scripts/motion_plot_retarget.py for each clip and
scripts/motion_plot_clips.py for the clip curves.
"""
import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build")
    ap.add_argument("--clips", default="config/clips/g1")
    a = ap.parse_args()
    out = os.path.join(a.clips, "plots")
    os.makedirs(out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([os.path.join(a.build, "bin", "pmg_make_clips"), "--out", tmp, "--csv-dir", tmp], check=True,
                       stdout=subprocess.DEVNULL)
        for f in sorted(os.listdir(tmp)):
            if f.endswith(".csv"):
                name = f[:-4]
                subprocess.run([sys.executable, os.path.join(HERE, "motion_plot_retarget.py"), os.path.join(tmp, f),
                                os.path.join(out, f"retarget_{name}.png"), "--title",
                                f"{name}: human x scale (grey, left), robot-proportioned targets (orange), G1 (blue)"],
                               check=True, stdout=subprocess.DEVNULL)
    subprocess.run([sys.executable, os.path.join(HERE, "motion_plot_clips.py"), a.clips, out], check=True)
    print(f"plots written to {out}")


if __name__ == "__main__":
    main()
