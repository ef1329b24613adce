#!/usr/bin/env python3
"""Checks pmg_policy_sil runs of the shipped full-PMG policy on the whole preset command sequence
(config/policies/eval_commands.yaml: stand, forward, backward, sideways, turns, combined, squat,
bend, lean; ctest pmg_policy_sil_full_sequence, label sil): no run falls, every run reaches the
end, the mean Table I errors stay below bounds about 1.5x what 5 seeds measured (training/README.md:
LinVel 0.122 m/s, YawVel 0.169 rad/s, Roll 0.042 rad, Pitch 0.050 rad, Height 0.005 m), the robot
really walks backward (mean v_x < -0.08 m/s over the last 3 s of the backward segment, commanded
-0.3 m/s after a 0.5 m/s forward segment; measured -0.12 to -0.23 m/s) and really squats (pelvis
below 0.70 m in the squat segment, commanded 0.66 m).
The per-segment block of summary.json (issue 12) is checked too: one entry per script segment with
the script's times and commands, every axis finite, the shaper's velocity command (`shaped`) never
larger than the command nor of the other sign, each mean equal to the one recomputed here from
the seed CSVs over the last 60 % of the segment, the ratios consistent, and the forward segment
tracked within a loose band (achieved and reference v_x within 0.5 m/s +-30 %; measured on the
shipped policy: achieved 0.47-0.49, reference 0.52). The issue's +-15 % targets are not asserted
yet (the policy is to be retrained).  Usage: check_sil_sequence.py OUT_DIR
"""
import csv
import json
import math
import os
import sys

import numpy as np
import yaml

AXES = ["vx", "vy", "wz", "pitch", "roll", "height"]
SEGMENT_KEYS = {"name", "t_begin", "t_end", "window", "seeds", "fallen", "command", "reference", "shaped", "achieved",
                "u_prime", "u_feedback", "estimate", "ratio", "reference_ratio", "feedback_held_fraction",
                "feedback_decayed_fraction"}

BOUNDS = {"lin_vel": 0.18, "yaw_vel": 0.25, "roll": 0.07, "pitch": 0.08, "height": 0.012}


def _last(x, t, seg, name, seconds):
    """Mean of x over the last `seconds` of segment `name` (nan if the run never got there)."""
    sel = seg == name
    if not sel.any():
        return float("nan")
    return float(x[sel & (t >= t[sel].max() - seconds)].mean())


