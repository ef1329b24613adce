#!/usr/bin/env python3
"""What the training environment costs XLA to compile on the CPU: a bench that prints numbers.

The CPU smoke tests (training/tests/test_smoke_cpu.py) spend most of their time compiling, not running
(docs/ci_timing.md, "Where the time goes"). This bench builds the smoke tests' env (full PMG with GCO,
upright walking, levelled stance soles, a calibrated robot, hand forces), relaunched as the tests are:
the training environment's interpreter, the tests' XLA flags and allocator, and no compilation cache.
For each part, jitted un-batched as the smoke rollout runs it, it prints the seconds spent tracing and
lowering to StableHLO, the seconds XLA spends compiling, and the size of the optimised HLO (lines):
- `generator`: one tick of the PMG generator port (pmg_generator.step, eqs. 4-12, the consistent blending);
- `reference`: the env's reference tick, the generator and GCO (level_soles, gco.step; eqs. 13-19);
- `reset`, `step`: the env's reset and one control step (4 MJX substeps, the actuator model, rewards).

  python3 training/bench_compile.py [--parts generator,reference,reset,step] [--out compile.json]

Errors: an unknown part is refused (argparse, exit 2); a missing training environment as the smoke tests
report it (exit 1).
"""
import argparse
import glob
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "tests"))

from bench_env_step import parts_list  # noqa: E402

PARTS = ("generator", "reference", "reset", "step")


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--parts", default=",".join(PARTS), help=f"comma-separated, in order: {', '.join(PARTS)}")
    ap.add_argument("--out", default=None, help="also write the numbers as JSON here")
    args = ap.parse_args(argv)
    args.parts = parts_list(ap, args.parts, PARTS)
    return args


def compile_times(fn, *args):
    """(trace + lower [s], compile [s], optimised HLO lines) of jax.jit(fn) at @p args."""
    import jax
    t0 = time.perf_counter()
    lowered = jax.jit(fn).lower(*args)
    t1 = time.perf_counter()
    compiled = lowered.compile()
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1, compiled.as_text().count("\n")


def main(argv=None):
    args = parse_args(argv)
    import test_smoke_cpu as smoke
    if os.environ.get(smoke.CHILD) != "1":
        os.environ["PMG_JAX_CACHE_DIR"] = "off"  # every compile is measured, none read from a cache
        smoke.relaunch(os.path.abspath(__file__))
    os.chdir(smoke.REPO)
    import jax
    import jax.numpy as jnp
    from pmg_train import pmg_generator as pg

    print(f"JAX {jax.__version__} ({jax.default_backend()}); XLA_FLAGS={os.environ.get('XLA_FLAGS', '')}; "
          f"LD_PRELOAD={os.environ.get('LD_PRELOAD', '') or '(none)'}", flush=True)
    with tempfile.TemporaryDirectory() as work:
        env, _ = smoke.make_smoke_env(work)
        st = jax.jit(env.reset)(jax.random.PRNGKey(0))
        cmd, phase = st.info["command"], st.info["phase"]
        fns = {
            "generator": (lambda p, c: pg.step(env.pmg, p, c[:3], c[3:], env.cfg.control_dt, xp=jnp), phase, cmd),
            "reference": (lambda p, c, g: env._reference(p, c, g), phase, cmd, st.info["gco"]),
            "reset": (env.reset, jax.random.PRNGKey(1)),
            "step": (env.step, st, jnp.zeros(env.action_size)),
        }
        results = {"jax": jax.__version__, "xla_flags": os.environ.get("XLA_FLAGS", ""),
                   "ld_preload": os.environ.get("LD_PRELOAD", ""), "parts": {}}
        print(f"{'part':<10} {'trace+lower [s]':>16} {'compile [s]':>12} {'HLO lines':>10}", flush=True)
        for part in args.parts:
            fn, *fargs = fns[part]
            lower_s, compile_s, lines = compile_times(fn, *fargs)
            results["parts"][part] = {"trace_lower_s": lower_s, "compile_s": compile_s, "hlo_lines": lines}
            print(f"{part:<10} {lower_s:>16.1f} {compile_s:>12.1f} {lines:>10d}", flush=True)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
