#!/usr/bin/env python3
"""Write a calibration command script for the command-response feed-forward (issue 12).

Random velocity commands (v_x, v_y, w in the heading frame) over the issue-12 envelope, each held
for --hold s and followed by a stand of --stand s, at the standing height, upright. One to three
axes move per segment; a combination whose normalised size sum_i |u_i| / max_i exceeds --max-load
is drawn again (the grid's hardest combinations, diag_turn and arc_r_fast, are about 1.9). The
script is in the format of config/policies/eval_envelope.yaml (include/pmg/controller/commands.hpp).

  python3 scripts/make_response_sweep.py --segments 72 --seed 1 --out config/policies/response_sweep_1.yaml
  build/bin/pmg_policy_sil --commands config/policies/response_sweep_1.yaml --seeds 2 --restart-after-fall \\
      --feedforward off --out out/response_1
  python3 scripts/fit_command_response.py out/response_*/summary.json --out out/feedforward.yaml

The shipped model's data: response_sweep_1.yaml (seeds 0-3), _2 and _3 (seeds 0-1), as
docs/controller.md "Command-response feed-forward" lists.

Drawn with its own seed, never from the evaluation scripts' commands: the grid and Table I stay
held out (docs/controller.md "Command-response feed-forward").
"""
import argparse
import random

# The issue-12 envelope: v_x [-0.5, 1.0] m/s, v_y [-0.4, 0.4] m/s, w [-0.8, 0.8] rad/s.
LO = (-0.5, -0.4, -0.8)
HI = (1.0, 0.4, 0.8)
MIN_ABS = (0.1, 0.08, 0.15)  # smaller commands are inside the shaper's and the evaluation's dead bands


def draw(rng, max_load):
    while True:
        active = [a for a in range(3) if rng.random() < 0.55]
        if not active:
            continue
        u = [0.0, 0.0, 0.0]
        for a in active:
            while abs(u[a]) < MIN_ABS[a]:
                u[a] = rng.uniform(LO[a], HI[a])
        load = sum(abs(u[a]) / (HI[a] if u[a] > 0 else -LO[a]) for a in range(3))
        if load <= max_load:
            return [round(x, 3) for x in u]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--segments", type=int, default=72)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--hold", type=float, default=4.0, help="seconds each command is held")
    ap.add_argument("--stand", type=float, default=2.5, help="seconds of standing after each")
    ap.add_argument("--max-load", type=float, default=2.0)
    ap.add_argument("--height", type=float, default=0.78)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    if args.segments < 1 or args.hold <= 0 or args.stand < 0:
        ap.error("--segments >= 1, --hold > 0, --stand >= 0")
    rng = random.Random(args.seed)
    rows = [("stand", 0.0, [0.0, 0.0, 0.0])]
    t = 3.0
    for k in range(args.segments):
        rows.append((f"r{k:03d}", t, draw(rng, args.max_load)))
        t += args.hold
        rows.append((f"stand_{k:03d}", t, [0.0, 0.0, 0.0]))
        t += args.stand
    with open(args.out, "w") as f:
        f.write("# Calibration sweep of the command-response feed-forward, written by\n")
        f.write(f"#   python3 scripts/make_response_sweep.py --segments {args.segments} --seed {args.seed} "
                f"--hold {args.hold} --stand {args.stand} --max-load {args.max_load} --height {args.height}\n")
        f.write("# (random commands over the issue-12 envelope; docs/controller.md \"Command-response feed-forward\").\n")
        f.write(f"ramp: 0.5\nduration: {t:.1f}\nsegments:\n")
        for name, t0, u in rows:
            f.write(f"  - {{name: {name}, t: {t0:.1f}, vx: {u[0]}, vy: {u[1]}, wz: {u[2]}, pitch: 0, roll: 0, "
                    f"height: {args.height}}}\n")
    print(f"{args.out}: {args.segments} commands, {t:.0f} s")


if __name__ == "__main__":
    main()
