#!/usr/bin/env python3
"""Tests scripts/segment_band.py (ctest segment_band_scores_a_known_summary, label unit) on a
synthetic pmg_policy_sil summary whose misses are known: backward at 80 % (outside +-15 %), forward
at 96 % (inside), a crouch 20 mm high (outside 0.015 m), a side-step rolling 0.07 rad and a bent
walk rolling 0.06 rad (cross-coupling beyond 0.05 rad), the bend itself on target, one seed
fallen in the backward walk (named with the segment), and the velocity feedback held for 25 % and
decayed for 40 % of the backward walk's window (named with the missed segment), and a crouched walk
that no seed reached (every seed fell before its window: `achieved` all null), a miss on both axes
it commands. Runaways: a crouched backward walk at 2.2 times its command that the controller's
estimate reads at 1.2 times, and the stop after it still moving 0.3 m/s, are named; a forward walk
at 1.4 times (0.2 m/s over) and a turn the wrong way are not.
Against the shaper's command (`shaped`): the crouched backward walk was slowed to -0.3 m/s and the
crouched forward walk to 0.3 (out of their commands' bands), every other segment shaped as commanded:
in band of the shaped command are fwd, left, bent_walk and the crouched forward walk at 0.28 (which
misses its command 0.6); the same summary without `shaped` prints no such line.
Usage: test_segment_band.py
"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def seg(name, command, achieved):
    base = {"vx": 0.0, "vy": 0.0, "wz": 0.0, "pitch": 0.0, "roll": 0.0, "height": 0.78}
    return {"name": name, "seeds": 2, "fallen": 0, "command": {**base, **command}, "reference": dict(base),
            "achieved": {**base, **achieved}, "shaped": {**base, **command}}


def main():
    summary = {"segments": [
        seg("stand", {}, {}),
        seg("fwd", {"vx": 0.5}, {"vx": 0.48}),
        {**seg("back", {"vx": -0.5}, {"vx": -0.40}), "fallen": 1, "feedback_held_fraction": 0.25,
         "feedback_decayed_fraction": 0.4},
        seg("left", {"vy": 0.3}, {"vy": 0.29, "roll": -0.07}),
        seg("crouch", {"height": 0.62}, {"height": 0.64}),
        seg("bent_walk", {"vx": 0.3, "pitch": 0.25}, {"vx": 0.3, "pitch": 0.25, "roll": 0.06}),
        {**seg("crouch_walk", {"vx": 0.4, "height": 0.68}, {}), "seeds": 0, "fallen": 2,
         "achieved": {k: None for k in ("vx", "vy", "wz", "pitch", "roll", "height")}},
        {**seg("back_crouched", {"vx": -0.5, "height": 0.74}, {"vx": -1.1, "height": 0.74}),
         "estimate": {"vx": -0.6, "vy": 0.0, "wz": 0.0, "pitch": None, "roll": None, "height": 0.74},
         "shaped": {"vx": -0.3, "vy": 0.0, "wz": 0.0, "pitch": 0.0, "roll": 0.0, "height": 0.74}},
        seg("stop_back_crouched", {"height": 0.74}, {"vx": -0.3, "height": 0.74}),
        seg("fwd_fast", {"vx": 0.5}, {"vx": 0.7}),
        seg("turn_wrong_way", {"wz": 0.5}, {"wz": -0.6}),
        {**seg("fwd_crouched", {"vx": 0.6, "height": 0.66}, {"vx": 0.28, "height": 0.66}),
         "shaped": {"vx": 0.3, "vy": 0.0, "wz": 0.0, "pitch": 0.0, "roll": 0.0, "height": 0.66}},
    ]}
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "summary.json")
        with open(path, "w") as f:
            json.dump(summary, f)
        out = subprocess.run([sys.executable, os.path.join(ROOT, "scripts/segment_band.py"), path],
                             capture_output=True, text=True, check=True).stdout
        for s in summary["segments"]:
            s.pop("shaped")
        with open(path, "w") as f:
            json.dump(summary, f)
        unshaped = subprocess.run([sys.executable, os.path.join(ROOT, "scripts/segment_band.py"), path],
                                  capture_output=True, text=True, check=True).stdout
    print(out)
    expect = [
        "vx: 2/7 in band; misses: back (-0.400 of -0.500), back_crouched (-1.100 of -0.500), "
        "fwd_fast (+0.700 of +0.500), fwd_crouched (+0.280 of +0.600), crouch_walk (no seed in its window)",
        "vy: 1/1 in band; misses: none",
        "velocity segments in band: 3/9",
        "velocity segments in band of the shaper's command: 4/9 (the shaper's envelopes slowed 2 of them out of "
        "the command's band); misses: back vx (-0.400 of -0.500), back_crouched vx (-1.100 of -0.300), "
        "fwd_fast vx (+0.700 of +0.500), crouch_walk vx (no seed in its window), turn_wrong_way wz (-0.600 of +0.500)",
        "runaways (beyond the command by more than 50% of it or 0.2 m/s / 0.3 rad/s): back_crouched vx -1.100 "
        "of -0.500 (estimated -0.600), stop_back_crouched vx -0.300 of +0.000",
        "posture misses: crouch height +0.640 of +0.620, crouch_walk height (no seed in its window)",
        "torso roll in the side-steps: 0.070-0.070 rad",
        "cross-coupling beyond 0.05 rad (pitch/roll not commanded, every segment; largest 0.070): "
        "left roll -0.070, bent_walk roll +0.060",
        "seeds fallen (summed over segments): 3; in back 1, crouch_walk 2",
        "velocity feedback in the missed segments (share of the window not integrated): back held 25% decayed 40%",
    ]
    missing = [e for e in expect if e not in out]
    for e in missing:
        print(f"FAIL expected line: {e}")
    if "shaper's command" in unshaped or "velocity segments in band: 3/9" not in unshaped:
        missing.append("without `shaped`")
        print(f"FAIL without `shaped` the score differs or claims a shaped count:\n{unshaped}")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
