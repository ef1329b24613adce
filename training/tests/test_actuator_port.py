#!/usr/bin/env python3
"""Equality of the actuator-model port (training/pmg_train/actuator.py) with the C++
pmg::calib::ActuatorModel::step.

Usage: test_actuator_port.py VECTORS.json [--tol 1e-9] [--jax | --jax32]
VECTORS.json comes from build*/bin/pmg_actuator_vectors (random parameter sets with every effect on
and off, fractional delays, driver rates 0..1000 Hz at dt 0.001/0.002/0.005 s, random command and
joint-sample sequences, and per step the C++ outputs). Cases with the same dt and length run
together, vectorised over the joint axis (one case = one joint), from a reset state with the C++
delay-line length. Checks every output of every step (tau_motor, tau_friction, tau_applied, the
stuck flag, the encoder reading) to --tol (absolute), and that the vectors cover the branches
(stiction held, explicit kinetic friction, saturation, disabled commands, zero-order hold).

Default: the NumPy float64 path (plain python3 with numpy; ctest actuator_port_equals_cpp).
--jax: the JAX path, jitted inside lax.scan, in float64 (jax_enable_x64), to the same --tol on at
least 99.9 % of the steps: XLA's CPU float64 division is not always correctly rounded (0.2375 / 0.001
gives 237.5 where IEEE, NumPy and C++ give 237.49999999999997), which flips the delay line's
k / frac branch where delay_s / dt sits on a step boundary (the long case of the vectors).
--jax32: the JAX path in float32 (what training runs); prints the error distribution and requires
99.5 % of the steps within 1e-3 * (1 + |tau|) (branch decisions at the stiction / driver-rate
thresholds may flip in float32, as they would between two float64 builds with different rounding).
Exit code 0 iff everything agrees; prints the largest difference per output.
"""
import argparse
import json
import math
import os
import sys
from collections import defaultdict

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from pmg_train import actuator as act  # noqa: E402

OUT_NAMES = ("tau_motor_Nm", "tau_friction_Nm", "tau_applied_Nm", "stuck", "encoder_rad")


def case_params(cases):
    vals = {k: [] for k in act.PARAM_KEYS}
    for c in cases:
        for k in act.PARAM_KEYS:
            v = c["params"][k]
            vals[k].append(math.inf if v is None else float(v))  # JSON null = +inf (torque_limit_Nm)
    return vals


def run_numpy(cases, dt, max_delay):
    """Steps the NumPy port over a group of cases (one joint each). Returns (T, n, 5) outputs."""
    n = len(cases)
    p = act.make_params(n, **case_params(cases))
    cmd = np.array([c["cmd"] for c in cases], np.float64)       # (n, T, 6)
    joint = np.array([c["joint"] for c in cases], np.float64)   # (n, T, 4)
    s = act.init_state(n, max_delay)
    outs = []
    for t in range(cmd.shape[1]):
        c = {k: cmd[:, t, i] for i, k in enumerate(act.COMMAND_KEYS)}
        c["enabled"] = cmd[:, t, 5] != 0
        j = {"q_rad": joint[:, t, 0], "dq_rad_per_s": joint[:, t, 1], "inertia_kgm2": joint[:, t, 2],
             "tau_other_Nm": joint[:, t, 3], "dt_s": dt}
        s, o = act.step(p, s, c, j)
        outs.append(np.stack([o["tau_motor_Nm"], o["tau_friction_Nm"], o["tau_applied_Nm"],
                              o["stuck"].astype(np.float64), act.encoder(p, j["q_rad"])], -1))
    return np.stack(outs)


