#!/usr/bin/env python3
"""Checks the default config's height limit through the product path (ctest pmg_policy_sil_squat_limit,
label sil): test/data/policy/eval_squat_deep.yaml (a squat standing still to 0.45 m, held 5 s, then
standing up) on seed 5 with H10a's actor (--model; F13, the default's actor since 2026-12-07, does not fall
here without the limit), with the default config's commands.height_range minimum (0.59 m, the lowest
height its actor was trained to) replaced by the old 0.45 (off) and as shipped (on).
The hidden effect: told 0.45 m, below anything it was trained on, the actor walks backwards at about
0.7 m/s while told to stand still, and in seed 5 falls. On:
- the generator's base height (height_ref of the CSV: the reference the shaped command gives) never
  goes below 0.585 m while the policy is active; off it goes below 0.5 (the effect's cause is there);
- off, the robot falls (the effect is there); on, no fall and no upset-guard latch;
- on, the squat still goes down: the pelvis below 0.66 m in the squat segment (mean of its last 60 %),
  and the robot stays put (|v_x| below 0.1 m/s there).
Usage: check_sil_squat_limit.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on, seg  # noqa: E402

SEED = 5


def checks(s_off, r_off, s_on, r_on):
    low_off = min(r["height_ref"] for r in r_off if r["episode"] == 0 and r["mode"] == "active")
    low_on = min(r["height_ref"] for r in r_on if r["episode"] == 0 and r["mode"] == "active")
    squat = seg(s_on, "squat")["achieved"]
    falls_off = sum(len(r["falls_s"]) for r in s_off["runs"])
    run_on = s_on["runs"][0]
    print(f"lowest reference base height: off {low_off:.3f}, on {low_on:.3f} m; falls off {falls_off}, on {len(run_on['falls_s'])}; "
          f"on: latches {run_on['upsets_s']}, squat pelvis {squat['height']:.3f} m, v_x {squat['vx']:+.3f} m/s")
    return {
        "off, the reference goes below 0.5 m (the cause is there)": low_off < 0.5,
        "on, never below 0.585 m": low_on >= 0.585,
        "off, the robot falls (the effect is there)": falls_off > 0,
        "on, no fall": len(run_on["falls_s"]) == 0,
        "on, no upset-guard latch": len(run_on["upsets_s"]) == 0,
        "on, the squat goes down and the robot stays put": squat["height"] < 0.66 and abs(squat["vx"]) < 0.1,
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
