#!/usr/bin/env python3
"""Checks the upset guard through the product path (ctest pmg_policy_sil_upset_guard, label sil): the
default config with velocity_feedback.upset_guard made so tight (max_error 0.1 m/s, 0.1 m/s,
0.3 rad/s; trigger_s 0.2 s; settle 0.5 s) that a walk's start trips it, runs
test/data/policy/eval_upset_guard.yaml (two 0.6 m/s walks with a stand between) with the guard off
and on (pmg_policy_sil --upset-guard off|on --seeds 1).
Off: both walks reach 0.6 m/s and no upset is listed. On:
- each walk latches the guard once (runs[0].upsets_s: one time in walk_1, one in walk_2): the
  release needs the robot settled with the command neutral (stand_1), and the next walk trips it anew;
- while it holds, the velocity command after the feedback (vx_fb) goes to zero although the script
  still commands 0.6 m/s, and stays continuous: no tick changes it by more than 0.03 m/s (the
  shaper's 1 m/s^2 slew, its feedback share and the integral);
- the robot stops: walk_1's achieved v_x (its last 60 %) is below 0.2 m/s, against off's above 0.45;
- no fall.
Usage: check_sil_upset_guard.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import rows  # noqa: E402


def seg(s, name):
    return next(x for x in s["segments"] if x["name"] == name)


def main(off_dir, on_dir):
    s_off, r_off = rows(off_dir, 0)
    s_on, r_on = rows(on_dir, 0)
    ups_off, ups_on = s_off["runs"][0]["upsets_s"], s_on["runs"][0]["upsets_s"]
    w1, s1, w2 = seg(s_on, "walk_1"), seg(s_on, "stand_1"), seg(s_on, "walk_2")
    in_walk1 = [t for t in ups_on if w1["t_begin"] <= t < s1["t_begin"]]
    in_walk2 = [t for t in ups_on if w2["t_begin"] <= t < w2["t_end"]]
    held = [r for r in r_on if r["upset_hold"] == 1.0]
    steps = [abs(b["vx_fb"] - a["vx_fb"]) for a, b in zip(r_on, r_on[1:]) if a["mode"] == b["mode"] == "active"]
    walk1_end = [r for r in r_on if s1["t_begin"] - 0.5 <= r["t"] < s1["t_begin"]]
    print(f"upsets off {ups_off}, on {ups_on}; walk_1 v_x off {seg(s_off, 'walk_1')['achieved']['vx']:+.3f}, "
          f"on {w1['achieved']['vx']:+.3f}; held ticks {len(held)}; largest vx_fb step {max(steps):.4f}; "
          f"vx_fb at walk_1's end {walk1_end[-1]['vx_fb']:+.3f} (command {walk1_end[-1]['vx_cmd']:+.3f})")
    checks = {
        "off: no guard, no upset listed": s_off["upset_guard"] is False and ups_off == [],
        "on: the guard is on": s_on["upset_guard"] is True,
        "off: walk_1 reaches the command (the effect is the guard's)": seg(s_off, "walk_1")["achieved"]["vx"] > 0.45,
        "on: one upset in each walk (released in the stand, tripped anew)": len(in_walk1) == 1 and len(in_walk2) == 1 and len(ups_on) == 2,
        "on: the command after the feedback goes to zero while the script still commands 0.6": all(
            abs(r["vx_fb"]) < 1e-6 and r["vx_cmd"] > 0.55 for r in walk1_end),
        "on: it stays continuous (no step above 0.03 m/s per tick)": max(steps) <= 0.03,
        "on: the robot stops (walk_1 below 0.2 m/s)": w1["achieved"]["vx"] < 0.2,
        "on: released in the stand (not held at its end)": any(
            r["upset_hold"] == 0.0 for r in r_on if s1["t_begin"] <= r["t"] < w2["t_begin"]),
        "no fall": all(len(r["falls_s"]) == 0 for r in s_on["runs"] + s_off["runs"]),
    }
    for name, ok in checks.items():
        print(("ok   " if ok else "FAIL ") + name)
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
