#!/usr/bin/env python3
"""Checks the upset guard's upright (velocity_feedback.upset_guard.upright, on in the default config)
through the product path (label sil): off with --upset-upright off, on as shipped.

The default config runs training/results/fidelity/run_on/bent_crouched_stops.yaml (crouched to 0.66 m
and bent 0.3 rad, told 0.6 m/s, then a stop with the pose kept) on seed 570, with the velocity
feedback's correction not bounded by the posture envelopes (--feedback-within-envelopes off), where the
default actor runs on after a stop more often.
The hidden effect: in the third stop the robot runs on at about 1 m/s, the upset guard latches, the
velocity command is already zero, and the robot, still bent forward, speeds up and falls. On:
- off, the guard latched, the torso was sent bent (pitch to the generator above 0.25 rad) on every
  latched tick, and the robot fell (the cause and the effect are there);
- on, the guard latched and there is no fall;
- on, within the latch the pitch sent to the generator comes down from 0.3 to below 0.05 rad (the
  shaped pitch goes to 0, and the posture feedback's correction decays);
- on, it never moves by more than the posture slew (0.5 rad/s) plus the posture feedback's step per
  tick: the reference stays continuous.

Usage: check_sil_upset_upright.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on  # noqa: E402

SEED = 570
MAX_PITCH_STEP = 0.5 * 0.01 + 0.0025  # posture_rate x dt, plus the posture feedback's integral step


def latched(rs):
    return [r for r in rs if r["upset_hold"] == 1.0 and r["mode"] == "active"]


def checks(s_off, r_off, s_on, r_on):
    run_off, run_on = s_off["runs"][0], s_on["runs"][0]
    held_off, held_on = latched(r_off), latched(r_on)
    active = [r for r in r_on if r["mode"] == "active"]
    steps = [abs(b["pitch_fb"] - a["pitch_fb"]) for a, b in zip(active, active[1:]) if b["t"] - a["t"] < 0.015]
    low_on = min((r["pitch_fb"] for r in held_on), default=1.0)
    low_off = min((r["pitch_fb"] for r in held_off), default=0.0)
    print(f"off: {len(held_off)} latched ticks, pitch to the generator at least {low_off:.3f} there, falls "
          f"{run_off['falls_s']}; on: {len(held_on)} latched ticks, pitch down to {low_on:.3f}, falls {run_on['falls_s']}, "
          f"largest pitch step {max(steps, default=float('nan')):.4f} rad per tick")
    return {
        "off run keeps the posture when upset, on run goes upright": (not s_off["upset_upright"]) and s_on["upset_upright"],
        "off, the guard latched with the torso sent bent (the cause is there)": len(held_off) > 0 and low_off > 0.25,
        "off, the robot fell (the effect is there)": len(run_off["falls_s"]) > 0,
        "on, the guard latched": len(held_on) > 0,
        "on, no fall": run_on["falls_s"] == [],
        "on, upright within the latch (pitch to the generator below 0.05 rad)": low_on < 0.05,
        "on, the pitch to the generator is continuous": len(steps) > 0 and max(steps) <= MAX_PITCH_STEP,
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
