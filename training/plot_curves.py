#!/usr/bin/env python3
"""Training curves (PNG) from one or more progress.jsonl files of train_pmg.py (chunks in order).

  python3 training/plot_curves.py --out training/results/curves.png RUN1/progress.jsonl RUN2/progress.jsonl
Chunks resumed with --restore continue the env-step axis of the previous chunk.
"""
import argparse
import json

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PANELS = [("eval/episode_reward", "episode reward (eval, 256 envs)", False),
          ("eval/avg_episode_length", "episode length [control steps of 10 ms]", False),
          ("eval/episode_lin_vel_err", "mean lin. velocity error [m/s]", True),
          ("eval/episode_ref_q_err", "mean leg joint RMS error to PMG [rad]", True),
          ("eval/episode_contact_match", "contact agreement with PMG [-]", True)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("files", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--offsets", type=float, nargs="*", default=None,
                    help="env steps of the checkpoint each file's chunk was restored from (default 0, ...)")
    a = ap.parse_args()
    offsets = a.offsets or [0.0] * len(a.files)
    recs = []
    for f, off in zip(a.files, offsets):
        chunk = [json.loads(l) for l in open(f) if l.strip()]
        for r in chunk:
            r["env_steps"] = r["step"] + off
        recs += chunk
    fig, axes = plt.subplots(1, len(PANELS), figsize=(4.2 * len(PANELS), 3.4))
    for ax, (key, label, per_step) in zip(axes, PANELS):
        pts = [(r["env_steps"] / 1e6, r[key] / (r["eval/avg_episode_length"] if per_step else 1.0))
               for r in recs if key in r]
        if pts:
            ax.plot(*zip(*pts), "o-", ms=3)
        ax.set_xlabel("env steps [M]")
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3)
    fig.suptitle("G1 PMG-tracking PPO (MJX, Brax)", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
