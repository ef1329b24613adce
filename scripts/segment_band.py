#!/usr/bin/env python3
"""Scores pmg_policy_sil per-segment results against issue 12's tracking targets.

Usage: scripts/segment_band.py SUMMARY.json [SUMMARY.json ...]

Reads `segments` of each summary (command / reference / achieved means over the last 60 % of each
segment and over seeds; written by `pmg_policy_sil`) and prints, per commanded velocity axis, the
segments whose achieved value is within the band
    |achieved - command| <= max(0.15 |command|, tol),  tol = 0.05 m/s (v_x, v_y), 0.08 rad/s (omega)
(issue 12: "within +-15 %, or +-0.05 m/s / +-0.08 rad/s"), the misses by name, the same count against
the shaper's command (`shaped`, when the summary has it: the command after the controller's limits
and envelopes, e.g. a crouched walk slowed by the crouched velocity envelope) with how many segments
the shaper slowed out of the command's band, the posture segments
against pitch / roll within 0.03 rad and height within 0.015 m, for each missed velocity segment
the share of its window in which the velocity feedback was held or decayed (when the summary has
it), the runaways (a segment moving beyond its command, or through a stop, by more than half the
command and 0.2 m/s / 0.3 rad/s, with the controller's velocity estimate beside it), the torso roll
in the side-steps
and, in every segment, the torso pitch or roll that it does not command (cross-coupling, target
<= 0.05 rad). Frames: commands and achieved velocities in the robot's
heading frame, as pmg_policy_sil writes them. A segment that no seed reached (every seed fell
before its window: `achieved` all null) counts as a miss on every axis it commands. Exit status 2 on
a file without `segments`. score(path) prints and also returns the counts (in_band, velocity_segments,
velocity_misses, in_band_shaped and shaper_slowed (None without `shaped`), posture_misses, coupling, coupling_largest, runaways, falls) for other scripts
(scripts/evaluate_candidate.py).
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# The bands, as the envelope plot draws them (one definition).
from plot_segments import COUPLING_ABS, POSTURE_ABS, VEL_ABS, VEL_REL, neutral_height  # noqa: E402


# A runaway: |achieved| beyond |command| by more than RUNAWAY_REL |command| and RUNAWAY_ABS [m/s, rad/s].
RUNAWAY_REL, RUNAWAY_ABS = 0.5, {"vx": 0.2, "vy": 0.2, "wz": 0.3}


def is_runaway(axis, cmd, ach):
    """Whether an achieved velocity @p ach runs away from its command @p cmd on @p axis ("vx", "vy", "wz"):
    beyond |cmd| by more than RUNAWAY_REL |cmd| and RUNAWAY_ABS[axis], and not against a nonzero command
    (a miss, not a runaway)."""
    wrong_way = abs(cmd) > 1e-9 and ach * cmd < 0.0
    return not wrong_way and abs(ach) - abs(cmd) > max(RUNAWAY_REL * abs(cmd), RUNAWAY_ABS[axis])


def in_band(cmd, ach, tol):
    return abs(ach - cmd) <= max(VEL_REL * abs(cmd), tol)


def posture_commanded(command, key, standing):
    """A posture axis the segment commands: height away from standing, pitch or roll away from 0."""
    return abs(command[key] - standing) > 1e-9 if key == "height" else abs(command[key]) > 1e-9


def score(path):
    with open(path) as f:
        summary = json.load(f)
    if "segments" not in summary:
        print(f"{path}: no 'segments' (expected pmg_policy_sil's summary.json)", file=sys.stderr)
        sys.exit(2)
    def measured(s):
        return bool(s.get("achieved")) and all(v is not None for v in s["achieved"].values())
    segs = [s for s in summary["segments"] if measured(s)]
    # No seed in the window (all fell before it): a miss on each axis it commands, without a value.
    unreached = [s for s in summary["segments"] if s.get("achieved") and not measured(s)]
    print(f"== {path}")
    total_in = total = 0
    missed = {}
    for axis, tol in VEL_ABS.items():
        hit, miss = [], []
        for s in segs:
            cmd, ach = s["command"][axis], s["achieved"][axis]
            if abs(cmd) < 1e-9:
                continue
            if in_band(cmd, ach, tol):
                hit.append(s["name"])
            else:
                miss.append(f"{s['name']} ({ach:+.3f} of {cmd:+.3f})")
                missed[s["name"]] = s
        miss += [f"{s['name']} (no seed in its window)" for s in unreached if abs(s["command"][axis]) >= 1e-9]
        total_in += len(hit)
        total += len(hit) + len(miss)
        print(f"{axis}: {len(hit)}/{len(hit) + len(miss)} in band; misses: {', '.join(miss) or 'none'}")
    print(f"velocity segments in band: {total_in}/{total}")
    # Against the shaper's command (pmg_policy_sil's `shaped`: the command after the controller's limits
    # and envelopes, what it chose to attempt): separates the envelopes' deliberate slowing from the
    # tracking gap. A segment is slowed on an axis when its shaped value is outside the command's band.
    shaped_in = shaped_total = slowed = None
    if segs and all(s.get("shaped") and s["shaped"].get("vx") is not None for s in segs):
        shaped_in = shaped_total = slowed = 0
        shaped_miss = []
        for axis, tol in VEL_ABS.items():
            for s in segs:
                cmd = s["command"][axis]
                if abs(cmd) < 1e-9:
                    continue
                shaped_total += 1
                slowed += not in_band(cmd, s["shaped"][axis], tol)
                if in_band(s["shaped"][axis], s["achieved"][axis], tol):
                    shaped_in += 1
                else:
                    shaped_miss.append(f"{s['name']} {axis} ({s['achieved'][axis]:+.3f} of {s['shaped'][axis]:+.3f})")
            for s in unreached:
                if abs(s["command"][axis]) >= 1e-9:
                    shaped_total += 1
                    shaped_miss.append(f"{s['name']} {axis} (no seed in its window)")
        print(f"velocity segments in band of the shaper's command: {shaped_in}/{shaped_total} "
              f"(the shaper's envelopes slowed {slowed} of them out of the command's band); misses: "
              f"{', '.join(shaped_miss) or 'none'}")
    # Where the velocity feedback was on (pmg_policy_sil's feedback_*_fraction), how much of each
    # missed segment's window it could not integrate: held (leg odometry rejected) or decayed (tilt).
    fb = [f"{name} held {s['feedback_held_fraction']:.0%} decayed {s['feedback_decayed_fraction']:.0%}"
          for name, s in missed.items() if s.get("feedback_held_fraction") is not None
          and s.get("feedback_decayed_fraction") is not None]
    if fb:
        print(f"velocity feedback in the missed segments (share of the window not integrated): {', '.join(fb)}")
    posture_miss = []
    standing = neutral_height(summary["segments"])
    for s in segs:
        c, a = s["command"], s["achieved"]
        for key, tol in POSTURE_ABS.items():
            if posture_commanded(c, key, standing) and abs(a[key] - c[key]) > tol:
                posture_miss.append(f"{s['name']} {key} {a[key]:+.3f} of {c[key]:+.3f}")
    posture_miss += [f"{s['name']} {key} (no seed in its window)" for s in unreached for key in POSTURE_ABS
                     if posture_commanded(s["command"], key, standing)]
    print(f"posture misses: {', '.join(posture_miss) or 'none'}")
    side = [s for s in segs if abs(s["command"]["vy"]) > 1e-9 and abs(s["command"]["vx"]) < 1e-9
            and abs(s["command"]["wz"]) < 1e-9 and abs(s["command"]["roll"]) < 1e-9]
    rolls = [abs(s["achieved"]["roll"]) for s in side]
    if rolls:
        print(f"torso roll in the side-steps: {min(rolls):.3f}-{max(rolls):.3f} rad (target <= {COUPLING_ABS})")
    # Cross-coupling everywhere: torso pitch or roll away from zero in a segment that does not
    # command it (walking, crouching, bending on the other axis), beyond the 0.05 rad.
    uncommanded = [(s["name"], key, s["achieved"][key]) for s in segs for key in ("pitch", "roll")
                   if abs(s["command"][key]) < 1e-9]
    coupling = [f"{name} {key} {a:+.3f}" for name, key, a in uncommanded if abs(a) > COUPLING_ABS]
    worst = max((abs(a) for _, _, a in uncommanded), default=0.0)
    print(f"cross-coupling beyond {COUPLING_ABS} rad (pitch/roll not commanded, every segment; largest {worst:.3f}): "
          f"{', '.join(coupling) or 'none'}")
    # Runaways: the robot moving well beyond its command on an axis, in the commanded direction or
    # with none commanded (a stop it runs on through): what a user fears more than a shortfall, and
    # what the band alone lists as one miss among many. With the velocity estimate the controller
    # acted on beside it (pmg_policy_sil's `estimate`, the velocity feedback's): a runaway that estimate
    # does not see is one the velocity feedback cannot correct.
    runaways = []
    for s in segs:
        for axis in RUNAWAY_ABS:
            cmd, ach = s["command"][axis], s["achieved"][axis]
            if is_runaway(axis, cmd, ach):
                est = (s.get("estimate") or {}).get(axis)
                runaways.append(f"{s['name']} {axis} {ach:+.3f} of {cmd:+.3f}" +
                                (f" (estimated {est:+.3f})" if est is not None else ""))
    print(f"runaways (beyond the command by more than {RUNAWAY_REL:.0%} of it or "
          f"{RUNAWAY_ABS['vx']} m/s / {RUNAWAY_ABS['wz']} rad/s): {', '.join(runaways) or 'none'}")
    falls = sum(s.get("fallen", 0) for s in summary["segments"])
    where = [f"{s['name']} {s['fallen']}" for s in summary["segments"] if s.get("fallen", 0)]
    print(f"seeds fallen (summed over segments): {falls}" + (f"; in {', '.join(where)}" if where else ""))
    return {"in_band": total_in, "velocity_segments": total, "velocity_misses": sorted(missed),
            "in_band_shaped": shaped_in, "shaper_slowed": slowed,
            "posture_misses": posture_miss, "coupling": coupling, "coupling_largest": worst,
            "runaways": runaways, "falls": falls}


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    for p in sys.argv[1:]:
        score(p)
