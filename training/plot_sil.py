#!/usr/bin/env python3
"""Tracking plots of a MuJoCo 2.2 SIL evaluation (apps/policy/pmg_policy_sil seed CSV), and the
sim-to-sim joint error against an MJX rollout of the same sequence (training/eval_mjx.py).

  python3 training/plot_sil.py OUT/seed0.csv --out tracking.png [--mjx RUN/mjx_eval.npz --sim2sim s2s.png]
      [--compare "LABEL=rollout.npz|other_seed.csv" ... --compare-out engines.png] [--label "SIL"]

--compare adds eval_mjx.py rollouts of the same sequence (any --physics, --pd-damping, --sim-dt), or
other pmg_policy_sil seed CSVs of it (another HAL setting, say), and --compare-out plots their forward
velocity and torso pitch (1 s moving means) against the SIL's (--label) and the command: which
simulator setting reproduces the SIL's behaviour.
"""
import argparse
import csv
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    text = {"segment", "mode"}  # the text columns (segment name, supervisor mode); the rest are numbers
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k not in text}, rows


def moving_mean(x, n):
    """Mean over the last @p n samples (fewer at the start)."""
    c = np.cumsum(np.insert(np.asarray(x, float), 0, 0.0))
    k = np.arange(1, len(x) + 1)
    lo = np.maximum(k - n, 0)
    return (c[k] - c[lo]) / (k - lo)


def compare(t, d, items, out, csv_path, main_label="MuJoCo 2.2 SIL"):
    """Forward velocity [m/s] (heading frame) and torso pitch [rad], 1 s moving means, of the SIL run and each
    eval_mjx.py rollout (LABEL=npz; measured[:, 0] and [:, 6], one robot) or SIL seed CSV (LABEL=csv; vx,
    pitch) against the command."""
    dt = float(np.median(np.diff(t)))
    n = max(1, int(round(1.0 / dt)))
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    axes[0].plot(t, d["vx_cmd"], "--", color="0.5", lw=1, label="command")
    for item in items:
        label, path = item.split("=", 1)
        if path.endswith(".csv"):
            o, _ = load(path)
            axes[0].plot(o["t"], moving_mean(o["vx"], n), lw=1.5, label=label)
            axes[1].plot(o["t"], moving_mean(o["pitch"], n), lw=1.5, label=label)
            continue
        m = np.load(path)
        meas = m["measured"] if m["measured"].ndim == 2 else m["measured"][0]
        alive = np.cumsum(m["done"] if m["done"].ndim == 1 else m["done"][0]) == 0
        tm = m["t"][alive]
        axes[0].plot(tm, moving_mean(meas[alive, 0], n), lw=1, label=label)
        axes[1].plot(tm, moving_mean(meas[alive, 6], n), lw=1, label=label)
    axes[0].plot(t, moving_mean(d["vx"], n), "k", lw=2, label=main_label)
    axes[1].plot(t, moving_mean(d["pitch"], n), "k", lw=2, label=main_label)
    axes[0].set_ylabel("forward velocity [m/s], 1 s mean")
    axes[1].set_ylabel("torso pitch [rad], 1 s mean")
    axes[1].set_xlabel("time [s]")
    axes[0].legend(fontsize=7, loc="upper left")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"the same actor and commands in each simulator setting (SIL: {os.path.basename(csv_path)})", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print("wrote", out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--out", required=True)
    ap.add_argument("--mjx")
    ap.add_argument("--sim2sim")
    ap.add_argument("--compare", action="append", default=[], metavar="LABEL=NPZ")
    ap.add_argument("--compare-out")
    ap.add_argument("--label", default="MuJoCo 2.2 SIL", help="--compare-out: the legend of the main CSV's run")
    a = ap.parse_args()
    if bool(a.compare) != bool(a.compare_out):
        ap.error("--compare and --compare-out go together")
    for item in a.compare:
        if "=" not in item:
            ap.error(f"--compare {item!r}: expected LABEL=rollout.npz or LABEL=seed.csv")
    d, _ = load(a.csv)
    t = d["t"]
    pairs = [("vx", "forward velocity [m/s]"), ("vy", "lateral velocity [m/s]"), ("wz", "yaw rate [rad/s]"),
             ("pitch", "torso pitch [rad]"), ("roll", "torso roll [rad]"), ("height", "pelvis height [m]")]
    fig, axes = plt.subplots(len(pairs), 1, figsize=(10, 11), sharex=True)
    for ax, (k, label) in zip(axes, pairs):
        ref = d["height_ref"] if k == "height" else d[k + "_cmd"]
        ax.plot(t, ref, "k--", lw=1, label="command" if k != "height" else "PMG height")
        ax.plot(t, d[k], lw=1, label="MuJoCo 2.2 SIL")
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)
    print("wrote", a.out)
    if a.compare:
        compare(t, d, a.compare, a.compare_out, a.csv, a.label)
    if a.mjx and a.sim2sim:
        m = np.load(a.mjx)
        n = min(len(t), len(m["t"]))
        q_sil = np.stack([d[f"q{j}"] for j in range(12)], 1)[:n]
        q_mjx = m["q"][:n]
        err = np.sqrt(np.mean((q_sil - q_mjx) ** 2, axis=1))
        fig, ax = plt.subplots(2, 1, figsize=(10, 5), sharex=True)
        ax[0].plot(t[:n], q_sil[:, 3], label="left knee, MuJoCo 2.2 SIL")
        ax[0].plot(t[:n], q_mjx[:, 3], label="left knee, MJX")
        ax[0].legend(fontsize=8)
        ax[0].set_ylabel("q [rad]")
        ax[1].plot(t[:n], err)
        ax[1].set_ylabel("leg joint RMS diff [rad]")
        ax[1].set_xlabel("time [s]")
        for x in ax:
            x.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(a.sim2sim, dpi=100)
        print(f"sim-to-sim leg joint RMS difference: mean {err.mean():.4f} rad over {n} ticks; wrote {a.sim2sim}")


if __name__ == "__main__":
    main()
