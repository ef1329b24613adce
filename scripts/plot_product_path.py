#!/usr/bin/env python3
"""The reference envelope through the product path (docs/policy.md "Through the product path"):
from two pmg_gco_eval --envelope grids, one of the generator alone and one with --controller (each
command shaped by the controller's limits first; the shaped command in target_vx/vy/wz), the share
of commands within issue 12's target per height command, and how far the controller's crouched
velocity envelope slows the crouched commands (|shaped| / |commanded| of (v_x, v_y, w)).

  scripts/plot_product_path.py --raw training/results/fidelity/gco_grid_consistent.csv.gz \
      --product training/results/fidelity/gco_grid_product_path.csv.gz --out docs/img/reference_product_path.png
"""
import argparse
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_cadence import HEIGHTS, read  # noqa: E402


def speed_share(r):
    """|shaped| / |commanded| over (v_x, v_y, w); 1 for a command the controller passes unchanged."""
    u = math.hypot(*(float(r[k]) for k in ("vx", "vy", "wz")))
    t = math.hypot(*(float(r[k]) for k in ("target_vx", "target_vy", "target_wz")))
    return t / u if u > 1e-9 else 1.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--raw", required=True, help="pmg_gco_eval --envelope grid without --controller")
    ap.add_argument("--product", required=True, help="the same with --controller")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    raw, product = read(a.raw), read(a.product)
    if "target_vx" not in product[0]:
        raise SystemExit(f"{a.product}: no target_vx column (pmg_gco_eval before --controller)")
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.5))
    for k, (name, rows) in enumerate((("generator alone, against the user's command", raw),
                                      ("product path, against the shaped command", product))):
        shares = []
        for key, _ in HEIGHTS:
            sel = [r for r in rows if r["height"] == key]
            shares.append(100.0 * sum(r["within_target"] == "1" for r in sel) / max(1, len(sel)))
        x = np.arange(len(HEIGHTS)) + (k - 0.5) * 0.4
        bars = ax0.bar(x, shares, 0.4, label=name)
        for b, v in zip(bars, shares):
            ax0.text(b.get_x() + b.get_width() / 2, v + 0.3, f"{v:.1f}", ha="center", fontsize=8, va="bottom")
    ax0.set_xticks(np.arange(len(HEIGHTS)), [label for _, label in HEIGHTS])
    ax0.set_ylim(80, 104)
    ax0.set_ylabel("commands within the target on all three axes [%]")
    ax0.set_title("reference-implied velocity, per height command")
    ax0.legend(loc="lower left", fontsize=8)
    for key, label in HEIGHTS:
        s = [speed_share(r) for r in product if r["height"] == key]
        slowed = sum(v < 1.0 - 1e-9 for v in s)
        ax1.hist(s, bins=40, range=(0.0, 1.0001), histtype="step", lw=1.5,
                 label=f"{label}: {slowed} of {len(s)} slowed")
    ax1.set_xlabel("|shaped| / |commanded| velocity (1: passed unchanged)")
    ax1.set_ylabel("commands")
    ax1.set_title("the crouched velocity envelope: how far it slows each command")
    ax1.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
