#!/usr/bin/env python3
"""Table II with trained policies on several calibrated robots (issue 15; docs/calibration.md,
"Table II with trained policies").

    scripts/table2_trained.py --out out/table2_trained --reality 1=docs/img/calib_joints/s1/reality.yaml \
        --reality 2=docs/img/calib_joints/s2/reality.yaml --reality 3=docs/img/calib_joints/s3/reality.yaml [--bin build/bin]

For robot S (its hidden reality REALITY.yaml, `pmg_reality_draw --seed S --joints 4`), pmg_sim2real_eval
runs the four policies as deployed on that robot: Baseline (g1_sil_table2_baseline.yaml) and Physically
Informed Gains (g1_sil_table2_pig.yaml) are the same actors on every robot; Dynamic Calibration
(g1_sil_table2_dynamic_sS.yaml) is the actor trained on robot S's identified actuator models, deployed
with them; Dynamic + Zero-point (g1_sil_table2_dynamic_zero_sS.yaml) the same actor deployed with the
models and robot S's zero offsets. The reality is read only by the SIL that plays the real robot.
Rows are means over the robots (each robot's value is pmg_sim2real_eval's: RMS over the 12 leg
joints). Writes OUT/table2_trained.json ({"robots": {S: {policy: {mie, s2r, fell}}}, "mean": {policy:
{mie, s2r, falls}}, "paper": ...}), OUT/table2_trained.md and OUT/table2_trained.png; exit 1 when an
evaluation fails.
"""
import argparse
import json
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from sim2real_table import PAPER  # noqa: E402  (the paper's Table II values; same folder)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROWS = list(PAPER)


def configs(robot):
    c = os.path.join(ROOT, "config", "controller")
    return {"Baseline": os.path.join(c, "g1_sil_table2_baseline.yaml"),
            "Physically Informed Gains": os.path.join(c, "g1_sil_table2_pig.yaml"),
            "Dynamic Calibration": os.path.join(c, f"g1_sil_table2_dynamic_s{robot}.yaml"),
            "Dynamic + Zero-point": os.path.join(c, f"g1_sil_table2_dynamic_zero_s{robot}.yaml")}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--reality", action="append", required=True, metavar="S=REALITY.yaml",
                    help="robot S (its g1_sil_table2_dynamic*_sS.yaml) and its hidden reality; repeat per robot")
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    robots = {}
    for item in a.reality:
        robot, sep, path = item.partition("=")
        if not sep or not robot.isdigit() or not os.path.isfile(path):
            ap.error(f"--reality {item!r}: expected S=REALITY.yaml with S a robot number and an existing file")
        cfg = configs(robot)
        missing = [p for p in cfg.values() if not os.path.isfile(p)]
        if missing:
            ap.error(f"--reality {item!r}: no controller config {missing[0]} (robot {robot} has no trained Dynamic actor)")
        out = os.path.join(a.out, f"s{robot}")
        cmd = [os.path.join(a.bin, "pmg_sim2real_eval"), "--realities", path, "--out", out,
               "--policies", ",".join(f"{k}={v}" for k, v in cfg.items())]
        print(f"robot s{robot}: {' '.join(cmd[:5])} ...", flush=True)
        rc = subprocess.run(cmd, stdout=subprocess.DEVNULL).returncode
        if rc not in (0, 3):  # 3: a policy fell (reported in the summary)
            print(f"pmg_sim2real_eval failed on robot s{robot} (exit {rc})", file=sys.stderr)
            return 1
        s = json.load(open(os.path.join(out, "summary.json")))["policies"]
        robots[robot] = {k: {"mie": s[k]["motion_imitation_error_rad"], "s2r": s[k]["sim_to_real_error_rad"],
                             "fell": s[k]["falls"] > 0} for k in ROWS}
    n = len(robots)
    mean = {k: {"mie": sum(r[k]["mie"] for r in robots.values()) / n,
                "s2r": sum(r[k]["s2r"] for r in robots.values()) / n,
                "falls": sum(r[k]["fell"] for r in robots.values())} for k in ROWS}
    json.dump({"robots": robots, "mean": mean, "paper": {k: {"mie": v[0], "s2r": v[1]} for k, v in PAPER.items()}},
              open(os.path.join(a.out, "table2_trained.json"), "w"), indent=1)
    base = mean["Baseline"]["s2r"]
    lines = [f"| policy (trained) | Motion Imitation Error [rad] | Sim-to-Real Error [rad] | S2R / Baseline | falls | "
             + " | ".join(f"s{r} MIE / S2R" for r in robots) + " | paper MIE / S2R |",
             "|---|---|---|---|---|" + "---|" * n + "---|"]
    for k in ROWS:
        m = mean[k]
        lines.append(f"| {k} | {m['mie']:.4f} | {m['s2r']:.4f} | {m['s2r'] / base:.2f} | {m['falls']}/{n} | "
                     + " | ".join(f"{r[k]['mie']:.4f} / {r[k]['s2r']:.4f}" for r in robots.values())
                     + f" | {PAPER[k][0]:.4f} / {PAPER[k][1]:.4f} |")
    open(os.path.join(a.out, "table2_trained.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    width = 0.8 / (n + 2)
    for ax, col, title in zip(axes, ["mie", "s2r"], ["Motion Imitation Error [rad]", "Sim-to-Real Error [rad]"]):
        for j, (r, vals) in enumerate(robots.items()):
            ax.bar([i + j * width for i in range(len(ROWS))], [vals[k][col] for k in ROWS], width,
                   label=f"robot s{r}", alpha=0.55)
        ax.bar([i + n * width for i in range(len(ROWS))], [mean[k][col] for k in ROWS], width, label="mean", color="k")
        ax.bar([i + (n + 1) * width for i in range(len(ROWS))], [PAPER[k][0 if col == "mie" else 1] for k in ROWS],
               width, label="paper (its real robot)", color="tab:red", alpha=0.6)
        ax.set_xticks([i + (n + 1) * width / 2 for i in range(len(ROWS))])
        ax.set_xticklabels(["Baseline", "PIG", "Dynamic", "Dyn + Zero"])
        ax.set_title(title)
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=7, loc="lower left", framealpha=0.9)
    fig.suptitle(f"Table II, trained policies, {n} calibrated robots (SIL plays each hidden reality)")
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "table2_trained.png"), dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
