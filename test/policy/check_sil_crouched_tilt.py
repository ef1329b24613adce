#!/usr/bin/env python3
"""Checks velocity_feedback.max_tilt_rad through the product path (ctest pmg_policy_sil_crouched_tilt, label sil):
the default config with H10a's actor (--model; F13, the default's actor since 2026-12-07, gains less here) runs test/data/policy/eval_crouched_tilt.yaml (crouched to the 0.66 m walking floor, a
forward side-step (0.9, 0.3) and a forward turn (0.9, -0.6), each stopped) on seed 0,
off: --max-tilt-rad 0.3 (the gate before 2026-12-06), on: as shipped (0.6), both with --walking-ki 3 0
--walking-filter-time-s 1 --stop-settle-s 0 (roll not fed back while walking and the walking posture loop undamped, the
config the gate was measured on; the roll feedback adopted after it raises the side-step's v_y at 0.3 by itself).
The hidden effect: H10a walks these gaits with its pelvis 0.3-0.43 rad from vertical, so with the gate at 0.3 the
velocity feedback's correction decays for most of the walk and the robot walks what the actor makes of the
feed-forward's command. Read from summary.json (pooled segments; feedback_decayed_fraction: the share of the window's
ticks in which the pelvis tilt made the correction decay) and the per-tick CSV (pelvis_tilt):
- off, the pelvis tilt's median over the side-step's window is above 0.3 rad, the correction decays in more than
  80 % of it and in more than half of the turn's;
- on, the correction decays in less than 10 % of either walk, the side-step's corrected v_y command is higher than
  off, the side-step's v_y is in band (+-15 % or 0.05 m/s) and at least 0.05 m/s more than off (the effect: seed 0,
  8 s walks, v_y 0.234 off, 0.318 on);
- on, the robot stops after each walk (|v_x| below 0.1 m/s 1-3 s into the stop) and does not fall.
Usage: check_sil_crouched_tilt.py OFF_DIR ON_DIR
"""
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import last60, run_off_on, seg, stop_speed  # noqa: E402

SEED = 0
SIDE, TURN = "fwd_side_0.66", "fwd_turn_0.66"


def in_band(achieved, command, rel=0.15, floor=0.05):
    return abs(achieved - command) <= max(rel * abs(command), floor) + 1e-9


def checks(s_off, r_off, s_on, r_on):
    tilt_off = statistics.median(r["pelvis_tilt"] for r in last60(r_off, SIDE))
    dec = {(tag, n): seg(s, n)["feedback_decayed_fraction"] for tag, s in (("off", s_off), ("on", s_on)) for n in (SIDE, TURN)}
    vy = {tag: seg(s, SIDE)["achieved"]["vy"] for tag, s in (("off", s_off), ("on", s_on))}
    vy_fb = {tag: seg(s, SIDE)["u_feedback"]["vy"] for tag, s in (("off", s_off), ("on", s_on))}
    stops = [abs(stop_speed(r_on, n)) for n in ("stop_fwd_side", "stop_fwd_turn")]
    print(f"off: pelvis tilt median {tilt_off:.3f} rad in {SIDE}; decayed {dec['off', SIDE]:.0%} / {dec['off', TURN]:.0%}; "
          f"v_y {vy['off']:+.3f} (command after the feedback {vy_fb['off']:+.3f})")
    print(f"on: decayed {dec['on', SIDE]:.0%} / {dec['on', TURN]:.0%}; v_y {vy['on']:+.3f} (command after the feedback "
          f"{vy_fb['on']:+.3f}); |v_x| 1-3 s into the stops {stops[0]:.3f}, {stops[1]:.3f} m/s")
    return {
        "the summaries record the gate (off 0.3, on 0.6)":
            abs(s_off.get("max_tilt_rad", -1) - 0.3) < 1e-9 and abs(s_on.get("max_tilt_rad", -1) - 0.6) < 1e-9,
        "off: the side-step's pelvis tilt median is beyond 0.3 rad (the cause is there)": tilt_off > 0.3,
        "off: the correction decays in more than 80 % of the side-step and half of the turn":
            dec["off", SIDE] > 0.8 and dec["off", TURN] > 0.5,
        "on: the correction decays in less than 10 % of either walk": dec["on", SIDE] < 0.1 and dec["on", TURN] < 0.1,
        "on: the side-step's corrected v_y command is higher than off": vy_fb["on"] > vy_fb["off"] + 0.01,
        "on: the side-step's v_y in band": in_band(vy["on"], 0.3),
        "on: the side-step's v_y at least 0.05 m/s more than off (the effect is there)": vy["on"] >= vy["off"] + 0.05,
        "on: the robot stops after each walk": max(stops) < 0.1,
        "on: no fall": all(len(r["falls_s"]) == 0 for r in s_on["runs"]),
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
