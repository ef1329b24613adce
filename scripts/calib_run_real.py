#!/usr/bin/env python3
"""Runs pmg_calib_dynamics on the three real data sets in config/bench/data/ and writes reports
(JSON), plots (PNG), console summaries and identified `actuator:` blocks into docs/calibration/,
then prints the markdown table used in docs/calibration.md.

Usage: scripts/calib_run_real.py [--build BUILD_DIR] [--only NAME ...] [--table-only] [--jobs N] [--threads T]
                                 [--out DIR] [--no-plot] [--exe CMD]

--jobs N runs N experiments at a time (each with --threads T workers); --exe replaces the
pmg_calib_dynamics command (e.g. a loader line on another machine); --out writes elsewhere than
docs/calibration (the table reads from there too).
"""
import argparse
import concurrent.futures
import json
import os
import shlex
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = "config/bench/data"
OUT = "docs/calibration"

XL330 = {100: ["10h28m10", "10h28m17", "10h28m24", "10h28m32"],
         200: ["10h28m42", "10h28m49", "10h28m57", "10h29m04"],
         400: ["10h29m14", "10h29m21", "10h29m29", "10h29m37"],
         800: ["10h29m47", "10h29m54", "10h30m02", "10h30m10"]}


def experiments():
    s = f"{DATA}/bam_sts3250"
    yield ("bam_sts3250", "config/bench/bam_sts3250.yaml",
           [f"{s}/2024-10-26_12h23m27.json", f"{s}/2024-10-26_12h23m42.json", f"{s}/2024-10-26_12h27m27.json"],
           [f"{s}/2024-10-26_12h24m55.json"])
    # DFKI energy shaping is torque-controlled (no position feedback) and balances the pendulum
    # upright for seconds: an open-loop replay of the logged torque falls off that unstable
    # equilibrium, so the run is cut into 0.5 s windows (multiple shooting), each started from the
    # measured state; even windows train, odd windows are held out (the run has several
    # swing-up / balance / fall phases, and both sets should see each kind).
    e = f"{DATA}/dfki_ak80_6/energy_shaping/data_measured.csv"
    win = [(round(0.5 * k, 1), round(0.5 * k + 0.5, 1)) for k in range(40)]
    yield ("dfki_ak80_6", "config/bench/dfki_ak80_6.yaml",
           [f"{e}@{a}:{b}" for k, (a, b) in enumerate(win) if k % 2 == 0],
           [f"{e}@{a}:{b}" for k, (a, b) in enumerate(win) if k % 2 == 1])
    x = f"{DATA}/bam_xl330"
    for held in (100, 200, 400, 800):
        train = [f"{x}/2026-01-15_{f}.json" for kp, fs in XL330.items() if kp != held for f in fs]
        ho = [f"{x}/2026-01-15_{f}.json" for f in XL330[held]]
        yield (f"bam_xl330_heldout_kp{held}", "config/bench/bam_xl330.yaml", train, ho)


def table(out=OUT):
    rows = ["| run | noise floor [mrad] | folds | baseline CV / held-out RMSE [rad] | extended CV / held-out RMSE [rad] | "
            "held-out gain | named causes (CV gain) | parameters |",
            "|---|---|---|---|---|---|---|---|"]
    for name, *_ in experiments():
        path = os.path.join(ROOT, out, name + ".json")
        if not os.path.exists(path):
            continue
        r = json.load(open(path))
        b, e = r["baseline"]["heldout_rmse_rad"], r["extended"]["heldout_rmse_rad"]
        bcv, ecv = r["baseline"]["selection"]["cv_rmse_rad"], r["extended"]["selection"]["cv_rmse_rad"]
        causes = ", ".join(f"{c['name']} ({c['gain']:.2f})" for c in r["causes"]) or "none"
        skip = ("kp_scale", "kd_scale", "kp_per_log_unit", "kd_per_log_unit")
        params = ", ".join(f"{k} {v:.4g}" for k, v in r["extended"]["params"].items() if k not in skip)
        sel = r["selection"]
        rows.append(f"| {name} | {1e3 * r['noise_floor_rad']:.2f} | {sel['folds']} {sel['fold_unit'].replace('_', ' ')} | "
                    f"{bcv:.4f} / {b:.4f} | {ecv:.4f} / {e:.4f} | {1 - e / b:.2f} | {causes} | {params} |")
    rows += ["", "Held-out RMSE [rad] per residual region, baseline → extended (share of samples):", "",
             "| run | velocity reversals | high torque | steady holds | fast moves |", "|---|---|---|---|---|"]
    for name, *_ in experiments():
        path = os.path.join(ROOT, out, name + ".json")
        if not os.path.exists(path):
            continue
        reg = {g["region"]: g for g in json.load(open(path))["residual_regions"]}
        cells = [f"{reg[k]['baseline_rmse_rad']:.3f} → {reg[k]['extended_rmse_rad']:.3f} ({100 * reg[k]['fraction_of_samples']:.0f} %)"
                 for k in ("velocity_reversal", "high_torque", "steady_hold", "fast_move")]
        rows.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--table-only", action="store_true")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=OUT)
    ap.add_argument("--no-plot", action="store_true")
    ap.add_argument("--exe")
    a = ap.parse_args()
    out = a.out
    os.makedirs(os.path.join(ROOT, out), exist_ok=True)
    if not a.table_only:
        exe = shlex.split(a.exe) if a.exe else [os.path.join(a.build, "bin", "pmg_calib_dynamics")]

        def run(job):
            name, rig, train, ho = job
            cmd = [*exe, "--rig", rig, "--train", *train, "--heldout", *ho, "--threads", str(a.threads),
                   "--report", f"{out}/{name}.json", "--actuator-out", f"{out}/{name}.actuator.yaml"]
            if not a.no_plot:
                cmd += ["--plot", f"{out}/{name}.png"]
            res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
            open(os.path.join(ROOT, out, name + ".txt"), "w").write(res.stdout)
            return name, res

        jobs = [e for e in experiments() if not a.only or e[0] in a.only]
        rc = 0
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
            for name, res in pool.map(run, jobs):
                print("==", name, flush=True)
                print(res.stdout, end="")
                if res.returncode != 0:
                    print(res.stderr, file=sys.stderr)
                    rc = res.returncode
        if rc:
            return rc
    print(table(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