def run_jax(cases, dt, max_delay, dtype):
    import jax
    import jax.numpy as jnp
    n = len(cases)
    p = act.make_params(n, xp=jnp, dtype=dtype, **case_params(cases))
    cmd = jnp.asarray(np.array([c["cmd"] for c in cases]).transpose(1, 0, 2), dtype)      # (T, n, 6)
    joint = jnp.asarray(np.array([c["joint"] for c in cases]).transpose(1, 0, 2), dtype)  # (T, n, 4)

    @jax.jit
    def rollout(p, cmd, joint):
        def body(s, x):
            c_t, j_t = x
            c = {k: c_t[:, i] for i, k in enumerate(act.COMMAND_KEYS)}
            c["enabled"] = c_t[:, 5] != 0
            j = {"q_rad": j_t[:, 0], "dq_rad_per_s": j_t[:, 1], "inertia_kgm2": j_t[:, 2],
                 "tau_other_Nm": j_t[:, 3], "dt_s": jnp.asarray(dt, dtype)}
            s, o = act.step(p, s, c, j, xp=jnp)
            return s, jnp.stack([o["tau_motor_Nm"], o["tau_friction_Nm"], o["tau_applied_Nm"],
                                 o["stuck"].astype(dtype), act.encoder(p, j["q_rad"])], -1)
        _, out = jax.lax.scan(body, act.init_state(n, max_delay, xp=jnp, dtype=dtype), (cmd, joint))
        return out
    return np.asarray(rollout(p, cmd, joint), np.float64)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vectors")
    ap.add_argument("--tol", type=float, default=1e-9)
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--jax", action="store_true", help="JAX path (jit + scan) in float64")
    mode.add_argument("--jax32", action="store_true", help="JAX path in float32 (training's precision)")
    args = ap.parse_args()
    if args.jax or args.jax32:
        import jax
        jax.config.update("jax_enable_x64", bool(args.jax))
    with open(args.vectors) as f:
        v = json.load(f)
    max_delay = int(v["max_delay_steps"])
    groups = defaultdict(list)
    for c in v["cases"]:
        groups[(c["dt_s"], len(c["cmd"]))].append(c)
    worst = np.zeros(len(OUT_NAMES))
    errs, scales = [], []
    for (dt, _), cases in sorted(groups.items()):
        if args.jax or args.jax32:
            import jax.numpy as jnp
            ours = run_jax(cases, dt, max_delay, jnp.float64 if args.jax else jnp.float32)
        else:
            ours = run_numpy(cases, dt, max_delay)
        ref = np.array([c["out"] for c in cases], np.float64).transpose(1, 0, 2)  # (T, n, 5)
        d = np.abs(ours - ref)
        worst = np.maximum(worst, d.reshape(-1, len(OUT_NAMES)).max(0))
        errs.append(d[..., :3].reshape(-1, 3).max(-1))
        scales.append(np.abs(ref[..., :3]).reshape(-1, 3).max(-1))
    steps = sum(len(c["cmd"]) for c in v["cases"])
    counts = v.get("counts", {})
    label = "JAX float64 (jit)" if args.jax else ("JAX float32 (jit)" if args.jax32 else "NumPy float64")
    print(f"{label}: {len(v['cases'])} cases in {len(groups)} vectorised groups, {steps} steps; C++ branch "
          f"counts {counts}")
    for name, w in zip(OUT_NAMES, worst):
        print(f"  max |port - C++| {name:16s} {w:.3e}")
    failed = []
    coverage = {k: counts.get(k, 0) for k in ("stuck", "kinetic_explicit", "saturated", "disabled_commands",
                                               "zoh_steps")}
    if min(coverage.values()) <= 0:
        failed.append(f"vectors do not cover every branch: {coverage}")
    if args.jax32:
        e, sc = np.concatenate(errs), np.concatenate(scales)
        ok = e <= 1e-3 * (1.0 + sc)
        print(f"  float32: median {np.median(e):.2e}, 99th percentile {np.percentile(e, 99):.2e} N m; "
              f"{ok.mean() * 100:.2f} % of the steps within 1e-3 (1 + |tau|)")
        if ok.mean() < 0.995:
            failed.append(f"float32: only {ok.mean() * 100:.2f} % of the steps within 1e-3 (1 + |tau|) (< 99.5 %)")
    elif args.jax:
        e = np.concatenate(errs)
        n_bad = int((e > args.tol).sum())
        print(f"  float64 JAX: {n_bad} of {e.size} steps differ by more than {args.tol:g}; the others "
              f"{(e[e <= args.tol].max() if n_bad < e.size else float('nan')):.2e} at most")
        if n_bad > 1e-3 * e.size:
            failed.append(f"JAX float64: {n_bad} steps differ by more than --tol (> 0.1 %)")
    elif worst.max() > args.tol:
        failed.append(f"largest difference {worst.max():.3e} > --tol {args.tol:g}")
    for f_ in failed:
        print("FAIL", f_)
    print("PASS" if not failed else "FAILED")
    return 0 if not failed else 1


if __name__ == "__main__":
    sys.exit(main())
