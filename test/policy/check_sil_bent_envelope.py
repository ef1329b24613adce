#!/usr/bin/env python3
"""Checks the bent velocity envelope through the product path (ctest pmg_policy_sil_bent_envelope,
label sil): the default config (commands.bent_pitch 0.4 rad, bent_max_velocity v_x 0.8 m/s) runs
test/data/policy/eval_bent_stop.yaml (bent forward 0.4 rad, 1.0 m/s forward, a stop with the bend
kept, then upright) with the envelope off and on (pmg_policy_sil --bent-envelope off|on --seeds 2
--first-seed 2), both with the posture feedback's envelope open (--posture-envelope off).
The hidden effect: without the envelope the bent robot does not stop when told (seeds 2 and 3: it
walks on at 0.7-0.9 m/s through the stop segment, until it is told to straighten). On:
- the stop segment's achieved v_x (mean over its last 60 % and the seeds) is below 0.25 m/s, and
  below half of off's; off's is above 0.5 m/s (the effect is there);
- in every seed the robot is still (|v_x| < 0.15 m/s, 0.5 s mean) within 2.5 s of the stop command;
- the bent walk still goes forward, slower than commanded: achieved v_x in (0.6, 0.9) m/s of 1.0;
- no fall.
Usage: check_sil_bent_envelope.py OFF_DIR ON_DIR
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import rows, seg, still_after, report  # noqa: E402


def main(off_dir, on_dir):
    with open(f"{off_dir}/summary.json") as f:
        s_off = json.load(f)
    with open(f"{on_dir}/summary.json") as f:
        s_on = json.load(f)
    stop_off, stop_on = seg(s_off, "bent_stop"), seg(s_on, "bent_stop")
    walk_on = seg(s_on, "bent_fwd")
    t_stop = stop_on["t_begin"]
    still = [still_after(rows(on_dir, r["seed"])[1], t_stop) for r in s_on["runs"]]
    print(f"stop segment v_x: off {stop_off['achieved']['vx']:+.3f}, on {stop_on['achieved']['vx']:+.3f}; on: bent walk "
          f"{walk_on['achieved']['vx']:+.3f} of {walk_on['command']['vx']:+.3f}, still {still} s after the stop, "
          f"falls off {sum(len(r['falls_s']) for r in s_off['runs'])}, "
          f"on {sum(len(r['falls_s']) for r in s_on['runs'])}")
    checks = {
        "off run has no bent envelope": s_off["bent_pitch"] == 0,
        "on run has it": s_on["bent_pitch"] > 0,
        "without the envelope the bent robot walks on through the stop (the effect is there)": stop_off["achieved"]["vx"] > 0.5,
        "with it, the stop segment is slow": stop_on["achieved"]["vx"] < min(0.25, 0.5 * stop_off["achieved"]["vx"]),
        "with it, every seed is still within 2.5 s of the stop": all(x is not None and x < 2.5 for x in still),
        "the bent walk still goes forward, slower than commanded": 0.6 < walk_on["achieved"]["vx"] < 0.9,
        "with it, no fall": all(len(r["falls_s"]) == 0 for r in s_on["runs"]),
    }
    return report(checks)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
