#!/usr/bin/env python3
"""Checks the posture feedback's walking low-pass and its wait after a stop through the product path (ctest
pmg_policy_sil_posture_settle, label sil): the default config (F13's actor) runs
test/data/policy/eval_bent_walk_settle.yaml (the grid's crouched walk and turn, a stand, a 0.25 rad bent walk at
0.3 m/s, then a 0.3 rad bent side-step at 0.3 m/s and its stop) on seed 1, off: --walking-filter-time-s 1
--stop-settle-s 0 (the default config before 2026-12-07), on: as shipped (0.5 s and 1.0 s).
The hidden effect: the walking integrator (walking_ki 3 /s) on a 1 s low-pass is a loop damped at about 0.3, so the
torso's dip as a bent walk starts winds a correction that carries the torso 0.03 rad past the command for the rest
of a 4 s walk; and the standing integrator, winding from the first tick of the stop, takes the torso's dip as the
side-step ends for an error and bends it past the command. Read from summary.json (the segment's means over its
last 60 %):
- the summaries record the settings (off 1 s and 0 s, on 0.5 s and 1 s);
- off, the bent walk bends more than 0.02 rad past its 0.25 rad and the stop after the side-step more than 0.03 rad
  past its 0.3 (the effect is there);
- on, both within issue 12's 0.03 rad, at least 0.02 rad nearer the command than off, the bent side-step within
  0.03 rad too, the bent walk's v_x within 15 % of 0.3 m/s, the crouched turn's uncommanded pitch within 0.05 rad,
  and no fall.
Usage: check_sil_posture_settle.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on, seg  # noqa: E402

SEED = 1
BENT, SIDE, STOP, TURN = "bent_walk", "bent0.3_side0.3", "stop_bent0.3_side0.3", "crouch_turn"


def checks(s_off, r_off, s_on, r_on):
    a = {tag: {name: seg(s, name)["achieved"] for name in (BENT, SIDE, STOP, TURN)} for tag, s in (("off", s_off), ("on", s_on))}
    err = {tag: {BENT: a[tag][BENT]["pitch"] - 0.25, SIDE: a[tag][SIDE]["pitch"] - 0.3, STOP: a[tag][STOP]["pitch"] - 0.3}
           for tag in a}
    for tag in ("off", "on"):
        print(f"{tag}: {BENT} pitch {a[tag][BENT]['pitch']:+.3f} (0.25), v_x {a[tag][BENT]['vx']:+.3f} (0.3); {SIDE} pitch "
              f"{a[tag][SIDE]['pitch']:+.3f} (0.3); {STOP} pitch {a[tag][STOP]['pitch']:+.3f} (0.3); {TURN} pitch "
              f"{a[tag][TURN]['pitch']:+.3f} (0)")
    return {
        "the summaries record the settings (off 1 s / 0 s, on 0.5 s / 1 s)":
            (s_off.get("walking_filter_time_s"), s_off.get("stop_settle_s")) == (1, 0) and
            (s_on.get("walking_filter_time_s"), s_on.get("stop_settle_s")) == (0.5, 1),
        "off: the bent walk bends more than 0.02 rad past the command (the effect is there)": err["off"][BENT] > 0.02,
        "off: the stop after the bent side-step bends more than 0.03 rad past the command": err["off"][STOP] > 0.03,
        "on: the bent walk within 0.03 rad, at least 0.02 nearer than off":
            abs(err["on"][BENT]) < 0.03 and abs(err["off"][BENT]) - abs(err["on"][BENT]) >= 0.02,
        "on: the stop after the side-step within 0.03 rad, at least 0.02 nearer than off":
            abs(err["on"][STOP]) < 0.03 and abs(err["off"][STOP]) - abs(err["on"][STOP]) >= 0.02,
        "on: the bent side-step within 0.03 rad": abs(err["on"][SIDE]) < 0.03,
        "on: the bent walk's v_x within 15 % of 0.3 m/s": abs(a["on"][BENT]["vx"] - 0.3) <= 0.045,
        "on: the crouched turn's pitch within 0.05 rad": abs(a["on"][TURN]["pitch"]) <= 0.05,
        "on: no fall": all(len(r["falls_s"]) == 0 for r in s_on["runs"]),
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, SEED, sys.argv))
