#!/usr/bin/env python3
"""What the accelerometer's aliasing did to the velocity estimate, and what the HAL's low-pass changes.

Usage: scripts/plot_imu_lowpass.py OUT.png OFF_DIR ON_DIR [--seed K] [--segment NAME] [--seconds 2]

OFF_DIR, ON_DIR: pmg_policy_sil output directories (per-tick seed<k>.csv) of the same command sequence with
timing.imu_acc_lowpass_s 0 (off: the raw accelerometer) and the shipped value (on). Top two panels: over the first
`--seconds` s of the last 60 % of segment NAME of seed K, v_x in the heading frame: the simulation's truth (vx), the
estimator's (vx_est) and the leg-odometry samples (vx_leg; hollow where the estimator's gate rejected them). Bottom:
per walking segment (a velocity command of at least 0.05), the mean of estimate - truth (v_x) over its last 60 %,
for every seed in both directories, off and on. docs/controller.md "The accelerometer aliased into the velocity estimate".
"""
import argparse
import csv
import glob
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    with open(path) as f:
        return [{k: (v if k in ("segment", "mode") else float(v)) for k, v in r.items()} for r in csv.DictReader(f)]


def last60(rows, name):
    seg = [r for r in rows if r["segment"] == name]
    t0, t1 = seg[0]["t"], seg[-1]["t"]
    return [r for r in seg if r["t"] >= t0 + 0.4 * (t1 - t0)]


def walking_segments(rows):
    names = []
    for r in rows:
        if r["segment"] not in names:
            names.append(r["segment"])
    out = []
    for n in names:
        end = [r for r in rows if r["segment"] == n][-1]
        if max(abs(end["vx_cmd"]), abs(end["vy_cmd"]), abs(end["wz_cmd"])) >= 0.05:
            out.append(n)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("off_dir")
    ap.add_argument("on_dir")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--segment", default="fwd1.0_0.7")
    ap.add_argument("--seconds", type=float, default=2.0)
    a = ap.parse_args()

    fig, axes = plt.subplots(3, 1, figsize=(10, 10))
    for ax, (tag, d) in zip(axes[:2], (("off (raw accelerometer)", a.off_dir), ("on (low-passed in the HAL)", a.on_dir))):
        rows = last60(load(os.path.join(d, f"seed{a.seed}.csv")), a.segment)
        t0 = rows[0]["t"]
        w = [r for r in rows if r["t"] < t0 + a.seconds]
        t = [r["t"] for r in w]
        ax.plot(t, [r["vx"] for r in w], "k-", lw=2, label="truth (simulation)")
        ax.plot(t, [r["vx_est"] for r in w], "C3-", lw=1.5, label="estimate")
        acc = [r for r in w if r["leg_rejected"] == 0]
        rej = [r for r in w if r["leg_rejected"] == 1]
        ax.plot([r["t"] for r in acc], [r["vx_leg"] for r in acc], "o", color="C0", ms=4, label="leg sample, accepted")
        ax.plot([r["t"] for r in rej], [r["vx_leg"] for r in rej], "o", mfc="none", color="C0", ms=4, label="leg sample, rejected")
        bias = sum(r["vx_est"] - r["vx"] for r in rows) / len(rows)
        share = sum(r["leg_rejected"] for r in rows) / len(rows)
        ax.set_title(f"{tag}: {a.segment}, seed {a.seed}: estimate - truth {bias:+.3f} m/s over the last 60 %, "
                     f"{share:.0%} of leg samples rejected", fontsize=10)
        ax.set_ylabel("v_x [m/s] (heading frame)")
        ax.set_ylim(0.0, 1.6)
        ax.legend(fontsize=8, loc="lower right", ncol=2)
    ax = axes[2]
    for k, (tag, d, color) in enumerate((("off", a.off_dir, "C3"), ("on", a.on_dir, "C2"))):
        files = sorted(glob.glob(os.path.join(d, "seed*.csv")))
        per = {}
        for f in files:
            rows = load(f)
            for n in walking_segments(rows):
                w = last60(rows, n)
                per.setdefault(n, []).append(sum(r["vx_est"] - r["vx"] for r in w) / len(w))
        names = list(per)
        x = [i + (k - 0.5) * 0.3 for i in range(len(names))]
        for xi, n in zip(x, names):
            ax.plot([xi] * len(per[n]), per[n], "o", color=color, ms=5)
        ax.plot([], [], "o", color=color, label=f"{tag} ({len(files)} seeds)")
        ax.set_xticks(range(len(names)))
        ax.set_xticklabels(names)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_ylabel("estimate - truth, v_x [m/s]")
    ax.set_title("mean over each walk's last 60 %, per seed", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
