#!/usr/bin/env python3
"""Tests training/symmetrize_actor.py (ctest symmetrize_actor_makes_a_mirror_symmetric_actor, label unit).

On the shipped default actor (config/policies/g1_pmg_policy_wh6g.onnx):
1. the input is not mirror-symmetric (max |a(M_o o) - M_a a(o)| > 0.1 on observations drawn from its
   normaliser's statistics), so the checks below can fail;
2. the symmetrized actor is: < 1e-5 on 200 fresh observations, with the maps built here from the robot
   config (pmg_train/symmetry.py);
3. symmetrizing it again changes nothing (< 1e-5): the average of a symmetric actor and its mirror
   image is itself;
4. its contract is the input's but for the reference pairs, and pmg.training says symmetrized;
5. an ONNX file that is not an exported actor is refused, naming the file, and nothing is written.
Usage: test_symmetrize_actor.py
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "training"))
from export_onnx import LEG, OBS_TERMS  # noqa: E402
from pmg_train import pmg_generator as pg  # noqa: E402
from pmg_train.contract import actor_forward, mlp_graph, save_onnx  # noqa: E402
from pmg_train.symmetry import actor_maps, mirror  # noqa: E402
from symmetrize_actor import load_onnx_actor  # noqa: E402

TOOL = os.path.join(ROOT, "training", "symmetrize_actor.py")
IN = os.path.join(ROOT, "config", "policies", "g1_pmg_policy_wh6g.onnx")


def load(path):
    """(mean, std, layers, metadata) of an exported actor (the tool's own reader)."""
    mean, std, layers, _, meta = load_onnx_actor(path)
    return mean, std, layers, meta


def main():
    failures = []
    js = pg.joint_space_from_robot_yaml(os.path.join(ROOT, "config/robots/g1/g1.yaml"))
    obs_map, act_map = actor_maps(js, OBS_TERMS, LEG)
    mean, std, layers, meta_in = load(IN)
    rng = np.random.default_rng(7)
    obs = (mean + std * rng.standard_normal((200, mean.size))).astype(np.float32)
    obs_m = mirror(obs, *obs_map).astype(np.float32)

    def asymmetry(lay):
        return float(np.abs(actor_forward(mean, std, lay, LEG, obs_m)
                            - mirror(actor_forward(mean, std, lay, LEG, obs), *act_map)).max())
    if not asymmetry(layers) > 0.1:
        failures.append(f"the input actor is already symmetric ({asymmetry(layers):.2e}): the test cannot fail")
    with tempfile.TemporaryDirectory() as d:
        a_path, b_path = os.path.join(d, "a.onnx"), os.path.join(d, "b.onnx")
        r = subprocess.run([sys.executable, TOOL, IN, a_path], capture_output=True, text=True)
        if r.returncode != 0:
            failures.append(f"symmetrize: rc {r.returncode}: {r.stdout} {r.stderr}")
        else:
            _, _, sym, meta = load(a_path)
            if not asymmetry(sym) < 1e-5:
                failures.append(f"the symmetrized actor's asymmetry {asymmetry(sym):.2e} (expected < 1e-5)")
            c_in, c_out = yaml.safe_load(meta_in["pmg.contract"]), yaml.safe_load(meta["pmg.contract"])
            c_in.pop("reference_pairs")
            c_out.pop("reference_pairs")
            if c_in != c_out or not json.loads(meta["pmg.training"]).get("symmetrized"):
                failures.append("the contract changed beyond its reference pairs, or pmg.training lacks symmetrized")
            r = subprocess.run([sys.executable, TOOL, a_path, b_path], capture_output=True, text=True)
            _, _, sym2, _ = load(b_path) if r.returncode == 0 else (None, None, None, None)
            diff = float(np.abs(actor_forward(mean, std, sym2, LEG, obs)
                                - actor_forward(mean, std, sym, LEG, obs)).max()) if sym2 else float("inf")
            if not diff < 1e-5:
                failures.append(f"symmetrizing twice changed the actor by {diff:.2e} (rc {r.returncode})")
        bad, out = os.path.join(d, "plain.onnx"), os.path.join(d, "never.onnx")
        save_onnx(bad, mlp_graph([(np.ones((62, 12), np.float32), np.zeros(12, np.float32))], 62, 12), {},
                  drop_contract=True)
        r = subprocess.run([sys.executable, TOOL, bad, out], capture_output=True, text=True)
        if r.returncode == 0 or bad not in r.stderr or os.path.exists(out):
            failures.append(f"a plain ONNX file: rc {r.returncode}, message {r.stderr.strip()!r}")
    print("\n".join("FAIL: " + f for f in failures) if failures else
          f"symmetrize_actor.py: input asymmetry {asymmetry(layers):.3f}, output symmetric, idempotent, bad input refused")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
