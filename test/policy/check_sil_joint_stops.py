#!/usr/bin/env python3
"""Checks mujoco.joint_stops through the product path (ctest pmg_policy_sil_joint_stops, label sil):
the default config runs the crouched probe (training/results/fidelity/crouched/probe_heights.yaml)
for 76 s on seed 124, off: with --joint-stops off (the MJCF's soft stops, MuJoCo's default solref
0.02 s), on: as shipped (0.004 s); both with the braking steps off and the yaw-rate correction within
the crouched envelope and max_velocity (--braking off --yaw-beyond-envelopes off --max-velocity-headroom off:
the config as the stumble was found).
The hidden effect: at 0.70 m, 1.2 s into the 1.0 m/s walk, the robot stumbles and a foot lands with
the right ankle pitch moving at 7 rad/s towards its lower stop (-0.873 rad). The soft stop lets it
through by more than the supervisor's 0.1 rad joint position margin; the supervisor latches damping
and the robot falls. A metal stop gives way by millirad. On:
- off, the supervisor latched a joint position fault on an ankle pitch joint, more than 0.1 rad
  beyond its range (the cause is there), and the robot fell (the effect);
- on, no supervisor fault and no fall;
- on, no leg joint reads more than 0.02 rad beyond its range in the whole run;
- on, the 1.0 m/s walk at 0.70 m still walks forward (above 0.3 m/s).
Usage: check_sil_joint_stops.py OFF_DIR ON_DIR
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on  # noqa: E402

SEED = 124


ROBOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "config", "robots", "g1", "g1.yaml")


def leg_ranges(robot=ROBOT):
    """[(lower, upper)] [rad] of the robot config's first 12 joints, the legs (q0..q11 of the CSV)."""
    with open(robot) as f:
        found = re.findall(r"name: \w+_joint, lower: ([-\d.e]+), upper: ([-\d.e]+)", f.read())
    return [(float(lo), float(hi)) for lo, hi in found[:12]]


RANGES = leg_ranges()
ANKLE_PITCH_LOWER = RANGES[10][0]  # right_ankle_pitch_joint


def overtravel(rows):
    """Largest reading beyond its range over the 12 leg joints and the run [rad] (0 if none)."""
    return max(max(lo - r[f"q{j}"], r[f"q{j}"] - hi, 0.0) for r in rows for j, (lo, hi) in enumerate(RANGES))


def checks(s_off, r_off, s_on, r_on):
    run_off, run_on = s_off["runs"][0], s_on["runs"][0]
    f_off = run_off["faults"]
    ankle_off = [f for f in f_off if f["cause"] == "joint position limit" and "ankle_pitch" in f["joint"]]
    beyond_off = min((ANKLE_PITCH_LOWER - f["value"] for f in ankle_off), default=0.0)
    walk = [r for r in r_on if r["segment"] == "fwd1.0_0.7" and r["t"] >= 73.5]
    v_walk = sum(r["vx"] for r in walk) / max(1, len(walk))
    print(f"off: faults {f_off}, falls {run_off['falls_s']}, largest overtravel {overtravel(r_off):.3f} rad; "
          f"on: faults {run_on['faults']}, falls {run_on['falls_s']}, largest overtravel {overtravel(r_on):.3f} rad, "
          f"v_x {v_walk:+.3f} m/s in the 1.0 m/s walk at 0.70 m after 73.5 s")
    return {
        "off run has the MJCF's stops, on run the config's": s_off["joint_stops_timeconst_s"] == 0
        and s_on["joint_stops_timeconst_s"] > 0,
        "off, the supervisor latched on an ankle pitch more than 0.1 rad beyond its stop (the cause is there)":
            len(ankle_off) > 0 and beyond_off > 0.1,
        "off, the robot fell (the effect is there)": len(run_off["falls_s"]) > 0,
        "on, no supervisor fault": run_on["faults"] == [],
        "on, no fall": run_on["falls_s"] == [],
        "on, no leg joint more than 0.02 rad beyond its range": overtravel(r_on) < 0.02,
        "on, the walk goes on forward": len(walk) > 0 and v_walk > 0.3,
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