def check_segments(out, summary, seeds):
    """Checks summary["segments"] against the script and the per-tick CSVs; returns {check: ok}."""
    checks = {}
    segs = summary.get("segments")
    checks["summary has a segments list"] = isinstance(segs, list)
    if not isinstance(segs, list):
        return checks
    script_path = summary.get("commands", "")  # as given to pmg_policy_sil (relative: same working directory)
    with open(script_path) as f:
        script = yaml.safe_load(f)
    checks[f"one entry per script segment ({len(script['segments'])})"] = len(segs) == len(script["segments"])
    csvs = {}
    for run in summary["runs"]:
        with open(f"{out}/seed{run['seed']}.csv") as f:
            rows = list(csv.DictReader(f))
        csvs[run["seed"]] = {k: np.array([float(r[k]) for r in rows]) for k in
                             ["t"] + AXES + [a + "_ref" for a in AXES[:5]] + ["height_ref"]}
    for s, sc in zip(segs, script["segments"]):
        name = s.get("name")
        good = set(s) == SEGMENT_KEYS and all(set(s[b]) == set(AXES) for b in
                                              ("command", "reference", "shaped", "achieved", "u_prime", "u_feedback",
                                               "estimate"))
        good &= all(set(s[b]) == {"vx", "vy", "wz"} for b in ("ratio", "reference_ratio"))
        checks[f"{name}: keys"] = good
        if not good:
            continue
        # The share of the window the velocity feedback did not integrate: a fraction when it is on, null when off.
        fractions = (s["feedback_held_fraction"], s["feedback_decayed_fraction"])
        checks[f"{name}: feedback held/decayed fractions"] = (
            all(isinstance(x, (int, float)) and 0.0 <= x <= 1.0 for x in fractions) if summary["velocity_feedback"]
            else all(x is None for x in fractions))
        checks[f"{name}: script's name, time, command"] = (
            name == sc["name"] and abs(s["t_begin"] - sc["t"]) < 1e-9 and
            all(abs(s["command"][a] - sc[a]) < 1e-9 for a in AXES))
        checks[f"{name}: window = last 60 %"] = abs(s["window"][0] - (s["t_begin"] + 0.4 * (s["t_end"] - s["t_begin"]))) < 1e-6
        checks[f"{name}: all {seeds} seeds, none fallen"] = s["seeds"] == seeds and s["fallen"] == 0
        if not summary.get("velocity_feedback", True):
            # Feedback off: the generator got the shaped command itself, and there is no estimate.
            checks[f"{name}: u_feedback = command, no estimate (feedback off)"] = (
                all(abs(s["u_feedback"][a] - s["command"][a]) < 1e-6 for a in AXES[:3]) and
                all(s["estimate"][a] is None for a in AXES))
        vals = [s[b][a] for b in ("reference", "shaped", "achieved", "u_prime") for a in AXES]
        checks[f"{name}: finite"] = all(v is not None and math.isfinite(v) for v in vals)
        if not checks[f"{name}: finite"]:
            continue
        # The shaper only slows: its velocity command keeps the command's sign and is not larger.
        checks[f"{name}: shaped velocity within the command"] = all(
            s["shaped"][a] * s["command"][a] >= -1e-9 and abs(s["shaped"][a]) <= abs(s["command"][a]) + 1e-6
            for a in AXES[:3])
        # Recompute the means from the per-tick CSVs: per seed over the window, then over seeds.
        w0, w1 = s["window"]
        worst = 0.0
        for block, suffix in (("achieved", ""), ("reference", "_ref")):
            for a in AXES:
                col = "height_ref" if (a == "height" and suffix) else a + suffix
                per_seed = []
                for d in csvs.values():
                    sel = (d["t"] >= w0 - 1e-6) & (d["t"] < w1 - 1e-6)
                    per_seed.append(np.nanmean(d[col][sel]))
                worst = max(worst, abs(float(np.mean(per_seed)) - s[block][a]))
        checks[f"{name}: means equal the CSVs' ({worst:.1e})"] = worst < 1e-3
        for a in ("vx", "vy", "wz"):
            c = s["command"][a]
            for rb, b in (("ratio", "achieved"), ("reference_ratio", "reference")):
                want = s[b][a] / c if abs(c) >= summary["ratio_min_command"] else None
                got = s[rb][a]
                checks[f"{name}: {rb}.{a}"] = (got is None) if want is None else (
                    got is not None and abs(got - want) < 1e-4 * max(1.0, abs(want)))
    # The reference posture is measured as the robot stands on it (stance soles flat): the bend
    # template (command 0.30 rad) then carries 0.236 rad; the level pelvis the generator plays gave 0.174.
    bend = next((s for s in segs if s.get("name") == "bend"), None)
    if bend is not None and bend.get("seeds"):
        v = bend["reference"]["pitch"]
        checks[f"bend reference pitch {v:.3f} (soles flat) in [0.2, 0.3]"] = 0.2 <= v <= 0.3
    fwd = next((s for s in segs if s.get("name") == "forward"), None)
    checks["forward segment present"] = fwd is not None
    if fwd is not None and fwd.get("seeds"):
        for b in ("achieved", "reference"):
            v = fwd[b]["vx"]
            checks[f"forward {b} v_x {v:.3f} within 0.5 +-30 %"] = 0.35 <= v <= 0.65
        checks[f"stand achieved |v_x| {abs(segs[0]['achieved']['vx']):.3f} < 0.1"] = abs(segs[0]["achieved"]["vx"]) < 0.1
    return checks


def main(out):
    with open(f"{out}/summary.json") as f:
        summary = json.load(f)
    ok = True
    for k, good in check_segments(out, summary, len(summary["runs"])).items():
        print(("ok   " if good else "FAIL ") + "segments: " + k)
        ok &= bool(good)
    for run in summary["runs"]:
        seed = run["seed"]
        with open(f"{out}/seed{seed}.csv") as f:
            rows = list(csv.DictReader(f))
        seg = np.array([r["segment"] for r in rows])
        vx = np.array([float(r["vx"]) for r in rows])
        h = np.array([float(r["height"]) for r in rows])
        t = np.array([float(r["t"]) for r in rows])
        checks = {"no fall": not run["fell"], "ran the whole sequence": t[-1] >= summary["duration_s"] - 0.02,
                  "walks backward (mean v_x < -0.08 m/s, last 3 s)": _last(vx, t, seg, "backward", 3.0) < -0.08,
                  "squats (pelvis < 0.70 m)": (seg == "squat").any() and h[seg == "squat"].min() < 0.70}
        for k, b in BOUNDS.items():
            checks[f"{k} {run[k]:.4f} < {b}"] = run[k] < b
        for k, good in checks.items():
            print(f"seed {seed}: " + ("ok   " if good else "FAIL ") + k)
            ok &= bool(good)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
