#!/usr/bin/env python3
"""Where the training environment's step spends its time: a bench that prints numbers.

Runs batches of the G1 PMG environment (pmg_train/g1_env.py) on the first local JAX device, jitted
and vmapped as Brax's PPO runs them (without PPO's networks and the domain randomisation), and times:
- `physics`: the MJX physics alone, the env's substeps of mjx.step per control step, on the same
  model and reset states (no actuator model, no PMG);
- `pmg`: the whole env.step with the generator but without GCO (EnvConfig mode "pmg");
- `pmg_gco`: the whole env.step of the full-PMG configuration that every issue-12 run trains.
For each it prints the compile time of the reset (once per mode) and of the first call and the steady-state time per control step
of the batch (the mean of --steps calls, each waited for), as environment steps per second. The
difference between the parts is what the generator, GCO, the observation and the rewards cost.

  python3 training/bench_env_step.py [--num-envs 16384] [--steps 20] [--parts physics,pmg,pmg_gco]
      [--clips config/clips/g1_walking_height] [--out bench.json]

Errors: an unknown part or a non-positive count is refused (argparse, exit 2).
"""
import argparse
import glob
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

PARTS = ("physics", "pmg", "pmg_gco")


def parts_list(ap, text, known):
    """The comma-separated --parts @p text as a list, in order; an unknown or empty list is an argparse error."""
    parts = [p.strip() for p in text.split(",") if p.strip()]
    bad = [p for p in parts if p not in known]
    if bad or not parts:
        ap.error(f"--parts {bad or '(empty)'}: expected a comma-separated list of {', '.join(known)}")
    return parts


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--num-envs", type=int, default=16384, help="environments per batch (a training run's count)")
    ap.add_argument("--steps", type=int, default=20, help="timed control steps per part, after the compiling call")
    ap.add_argument("--parts", default=",".join(PARTS), help=f"comma-separated, in order: {', '.join(PARTS)}")
    ap.add_argument("--clips", default="config/clips/g1_walking_height", help="clip folder, relative to the checkout")
    ap.add_argument("--out", default=None, help="also write the numbers as JSON here")
    args = ap.parse_args(argv)
    args.parts = parts_list(ap, args.parts, PARTS)
    for name in ("num_envs", "steps"):
        if getattr(args, name) < 1:
            ap.error(f"--{name.replace('_', '-')} = {getattr(args, name)}: expected >= 1")
    return args


def timed(fn, state, steps):
    """(compile + first call [s], steady mean per call [s], final state) of state -> fn(state)."""
    import jax
    t0 = time.perf_counter()
    state = jax.block_until_ready(fn(state))
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(steps):
        state = jax.block_until_ready(fn(state))
    return first, (time.perf_counter() - t0) / steps, state


def main(argv=None):
    args = parse_args(argv)
    from pmg_train.paths import repo_root
    os.chdir(repo_root(None))
    import jax
    import jax.numpy as jnp
    from mujoco import mjx
    from pmg_train.g1_env import EnvConfig, G1PmgEnv

    clips = sorted(glob.glob(os.path.join(args.clips, "*.yaml")))
    if not clips:
        raise SystemExit(f"--clips {args.clips}: no clip files (*.yaml) there")
    dev = jax.devices()[0]
    print(f"JAX {jax.__version__} on {dev}; {args.num_envs} environments, {args.steps} timed steps per part", flush=True)
    keys = jax.random.split(jax.random.PRNGKey(0), args.num_envs)
    results = {"device": str(dev), "num_envs": args.num_envs, "steps": args.steps, "parts": {}}
    envs, resets = {}, {}
    for part in args.parts:
        mode = "pmg_gco" if part == "physics" else part
        reset_s = 0.0
        if mode not in envs:  # one environment and one batch of reset states per mode
            envs[mode] = G1PmgEnv(EnvConfig(mode=mode), clips)
            t0 = time.perf_counter()
            resets[mode] = jax.block_until_ready(jax.jit(jax.vmap(envs[mode].reset))(keys))
            reset_s = time.perf_counter() - t0
        env, state = envs[mode], resets[mode]
        if part == "physics":
            sys_ = env.sys
            n_sub = env.n_substeps

            def physics(data):
                def sub(d, _):
                    return mjx.step(sys_, d), None
                return jax.lax.scan(sub, data, None, length=n_sub)[0]

            fn = jax.jit(jax.vmap(physics))
            first, per, _ = timed(fn, state.pipeline_state, args.steps)
        else:
            action = jnp.zeros((args.num_envs, env.action_size))
            step = jax.jit(jax.vmap(env.step))
            first, per, _ = timed(lambda s: step(s, action), state, args.steps)
        rate = args.num_envs / per
        results["parts"][part] = {"reset_compile_s": reset_s, "compile_and_first_s": first, "per_step_ms": per * 1e3,
                                  "env_steps_per_s": rate}
        print(f"{part:8s} reset {reset_s:6.1f} s  compile+first {first:6.1f} s  per control step {per * 1e3:8.2f} ms  "
              f"{rate / 1e3:8.1f} k env steps/s", flush=True)
        if args.out:
            with open(args.out, "w") as f:
                json.dump(results, f, indent=1)
    full = results["parts"].get("pmg_gco")
    for part, r in results["parts"].items():
        if full and part != "pmg_gco":
            print(f"{part} is {r['per_step_ms'] / full['per_step_ms'] * 100:.0f} % of the full step's time", flush=True)


if __name__ == "__main__":
    main()
