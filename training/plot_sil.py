#!/usr/bin/env python3
"""Tracking plots of a MuJoCo 2.2 SIL evaluation (apps/policy/pmg_policy_sil seed CSV), and the
sim-to-sim joint error against an MJX rollout of the same sequence (training/eval_mjx.py).

  python3 training/plot_sil.py OUT/seed0.csv --out tracking.png [--mjx RUN/mjx_eval.npz --sim2sim s2s.png]
"""
import argparse
import csv

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) if k != "segment" else 0.0 for r in rows]) for k in rows[0]}, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--out", required=True)
    ap.add_argument("--mjx")
    ap.add_argument("--sim2sim")
    a = ap.parse_args()
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
