#!/usr/bin/env python3
"""Checks the braking steps scaled by the crouch (velocity_feedback.brake_ratio with
brake_crouch_scaled, on in the default config) through the product path (label sil), off: with
--braking off, on: as shipped.

Crouched (ctest pmg_policy_sil_crouch_braking): the default config runs
training/results/fidelity/run_on/bent_crouched_stops.yaml (crouched to 0.66 m and bent 0.3 rad, told
0.6 m/s, then a stop with the pose kept) on seed 331 to 16 s, with the velocity feedback's correction
not bounded by the posture envelopes (--feedback-within-envelopes off), the harder case in which the
default actor runs on after the stop more often.
The hidden effect: told to stop, the robot goes on at 1 m/s and speeds up while the generator gives it
a standing reference, and it falls. On:
- off, the robot runs faster than 1.0 m/s in the stop while the generator's command (the CSV's vx_fb)
  is zero (the cause is there), and it falls (the effect is there);
- on, no fall;
- on, in the stop the generator's command stays above the shaped command by more than 0.2 m/s at some
  tick (the floor keeps a gait), never rises from one tick to the next (it only lets the reference
  decelerate more slowly), and is zero again by the end of the stop;
- on, the robot is still (|v_x| < 0.15 m/s, 0.5 s mean) within 3 s of the stop command.

At the standing height (ctest pmg_policy_sil_crouch_braking_standing, with --standing): the default
config runs test/data/policy/eval_standing_height_stops.yaml (stops from 1.0 m/s upright and bent
0.4 rad) on seed 0. At the standing height the crouch's weight is 0: the floor never acts and the run
is the same tick for tick (v_x achieved and sent to the generator), so those stops are not lengthened.

Usage: check_sil_crouch_braking.py [--standing] OFF_DIR ON_DIR
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on, still_after  # noqa: E402

SEED = 331
STANDING_SEED = 0


def stop1(rs):
    """The first episode's rows of segment stop1."""
    return [r for r in rs if r["segment"] == "stop1" and r["episode"] == 0]


def braking_keys(s_off, s_on):
    return s_off["brake_ratio"] == 0 and s_on["brake_ratio"] > 0 and s_on["brake_crouch_scaled"]


def checks(s_off, r_off, s_on, r_on):
    run_off, run_on = s_off["runs"][0], s_on["runs"][0]
    st_off, st_on = stop1(r_off), stop1(r_on)
    standing_ref_fast = [r for r in st_off if r["vx_fb"] == 0.0 and r["vx"] > 1.0]
    lift = max((r["vx_fb"] - r["vx_shaped"] for r in st_on), default=0.0)
    rise = max((b["vx_fb"] - a["vx_fb"] for a, b in zip(st_on, st_on[1:])), default=1.0)
    t_stop = next((r["t"] for r in st_on if r["vx_cmd"] == 0.0), None)
    still = still_after(r_on, t_stop) if t_stop is not None else None
    print(f"off: falls {run_off['falls_s']}, {len(standing_ref_fast)} stop ticks faster than 1.0 m/s on a standing "
          f"reference (largest v_x {max((r['vx'] for r in st_off), default=0):.2f}); on: falls {run_on['falls_s']}, "
          f"generator command up to {lift:.3f} m/s above the shaped one, largest rise per tick {rise:.4f}, "
          f"at the end of the stop {st_on[-1]['vx_fb'] if st_on else float('nan'):.3f}, still {still} s after the stop")
    return {
        "off run without braking, on run with the crouch-scaled floor": braking_keys(s_off, s_on),
        "off, faster than 1.0 m/s in the stop on a standing reference (the cause is there)": len(standing_ref_fast) > 0,
        "off, the robot fell (the effect is there)": len(run_off["falls_s"]) > 0,
        "on, no fall": run_on["falls_s"] == [],
        "on, the floor keeps a gait in the stop (more than 0.2 m/s above the shaped command)": lift > 0.2,
        "on, the generator's command never rises in the stop": rise <= 1e-9,
        "on, the floor is gone by the end of the stop": len(st_on) > 0 and st_on[-1]["vx_fb"] == 0.0,
        "on, still within 3 s of the stop command": still is not None and still < 3.0,
    }


def equal(a, b):
    """Equal, or both NaN (vx_fb is NaN before the loop drives the motors)."""
    return a == b or (math.isnan(a) and math.isnan(b))


def standing_checks(s_off, r_off, s_on, r_on):
    same = len(r_off) == len(r_on) and all(equal(a["vx"], b["vx"]) and equal(a["vx_fb"], b["vx_fb"]) for a, b in zip(r_off, r_on))
    largest = max((abs(a["vx_fb"] - b["vx_fb"]) for a, b in zip(r_off, r_on) if not math.isnan(a["vx_fb"] - b["vx_fb"])),
                  default=float("nan"))
    bent = [r for r in r_on if r["segment"] == "bent_fwd"]
    print(f"stops from 1.0 m/s upright and bent at the standing height: {len(r_on)} ticks, largest difference of the "
          f"generator's v_x {largest}; the bent walk's pitch {max((r['pitch'] for r in bent), default=0):.2f} rad at most")
    return {
        "off run without braking, on run with the crouch-scaled floor": braking_keys(s_off, s_on),
        "at the standing height, the stops are the same tick for tick with and without": same,
        "the bent walk bends (the bent case is there)": len(bent) > 0 and max(r["pitch"] for r in bent) > 0.3,
        "no fall": s_on["runs"][0]["falls_s"] == [],
    }


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--standing":
        sys.exit(run_off_on(standing_checks, STANDING_SEED, sys.argv[1:]))
    sys.exit(run_off_on(checks, SEED, sys.argv))
