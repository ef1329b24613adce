#!/usr/bin/env python3
"""docs/img/walking_height_feedback.png: N24b's pelvis height and the commanded height over the crouched
backward walks at 0.74 and 0.70 m (seeds_V20b/crouched_backward.yaml, seed 2: held out), with and without the
walking height feedback. Usage: plot_height.py WITH_DIR WITHOUT_DIR OUT.png (the pmg_policy_sil folders)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def load(d, seed=2):
    t, cmd, h, seg = [], [], [], []
    with open(f"{d}/seed{seed}.csv") as f:
        for r in csv.DictReader(f):
            t.append(float(r["t"]))
            cmd.append(float(r["height_cmd"]))
            h.append(float(r["height"]))
            seg.append(r["segment"])
    return t, cmd, h, seg


def smooth(x, n=100):
    """Centred 1 s moving average: the per-tick height swings with every step."""
    out, acc = [], [0.0]
    for v in x:
        acc.append(acc[-1] + v)
    for i in range(len(x)):
        a, b = max(0, i - n // 2), min(len(x), i + n // 2)
        out.append((acc[b] - acc[a]) / (b - a))
    return out


with_fb, without, out = sys.argv[1:4]
fig, ax = plt.subplots(figsize=(11, 4.2))
t, cmd, h, seg = load(without)
ax.plot(t, smooth(h), color="tab:red", lw=1.0, label="pelvis height (1 s mean), without (walking_height_ki 0)")
t, cmd, h, seg = load(with_fb)
ax.plot(t, smooth(h), color="tab:blue", lw=1.0, label="pelvis height (1 s mean), with (walking_height_ki 3.0)")
ax.plot(t, cmd, color="k", lw=1.2, label="commanded height")
ax.fill_between(t, [c - 0.015 for c in cmd], [c + 0.015 for c in cmd], color="0.85", label="issue 12's band (±0.015 m)")
for i in range(1, len(seg)):
    if seg[i] != seg[i - 1] and seg[i].startswith("back") and t[i] >= 43:
        ax.axvline(t[i], color="0.6", lw=0.5)
        ax.text(t[i] + 0.2, 0.764, seg[i].replace("back", "−").replace("_", " m/s @ ") + " m", fontsize=6, rotation=90, va="top")
ax.set_xlim(42, 118)
ax.set_ylim(0.685, 0.765)
ax.set_xlabel("time [s]")
ax.set_ylabel("height [m] (pmg_policy_sil's Table I height)")
ax.set_title("N24b walking backward crouched (seed 2, held out): the walking height feedback through the product path")
ax.legend(loc="lower left", fontsize=7)
fig.tight_layout()
fig.savefig(out, dpi=110)
