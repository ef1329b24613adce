#!/usr/bin/env python3
"""The training command mix's focus box (EnvConfig.p_focus, command_focus; train_pmg.py --command-focus,
--p-focus): training/pmg_train/g1_env.py focus_box and G1PmgEnv._sample_command.

  python3 training/tests/test_command_focus.py

Checks (no physics, no env step compiled; seconds):
- focus_box resolves the box in command order, an axis not named zero or the standing height, and refuses
  naming the field: an unknown axis, a reversed or non-finite bound, a box outside the axis's range,
  p_focus outside [0, 1], p_focus > 0 without a box.
- With p_focus 0 and a box given, the 4000 drawn goals equal those without the box bit for bit (the random
  stream is unchanged: every earlier run's draws stay as they were). The config is EnvConfig's with the
  runs' v_x range, -0.85..1.25 m/s.
- With p_focus 0.25 and the box v_x in [-0.6, -0.3] m/s at 0.66-0.72 m (walking backward crouched), the
  share of goals inside the box is 0.25 within 0.03 (without the focus: below 0.01), its goals fill the box
  (each bound within 0.02 of the drawn extremes), and the rest are the plain mix's draws.
- The focus reaches what the actor sees: with the controller's slew and envelopes (command_gap.roll, 256
  episodes x 400 steps), the share of walking steps walking backward faster than 0.25 m/s below 0.73 m is
  at least twice the plain mix's.
- EnvConfig with the focus survives train_config.json (dataclasses.asdict, JSON, EnvConfig(**), as
  eval_mjx.py reads it): the same box.
It re-runs itself in the training environment (test_smoke_cpu.relaunch; exit 77 with
PMG_SKIP_TRAINING_TESTS=1). Exit 0 on success, 1 on a failed check.
"""
import dataclasses
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))  # training/: pmg_train, command_gap, train_pmg
from test_smoke_cpu import CHILD, relaunch  # noqa: E402

BOX = {"vx": (-0.6, -0.3), "height": (0.66, 0.72)}


