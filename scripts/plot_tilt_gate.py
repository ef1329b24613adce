#!/usr/bin/env python3
"""The pelvis tilt of each walking segment against the velocity feedback's tilt gate, and what the gate costs.

Usage: scripts/plot_tilt_gate.py OUT.png CSV_DIR OFF_SUMMARY ON_SUMMARY [--seed K] [--gates 0.3,0.6]

Top: from CSV_DIR/seed<K>.csv (pmg_policy_sil, per tick), the median and the 10-90 % range of pelvis_tilt
(the pelvis's angle from vertical [rad], from the IMU orientation) over the last 60 % of every walking segment
(a velocity command of at least 0.05 at its end), with the gates as horizontal lines: beyond velocity_feedback.max_tilt_rad the
feedback's correction decays instead of integrating. Bottom: per walking segment and commanded axis
(|command| >= 0.05), achieved / commanded from two summary.json files (pooled over their seeds; OFF: the lower
gate, ON: the higher), with issue 12's band (+-15 %) shaded. docs/controller.md "The tilt gate and H10a's gait".
"""
import argparse
import csv
import json
import os
import statistics

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

AXES = ("vx", "vy", "wz")


def walking_tilts(path):
    """{segment: sorted pelvis tilts over its last 60 %} for the segments with a velocity command, in order."""
    seg, last = {}, {}
    with open(path) as f:
        for r in csv.DictReader(f):
            if r["mode"] != "active":
                continue
            seg.setdefault(r["segment"], []).append((float(r["t"]), float(r["pelvis_tilt"])))
            last[r["segment"]] = r
    out = {}
    for name, rows in seg.items():
        if not any(abs(float(last[name][a + "_cmd"])) >= 0.05 for a in AXES):
            continue  # standing: its command at the segment's end is zero
        t0, t1 = rows[0][0], rows[-1][0]
        out[name] = sorted(v for t, v in rows if t >= t0 + 0.4 * (t1 - t0))
    return out


def ratios(path):
    """{(segment, axis): achieved / command} for the commanded axes of the summary's pooled segments."""
    with open(path) as f:
        s = json.load(f)
    out = {}
    for x in s["segments"]:
        for a in AXES:
            c = x["command"][a]
            if abs(c) >= 0.05:
                out[x["name"], a] = x["achieved"][a] / c
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("csv_dir")
    ap.add_argument("off_summary")
    ap.add_argument("on_summary")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--gates", default="0.3,0.6", help="the OFF and ON gates [rad]")
    a = ap.parse_args()
    gates = [float(g) for g in a.gates.split(",")]
    if len(gates) != 2:
        ap.error("--gates: expected two values, OFF,ON [rad]")
    tilts = walking_tilts(f"{a.csv_dir}/seed{a.seed}.csv")
    if not tilts:
        raise SystemExit(f"{a.csv_dir}/seed{a.seed}.csv: no walking segment (a velocity command of at least 0.05)")
    off, on = ratios(a.off_summary), ratios(a.on_summary)
    names = list(tilts)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(14, 8), sharex=True)
    x = range(len(names))
    med = [statistics.median(tilts[n]) for n in names]
    lo = [m - tilts[n][int(0.1 * (len(tilts[n]) - 1))] for m, n in zip(med, names)]
    hi = [tilts[n][int(0.9 * (len(tilts[n]) - 1))] - m for m, n in zip(med, names)]
    ax1.errorbar(x, med, yerr=[lo, hi], fmt="o", color="k", ecolor="0.5", capsize=3, label="pelvis tilt: median, 10-90 %")
    for g, style, label in ((gates[0], "--", "off"), (gates[1], "-", "on")):
        ax1.axhline(g, color="tab:red", ls=style, label=f"max_tilt_rad {g:g} ({label})")
    ax1.set_ylabel("pelvis tilt from vertical [rad]")
    ax1.set_title(f"{os.path.basename(os.path.normpath(a.csv_dir))}, seed {a.seed}: walking segments, last 60 %")
    ax1.legend(loc="upper left", fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.axhspan(0.85, 1.15, color="tab:green", alpha=0.15, label="issue 12's band (+-15 %)")
    marks = {"vx": "o", "vy": "s", "wz": "^"}
    for k, (src, color, label) in enumerate(((off, "tab:red", f"gate {gates[0]:g}"), (on, "tab:blue", f"gate {gates[1]:g}"))):
        for axis in AXES:
            pts = [(i + (k - 0.5) * 0.2, src[n, axis]) for i, n in enumerate(names) if (n, axis) in src]
            if pts:
                ax2.scatter(*zip(*pts), marker=marks[axis], color=color, s=22, label=f"{axis}, {label}")
    ax2.set_ylabel("achieved / commanded")
    ax2.set_title(f"pooled: {a.off_summary} (red) vs {a.on_summary} (blue)", fontsize=9)
    ax2.set_xticks(list(x))
    ax2.set_xticklabels(names, rotation=70, fontsize=8)
    ax2.legend(loc="lower left", fontsize=7, ncol=3)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
