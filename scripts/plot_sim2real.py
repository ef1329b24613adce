#!/usr/bin/env python3
"""Plots a pmg_sim2real_eval run (the paper's Table II in the SIL; docs/calibration.md
"Sim-to-real evaluation: pmg_sim2real_eval").

Reads <out>/summary.json and the per-run CSVs it names, writes <out>/sim2real.png (or --png):

  left    per policy, Motion Imitation Error and Sim-to-Real Error [rad] (bars: mean over the
          realities; dots: each reality; x: a reality on which the robot fell), and the paper's
          Table II (hardware) beside them, hatched
  right   one leg joint over time on one reality: the "real" robot (SIL with the hidden reality),
          the policy's simulator rollout and the PMG reference, with the commanded forward velocity;
          by default the policy, reality and joint with the largest Sim-to-Real Error

  python3 scripts/plot_sim2real.py OUT [--png PATH] [--policy NAME] [--reality K] [--joint NAME] [--title TEXT]
"""
import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

METRICS = [("motion_imitation_error_rad", "Motion Imitation Error"), ("sim_to_real_error_rad", "Sim-to-Real Error")]
COLORS = ["#1f77b4", "#d62728"]


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"plot_sim2real.py: {path}: no rows")
    return rows


def column(rows, key):
    return np.array([float(r[key]) for r in rows])


def num(x):
    return float("nan") if x is None else float(x)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="pmg_sim2real_eval --out folder")
    ap.add_argument("--png", help="output image (default: OUT/sim2real.png)")
    ap.add_argument("--policy", help="policy of the joint trace (default: the largest Sim-to-Real Error)")
    ap.add_argument("--reality", type=int, help="reality index of the joint trace")
    ap.add_argument("--joint", help="leg joint of the trace (default: the largest real - sim RMS)")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    path = os.path.join(a.out, "summary.json")
    try:
        with open(path) as f:
            s = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"plot_sim2real.py: {path}: {e}")
    policies = s["policies"]
    if not policies:
        sys.exit(f"plot_sim2real.py: {path}: policies: empty")
    names = list(policies)

    fig, (ax, axt) = plt.subplots(1, 2, figsize=(14, 5.2), gridspec_kw={"width_ratios": [1.1, 1.4]})
    # --- bars: ours, then the paper's
    paper = s.get("paper", {})
    groups = [(n, policies[n], False) for n in names] + [(n, v, True) for n, v in paper.items()]
    width = 0.38
    for g, (name, p, is_paper) in enumerate(groups):
        for m, (key, label) in enumerate(METRICS):
            x = g + (m - 0.5) * width
            val = p[m] if is_paper else num(p[key])
            ax.bar(x, val, width, color=COLORS[m], alpha=0.35 if is_paper else 0.85,
                   hatch="//" if is_paper else None, edgecolor=COLORS[m],
                   label=(label if g == 0 else None))
            if not is_paper:
                pts = [(num(r[key]), r["fell"]) for r in p["per_reality"]]
                for v, fell in pts:
                    ax.plot(x, v, "kx" if fell else "k.", ms=7 if fell else 5)
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels([(n if not ip else n + "\n(paper)") for n, _, ip in groups], rotation=30, ha="right",
                       fontsize=8)
    if paper:
        ax.axvline(len(names) - 0.5, color="0.5", lw=0.8, ls="--")
    ax.set_ylabel("RMS over the 12 leg joints [rad]")
    nreal = len(s.get("realities", []))
    ax.set_title(f"{a.title + ': ' if a.title else ''}SIL, {nreal} hidden realities (dots) vs. paper Table II")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)

    # --- joint trace
    cands = []
    for n in names:
        for k, r in enumerate(policies[n]["per_reality"]):
            cands.append((num(r["sim_to_real_error_rad"]), n, k))
    if a.policy is not None:
        if a.policy not in policies:
            sys.exit(f"plot_sim2real.py: --policy {a.policy}: not in {path} ({', '.join(names)})")
        cands = [c for c in cands if c[1] == a.policy]
    if a.reality is not None:
        cands = [c for c in cands if c[2] == a.reality]
    if not cands:
        sys.exit("plot_sim2real.py: no run matches --policy / --reality")
    cands.sort(key=lambda c: -1.0 if math.isnan(c[0]) else c[0], reverse=True)
    _, pname, k = cands[0]
    run = policies[pname]["per_reality"][k]
    rows = read_csv(os.path.join(a.out, run["csv"]))
    joints = s["protocol"]["leg_joints"]
    t = column(rows, "t")
    if a.joint is None:
        skip = s["protocol"].get("skip_s", 0.0)
        sel = t >= skip

        def err(j):
            d = column(rows, "q_" + j)[sel] - column(rows, "qsim_" + j)[sel]
            d = d[np.isfinite(d)]
            return float(np.sqrt(np.mean(d * d))) if d.size else 0.0

        joint = max(joints, key=err)
    else:
        if a.joint not in joints:
            sys.exit(f"plot_sim2real.py: --joint {a.joint}: not a leg joint ({', '.join(joints)})")
        joint = a.joint
    axt.plot(t, column(rows, "qref_" + joint), color="0.4", lw=1.0, ls="--", label="PMG reference")
    axt.plot(t, column(rows, "qsim_" + joint), color="#2ca02c", lw=1.2, label="simulator (policy's robot config)")
    axt.plot(t, column(rows, "q_" + joint), color="#d62728", lw=1.2, label="real (SIL + hidden reality)")
    axt.set_xlabel("t [s]")
    axt.set_ylabel(f"{joint} [rad]")
    axv = axt.twinx()
    axv.plot(t, column(rows, "vx_cmd"), color="#9467bd", lw=0.8, alpha=0.6)
    axv.set_ylabel("commanded v_x [m/s]", color="#9467bd")
    reality = os.path.basename(run["reality"])
    axt.set_title(f"{pname} on {reality}: MIE {num(run['motion_imitation_error_rad']):.4f}, "
                  f"S2R {num(run['sim_to_real_error_rad']):.4f} rad" + (" (fell)" if run["fell"] else ""),
                  fontsize=10)
    axt.legend(fontsize=8, loc="lower left")
    axt.grid(alpha=0.3)
    fig.tight_layout()
    png = a.png or os.path.join(a.out, "sim2real.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
