#!/usr/bin/env python3
"""Checks pmg_policy_sil --restart-after-fall (ctest pmg_policy_sil_restart_after_fall, label sil) on
test/data/policy/eval_fall_restart.yaml: stand 2 s, the operator's e-stop (mode: damping) in
`estop` drops the robot, then `stand_2` and `forward` (0.4 m/s). Expected: one fall, inside `estop`;
one restart, whose fresh robot stands 2 s before `stand_2` (CSV rows `restart_stand`, episode 1);
`estop` has no seed and counts the fall; `stand`, `stand_2` and `forward` have their seed, with
finite means, and the robot walks forward again (achieved v_x > 0.2 m/s).
Usage: check_sil_restart.py OUT_DIR
"""
import csv
import json
import math
import sys


def main(out):
    with open(f"{out}/summary.json") as f:
        summary = json.load(f)
    run = summary["runs"][0]
    segs = {s["name"]: s for s in summary["segments"]}
    with open(f"{out}/seed0.csv") as f:
        rows = list(csv.DictReader(f))
    ep1 = [r for r in rows if r["episode"] == "1"]
    estop = segs.get("estop", {})
    fall = run["falls_s"][0] if run["falls_s"] else math.nan
    checks = {
        "one fall, one restart": run["fell"] and run["restarts"] == 1 and len(run["falls_s"]) == 1,
        f"the fall ({fall:.2f} s) is in estop": estop and estop["t_begin"] <= fall < estop["t_end"],
        "estop: no seed, one fallen": estop and estop["seeds"] == 0 and estop["fallen"] == 1,
        "episode 1 starts standing 2 s before stand_2": bool(ep1) and ep1[0]["segment"] == "restart_stand"
        and abs(float(ep1[0]["t"]) - (segs["stand_2"]["t_begin"] - 2.0)) < 0.015,
        "episode 1 runs to the end": bool(ep1) and float(ep1[-1]["t"]) >= summary["duration_s"] - 0.02,
    }
    for name in ("stand", "stand_2", "forward"):
        s = segs[name]
        checks[f"{name}: 1 seed, 0 fallen, finite"] = s["seeds"] == 1 and s["fallen"] == 0 and all(
            v is not None and math.isfinite(v) for b in ("achieved", "reference") for v in s[b].values())
    vx = segs["forward"]["achieved"]["vx"]
    checks[f"walks again after the restart (v_x {vx if vx is not None else math.nan:.3f} > 0.2 m/s)"] = (
        vx is not None and vx > 0.2)
    for k, ok in checks.items():
        print(("ok   " if ok else "FAIL ") + k)
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
