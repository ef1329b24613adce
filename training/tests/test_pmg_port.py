#!/usr/bin/env python3
"""Equality of the Python PMG port with the C++ generator.

Usage: test_pmg_port.py VECTORS.json [--tol 1e-5] [--jax]
VECTORS.json comes from build*/bin/pmg_generator_vectors (same inputs: joint space, clips,
commands, dt, initial phase). The port is stepped from the same initial phase with its own phase
update, so phase drift would show up too. Exit code 0 iff every output of every tick agrees to
--tol (absolute); prints the largest difference per field.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from pmg_train.pmg_generator import model_from_vectors, step  # noqa: E402

FIELDS = ["phase", "next_phase", "period", "q_ref", "qd_ref", "alpha", "weight", "standing_weight", "beta",
          "contact_mu", "contact_sigma", "in_contact", "v_base", "yaw_rate", "base_height", "clamped_joints"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vectors")
    ap.add_argument("--tol", type=float, default=1e-5)
    args = ap.parse_args()
    with open(args.vectors) as f:
        v = json.load(f)
    model = model_from_vectors(v)
    phase = v["phase0"]
    worst = {k: 0.0 for k in FIELDS}
    where = {k: -1 for k in FIELDS}
    for t, tick in enumerate(v["ticks"]):
        out = step(model, phase, np.array(tick["u_d"]), np.array(tick["u_s"]), v["dt"])
        for k in FIELDS:
            # Phases are circular: compare the wrapped difference.
            d = np.abs(np.asarray(out[k], float) - np.asarray(tick[k], float))
            if k in ("phase", "next_phase", "contact_mu"):
                d = np.minimum(d, 1.0 - d)
            m = float(np.max(d)) if d.size else 0.0
            if m > worst[k]:
                worst[k], where[k] = m, t
        phase = out["next_phase"]
    ok = True
    for k in FIELDS:
        flag = "ok" if worst[k] <= args.tol else "MISMATCH"
        ok &= worst[k] <= args.tol
        print(f"{k:16s} max |python - c++| = {worst[k]:.3e}  (tick {where[k]})  {flag}")
    print(f"{len(v['ticks'])} ticks, {len(v['dynamic_clips'])} dynamic + {len(v['static_clips'])} static clips, tol {args.tol}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
