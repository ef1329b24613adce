#!/usr/bin/env python3
"""Plot the 500 Hz HAL wake-up period from `pmg_bench_hal --csv jitter.csv`.

Usage: python3 apps/hal/plot_jitter.py jitter.csv jitter.png
Left: distribution of the period (log count); right: the period over time. The target is 2000 us;
a period above 4000 us means a whole cycle was lost.
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def pct(v, q):
    s = sorted(v)
    return s[min(len(s) - 1, int(q * len(s)))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("png")
    args = ap.parse_args()
    runs = {}
    for r in csv.DictReader(open(args.csv)):
        runs.setdefault(r["run"], []).append(float(r["period_us"]))
    if not runs:
        raise SystemExit(f"{args.csv}: no rows (run pmg_bench_hal --csv {args.csv})")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    top = 8000.0  # longer periods are drawn in the last bin
    bins = [1000 + 25 * i for i in range(int((top - 1000) / 25) + 2)]
    for i, (name, v) in enumerate(runs.items()):
        over = sum(1 for x in v if x > top)
        label = f"{name}: p50 {pct(v, .5):.0f}, p99 {pct(v, .99):.0f}, max {max(v):.0f} us"
        if over:
            label += f" ({over} > {top:.0f} us in the last bin)"
        ax1.hist([min(x, top) for x in v], bins=bins, histtype="step", lw=1.5, color=f"C{i}", label=label)
        ax2.plot([2e-3 * k for k in range(len(v))], v, lw=0.6, color=f"C{i}", label=name)
    ax1.set_yscale("log")
    ax1.axvline(2000, color="k", ls=":")
    ax1.set_xlabel("wake-up period [us] (target 2000)")
    ax1.set_ylabel("cycles")
    ax1.legend(fontsize=7)
    ax1.set_title("HAL cycle period distribution")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("period [us]")
    ax2.set_yscale("log")
    ax2.legend(fontsize=7)
    ax2.set_title("period over time")
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
