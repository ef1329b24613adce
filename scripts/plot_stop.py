#!/usr/bin/env python3
"""A stop, seen side by side in several pmg_policy_sil runs (docs/controller.md "Braking steps").

One column per run, for one seed: top, the velocity along --axis (the script's command, the shaper's
command where the CSV has it (vx_shaped: after its limits and envelopes), the command the generator
got u_fb, the achieved velocity and the estimate); bottom, the torso pitch (--axis vx)
or roll (--axis vy): commanded, sent to the actor after the posture feedback, achieved; with --height a third row, the pelvis height (the script's command, the
generator's base height, achieved). A fall ends the trace and is marked; with --restart-after-fall
runs only the first episode is drawn.

  python3 scripts/plot_stop.py --run "LABEL=OUT_DIR[@SEED]" [--run ...] [--seed 0] [--t0 17] [--t1 22]
      [--axis vx|vy] [--height] [--title TEXT] --out PNG
(OUT_DIR: pmg_policy_sil --out, e.g. with --commands training/results/fidelity/fast20s_ft2/stop/fast_fwd.yaml;
@SEED: that run's seed instead of --seed.)
"""
import argparse
import csv
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def series(path, t0, t1, axis):
    att = "pitch" if axis == "vx" else "roll"
    keys = ("t", f"{axis}_cmd", f"{axis}_fb", axis, f"{axis}_est", att, f"{att}_cmd", f"{att}_fb",
            "height_cmd", "height_ref", "height")
    cols = {k: [] for k in keys + (f"{axis}_shaped",)}
    for row in csv.DictReader(open(path)):
        t = float(row["t"])
        if t < t0 or t > t1 or row.get("episode", "0") != "0":
            continue
        for k in cols:
            v = row.get(k, "nan")  # vx_shaped: CSVs before 2026-11-28 lack it
            cols[k].append(float(v) if v not in ("", "nan") else float("nan"))
    return cols


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", action="append", required=True, help="LABEL=OUT_DIR")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--t0", type=float, default=17.0)
    ap.add_argument("--t1", type=float, default=22.0)
    ap.add_argument("--axis", choices=("vx", "vy"), default="vx")
    ap.add_argument("--height", action="store_true", help="a third row: the pelvis height")
    ap.add_argument("--title", default="Stopping from 1.0 m/s")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    v, att = a.axis, ("pitch" if a.axis == "vx" else "roll")
    runs = []
    for item in a.run:
        label, sep, d = item.partition("=")
        if not sep:
            raise SystemExit(f"--run {item!r}: expected LABEL=OUT_DIR[@SEED]")
        seed = a.seed
        if "@" in d:
            d, _, seed_text = d.rpartition("@")
            try:
                seed = int(seed_text)
            except ValueError:
                raise SystemExit(f"--run {item!r}: SEED {seed_text!r} is not an integer")
        path = os.path.join(d, f"seed{seed}.csv")
        if not os.path.exists(path):
            raise SystemExit(f"{path}: no such file (pmg_policy_sil --out with seed {seed})")
        fall = None
        for r in json.load(open(os.path.join(d, "summary.json")))["runs"]:
            if r["seed"] == seed and r["fell"]:
                fall = r["fall_time_s"]
        runs.append((label, seed, series(path, a.t0, a.t1, v), fall))
    one_seed = all(seed == a.seed for _, seed, _, _ in runs)
    runs = [(label if one_seed else f"{label}, seed {seed}", s, fall) for label, seed, s, fall in runs]
    rows = 3 if a.height else 2
    fig, ax = plt.subplots(rows, len(runs), figsize=(4.2 * len(runs), 2.8 * rows), sharex=True, sharey="row",
                           squeeze=False)
    for j, (label, s, fall) in enumerate(runs):
        top, bottom = ax[0][j], ax[1][j]
        top.plot(s["t"], s[f"{v}_cmd"], "k--", lw=1.2, label="command u")
        if any(x == x for x in s[f"{v}_shaped"]):
            top.plot(s["t"], s[f"{v}_shaped"], color="tab:gray", lw=1.2, label="shaped (envelopes)")
        top.plot(s["t"], s[f"{v}_fb"], color="tab:orange", lw=1.2, label="to the generator u_fb")
        top.plot(s["t"], s[v], color="tab:blue", lw=1.0, label="achieved")
        top.plot(s["t"], s[f"{v}_est"], color="tab:green", lw=0.8, alpha=0.7, label="estimate")
        bottom.plot(s["t"], s[f"{att}_cmd"], "k--", lw=1.2, label="command")
        bottom.plot(s["t"], s[f"{att}_fb"], color="tab:orange", lw=1.2, label="to the actor (fed back)")
        bottom.plot(s["t"], s[att], color="tab:red", lw=1.0, label="achieved")
        if a.height:
            h = ax[2][j]
            h.plot(s["t"], s["height_cmd"], "k--", lw=1.2, label="command")
            h.plot(s["t"], s["height_ref"], color="tab:orange", lw=1.2, label="generator base height")
            h.plot(s["t"], s["height"], color="tab:blue", lw=1.0, label="achieved")
        title = label + (f"\nfell at {fall:.1f} s" if fall is not None else "\nstays up")
        top.set_title(title, fontsize=10)
        for axis in ax[:, j]:
            axis.grid(alpha=0.3)
            if fall is not None:
                axis.axvline(fall, color="red", lw=0.8, ls=":")
        ax[-1][j].set_xlabel("t [s]")
    ax[0][0].set_ylabel(f"v_{v[1]} [m/s] (heading frame)")
    ax[1][0].set_ylabel(f"torso {att} [rad]")
    ax[1][0].legend(fontsize=8, loc="lower left")
    if a.height:
        ax[2][0].set_ylabel("pelvis height [m]")
        ax[2][0].legend(fontsize=8, loc="upper left")
    ax[0][0].legend(fontsize=8, loc="lower left" if v == "vx" else "upper left")
    fig.suptitle(f"{a.title}, seed {a.seed}" if one_seed else a.title, fontsize=11)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
