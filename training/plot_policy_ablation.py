#!/usr/bin/env python3
"""Policy-level ablation on the envelope grid (issue 12): per velocity axis, the share of the
segments whose achieved velocity is within the issue's band (+-15 % of the command, or +-0.05 m/s /
+-0.08 rad/s when that is larger), and the falls per seed, for several policies' pmg_policy_sil
summary.json files (run with --commands config/policies/eval_envelope.yaml --restart-after-fall).
Segments where every seed had fallen have no achieved value and count as missed.

  python3 training/plot_policy_ablation.py --out ablation.png "LABEL=DIR/summary.json" [...]
Prints the table it plots.
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

BAND_REL, BAND_ABS = 0.15, {"vx": 0.05, "vy": 0.05, "wz": 0.08}


def score(path):
    with open(path) as f:
        s = json.load(f)
    out = {}
    for ax in ("vx", "vy", "wz"):
        hit = n = 0
        for seg in s["segments"]:
            c = seg["command"][ax]
            if abs(c) < 1e-9:
                continue
            n += 1
            a = (seg.get("achieved") or {}).get(ax)
            hit += a is not None and abs(a - c) <= max(BAND_REL * abs(c), BAND_ABS[ax])
        out[ax] = (hit, n)
    runs = s.get("runs", [])
    falls = sum(len(r.get("falls_s", [])) for r in runs)
    return out, falls, len(runs)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("runs", nargs="+", help="LABEL=summary.json")
    args = ap.parse_args()
    labels, scores = [], []
    for spec in args.runs:
        label, path = spec.split("=", 1)
        labels.append(label)
        scores.append(score(path))
    print(f"{'policy':<40} {'v_x':>9} {'v_y':>9} {'w_z':>9}  falls/seed")
    for label, (sc, falls, seeds) in zip(labels, scores):
        cells = " ".join(f"{h:>3}/{n:<3} " for h, n in (sc[a] for a in ("vx", "vy", "wz")))
        print(f"{label:<40} {cells}  {falls / max(seeds, 1):.1f}")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [3, 1]})
    width = 0.8 / len(labels)
    for i, (label, (sc, falls, seeds)) in enumerate(zip(labels, scores)):
        vals = [100.0 * sc[a][0] / max(sc[a][1], 1) for a in ("vx", "vy", "wz")]
        ax1.bar([k + i * width for k in range(3)], vals, width, label=label)
        ax2.bar(i, falls / max(seeds, 1), 0.7, label=label)
    ax1.set_xticks([k + 0.4 - width / 2 for k in range(3)], ["v_x", "v_y", "ω"])
    ax1.set_ylabel("segments within ±15 % (or 0.05 m/s, 0.08 rad/s) [%]")
    ax1.set_ylim(0, 100)
    ax1.legend(fontsize=8)
    ax1.set_title("achieved velocity on the envelope grid (SIL, product path)")
    ax2.set_xticks(range(len(labels)), [str(i + 1) for i in range(len(labels))])
    ax2.set_xlabel("policy (legend order)")
    ax2.set_ylabel("falls per seed (171 s script)")
    ax2.set_ylim(0, max(1.0, 1.2 * max(f / max(n, 1) for _, f, n in scores)))
    ax2.set_title("falls")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
