#!/usr/bin/env python3
"""Write a calibration command script for the command-response feed-forward (issue 12).

Random velocity commands (v_x, v_y, w in the heading frame) over the issue-12 envelope, each held
for --hold s and followed by a stand of --stand s, at the standing height, upright. One to three
axes move per segment; a combination whose normalised size sum_i |u_i| / max_i exceeds --max-load
is drawn again (the grid's hardest combinations, diag_turn and arc_r_fast, are about 1.9). The
script is in the format of config/policies/eval_envelope.yaml (include/pmg/controller/commands.hpp).

With --height-range LO HI each segment walks at its own height, drawn uniformly from [max(LO,
walking_min_height), HI] (the crouched sweep: the feed-forward's gains per crouch), and a command is
drawn again unless the controller's crouched velocity envelope (commands: of --controller) lets it
through unscaled at that height: the shaper would otherwise slow it, and the fit would read the
shaper's scaling as the robot's response. The stand after a segment is long enough for the height's
slew (commands.height_rate).

  python3 scripts/make_response_sweep.py --segments 72 --seed 1 --out config/policies/response_sweep_1.yaml
  build/bin/pmg_policy_sil --commands config/policies/response_sweep_1.yaml --seeds 2 --restart-after-fall \\
      --feedforward off --out out/response_1
  python3 scripts/fit_command_response.py out/response_*/summary.json --out out/feedforward.yaml
  python3 scripts/make_response_sweep.py --segments 72 --seed 7 --height-range 0.66 0.78 \\
      --controller config/controller/g1_sil_policy_wh6g.yaml \\
      --out config/policies/response_sweep_7.yaml   # a crouched sweep (7 and 8 shipped, wh6g's L1 envelope)

The shipped model's data: response_sweep_1.yaml (seeds 0-3), _2 and _3 (seeds 0-1), as
docs/controller.md "Command-response feed-forward" lists.

Drawn with its own seed, never from the evaluation scripts' commands: the grid and Table I stay
held out (docs/controller.md "Command-response feed-forward").
"""
import argparse
import os
import random

import yaml

# The issue-12 envelope: v_x [-0.5, 1.0] m/s, v_y [-0.4, 0.4] m/s, w [-0.8, 0.8] rad/s.
LO = (-0.5, -0.4, -0.8)
HI = (1.0, 0.4, 0.8)
MIN_ABS = (0.1, 0.08, 0.15)  # smaller commands are inside the shaper's and the evaluation's dead bands


REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# CommandLimits' defaults (include/pmg/controller/commands.hpp) for keys a config leaves out.
COMMAND_DEFAULTS = {"max_velocity": [1.0, 0.5, 1.0], "height_rate": 0.2, "standing_height": 0.78, "crouched_height": 0.0,
                    "crouched_max_velocity": [0.4, 0.3, 0.6], "crouched_per_axis": False, "walking_min_height": 0.0}


def crouch_scale(u, height, limits):
    """The crouched envelope's scale of command u at pelvis height h (CommandShaper::envelopeScales, the
    crouch part; pitch 0; the L1 rule, or max_i with commands.crouched_per_axis): > 1 means the shaper slows
    the command along its direction."""
    standing, crouched = limits["standing_height"], limits.get("crouched_height", 0.0)
    if not crouched > 0.0:
        return 0.0
    f = min(max((standing - height) / (standing - crouched), 0.0), 1.0)
    if f <= 0.0:
        return 0.0
    m, mc = limits["max_velocity"], limits["crouched_max_velocity"]
    box = max(abs(u[i]) / m[i] for i in range(3))
    r = [abs(u[i]) / (m[i] + f * (mc[i] - m[i])) for i in range(3)]
    return (1.0 - f) * box + f * (max(r) if limits.get("crouched_per_axis", False) else sum(r))


