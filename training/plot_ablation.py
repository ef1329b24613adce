#!/usr/bin/env python3
"""Training curves of the Table I configurations side by side (eval reward and episode length vs env
steps), from each run's progress files in order (chunks resumed with --restore continue the axis).

  python3 training/plot_ablation.py --out curves.png NAME=RUN/chunk1.jsonl,RUN/chunk2.jsonl [...]
"""
import argparse
import json

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(paths):
    steps, reward, length, offset = [], [], [], 0
    for p in paths:
        last = 0
        with open(p) as f:
            for line in f:
                r = json.loads(line)
                if "eval/episode_reward" not in r:
                    continue
                steps.append((offset + r["step"]) / 1e6)
                reward.append(r["eval/episode_reward"])
                length.append(r["eval/avg_episode_length"])
                last = r["step"]
        offset += last
    return steps, reward, length


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("runs", nargs="+", help="NAME=progress1.jsonl,progress2.jsonl")
    a = ap.parse_args()
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.8))
    for run in a.runs:
        name, files = run.split("=", 1)
        s, r, n = load(files.split(","))
        ax[0].plot(s, r, marker=".", label=name)
        ax[1].plot(s, n, marker=".", label=name)
    ax[0].set_ylabel("eval episode reward (256 envs)")
    ax[1].set_ylabel("eval episode length [10 ms steps]")
    for x in ax:
        x.set_xlabel("env steps [M]")
        x.grid(alpha=0.3)
    ax[0].legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
