#!/usr/bin/env python3
"""Equality of the Python GCO port (training/pmg_train/gco.py) with the C++ GeneratorWithGco.

Usage: test_gco_port.py VECTORS.json [--tol 1e-5] [--jax]
VECTORS.json comes from build*/bin/pmg_generator_vectors (it carries the KDL leg chains, the
resolved GCO options and, per tick, the C++ u', Δ and contact weights). Checks (1) leg forward
kinematics and velocities at the file's random configurations, (2) the generator port + GCO port
stepped from the same initial phase over the whole schedule. Exit code 0 iff everything agrees to
--tol (absolute); prints the largest difference per quantity. --jax runs (2) as the training env does:
each tick (generator, sole levelling or stride adaptation, GCO) under jax.jit, in float64, in the
training environment.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from pmg_train import gco  # noqa: E402
from pmg_train.pmg_generator import model_from_vectors, step  # noqa: E402


def _flat(x):
    """Numbers of a JSON tree in document order (strings skipped, booleans as 0/1)."""
    if isinstance(x, dict):
        return [y for k in sorted(x) for y in _flat(x[k])]
    if isinstance(x, list):
        return [y for e in x for y in _flat(e)]
    if isinstance(x, str):
        return []
    return [float(x)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vectors")
    ap.add_argument("--tol", type=float, default=1e-5)
    ap.add_argument("--model-file", help="committed GCO model used by training (must equal the vectors' model)")
    ap.add_argument("--write-model", action="store_true", help="(re)write --model-file from the vectors")
    ap.add_argument("--jax", action="store_true", help="run each tick under jax.jit (float64)")
    args = ap.parse_args()
    xp = np
    if args.jax:
        from test_smoke_cpu import CHILD, relaunch
        if os.environ.get(CHILD) != "1":
            relaunch(__file__)  # JAX lives in the training environment (.venv-training)
        import jax
        jax.config.update("jax_enable_x64", True)
        import jax.numpy as xp
    with open(args.vectors) as f:
        v = json.load(f)
    keys = ("gco_options", "leg_chains", "leg_joint_index")
    if args.model_file and args.write_model:
        doc = {"source": "apps/policy/pmg_generator_vectors (robot config + config/gco/g1.yaml); regenerate with "
                         "training/tests/test_gco_port.py VECTORS --model-file FILE --write-model"}
        doc.update({k: v[k] for k in keys})
        with open(args.model_file, "w") as f:
            json.dump(doc, f, indent=1)
    if args.model_file:
        with open(args.model_file) as f:
            committed = json.load(f)
        a = np.concatenate([np.ravel(np.asarray(_flat(committed[k]), float)) for k in keys])
        b = np.concatenate([np.ravel(np.asarray(_flat(v[k]), float)) for k in keys])
        if a.shape != b.shape or float(np.max(np.abs(a - b))) > 1e-12:
            print(f"{args.model_file}: differs from the C++ leg chains / GCO options: regenerate it (--write-model)")
            return 1
        print(f"{args.model_file}: equals the C++ model")
    chains, opt = gco.LegChains.from_doc(v), gco.GcoOptions.from_doc(v)
    worst = {"fk_p": 0.0, "fk_v": 0.0, "fk_w": 0.0, "u_opt": 0.0, "delta": 0.0, "s": 0.0}
    for c in v["fk_checks"]:
        p, vel, w = gco.foot_kinematics(chains, c["foot"], np.array(c["q"]), np.array(c["qd"]))
        worst["fk_p"] = max(worst["fk_p"], float(np.max(np.abs(p - c["p_BS_B"]))))
        worst["fk_v"] = max(worst["fk_v"], float(np.max(np.abs(vel - c["v_BS_B"]))))
        worst["fk_w"] = max(worst["fk_w"], float(np.max(np.abs(w - c["w_BF_B"]))))
    def ticker(model, level, adapt=False):
        """(phase, u_d, u_s, state) -> (generator output, q_ref before levelling and stride adaptation, u', Δ,
        s, state): one tick."""
        def tick_fn(phase, u_d, u_s, state):
            out = step(model, phase, u_d, u_s, v["dt"], xp=xp)
            q_gen = out["q_ref"]
            js = model.js
            if level:
                out, _, _, state = gco.level_soles(chains, opt, out, js.q_stand, js.lower, js.upper, state, xp=xp)
            if adapt:
                out, _, _, state = gco.adapt_strides(chains, opt, out, u_d, js.lower, js.upper, state, xp=xp)
            u_opt, delta, s, state = gco.step(chains, opt, out, u_s, state, xp=xp)
            return out, q_gen, u_opt, delta, s, state
        if xp is np:
            return tick_fn
        import jax
        jitted = jax.jit(tick_fn)
        return lambda phase, u_d, u_s, state: jitted(xp.float64(phase), xp.asarray(u_d), xp.asarray(u_s), state)

    tick_fn = ticker(model_from_vectors(v), level=False)
    phase = v["phase0"]
    state = gco.initial_state()
    where = {}
    statuses = set()
    for t, tick in enumerate(v["ticks"]):
        out, _, u_opt, delta, s, state = tick_fn(phase, np.array(tick["u_d"]), np.array(tick["u_s"]), state)
        statuses.add(int(tick["gco_status"]))
        for k, mine, theirs in (("u_opt", u_opt, tick["gco_u_opt"]), ("delta", delta, tick["gco_delta"]),
                                ("s", s, tick["gco_s"])):
            d = float(np.max(np.abs(np.asarray(mine, float) - np.asarray(theirs, float))))
            if d > worst[k]:
                worst[k], where[k] = d, t
        phase = float(out["next_phase"])
    def compare_variant(name, prefix, what, **kw):
        """Steps the ports on v[name]'s ticks and compares q_ref, q̇_ref and u' with the C++; returns the largest
        change the variant made to the generator's q_ref, or None when the file has no such ticks."""
        if name not in v:
            return None
        keys = (prefix + "_q", prefix + "_qd", prefix + "_uopt")
        worst.update({k: 0.0 for k in keys})
        tick_fn = ticker(model_from_vectors(v, upright_walking=v[name].get("upright_walking", False)), **kw)
        phase = v["phase0"]
        state = gco.initial_state()
        largest = 0.0
        for t, tick in enumerate(v[name]["ticks"]):
            out, q_gen, u_opt, _, _, state = tick_fn(phase, np.array(tick["u_d"]), np.array(tick["u_s"]), state)
            largest = max(largest, float(np.max(np.abs(np.asarray(out["q_ref"], float) - np.asarray(q_gen, float)))))
            for k, mine, theirs in zip(keys, (out["q_ref"], out["qd_ref"], u_opt),
                                       (tick["q_ref"], tick["qd_ref"], tick["gco_u_opt"])):
                d = float(np.max(np.abs(np.asarray(mine, float) - np.asarray(theirs, float))))
                if d > worst[k]:
                    worst[k], where[k] = d, t
            phase = float(out["next_phase"])
        print(f"{name}: largest {what} {largest:.3f} rad")
        return largest
    # The stance sole levelling (gco.level_soles, sole_levelling.hpp) on the "levelled" ticks, and the stride
    # adaptation (gco.adapt_strides, stride_adaptation.hpp) on the "adapted" ticks.
    for name, prefix, what, kw in (("levelled", "lev", "ankle offset", {"level": True}),
                                   ("adapted", "sa", "leg joint offset", {"level": False, "adapt": True})):
        largest = compare_variant(name, prefix, what, **kw)
        if largest is not None and largest < 1e-2:
            print(f"{name}: the reference never changed: the vectors do not exercise it")
            return 1
    ok = True
    for k, d in worst.items():
        flag = "ok" if d <= args.tol else "MISMATCH"
        ok &= d <= args.tol
        print(f"{k:8s} max |python - c++| = {d:.3e}  (tick {where.get(k, '-')})  {flag}")
    moved = max(abs(x) for t in v["ticks"] for x in t["gco_delta"])
    print(f"{len(v['ticks'])} ticks, C++ GCO statuses {sorted(statuses)}, largest |Δ| {moved:.3f}, "
          f"{'jax' if args.jax else 'numpy'}, tol {args.tol}")
    if moved < 1e-3:  # the schedule must make GCO act, or the comparison proves nothing
        print("GCO never changed the command: the vectors do not exercise it")
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
