#!/usr/bin/env python3
"""Checks the walking posture feedback on roll through the product path (ctest pmg_policy_sil_walking_roll, label
sil): the default config with H10a's actor (--model; F13, the default's actor since 2026-12-07, rolls 0.02 rad) runs test/data/policy/eval_crouched_side_turn.yaml (crouched to 0.70 m, a side-step
while turning, (0, 0.3, 0.6), for 8 s, a stop) on seed 0, off: --walking-ki 3 0 (roll not fed back while walking,
the default config before 2026-12-06), on: as shipped (posture_feedback.walking_ki [3, 3]).
The hidden effect: walking this command H10a's torso rolls about 0.06 rad toward the side-step, beyond issue 12's
0.05 rad of cross-coupling, with no roll commanded. Read from summary.json (the segment's means over its last 60 %)
and the per-tick CSV (roll_fb: the roll command after the feedback, the one the generator and the actor get):
- off, the torso rolls more than 0.04 rad in the side-step and the roll command stays 0;
- on, the roll command leans against it (its mean below -0.02 rad), the torso's roll is within 0.03 rad of upright and
  at least 0.04 rad less than off, the side-step and the turn stay within 0.06 of off's, and the summaries record
  the gains;
- on, the robot stops (|v_y| below 0.1 m/s 1-3 s into the stop), its roll within 0.03 rad 1-3 s into the stop, and
  it does not fall.
Usage: check_sil_walking_roll.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import last60, run_off_on, seg, window  # noqa: E402

SEED = 0
WALK, STOP = "side_turn_0.7", "stop_side_turn_0.7"


def mean(rs, key):
    return sum(r[key] for r in rs) / len(rs)


def checks(s_off, r_off, s_on, r_on):
    walk = {"off": last60(r_off, WALK), "on": last60(r_on, WALK)}
    a = {tag: seg(s, WALK)["achieved"] for tag, s in (("off", s_off), ("on", s_on))}
    roll_fb = {tag: mean(walk[tag], "roll_fb") for tag in walk}
    stop = window(r_on, STOP, 1.0, 3.0)
    stop_vy, stop_roll = abs(mean(stop, "vy")), abs(mean(stop, "roll"))
    for tag in ("off", "on"):
        print(f"{tag}: {WALK} roll {a[tag]['roll']:+.3f} rad (roll command after the feedback {roll_fb[tag]:+.3f}), "
              f"v_y {a[tag]['vy']:+.3f} m/s, yaw rate {a[tag]['wz']:+.3f} rad/s")
    print(f"on: 1-3 s into the stop |v_y| {stop_vy:.3f} m/s, |roll| {stop_roll:.3f} rad")
    return {
        "the summaries record the gains (off [3, 0], on [3, 3])":
            s_off.get("walking_ki") == [3, 0] and s_on.get("walking_ki") == [3, 3],
        "off: the torso rolls more than 0.04 rad in the side-step (the effect is there)": a["off"]["roll"] > 0.04,
        "off: the roll command stays 0": abs(roll_fb["off"]) < 1e-3,
        "on: the roll command leans against the roll": roll_fb["on"] < -0.02,
        "on: the torso's roll within 0.03 rad and at least 0.04 rad less than off":
            abs(a["on"]["roll"]) < 0.03 and a["off"]["roll"] - a["on"]["roll"] >= 0.04,
        "on: the side-step and the turn within 0.06 of off's":
            abs(a["on"]["vy"] - a["off"]["vy"]) < 0.06 and abs(a["on"]["wz"] - a["off"]["wz"]) < 0.06,
        "on: the robot stops, upright": stop_vy < 0.1 and stop_roll < 0.03,
        "on: no fall": all(len(r["falls_s"]) == 0 for r in s_on["runs"]),
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
