#!/usr/bin/env python3
"""Convergence plot of pmg_calib_zero: estimated zero offset per leg joint vs. iteration.

usage: pmg_plot_zero.py HISTORY.csv OUT.png   (HISTORY.csv from pmg_calib_zero --history-csv / --plot)
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{sys.argv[1]}: no iterations")
    joints = [k for k in rows[0] if k not in ("iteration", "step")]
    it = [int(r["iteration"]) for r in rows]
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for j in joints:
        a.plot(it, [1e3 * float(r[j]) for r in rows], label=j.replace("_joint", ""),
               linestyle="-" if j.startswith("left") else "--")
    a.set_ylabel("estimated offset [mrad]")
    a.legend(ncol=3, fontsize=7)
    a.grid(True, alpha=0.3)
    b.semilogy(it, [max(float(r["step"]), 1e-16) for r in rows])
    b.set_ylabel("max |alpha delta| [rad]")
    b.set_xlabel("iteration")
    b.grid(True, alpha=0.3)
    fig.suptitle("pmg_calib_zero: convergence (eqs. 21-25)")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