def draw(rng, max_load, height=None, limits=None):
    while True:
        active = [a for a in range(3) if rng.random() < 0.55]
        if not active:
            continue
        u = [0.0, 0.0, 0.0]
        for a in active:
            while abs(u[a]) < MIN_ABS[a]:
                u[a] = rng.uniform(LO[a], HI[a])
        load = sum(abs(u[a]) / (HI[a] if u[a] > 0 else -LO[a]) for a in range(3))
        u = [round(x, 3) for x in u]
        if load <= max_load and (limits is None or crouch_scale(u, height, limits) <= 1.0):
            return u


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--segments", type=int, default=72)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--hold", type=float, default=4.0, help="seconds each command is held")
    ap.add_argument("--stand", type=float, default=2.5, help="seconds of standing after each")
    ap.add_argument("--max-load", type=float, default=2.0)
    ap.add_argument("--height", type=float, default=0.78, help="every segment's height [m] (without --height-range)")
    ap.add_argument("--height-range", type=float, nargs=2, metavar=("LO", "HI"),
                    help="each segment's height drawn from [max(LO, walking_min_height), HI] [m]")
    ap.add_argument("--controller", default=os.path.join(REPO, "config/controller/g1_sil_policy.yaml"),
                    help="the controller config whose commands: limits (envelope, heights) the crouched draws respect")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    if args.segments < 1 or args.hold <= 0 or args.stand < 0:
        ap.error("--segments >= 1, --hold > 0, --stand >= 0")
    rng = random.Random(args.seed)
    limits, lo, hi = None, args.height, args.height
    if args.height_range:
        with open(args.controller) as f:
            limits = {**COMMAND_DEFAULTS, **(yaml.safe_load(f).get("commands") or {})}
        lo = max(args.height_range[0], limits.get("walking_min_height", 0.0))
        hi = args.height_range[1]
        if not (limits["crouched_height"] > 0.0 and limits["crouched_height"] <= lo <= hi <= limits["standing_height"]):
            ap.error(f"--height-range: expected commands.crouched_height (> 0) <= LO <= HI <= standing_height: "
                     f"{limits['crouched_height']}, {lo}, {hi}, {limits['standing_height']} (commands: of {args.controller})")
        if args.stand < (hi - lo) / limits["height_rate"] + 0.5:
            ap.error(f"--stand {args.stand}: the height's slew needs {(hi - lo) / limits['height_rate'] + 0.5:.1f} s")
    # A stand is at the next walk's height: the robot crouches or rises standing, not walking.
    heights = [args.height if limits is None else round(rng.uniform(lo, hi), 3) for _ in range(args.segments)]
    rows = [("stand", 0.0, [0.0, 0.0, 0.0], heights[0])]
    t = 3.0
    for k in range(args.segments):
        rows.append((f"r{k:03d}", t, draw(rng, args.max_load, heights[k], limits), heights[k]))
        t += args.hold
        rows.append((f"stand_{k:03d}", t, [0.0, 0.0, 0.0], heights[min(k + 1, args.segments - 1)]))
        t += args.stand
    with open(args.out, "w") as f:
        f.write("# Calibration sweep of the command-response feed-forward, written by\n")
        f.write(f"#   python3 scripts/make_response_sweep.py --segments {args.segments} --seed {args.seed} "
                f"--hold {args.hold} --stand {args.stand} --max-load {args.max_load} "
                + (f"--height-range {args.height_range[0]} {args.height_range[1]} (envelope of "
                   f"{os.path.relpath(args.controller, REPO)})" if limits else f"--height {args.height}") + "\n")
        f.write("# (random commands over the issue-12 envelope; docs/controller.md \"Command-response feed-forward\").\n")
        f.write(f"ramp: 0.5\nduration: {t:.1f}\nsegments:\n")
        for name, t0, u, h in rows:
            f.write(f"  - {{name: {name}, t: {t0:.1f}, vx: {u[0]}, vy: {u[1]}, wz: {u[2]}, pitch: 0, roll: 0, "
                    f"height: {h}}}\n")
    print(f"{args.out}: {args.segments} commands, {t:.0f} s")


if __name__ == "__main__":
    main()
