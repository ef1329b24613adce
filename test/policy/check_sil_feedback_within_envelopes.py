#!/usr/bin/env python3
"""Checks velocity_feedback.within_posture_envelopes through the product path (ctest
pmg_policy_sil_feedback_within_envelopes, label sil): the default config runs
test/data/policy/eval_bent_crouched_fast_stop.yaml (crouched to 0.66 m and bent 0.3 rad, told 0.6 m/s,
a stop with the pose kept, then upright) on seed 226, off: with --feedback-within-envelopes off, on:
as shipped.
The hidden effect: the crouched and bent velocity envelopes slow the shaped command, but off, the
velocity feedback's correction carries the command sent to the generator back beyond it, and in seed
226 the robot runs on after the stop (0.5 m/s 1-3 s in). On:
- in the walk's steady part (its last 3 s) the corrected v_x (the CSV's vx_fb) never exceeds the
  shaped command (vx_shaped, on the envelope's edge there) by more than 1 mm/s; off it exceeds it by
  more than 0.03 m/s (the cause is there);
- off, the robot is faster than 0.3 m/s 1-3 s into the stop (the effect is there); on, below 0.15;
- on, it is still (|v_x| < 0.15 m/s, 0.5 s mean) within 2.5 s of the stop command;
- on, the corrected command stays continuous: no tick changes vx_fb by more than 0.02 m/s;
- on, the crouched bent walk still walks forward (above 0.35 m/s of the shaped ~0.55) and bends
  (achieved pitch above 0.2 rad);
- on, no fall.
Usage: check_sil_feedback_within_envelopes.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on, seg, still_after, stop_speed, window  # noqa: E402

SEED = 226


def excess(rs):
    """Largest vx_fb - vx_shaped over the walk's last 3 s."""
    return max(r["vx_fb"] - r["vx_shaped"] for r in window(rs, "walk", 1.0, 4.0))


def checks(s_off, r_off, s_on, r_on):
    ex_off, ex_on = excess(r_off), excess(r_on)
    v_off, v_on = stop_speed(r_off, "stop"), stop_speed(r_on, "stop")
    t_stop = seg(s_on, "stop")["t_begin"]
    still = still_after(r_on, t_stop)
    active = [r for r in r_on if r["vx_fb"] == r["vx_fb"]]
    jump = max(abs(b["vx_fb"] - a["vx_fb"]) for a, b in zip(active, active[1:]) if b["t"] - a["t"] < 0.015)
    walk_on = seg(s_on, "walk")
    print(f"v_x fed back beyond the shaped command, largest: off {ex_off:+.3f}, on {ex_on:+.3f} m/s; 1-3 s into the "
          f"stop: off {v_off:+.3f}, on {v_on:+.3f} m/s; on: still {still} s after the stop, walk v_x "
          f"{walk_on['achieved']['vx']:+.3f} pitch {walk_on['achieved']['pitch']:.3f}, largest step of vx_fb {jump:.4f}")
    return {
        "off run has the switch off, on run on": s_off["feedback_within_envelopes"] is False
        and s_on["feedback_within_envelopes"] is True,
        "without it the correction carries v_x beyond the envelope (the cause is there)": ex_off > 0.03,
        "with it, never beyond the shaped command by more than 1 mm/s": ex_on <= 0.001,
        "without it the robot runs on after the stop (the effect is there)": v_off > 0.3,
        "with it, the stop is slow": v_on < 0.15,
        "with it, still within 2.5 s of the stop": still is not None and still < 2.5,
        "with it, the corrected command is continuous": jump <= 0.02,
        "the crouched bent walk still walks and bends": walk_on["achieved"]["vx"] > 0.35 and walk_on["achieved"]["pitch"] > 0.2,
        "with it, no fall": all(len(r["falls_s"]) == 0 for r in s_on["runs"]),
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
