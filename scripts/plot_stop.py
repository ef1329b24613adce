#!/usr/bin/env python3
"""A stop, seen side by side in several pmg_policy_sil runs (docs/controller.md "Braking steps").

One column per run, for one seed: top, the forward velocity (the shaped command u, the command the
generator got u_fb, the achieved v_x and the estimate); bottom, the torso pitch. A fall ends the
trace and is marked.

  python3 scripts/plot_stop.py --run "LABEL=OUT_DIR" [--run ...] [--seed 0] [--t0 17] [--t1 22] --out PNG
(OUT_DIR: pmg_policy_sil --out, e.g. with --commands training/results/fidelity/fast20s_ft2/stop/fast_fwd.yaml.)
"""
import argparse
import csv
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def series(path, t0, t1):
    cols = {k: [] for k in ("t", "vx_cmd", "vx_fb", "vx", "vx_est", "pitch")}
    for row in csv.DictReader(open(path)):
        t = float(row["t"])
        if t < t0 or t > t1:
            continue
        for k in cols:
            v = row[k]
            cols[k].append(float(v) if v not in ("", "nan") else float("nan"))
    return cols


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", action="append", required=True, help="LABEL=OUT_DIR")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--t0", type=float, default=17.0)
    ap.add_argument("--t1", type=float, default=22.0)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    runs = []
    for item in a.run:
        label, sep, d = item.partition("=")
        if not sep:
            raise SystemExit(f"--run {item!r}: expected LABEL=OUT_DIR")
        path = os.path.join(d, f"seed{a.seed}.csv")
        if not os.path.exists(path):
            raise SystemExit(f"{path}: no such file (pmg_policy_sil --out with seed {a.seed})")
        fall = None
        for r in json.load(open(os.path.join(d, "summary.json")))["runs"]:
            if r["seed"] == a.seed and r["fell"]:
                fall = r["fall_time_s"]
        runs.append((label, series(path, a.t0, a.t1), fall))
    fig, ax = plt.subplots(2, len(runs), figsize=(4.2 * len(runs), 5.6), sharex=True, sharey="row", squeeze=False)
    for j, (label, s, fall) in enumerate(runs):
        top, bottom = ax[0][j], ax[1][j]
        top.plot(s["t"], s["vx_cmd"], "k--", lw=1.2, label="command u")
        top.plot(s["t"], s["vx_fb"], color="tab:orange", lw=1.2, label="to the generator u_fb")
        top.plot(s["t"], s["vx"], color="tab:blue", lw=1.0, label="achieved")
        top.plot(s["t"], s["vx_est"], color="tab:green", lw=0.8, alpha=0.7, label="estimate")
        bottom.plot(s["t"], s["pitch"], color="tab:red", lw=1.0)
        title = label + (f"\nfell at {fall:.1f} s" if fall is not None else "\nstays up")
        top.set_title(title, fontsize=10)
        for axis in (top, bottom):
            axis.grid(alpha=0.3)
            if fall is not None:
                axis.axvline(fall, color="red", lw=0.8, ls=":")
        bottom.set_xlabel("t [s]")
    ax[0][0].set_ylabel("v_x [m/s] (heading frame)")
    ax[1][0].set_ylabel("torso pitch [rad]")
    ax[0][0].legend(fontsize=8, loc="lower left")
    fig.suptitle(f"Stopping from 1.0 m/s, seed {a.seed}", fontsize=11)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
