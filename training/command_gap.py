#!/usr/bin/env python3
"""How much of a run's training commands the product path never gives: the user's command u as the
training environment draws and shapes it (G1PmgEnv._first_command, _next_command: the run's ranges, mix,
stops and slew), rolled for --envs episodes of --steps control steps, once as the run trained (its
train_config.json) and once with the controller's velocity envelopes and walking height floor
(EnvConfig.command_envelopes, the values of --controller's `commands:`). No physics, no actor.

  python3 training/command_gap.py RUN/train_config.json [--controller config/controller/g1_sil_policy_wh6g.yaml]
      [--clips DIR] [--envs 4096] [--steps 1000] [--seed 0] [--json OUT.json]

Per process, over the walking steps (|v_x|, |v_y| or |w| of u above 0.01): the share below the walking
height floor (u_h more than 1 mm under walking_min_height), beyond the crouched envelope and beyond the
bent envelope (the scale above 1.01, at u's own posture: pmg_train.g1_env.envelope_scales, the
controller's, with training's headroom beyond the controller's box passing upright), any of the three, and the share of walking steps crouched to the floor's band (u_h in [floor - 0.005, floor +
0.02] m) and below 0.70 m. The scales are proven equal to pmg::CommandShaper's inside its box by
training/tests/test_command_envelopes.py. What stays beyond with the envelopes on is the velocity slewing
down while the height or the pitch moves faster into the envelope, as the controller's does. Writes the table to stdout and, with --json, the
numbers.
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("train_config", help="a run's train_config.json (its 'env' entry)")
    ap.add_argument("--controller", default="config/controller/g1_sil_policy_wh6g.yaml",
                    help="controller config whose `commands:` envelopes and floor the second process applies")
    ap.add_argument("--clips", default=None,
                    help="clip folder instead of the run's (a run trained on a folder since renamed); its squat "
                         "clip's neutral is the standing height")
    ap.add_argument("--envs", type=int, default=4096, help="episodes rolled at once")
    ap.add_argument("--steps", type=int, default=1000, help="control steps per episode")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None, help="also write the numbers here")
    args = ap.parse_args(argv)
    if args.envs < 1 or args.steps < 1:
        ap.error(f"--envs {args.envs} --steps {args.steps}: expected at least 1 each")
    return args


def roll(env, key, n_envs, n_steps):
    """The shaped command u of n_envs episodes, (n_steps, n_envs, 6)."""
    import jax
    import jax.numpy as jnp
    c = env.cfg

    def episode(k):
        k0, k1 = jax.random.split(k)
        goal = env._sample_command(k0)
        command = env._first_command(goal)

        def body(carry, t):
            goal, command, since = carry
            resample = ((t + 1) % c.command_resample) == 0
            goal, command, since = env._next_command(goal, command, since, jax.random.fold_in(k1, t), resample)
            return (goal, command, since), command

        _, us = jax.lax.scan(body, (goal, command, jnp.float32(1e3)), jnp.arange(n_steps))
        return us

    return jax.jit(jax.vmap(episode))(jax.random.split(key, n_envs)).swapaxes(0, 1)


def shares(jnp, u, lim):
    walking = jnp.any(jnp.abs(u[..., :3]) > 0.01, -1)
    n = float(walking.sum())
    floor = lim["walking_min_height"]
    below = walking & (u[..., 5] < floor - 1e-3)
    from pmg_train.g1_env import envelope_scales
    crouch, bent = envelope_scales(jnp, u[..., :3], u[..., 3], u[..., 5], lim)
    beyond_c, beyond_b = walking & (crouch > 1.01), walking & (bent > 1.01)
    at_floor = walking & (u[..., 5] >= floor - 0.005) & (u[..., 5] <= floor + 0.02)
    under70 = walking & (u[..., 5] < 0.70)
    out = {"walking_steps": n, "share_walking": n / u[..., 0].size}
    for name, m in (("below_floor", below), ("beyond_crouched", beyond_c), ("beyond_bent", beyond_b),
                    ("any", below | beyond_c | beyond_b), ("at_floor_band", at_floor), ("under_0.70", under70)):
        out[name] = float(m.sum()) / max(n, 1.0)
    return out


def main(argv=None):
    args = parse_args(argv)
    import dataclasses

    import jax
    import jax.numpy as jnp
    from eval_mjx import env_from_train_config
    from pmg_train.g1_env import EnvConfig, G1PmgEnv
    from train_pmg import command_envelopes_from
    trained = env_from_train_config(args.train_config)
    if args.clips:
        trained["clips"] = args.clips
    cfg = EnvConfig(**trained)
    enveloped = G1PmgEnv(dataclasses.replace(cfg, command_slew=True, **command_envelopes_from(args.controller)))
    lim = enveloped.envelope_limits
    rows = {}
    for name, env in (("as trained", G1PmgEnv(cfg)), ("with the controller's envelopes", enveloped)):
        u = roll(env, jax.random.PRNGKey(args.seed), args.envs, args.steps)
        rows[name] = shares(jnp, u, lim)
    print(f"{args.train_config}: {args.envs} episodes x {args.steps} steps; envelopes and floor of {args.controller} "
          f"(floor {lim['walking_min_height']} m, standing {lim['standing_height']:.4f} m)")
    print("| command process | walking share of steps | below the floor | beyond the crouched envelope | "
          "beyond the bent envelope | any of the three | at the floor (0.655-0.68 m) | below 0.70 m |")
    print("|---|---|---|---|---|---|---|---|")
    for name, r in rows.items():
        print(f"| {name} | {r['share_walking']:.3f} | {r['below_floor']:.3f} | {r['beyond_crouched']:.3f} | "
              f"{r['beyond_bent']:.3f} | {r['any']:.3f} | {r['at_floor_band']:.3f} | {r['under_0.70']:.3f} |")
    print("(shares of the walking steps; a step walks when |v_x|, |v_y| or |w| of u is above 0.01)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"train_config": args.train_config, "controller": args.controller, "envs": args.envs,
                       "steps": args.steps, "seed": args.seed, "limits": lim, "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
