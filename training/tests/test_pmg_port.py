#!/usr/bin/env python3
"""Equality of the Python PMG port with the C++ generator, for both blendings.

Usage: test_pmg_port.py VECTORS.json [--tol 1e-5] [--jax]
VECTORS.json comes from build*/bin/pmg_generator_vectors (same inputs: joint space, clips with their
implied_motion tables, the consistency map, commands, dt, initial phase). It holds one tick
schedule per blending: "ticks" under the document's "blending" (consistent) and "paper": {"blending",
"ticks"}; both must be present and agree. The port is stepped from the same initial phase with its
own phase update, so phase drift would show up too. Exit code 0 iff every GeneratorOutput field of
every tick of both blendings agrees to --tol (absolute); prints the largest difference per field.
--jax runs the port under jax.jit in float64 instead of NumPy (needs JAX installed).
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from pmg_train.pmg_generator import BLENDINGS, model_from_vectors, step  # noqa: E402

FIELDS = ["phase", "next_phase", "period", "q_ref", "qd_ref", "alpha", "weight", "amplitude", "clip_direction",
          "amplitude_saturated", "command_correction", "standing_weight", "beta", "contact_mu", "contact_sigma",
          "in_contact", "v_base", "omega_base", "yaw_rate", "base_height", "clamped_joints"]


def schedules(v):
    """(blending, ticks) of every vector set in the document; both blendings required."""
    out = [(v.get("blending"), v["ticks"])]
    if isinstance(v.get("paper"), dict):
        out.append((v["paper"].get("blending"), v["paper"]["ticks"]))
    names = sorted(b for b, _ in out if b is not None)
    if names != sorted(BLENDINGS):
        raise SystemExit(f"vectors hold blendings {names}: expected {sorted(BLENDINGS)} (regenerate them with "
                         f"pmg_generator_vectors)")
    return out


def compare(v, blending, ticks, stepper, tol):
    model = model_from_vectors(v, blending)
    fn = stepper(model)
    phase = v["phase0"]
    worst = {k: 0.0 for k in FIELDS}
    where = {k: -1 for k in FIELDS}
    for t, tick in enumerate(ticks):
        out = fn(phase, np.array(tick["u_d"]), np.array(tick["u_s"]), v["dt"])
        for k in FIELDS:
            if k not in tick:
                raise SystemExit(f"{blending} tick {t}: no field {k!r} in the vectors (regenerate them)")
            # Phases are circular: compare the wrapped difference.
            d = np.abs(np.asarray(out[k], float) - np.asarray(tick[k], float))
            if k in ("phase", "next_phase", "contact_mu"):
                d = np.minimum(d, 1.0 - d)
            m = float(np.max(d)) if d.size else 0.0
            if not np.isfinite(m):
                m = np.inf
            if m > worst[k]:
                worst[k], where[k] = m, t
        phase = float(out["next_phase"])
    ok = True
    for k in FIELDS:
        flag = "ok" if worst[k] <= tol else "MISMATCH"
        ok &= worst[k] <= tol
        print(f"[{blending:10s}] {k:20s} max |python - c++| = {worst[k]:.3e}  (tick {where[k]})  {flag}")
    # The schedule must exercise the consistent solve's paths, or the comparison proves little.
    if blending == "consistent":
        sat = sum(1 for t in ticks if t["amplitude_saturated"] > 0)
        other = sum(1 for t in ticks if any(a > 0 and d != (-1 if u < 0 else 1)
                                            for a, d, u in zip(t["amplitude"], t["clip_direction"], t["u_d"])))
        corr = max(max(abs(x) for x in t["command_correction"]) for t in ticks)
        print(f"[{blending:10s}] ticks with a saturated amplitude {sat}, playing the other sign's clip {other}, "
              f"largest |correction| {corr:.3f}")
    return ok, max(worst.values())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vectors")
    ap.add_argument("--tol", type=float, default=1e-5)
    ap.add_argument("--jax", action="store_true", help="run the port under jax.jit (float64)")
    args = ap.parse_args()
    with open(args.vectors) as f:
        v = json.load(f)
    if args.jax:
        from test_smoke_cpu import CHILD, relaunch
        if os.environ.get(CHILD) != "1":
            relaunch(__file__)  # JAX lives in the training environment (.venv-training)
        import jax
        jax.config.update("jax_enable_x64", True)
        import jax.numpy as jnp

        def stepper(model):
            jitted = jax.jit(lambda phase, u_d, u_s: step(model, phase, u_d, u_s, v["dt"], xp=jnp))
            return lambda phase, u_d, u_s, dt: jitted(jnp.float64(phase), jnp.asarray(u_d), jnp.asarray(u_s))
    else:
        def stepper(model):
            return lambda phase, u_d, u_s, dt: step(model, phase, u_d, u_s, dt)
    ok, worst = True, 0.0
    sets = schedules(v)
    for blending, ticks in sets:
        o, w = compare(v, blending, ticks, stepper, args.tol)
        ok &= o
        worst = max(worst, w)
    print(f"{len(v['ticks'])} ticks x {len(sets)} blendings, {len(v['dynamic_clips'])} dynamic "
          f"({sum(c.get('implied_motion') is not None for c in v['dynamic_clips'])} with implied_motion) + "
          f"{len(v['static_clips'])} static clips, consistency map: "
          f"{'yes' if v.get('consistency_map') else 'no'}, {'jax' if args.jax else 'numpy'}; largest difference "
          f"{worst:.3e}, tol {args.tol}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
