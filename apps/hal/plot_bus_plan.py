#!/usr/bin/env python3
"""Draw the 2 ms HAL slot per CAN bus from `pmg_bus_plan <plan> --csv slots.csv`.

Usage: python3 apps/hal/plot_bus_plan.py slots.csv slot.png [--period-us 2000] [--max-load 0.8]
Per motor: the command frame, the driver turnaround (gap) and the reply frame, with worst-case bit
stuffing. The number on the right is the wire load (frames / slot) that the HAL checks against
80 % at start-up.
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("png")
    ap.add_argument("--period-us", type=float, default=2000.0)
    ap.add_argument("--max-load", type=float, default=0.8)
    args = ap.parse_args()
    rows = list(csv.DictReader(open(args.csv)))
    if not rows:
        raise SystemExit(f"{args.csv}: no rows (run pmg_bus_plan <plan.yaml> --csv {args.csv})")
    buses = []
    for r in rows:
        if r["bus"] not in buses:
            buses.append(r["bus"])
    fig, ax = plt.subplots(figsize=(10, 0.7 * len(buses) + 2.0))
    for y, bus in enumerate(buses):
        mine = [r for r in rows if r["bus"] == bus]
        for i, r in enumerate(mine):
            start, end = float(r["send_us"]), float(r["reply_due_us"])
            cmd, rep = float(r["command_us"]), float(r["reply_us"])
            ax.barh(y, cmd, left=start, color="C0", edgecolor="k", height=0.6,
                    label="command frame" if y == 0 and i == 0 else None)
            ax.barh(y, rep, left=end - rep, color="C1", edgecolor="k", height=0.6,
                    label="reply frame" if y == 0 and i == 0 else None)
            ax.text(start + 4, y - 0.38, r["joint"].replace("_joint", ""), va="bottom", fontsize=6)
        ax.text(args.period_us + 20, y, f"{100 * float(mine[0]['load']):.1f} %", va="center", fontsize=8)
    ax.axvline(args.period_us, color="r", label="2 ms slot")
    ax.set_yticks(range(len(buses)))
    ax.set_yticklabels(buses)
    ax.invert_yaxis()
    ax.set_xlim(0, args.period_us * 1.12)
    ax.set_xlabel("time in the HAL slot [us]")
    ax.set_title(f"CAN send schedule per bus (right: wire load, refused above {100 * args.max_load:.0f} %)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3, fontsize=8)
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
