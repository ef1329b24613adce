#!/usr/bin/env python3
"""The training environment's command shaper with the controller's envelopes
(training/pmg_train/g1_env.py: shape_with_envelopes, EnvConfig.command_envelopes) equals the
controller's (pmg::CommandShaper, src/controller/commands.cpp) tick for tick.

  python3 training/tests/test_command_envelopes.py SHAPER_JSON

SHAPER_JSON is pmg_shaper_vectors' output (a goal schedule that crouches below the walking height floor
while walking, stops there, walks bent and bent-crouched, and backward; the config's `commands:` limits).
Checks, in float64 NumPy: every tick's shaped command equals the C++ one within 1e-9; the envelopes and
the floor acted in the schedule (the test can fail: with them off the port leaves the C++ by more than
0.1 m/s and 0.03 m); the floor holds for the configured time after the stop, then the height descends.
Then the same under jax.jit in float32 (the training environment's precision), within 1e-4, and
EnvConfig's defaults equal the JSON's limits (the defaults are wh6g's config's `commands:`, the L1 rule). Last,
the environment's own command process (training/command_gap.py, 256 episodes x 400 steps, heights down to
0.59 m): with the envelopes the share of walking below the floor or beyond the envelopes falls below 2 %
(above 10 % without), and more than twice as much walking happens at the floor. It
re-runs itself in the training environment (test_smoke_cpu.relaunch; exit 77 with
PMG_SKIP_TRAINING_TESTS=1). Exit 0 on success, 1 on a failed check.
"""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))  # training/: pmg_train, command_gap
from test_smoke_cpu import CHILD, relaunch  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("vectors")
    args = ap.parse_args()
    if os.environ.get(CHILD) != "1":
        relaunch(__file__)
    import jax
    import jax.numpy as jnp
    with open(args.vectors) as f:
        doc = json.load(f)
    lim = dict(doc["limits"], dt=doc["dt"])
    goals = np.array([t["goal"] for t in doc["ticks"]])
    cpp = np.array([t["shaped"] for t in doc["ticks"]])
    failures = []

    def check(ok, msg):
        print(("ok   " if ok else "FAIL ") + msg)
        if not ok:
            failures.append(msg)

    from pmg_train.g1_env import EnvConfig, shape_with_envelopes

    def run(xp, limits, dtype):
        cmd = xp.asarray(np.r_[0.0, 0.0, 0.0, 0.0, 0.0, limits["standing_height"]], dtype)
        since = xp.asarray(1e3, dtype)
        step = lambda c, g, t: shape_with_envelopes(xp, c, g, t, limits)  # noqa: E731
        step = step if xp is np else jax.jit(step)
        out = []
        for g in goals:
            cmd, since = step(cmd, xp.asarray(g, dtype), since)
            out.append(np.asarray(cmd, float))
        return np.array(out)

    py = run(np, lim, np.float64)
    err = np.abs(py - cpp).max(axis=0)
    check(err.max() < 1e-9, f"{len(goals)} ticks: the port equals pmg::CommandShaper (largest |diff| per axis "
                            f"{', '.join(f'{e:.1e}' for e in err)})")
    off = run(np, dict(lim, crouched_height=0.0, bent_pitch=0.0, walking_min_height=0.0), np.float64)
    dv, dh = np.abs(off[:, :3] - cpp[:, :3]).max(), np.abs(off[:, 5] - cpp[:, 5]).max()
    check(dv > 0.1 and dh > 0.03, f"the envelopes and the floor act in the schedule (without them the shaped "
                                  f"command leaves the C++ one by up to {dv:.3f} m/s or rad/s and {dh:.3f} m)")
    # The crouched stop (schedule's 4th segment, ticks 700-1049, goal height 0.62): the floor holds for
    # walking_min_height_hold_s after the shaped velocity reaches 0, then the height descends at its rate.
    seg = slice(700, 1050)
    v0 = np.flatnonzero(np.all(cpp[seg, :3] == 0.0, axis=1))[0] + 700
    left = np.flatnonzero(py[v0:1050, 5] < lim["walking_min_height"] - 1e-9)[0] + v0
    held = (left - v0) * lim["dt"]
    check(abs(held - lim["walking_min_height_hold_s"]) <= 1.5 * lim["dt"] and py[1049, 5] < lim["walking_min_height"] - 0.03,
          f"the crouched stop: the height floor held {held:.2f} s after the stop "
          f"(walking_min_height_hold_s {lim['walking_min_height_hold_s']}), then the height went to {py[1049, 5]:.3f} m")
    c = EnvConfig()
    mine = dict(max_velocity=c.envelope_max_velocity, crouched_height=c.crouched_height,
                crouched_max_velocity=c.crouched_max_velocity, bent_pitch=c.bent_pitch,
                bent_max_velocity=c.bent_max_velocity, walking_min_height=c.walking_min_height,
                walking_min_height_hold_s=c.walking_min_height_hold_s, max_acceleration=c.command_max_accel,
                posture_rate=c.command_posture_rate, height_rate=c.command_height_rate)
    same = all(np.allclose(np.asarray(v, float), np.asarray(lim[k], float)) for k, v in mine.items())
    check(same, "EnvConfig's envelope defaults equal the config's `commands:` limits")
    py = run(jnp, lim, jnp.float32)
    err = np.abs(py - cpp).max()
    check(err < 1e-4, f"under jax.jit in float32: largest |diff| {err:.1e} (< 1e-4)")
    # The environment's command process (command_gap.py: _first_command, _next_command, 256 episodes of 400
    # steps) with training's height range down to 0.59 m: without the envelopes some walks go below the floor;
    # with them (the same draws) next to none do, and more walking happens at the floor.
    import dataclasses
    from command_gap import roll, shares
    from pmg_train.g1_env import G1PmgEnv
    base = dataclasses.replace(c, command_slew=True, height=(0.59, 0.78), p_posture_walk=0.6)
    rows = {}
    for name, on in (("as trained", False), ("enveloped", True)):
        env = G1PmgEnv(dataclasses.replace(base, command_envelopes=on))
        rows[name] = shares(jnp, roll(env, jax.random.PRNGKey(0), 256, 400), lim)
    a, b = rows["as trained"], rows["enveloped"]
    check(a["below_floor"] > 0.05 and b["below_floor"] < 0.01 and a["any"] > 0.1 and b["any"] < 0.02 and
          b["at_floor_band"] > 2 * a["at_floor_band"],
          f"the env's command process (command_gap.py): walking below the floor {a['below_floor']:.3f} -> "
          f"{b['below_floor']:.3f}, beyond the controller's envelopes or floor {a['any']:.3f} -> {b['any']:.3f}, "
          f"walking at the floor {a['at_floor_band']:.3f} -> {b['at_floor_band']:.3f}")
    print("FAILED" if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
