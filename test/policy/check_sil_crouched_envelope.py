#!/usr/bin/env python3
"""Checks the crouched velocity envelope through the product path (ctest
pmg_policy_sil_crouched_envelope, label sil): the previous default config (g1_sil_policy_bk_vy6.yaml,
the actor whose falls the envelope was made for; the default's wh6g did not fall here without it) runs
test/data/policy/eval_crouched_corners.yaml (0.9 m/s forward with a 0.3 m/s side-step crouched to
0.66 m, 0.8 m/s forward crouched to 0.62 m, stops) with the envelope off and on
(pmg_policy_sil --crouched-envelope off|on --seeds 2 --restart-after-fall).
The hidden effect: without the envelope the actor falls at these corners (off: at least one fall).
On: no fall, the crouched walks still go forward (v_x > 0.2 m/s) in the commanded direction
(v_y of the side-step positive, below its share of the command), and slower than commanded.
The summary's `shaped` (the shaper's command, per segment) shows the envelope at work: on, the
crouched side-step's shaped command is slowed along its direction (both axes below the command, v_y/v_x
the command's 1/3 within 2 %) and the 0.62 m walk's below 0.4 m/s; off, the 0.62 m walk's (which no seed
falls in) is the command itself (within 1e-6).
Usage: check_sil_crouched_envelope.py OFF_DIR ON_DIR
"""
import json
import sys


def load(out):
    with open(f"{out}/summary.json") as f:
        return json.load(f)


def seg(s, name):
    return next(x for x in s["segments"] if x["name"] == name)


def main(off_dir, on_dir):
    off, on = load(off_dir), load(on_dir)
    falls_off = sum(len(r["falls_s"]) for r in off["runs"])
    falls_on = sum(len(r["falls_s"]) for r in on["runs"])
    side, fwd = seg(on, "fwd_side_0.66"), seg(on, "fwd_0.62")
    fwd_off = seg(off, "fwd_0.62")
    sh, sh_fwd, sh_off = side.get("shaped") or {}, fwd.get("shaped") or {}, fwd_off.get("shaped") or {}

    def number(x):
        return isinstance(x, (int, float))
    print(f"falls: off {falls_off}, on {falls_on}; on: fwd_side_0.66 achieved ({side['achieved']['vx']:+.3f}, "
          f"{side['achieved']['vy']:+.3f}) of ({side['command']['vx']:+.3f}, {side['command']['vy']:+.3f}), "
          f"fwd_0.62 {fwd['achieved']['vx']:+.3f} of {fwd['command']['vx']:+.3f}")
    checks = {
        "off run has no crouched envelope": off["crouched_height"] == 0,
        "on run has it": on["crouched_height"] > 0,
        "without the envelope the actor falls at these corners (the effect is there)": falls_off >= 1,
        "with it, no fall": falls_on == 0,
        "crouched walks still go forward, slower than commanded": all(
            0.2 < s["achieved"]["vx"] < s["command"]["vx"] - 0.1 for s in (side, fwd)),
        "the side-step keeps its direction": 0.0 < side["achieved"]["vy"] < side["command"]["vy"],
        f"on, the side-step's shaped command is slowed along its direction ({sh.get('vx')}, {sh.get('vy')})":
            number(sh.get("vx")) and number(sh.get("vy")) and
            0.0 < sh["vx"] < side["command"]["vx"] - 0.1 and 0.0 < sh["vy"] < side["command"]["vy"] and
            abs(sh["vy"] / sh["vx"] - side["command"]["vy"] / side["command"]["vx"]) < 0.02 * side["command"]["vy"] / side["command"]["vx"],
        f"on, the 0.62 m walk's shaped command is below 0.4 m/s ({sh_fwd.get('vx')})":
            number(sh_fwd.get("vx")) and 0.0 < sh_fwd["vx"] < 0.4,
        f"off, the 0.62 m walk's shaped command is the command ({sh_off.get('vx')})": all(
            number(sh_off.get(k)) and abs(sh_off[k] - fwd_off["command"][k]) < 1e-6 for k in ("vx", "vy", "wz", "height")),
    }
    for name, ok in checks.items():
        print(("ok   " if ok else "FAIL ") + name)
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
