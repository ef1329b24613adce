#!/usr/bin/env python3
"""Held-out responses of pmg_calib_joints: robot vs. nominal vs. calibrated whole-robot simulator.

    plot_joint_calibration.py --report REPORT.json --out joint_calibration.png TRACES.csv [...]

TRACES.csv (one per fitted joint, <joint>_heldout.csv): t, q_cmd, q_robot, q_nominal, q_calibrated
[s, rad]. Each panel shows the command, the robot's response and both simulators' residuals
(robot - simulator, mean removed), titled with what was named and the held-out RMS residuals.
"""
import argparse
import csv
import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--report", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("traces", nargs="+")
    a = ap.parse_args()
    report = json.load(open(a.report))["joints"]
    n = len(a.traces)
    cols = 2 if n > 1 else 1
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(2 * rows, cols, figsize=(7 * cols, 4.2 * rows), squeeze=False)
    for k, path in enumerate(a.traces):
        joint = os.path.basename(path).replace("_heldout.csv", "")
        d = {key: [] for key in ("t", "q_cmd", "q_robot", "q_nominal", "q_calibrated")}
        for row in csv.DictReader(open(path)):
            for key in d:
                d[key].append(float(row[key]))
        r, c = divmod(k, cols)
        top, bottom = axes[2 * r][c], axes[2 * r + 1][c]
        top.plot(d["t"], d["q_cmd"], "k--", lw=0.8, label="command")
        top.plot(d["t"], d["q_robot"], "C0", lw=1.2, label="robot")
        top.plot(d["t"], d["q_nominal"], "C3", lw=0.8, label="nominal simulator")
        top.plot(d["t"], d["q_calibrated"], "C2", lw=0.8, label="calibrated simulator")
        top.set_ylabel("q [rad]")
        j = report.get(joint, {})
        causes = j.get("causes", [])
        named = ", ".join(c["name"] for c in causes)
        if causes:
            named += ": " + ", ".join(f"{p} {v:.3g}" for p, v in causes[-1]["params"].items())
        named = named or "nothing named"
        top.set_title(f"{joint}: {named}", fontsize=9)
        top.legend(fontsize=7, loc="upper right")
        for key, col, lab in (("q_nominal", "C3", "nominal"), ("q_calibrated", "C2", "calibrated")):
            e = [x - y for x, y in zip(d["q_robot"], d[key])]
            m = sum(e) / max(len(e), 1)
            rms = math.sqrt(sum((x - m) ** 2 for x in e) / max(len(e), 1))
            bottom.plot(d["t"], [1e3 * (x - m) for x in e], col, lw=0.8, label=f"robot - {lab} (RMS {1e3 * rms:.2f} mrad)")
        bottom.set_ylabel("residual [mrad]")
        bottom.set_xlabel("t [s] (held-out log)")
        bottom.legend(fontsize=7)
    for k in range(n, rows * cols):
        r, c = divmod(k, cols)
        axes[2 * r][c].axis("off")
        axes[2 * r + 1][c].axis("off")
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
