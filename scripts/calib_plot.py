#!/usr/bin/env python3
"""Plot of a pmg_calib_dynamics run: measured vs baseline vs extended response on the held-out
logs (top), residuals (bottom), and the held-out RMSE per residual region (right).

Usage: calib_plot.py --report OUT.json --traces TRACES.csv --out OUT.png
(pmg_calib_dynamics --plot calls it with the traces it writes.)
"""
import argparse
import csv
import json
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--report", required=True)
    ap.add_argument("--traces", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--max-logs", type=int, default=2, help="held-out logs to draw")
    a = ap.parse_args()
    rep = json.load(open(a.report))
    logs = {}
    with open(a.traces) as f:
        for row in csv.DictReader(f):
            logs.setdefault(int(row["log"]), []).append(row)
    keys = sorted(logs)[: a.max_logs]
    fig = plt.figure(figsize=(13, 3.2 * len(keys) + 1.5))
    gs = fig.add_gridspec(2 * len(keys), 3)
    names = rep.get("heldout_logs", [])
    ext_causes = ", ".join(rep["extended"].get("causes", [])) or "none"
    for i, k in enumerate(keys):
        rows = logs[k]
        t = [float(r["t"]) for r in rows]
        col = {c: [float(r[c]) for r in rows] for c in ("q_cmd", "q_measured", "q_baseline", "q_extended")}
        ax = fig.add_subplot(gs[2 * i, :2])
        ax.plot(t, col["q_cmd"], color="0.7", lw=1, label="command")
        ax.plot(t, col["q_measured"], "k", lw=1.2, label="measured")
        ax.plot(t, col["q_baseline"], "tab:red", lw=1, label="baseline (PD + armature)")
        ax.plot(t, col["q_extended"], "tab:blue", lw=1, ls="--", label=f"extended ({ext_causes})")
        ax.set_ylabel("q [rad]")
        ax.set_title(os.path.basename(names[k]) if k < len(names) else f"held-out log {k}", fontsize=9)
        if i == 0:
            ax.legend(fontsize=8, loc="upper right")
        ax2 = fig.add_subplot(gs[2 * i + 1, :2], sharex=ax)
        ax2.plot(t, [b - m for b, m in zip(col["q_baseline"], col["q_measured"])], "tab:red", lw=1, label="baseline")
        ax2.plot(t, [e - m for e, m in zip(col["q_extended"], col["q_measured"])], "tab:blue", lw=1, label="extended")
        ax2.axhline(0, color="0.5", lw=0.5)
        ax2.set_ylabel("residual [rad]")
        ax2.set_xlabel("t [s]")
    axr = fig.add_subplot(gs[:, 2])
    regs = rep.get("residual_regions", [])
    labels = [f"{r['region']}\n({100 * r['fraction_of_samples']:.0f}% of samples)" for r in regs]
    y = list(range(len(regs)))
    axr.barh([v + 0.2 for v in y], [r["baseline_rmse_rad"] for r in regs], height=0.4, color="tab:red", label="baseline")
    axr.barh([v - 0.2 for v in y], [r["extended_rmse_rad"] for r in regs], height=0.4, color="tab:blue", label="extended")
    axr.set_yticks(y)
    axr.set_yticklabels(labels, fontsize=8)
    axr.invert_yaxis()
    axr.set_xlabel("held-out RMSE [rad]")
    axr.set_title("where the residuals are", fontsize=9)
    axr.legend(fontsize=8)
    b, e = rep["baseline"]["heldout_rmse_rad"], rep["extended"]["heldout_rmse_rad"]
    fig.suptitle(f"held-out RMSE: baseline {b:.4f} rad -> extended {e:.4f} rad (gain {1 - e / b:.2f}); causes: {ext_causes}",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)


if __name__ == "__main__":
    main()
