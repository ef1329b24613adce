#!/usr/bin/env python3
"""Table II analogue on calibrated realities (issue 15): what calibration changes when one actor is
deployed with and without it.

    scripts/sim2real_table.py --out out/table2 out/reality_s1 out/reality_s2 out/reality_s3 [--build build]
                              [--controller config/controller/g1_sil_policy_consistent.yaml]

Each REALITY_DIR is the output of scripts/calib_reality_check.py: reality.yaml (the hidden truth,
used here only by the SIL that plays the real robot), calibrated_robot.yaml (pmg_calib_joints'
actuator blocks + `zero_offsets: zero.yaml` from pmg_calib_zero). Per reality, pmg_sim2real_eval
runs the same actor three ways (controller configs written into OUT):
  Baseline               the nominal robot config (no calibration)
  Dynamic Calibration    the calibrated robot config without its zero offsets
  Dynamic + Zero-point   the calibrated robot config
The trained rows (an actor per row, test table2_trained_policies) are in docs/calibration.md, "Table II
with trained policies"; here the actor is the same, so Motion Imitation Error changes only through the
zero offsets the HAL corrects, and Sim-to-Real Error measures how well each deployed simulator predicts
the real robot. A REALITY_DIR's calibrated_robot.yaml may use model paths relative to it. Writes OUT/table2.json, OUT/table2.md and OUT/table2.png.
"""
import argparse
import json
import os
import re
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER = {"Baseline": (0.0571, 0.0781), "Physically Informed Gains": (0.0747, 0.0656),
         "Dynamic Calibration": (0.0682, 0.0562), "Dynamic + Zero-point": (0.0562, 0.0414)}
ROWS = ["Baseline", "Dynamic Calibration", "Dynamic + Zero-point"]


def controller_with_robot(src, robot, path):
    """The controller config src with robot: replaced and every relative path made absolute."""
    base = os.path.dirname(os.path.abspath(src))
    out = []
    for line in open(src):
        m = re.match(r"^(\s*[A-Za-z_]+:\s*)(\.\./[^\s#]*)(.*)$", line)
        if m:
            line = m.group(1) + os.path.normpath(os.path.join(base, m.group(2))) + m.group(3) + "\n"
        if line.startswith("robot:"):
            line = f"robot: {robot}\n"
        out.append(line)
    open(path, "w").write("".join(out))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("realities", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--controller", default=os.path.join(ROOT, "config", "controller", "g1_sil_policy_consistent.yaml"))
    a = ap.parse_args()
    a.out = os.path.abspath(a.out)
    os.makedirs(a.out, exist_ok=True)
    exe = os.path.join(os.path.abspath(a.build), "bin", "pmg_sim2real_eval")
    results = {r: [] for r in ROWS}
    for rdir in a.realities:
        rdir = os.path.abspath(rdir)
        tag = os.path.basename(rdir)
        cal = os.path.join(rdir, "calibrated_robot.yaml")
        nozero = os.path.join(a.out, f"{tag}_robot_dynamic.yaml")
        # The calibrated config without its zero offsets (the Dynamic Calibration row).
        # (written elsewhere: its relative model paths made absolute)
        text = "".join(re.sub(r"^(\s*(?:urdf|mjcf):\s*)([^\s#/][^\s#]*)",
                              lambda m: m.group(1) + os.path.normpath(os.path.join(rdir, m.group(2))), l)
                       for l in open(cal) if not l.startswith("zero_offsets:"))
        open(nozero, "w").write(text)
        cfgs = {"Baseline": os.path.join(a.out, f"{tag}_baseline.yaml"),
                "Dynamic Calibration": os.path.join(a.out, f"{tag}_dynamic.yaml"),
                "Dynamic + Zero-point": os.path.join(a.out, f"{tag}_dynamic_zero.yaml")}
        controller_with_robot(a.controller, os.path.join(ROOT, "config", "robots", "g1", "g1.yaml"), cfgs["Baseline"])
        controller_with_robot(a.controller, nozero, cfgs["Dynamic Calibration"])
        controller_with_robot(a.controller, cal, cfgs["Dynamic + Zero-point"])
        run_out = os.path.join(a.out, tag)
        pol = ",".join(f"{n}={p}" for n, p in cfgs.items())
        print(f"== {tag}", flush=True)
        rc = subprocess.run([exe, "--policies", pol, "--realities", os.path.join(rdir, "reality.yaml"), "--out", run_out]).returncode
        if rc not in (0, 3):
            sys.exit(f"pmg_sim2real_eval failed on {tag} ({rc})")
        s = json.load(open(os.path.join(run_out, "summary.json")))
        for n in ROWS:
            pr = s["policies"][n]["per_reality"][0]
            results[n].append({"reality": tag, "mie": pr["motion_imitation_error_rad"],
                               "s2r": pr["sim_to_real_error_rad"], "fell": pr["fell"]})
    table = {}
    for n in ROWS:
        k = len(results[n])
        table[n] = {"motion_imitation_error_rad": sum(x["mie"] for x in results[n]) / k,
                    "sim_to_real_error_rad": sum(x["s2r"] for x in results[n]) / k, "per_reality": results[n],
                    "paper": PAPER[n]}
    base = table["Baseline"]["sim_to_real_error_rad"]
    json.dump({"rows": table, "actor": a.controller, "realities": a.realities}, open(os.path.join(a.out, "table2.json"), "w"),
              indent=1)
    lines = ["| policy (one actor) | Motion Imitation Error [rad] | Sim-to-Real Error [rad] | S2R / Baseline | paper MIE / S2R |",
             "|---|---|---|---|---|"]
    for n in ROWS:
        t = table[n]
        lines.append(f"| {n} | {t['motion_imitation_error_rad']:.4f} | {t['sim_to_real_error_rad']:.4f} | "
                     f"{t['sim_to_real_error_rad'] / base:.2f} | {PAPER[n][0]} / {PAPER[n][1]} |")
    lines.append(f"| Physically Informed Gains | a trained row only (docs/calibration.md, 'Table II with trained policies') | | | "
                 f"{PAPER['Physically Informed Gains'][0]} / {PAPER['Physically Informed Gains'][1]} |")
    open(os.path.join(a.out, "table2.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, key, idx, title in ((axes[0], "mie", 0, "Motion Imitation Error"), (axes[1], "s2r", 1, "Sim-to-Real Error")):
        xs = range(len(ROWS))
        ax.bar([x - 0.2 for x in xs], [table[n]["motion_imitation_error_rad" if key == "mie" else "sim_to_real_error_rad"]
                                       for n in ROWS], 0.4, label="SIL, one actor (mean)")
        for x, n in zip(xs, ROWS):
            ax.plot([x - 0.2] * len(results[n]), [r[key] for r in results[n]], "k.", ms=5)
        ax.bar([x + 0.2 for x in xs], [PAPER[n][idx] for n in ROWS], 0.4, hatch="//", alpha=0.5, label="paper (hardware)")
        ax.set_xticks(list(xs))
        ax.set_xticklabels([n.replace(" + ", "\n+ ") for n in ROWS], fontsize=8)
        ax.set_ylabel("[rad]")
        ax.set_title(title)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "table2.png"), dpi=100)
    print("wrote", os.path.join(a.out, "table2.png"))


if __name__ == "__main__":
    main()
