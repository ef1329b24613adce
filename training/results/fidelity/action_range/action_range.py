#!/usr/bin/env python3
"""Does the PMG reference lie inside the actor's reach? Per segment of a pmg_policy_sil run.

An actor's leg joint target is q_des = q_stand + scale * clamp(a, -1, 1) [rad] (the ONNX contract's action offset and
scale; the offset is the standing pose of config/robots/g1/g1.yaml, the scale the run's train_config.json
"action_scale"). So the actor can command nothing outside [q_stand - scale, q_stand + scale], whatever the reference
asks. This reads the reference (qref0..11) and the measured joints (q0..11) of pmg_policy_sil's per-seed CSVs and
prints, per segment and leg joint kind (both legs pooled): the share of ticks whose reference lies outside that range
and its largest excess [rad]. With --probe (pmg_policy_sil --probe of the same run: the first CSV's seed) it also prints the
actor's mean |action| per segment for the hip pitch, knee and ankle pitch (1.0 = the clamp).

    .venv-training/bin/python training/results/fidelity/action_range/action_range.py OUT/seed0.csv \\
        --train-config training/results/fidelity/crouched_box/H10a/train_config.json [--probe OUT/probe.csv] [--json F]
"""
import argparse
import collections
import csv
import json
import os
import sys

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4))
KINDS = ("hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll")


def leg_range(train_config):
    """(lower, upper) lists of the 12 leg joints' reachable targets [rad], clipped to the joint limits."""
    with open(os.path.join(ROOT, "config/robots/g1/g1.yaml")) as f:
        joints = yaml.safe_load(f)["joints"][:12]
    try:
        with open(train_config) as f:
            scale = json.load(f)["action_scale"]
    except (OSError, ValueError, KeyError) as e:
        raise SystemExit(f"--train-config {train_config}: no action_scale ({e})")
    if len(scale) != 12:
        raise SystemExit(f"--train-config {train_config}: action_scale has {len(scale)} values, expected 12")
    lo = [max(j["lower"], j["default"] - s) for j, s in zip(joints, scale)]
    hi = [min(j["upper"], j["default"] + s) for j, s in zip(joints, scale)]
    return lo, hi


def reference_outside(paths, lo, hi):
    """{segment: {"ticks": n, kind: [ticks outside, largest excess, measured min, measured max]}}, legs pooled."""
    out = collections.OrderedDict()
    for path in paths:
        with open(path) as f:
            for r in csv.DictReader(f):
                s = out.setdefault(r["segment"], {"ticks": 0})
                s["ticks"] += 2
                for j in range(12):
                    k = KINDS[j % 6]
                    q_ref, q = float(r[f"qref{j}"]), float(r[f"q{j}"])
                    e = s.setdefault(k, [0, 0.0, q, q])
                    excess = max(lo[j] - q_ref, q_ref - hi[j], 0.0)
                    if excess > 0:
                        e[0] += 1
                        e[1] = max(e[1], excess)
                    e[2], e[3] = min(e[2], q), max(e[3], q)
    return out


def action_use(path, seed_csv):
    """{segment: [mean |a| of hip pitch, knee, ankle pitch]} from a probe CSV (active ticks), each tick given the
    segment of the seed CSV's row at the same time t [s]."""
    with open(seed_csv) as f:
        segment_at = {round(float(r["t"]), 3): r["segment"] for r in csv.DictReader(f)}
    use = collections.OrderedDict()
    with open(path) as f:
        for r in csv.DictReader(f):
            seg = segment_at.get(round(float(r["t"]), 3))
            if r["mode"] != "active" or seg is None:
                continue
            u = use.setdefault(seg, [0, 0.0, 0.0, 0.0])
            u[0] += 2
            for c, j in enumerate((0, 3, 4)):
                u[1 + c] += abs(float(r[f"action{j}"])) + abs(float(r[f"action{j + 6}"]))
    return {k: [v / u[0] for v in u[1:]] for k, u in use.items()}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", nargs="+", help="pmg_policy_sil per-seed CSVs (OUT/seedN.csv)")
    ap.add_argument("--train-config", required=True, help="the actor's train_config.json (its action_scale)")
    ap.add_argument("--probe", default=None, help="pmg_policy_sil --probe CSV of the same run (actions)")
    ap.add_argument("--json", default=None, help="write the table as JSON")
    args = ap.parse_args(argv)
    lo, hi = leg_range(args.train_config)
    print("reachable targets [rad] (left leg): " + ", ".join(f"{k} {lo[j]:+.3f}..{hi[j]:+.3f}"
                                                         for j, k in enumerate(KINDS)))
    table = reference_outside(args.csv, lo, hi)
    print(f"{'segment':24s} {'reference outside the reach: share of ticks (largest excess rad)':66s} | measured knee")
    for seg, s in table.items():
        cells = [f"{k} {100 * s[k][0] / s['ticks']:3.0f}% ({s[k][1]:.2f})" for k in KINDS if s[k][0] > 0]
        print(f"{seg:24s} {', '.join(cells) or '-':66s} | {s['knee'][2]:.2f}..{s['knee'][3]:.2f}")
    if args.probe:
        print("\nmean |action| (1.0 = the clamp): segment hip_pitch knee ankle_pitch")
        for seg, u in action_use(args.probe, args.csv[0]).items():
            print(f"{seg:24s} {u[0]:.2f} {u[1]:.2f} {u[2]:.2f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"reach_lower": lo, "reach_upper": hi, "segments": table}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
