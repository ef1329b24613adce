#!/usr/bin/env python3
"""Checks the walking height floor through the product path (ctest pmg_policy_sil_walking_height_floor,
label sil): the default config (commands.walking_min_height 0.66 m, walking_min_height_hold_s 1.5 s)
runs test/data/policy/eval_walking_floor.yaml (crouched to 0.62 m, a 0.3 m/s side-step, a stop) with
the floor off and on (pmg_policy_sil --walking-height-floor off|on --seeds 1).
The hidden effect, read from the per-tick CSV (height_ref: the generator's base height, which follows
the shaped height command, about 1.5 cm below it while walking and 1 cm above it standing; height:
the pelvis height achieved):
- on, the side-step's reference is at least 3 cm higher than off (the floor lifts the 0.62 m command
  to 0.66 m) and the pelvis walks higher;
- on, the floor holds after the stop: 0.5-2.0 s into it the reference stands at least 3 cm above
  off's;
- by the end of the stop the robot stands crouched as commanded: on's reference within 3 mm of off's;
- the reference's height never moves faster than 0.5 m/s (the shaper's slew is 0.2 m/s);
- on, no fall.
Usage: check_sil_walking_floor.py OFF_DIR ON_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import rows, window  # noqa: E402


def mean(rs, key):
    return sum(r[key] for r in rs) / len(rs)


def main(off_dir, on_dir):
    s_off, off = rows(off_dir)
    s_on, on = rows(on_dir)
    walk_off, walk_on = window(off, "left_0.3", 2.0, 4.0), window(on, "left_0.3", 2.0, 4.0)
    hold_off, hold_on = window(off, "stop", 0.5, 2.0), window(on, "stop", 0.5, 2.0)
    end_off, end_on = window(off, "stop", 4.0, 7.0), window(on, "stop", 4.0, 7.0)
    live = [r for r in on if r["t"] >= 0.5]  # the generator's first output comes after the first ticks
    rate = max(abs(b["height_ref"] - a["height_ref"]) / (b["t"] - a["t"]) for a, b in zip(live, live[1:]) if b["t"] > a["t"])
    print(f"side-step: reference off {mean(walk_off, 'height_ref'):.3f} on {mean(walk_on, 'height_ref'):.3f} m, "
          f"pelvis off {mean(walk_off, 'height'):.3f} on {mean(walk_on, 'height'):.3f} m; stop 0.5-2 s: reference "
          f"off max {max(r['height_ref'] for r in hold_off):.3f} on min {min(r['height_ref'] for r in hold_on):.3f} m; "
          f"stop 4-7 s: off {mean(end_off, 'height_ref'):.3f} on {mean(end_on, 'height_ref'):.3f} m; largest reference "
          f"height rate {rate:.3f} m/s; falls off {sum(len(r['falls_s']) for r in s_off['runs'])}, "
          f"on {sum(len(r['falls_s']) for r in s_on['runs'])}")
    checks = {
        "on: the side-step's reference >= 3 cm above off's": mean(walk_on, "height_ref") >= mean(walk_off, "height_ref") + 0.03,
        "on: the pelvis walks higher than off": mean(walk_on, "height") > mean(walk_off, "height") + 0.01,
        "on: the floor holds after the stop (0.5-2 s: >= 3 cm above off)":
            min(r["height_ref"] for r in hold_on) >= max(r["height_ref"] for r in hold_off) + 0.03,
        "on: then the robot stands crouched as commanded (within 3 mm of off)":
            abs(mean(end_on, "height_ref") - mean(end_off, "height_ref")) <= 0.003,
        "on: the reference's height moves continuously (< 0.5 m/s)": rate < 0.5,
        "on: no fall": all(not r["falls_s"] for r in s_on["runs"]),
    }
    for name, ok in checks.items():
        print(("ok   " if ok else "FAIL ") + name)
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
