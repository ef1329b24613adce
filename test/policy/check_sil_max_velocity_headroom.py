#!/usr/bin/env python3
"""Checks velocity_feedback.max_velocity_headroom through the product path (ctest
pmg_policy_sil_max_velocity_headroom, label sil): the default config runs
test/data/policy/eval_fast_turns.yaml (turns in place at +-0.8 rad/s, the shaper's largest yaw rate, and a
tight right arc at 0.3 m/s, -0.8 rad/s) on seeds 0-1, off: with --max-velocity-headroom off, on: as shipped
(0.2 rad/s beyond max_velocity for the yaw rate).
The hidden effect: told 0.8 rad/s the actor turns 0.63-0.70, and off the corrected command may not leave
the shaper's +-0.8, so the correction has nowhere to go. On:
- the corrected yaw rate (the CSV's wz_fb, seed 0) goes beyond 0.8 rad/s in the turns (the cause), and
  never beyond the feedback's envelope, 1.0; off it never leaves +-0.8;
- off, at least two of the three turns miss issue 12's band (|w| below 0.68 rad/s, pooled over the seeds:
  the effect is there); on, all three are in band (0.68-0.92) and each turns at least 0.04 rad/s faster;
- the arc's v_x stays in its band (0.25-0.35 m/s for 0.3);
- the corrected command stays continuous (no tick changes wz_fb by more than 0.05 rad/s) and vanishes
  with the command: 1-3 s into the final stop the robot turns below 0.1 rad/s;
- on, no fall.
Usage: check_sil_max_velocity_headroom.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on, seg, window  # noqa: E402

SEED = 0
TURNS = ("turn_l_0.8", "turn_r_0.8", "arc_tight_r")


def checks(s_off, r_off, s_on, r_on):
    w_off = {n: abs(seg(s_off, n)["achieved"]["wz"]) for n in TURNS}
    w_on = {n: abs(seg(s_on, n)["achieved"]["wz"]) for n in TURNS}
    fb_off = max(abs(r["wz_fb"]) for r in r_off if r["wz_fb"] == r["wz_fb"])
    turning = [r for n in TURNS for r in window(r_on, n, 2.0, 8.0)]
    fb_on_turns = max(abs(r["wz_fb"]) for r in turning)
    active = [r for r in r_on if r["wz_fb"] == r["wz_fb"]]
    fb_on = max(abs(r["wz_fb"]) for r in active)
    jump = max(abs(b["wz_fb"] - a["wz_fb"]) for a, b in zip(active, active[1:]) if b["t"] - a["t"] < 0.015)
    stop = window(r_on, "stop", 1.0, 3.0)
    w_stop = abs(sum(r["wz"] for r in stop) / len(stop))
    arc_vx = seg(s_on, "arc_tight_r")["achieved"]["vx"]
    print("|w| achieved off / on [rad/s]: " + ", ".join(f"{n} {w_off[n]:.3f} / {w_on[n]:.3f}" for n in TURNS))
    print(f"largest |wz_fb|: off {fb_off:.3f}, on {fb_on:.3f} (in the turns {fb_on_turns:.3f}); on: largest step "
          f"{jump:.4f}, |w| 1-3 s into the stop {w_stop:.3f}, arc v_x {arc_vx:+.3f}")
    return {
        "off run has no headroom, on run the config's 0.2 rad/s":
            s_off["max_velocity_headroom"] == [0, 0, 0] and s_on["max_velocity_headroom"] == [0, 0, 0.2],
        "without it the corrected yaw rate never leaves max_velocity": fb_off <= 0.8 + 1e-9,
        "with it the corrected yaw rate goes beyond 0.8 in the turns (the cause)": fb_on_turns > 0.85,
        "with it, never beyond the envelope, 1.0 rad/s": fb_on <= 1.0 + 1e-9,
        "without it at least two turns miss the band (the effect is there)": sum(w < 0.68 for w in w_off.values()) >= 2,
        "with it every turn is in band": all(0.68 <= w <= 0.92 for w in w_on.values()),
        "with it every turn is at least 0.04 rad/s faster": all(w_on[n] >= w_off[n] + 0.04 for n in TURNS),
        "the arc's v_x stays in band": 0.25 <= arc_vx <= 0.35,
        "with it, the corrected command is continuous": jump <= 0.05,
        "with it, the turn stops with the command": w_stop < 0.1,
        "with it, no fall": all(len(r["falls_s"]) == 0 for r in s_on["runs"]),
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