def main():
    if os.environ.get(CHILD) != "1":
        relaunch(__file__)
    import jax
    import jax.numpy as jnp
    from command_gap import roll
    from pmg_train.g1_env import EnvConfig, G1PmgEnv, focus_box
    from train_pmg import command_envelopes_from
    failures = []

    def check(ok, msg):
        print(("ok   " if ok else "FAIL ") + msg)
        if not ok:
            failures.append(msg)

    base = dataclasses.replace(EnvConfig(), vx=(-0.85, 1.25))  # the runs' v_x range (train_pmg --command-range)
    lo, hi = focus_box(dataclasses.replace(base, command_focus=BOX, p_focus=0.2), 0.79)
    check(np.allclose(lo, [-0.6, 0, 0, 0, 0, 0.66]) and np.allclose(hi, [-0.3, 0, 0, 0, 0, 0.72]),
          f"focus_box: lo {np.round(lo.astype(float), 3).tolist()}, hi {np.round(hi.astype(float), 3).tolist()} (unnamed axes zero)")
    lo, hi = focus_box(dataclasses.replace(base, command_focus={"wz": [0.2, 0.4]}, p_focus=0.2), 0.79)
    check(abs(lo[5] - 0.79) < 1e-6 and abs(hi[5] - 0.79) < 1e-6 and lo[2] == np.float32(0.2),
          "focus_box: an unnamed height is the standing height; bounds from a JSON list parse")
    for bad, field in (({"command_focus": {"speed": (0, 1)}, "p_focus": 0.1}, "unknown axis 'speed'"),
                       ({"command_focus": {"vx": (-0.3, -0.6)}, "p_focus": 0.1}, "command_focus['vx']"),
                       ({"command_focus": {"vx": (float("nan"), 0.1)}, "p_focus": 0.1}, "command_focus['vx']"),
                       ({"command_focus": {"vx": (0.1,)}, "p_focus": 0.1}, "command_focus['vx']"),
                       ({"command_focus": {"height": (0.5, 0.7)}, "p_focus": 0.1}, "EnvConfig.height"),
                       ({"command_focus": {"vy": (-0.5, 0.1)}, "p_focus": 0.1}, "EnvConfig.vy"),
                       ({"command_focus": BOX, "p_focus": 1.5}, "p_focus"),
                       ({"p_focus": 0.1}, "needs a command_focus")):
        try:
            focus_box(dataclasses.replace(base, **bad), 0.79)
            check(False, f"focus_box accepted {bad}")
        except ValueError as e:
            check(field in str(e), f"focus_box refuses {bad}: {e}")

    n = 4000
    keys = jax.random.split(jax.random.PRNGKey(3), n)

    def draws(cfg):
        env = G1PmgEnv(cfg)
        return np.asarray(jax.jit(jax.vmap(env._sample_command))(keys)), env

    plain, env = draws(base)
    off, _ = draws(dataclasses.replace(base, command_focus=BOX, p_focus=0.0))
    check(np.array_equal(plain, off), "p_focus 0 with a box: the goals equal the same config's without it bit for bit")
    focused, _ = draws(dataclasses.replace(base, command_focus=BOX, p_focus=0.25))
    stand = env.js.standing_base_height

    def inside(g):
        return ((g[:, 0] >= -0.6 - 1e-6) & (g[:, 0] <= -0.3 + 1e-6) & (g[:, 1] == 0) & (g[:, 2] == 0) &
                (g[:, 3] == 0) & (g[:, 4] == 0) & (g[:, 5] >= 0.66 - 1e-6) & (g[:, 5] <= 0.72 + 1e-6))
    share, share0 = inside(focused).mean(), inside(plain).mean()
    check(abs(share - 0.25) < 0.03 and share0 < 0.01,
          f"p_focus 0.25: {share:.3f} of {n} goals in the box (plain mix: {share0:.4f}; standing height {stand:.3f})")
    box = focused[inside(focused) & ~inside(plain)]
    check(len(box) > 0 and abs(box[:, 0].min() + 0.6) < 0.02 and abs(box[:, 0].max() + 0.3) < 0.02 and
          abs(box[:, 5].min() - 0.66) < 0.02 and abs(box[:, 5].max() - 0.72) < 0.02,
          f"the box's goals fill it: v_x {box[:, 0].min():.3f}..{box[:, 0].max():.3f}, "
          f"height {box[:, 5].min():.3f}..{box[:, 5].max():.3f}")
    rest = ~inside(focused)
    check(np.array_equal(focused[rest], plain[rest]), f"the other {int(rest.sum())} goals are the plain mix's draws")

    shaped = dict(command_slew=True, p_posture_walk=0.6, **command_envelopes_from("config/controller/g1_sil_policy_wh6g.yaml"))
    corner = {}
    for name, focus in (("plain", {}), ("focused", {"command_focus": BOX, "p_focus": 0.25})):
        u = np.asarray(roll(G1PmgEnv(dataclasses.replace(base, **shaped, **focus)), jax.random.PRNGKey(0), 256, 400))
        walking = np.any(np.abs(u[..., :3]) > 0.01, -1)
        corner[name] = float((walking & (u[..., 0] < -0.25) & (u[..., 5] < 0.73)).sum() / max(walking.sum(), 1))
    check(corner["focused"] > 2 * corner["plain"] and corner["focused"] > 0.05,
          f"with the controller's slew and envelopes, walking backward beyond 0.25 m/s below 0.73 m: "
          f"{corner['plain']:.3f} -> {corner['focused']:.3f} of the walking steps")

    cfg = dataclasses.replace(base, command_focus=BOX, p_focus=0.25)
    back = EnvConfig(**json.loads(json.dumps(dataclasses.asdict(cfg))))
    same = [np.allclose(a, b) for a, b in zip(focus_box(back, stand), focus_box(cfg, stand))]
    check(all(same) and back.p_focus == 0.25, "the focus survives train_config.json (asdict, JSON, EnvConfig(**))")
    print("FAILED" if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
