#!/usr/bin/env python3
"""Reference side of the generator's cadence (docs/generator.md "Cadence", docs/policy.md "Stepping
faster where the stride ends"): from pmg_gco_eval --envelope grids (gco_grid.csv, optionally .gz),
the share of commands whose stance-implied velocity is within issue 12's target, per height command,
and the achieved/commanded ratio of the crouched commands' largest axis.

  scripts/plot_cadence.py --grid "before=OLD.csv.gz" --grid "cadence=NEW.csv.gz" --out docs/img/cadence_envelope.png
"""
import argparse
import csv
import gzip

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

TOL = (0.03, 0.03, 0.05)
HEIGHTS = (("0", "standing"), ("0.66", "0.66 m"), ("0.62", "0.62 m"))


def read(path):
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as f:
        rows = list(csv.DictReader(f))
    if not rows or "within_target" not in rows[0]:
        raise SystemExit(f"{path}: expected pmg_gco_eval's gco_grid.csv (column within_target)")
    return rows


def worst_ratio(r):
    """Implied / commanded on the axis that misses most relative to its band (1 = carried)."""
    cmd = [float(r[k]) for k in ("vx", "vy", "wz")]
    imp = [float(r[k]) for k in ("cycle_implied_vx", "cycle_implied_vy", "cycle_implied_wz")]
    worst, ratio = -1.0, 1.0
    for c, m, tol in zip(cmd, imp, TOL):
        if abs(c) < 1e-9:
            continue
        miss = abs(m - c) / max(0.1 * abs(c), tol)
        if miss > worst:
            worst, ratio = miss, m / c
    return ratio


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grid", action="append", required=True, metavar="NAME=PATH")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    grids = []
    for spec in a.grid:
        name, _, path = spec.partition("=")
        if not path:
            raise SystemExit(f"--grid: expected NAME=PATH, got {spec!r}")
        grids.append((name, read(path)))
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.5))
    width = 0.8 / len(grids)
    for k, (name, rows) in enumerate(grids):
        shares = []
        for key, _ in HEIGHTS:
            sel = [r for r in rows if r["height"] == key]
            shares.append(100.0 * sum(r["within_target"] == "1" for r in sel) / max(1, len(sel)))
        total = 100.0 * sum(r["within_target"] == "1" for r in rows) / len(rows)
        x = np.arange(len(HEIGHTS)) + (k - (len(grids) - 1) / 2) * width
        bars = ax0.bar(x, shares, width, label=f"{name} (all: {total:.1f} %)")
        for b, v in zip(bars, shares):
            ax0.text(b.get_x() + b.get_width() / 2, v + 0.5, f"{v:.1f}", ha="center", fontsize=7, rotation=90, va="bottom")
        crouched = [worst_ratio(r) for r in rows if r["height"] != "0"]
        ax1.hist(np.clip(crouched, 0.5, 1.5), bins=50, range=(0.5, 1.5), histtype="step", lw=1.5, label=name)
    ax0.set_xticks(np.arange(len(HEIGHTS)), [label for _, label in HEIGHTS])
    ax0.set_ylim(70, 106)
    ax0.set_ylabel("commands within the target on all three axes [%]")
    ax0.set_title("reference-implied velocity vs command, per height command")
    ax0.legend(loc="lower left", fontsize=8)
    ax1.axvspan(0.9, 1.1, color="0.9", label="±10 % band")
    ax1.set_xlabel("implied / commanded, each command's worst axis (clipped to 0.5–1.5)")
    ax1.set_ylabel("commands")
    ax1.set_title("crouched commands (0.66 and 0.62 m)")
    ax1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
