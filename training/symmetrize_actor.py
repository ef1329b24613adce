#!/usr/bin/env python3
"""Make an exported actor exactly mirror-symmetric: a(o) = tanh(1/2 (mu(o) + M_a mu(M_o o))).

  python3 training/symmetrize_actor.py IN.onnx OUT.onnx [--robot config/robots/g1/g1.yaml]

IN is an actor exported by export_onnx.py (normaliser -> MLP(swish) -> loc -> tanh, with its
pmg.contract). mu is its mean action before the tanh; M_o and M_a are the mirror maps of
pmg_train/symmetry.py (the robot config's joint mirror map; sign flips of the lateral terms; the
phase moved by half a cycle). The average of the actor and its mirror image is itself an MLP of the
same depth and twice the width, so OUT is an ordinary exported actor: the controller runs it unchanged.
- first layer: [W1 | A^T W1], where A x + c is the normalised mirrored observation written in the
  normalised original one (A[i, pi_i] = s_i std[pi_i] / std[i], c = (s mean[pi] - mean) / std);
- hidden layers: block-diagonal (the two branches do not mix);
- last layer: half the loc of each branch, the second mapped by M_a; the scale columns of the first
  branch (unused by the deterministic actor).
The contract is IN's, with its reference pairs recomputed on OUT; `pmg.training` gains
"symmetrized": true. Needs numpy, pyyaml, onnx (no JAX). Checks before writing: OUT's forward
pass equals the formula on IN (random observations around the normaliser's statistics, < 1e-5) and
OUT(M_o o) = M_a OUT(o) (< 1e-5); a failed check writes nothing (exit 1).
"""
import argparse
import json
import os
import sys

import numpy as np
import onnx
import yaml
from onnx import numpy_helper

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from export_onnx import LEG, OBS_TERMS  # noqa: E402
from pmg_train import pmg_generator as pg  # noqa: E402
from pmg_train.contract import CONTRACT_KEY, _floats, actor_forward, actor_graph, save_onnx  # noqa: E402
from pmg_train.paths import repo_root  # noqa: E402
from pmg_train.symmetry import actor_maps, mirror  # noqa: E402


def load_onnx_actor(path):
    """(mean, std, layers, contract dict, metadata dict) of an actor written by export_onnx.py."""
    model = onnx.load(path)
    init = {t.name: numpy_helper.to_array(t) for t in model.graph.initializer}
    if "obs_mean" not in init or "w0" not in init:
        raise SystemExit(f"{path}: not an actor exported by export_onnx.py (no obs_mean / w0 initializers)")
    n = len([k for k in init if k.startswith("w") and k[1:].isdigit()])
    layers = [(init[f"w{i}"], init[f"b{i}"].reshape(-1)) for i in range(n)]
    meta = {p.key: p.value for p in model.metadata_props}
    if CONTRACT_KEY not in meta:
        raise SystemExit(f"{path}: no {CONTRACT_KEY} metadata")
    return init["obs_mean"].reshape(-1), init["obs_std"].reshape(-1), layers, yaml.safe_load(meta[CONTRACT_KEY]), meta


def symmetrized_layers(mean, std, layers, obs_map, act_map, n_act):
    """The layers of tanh(1/2 (mu(o) + M_a mu(M_o o))) as one MLP (module docstring)."""
    pi, s = obs_map
    ai, sa = act_map
    n_obs = mean.size
    A = np.zeros((n_obs, n_obs))
    A[np.arange(n_obs), pi] = s * std[pi] / std
    c = (s * mean[pi] - mean) / std
    Q = np.zeros((n_act, n_act))  # row vector v -> M_a v: (v @ Q)[j] = sa[j] v[ai[j]]
    Q[ai, np.arange(n_act)] = sa
    out = []
    for i, (w, b) in enumerate(layers):
        w, b = w.astype(np.float64), b.astype(np.float64)
        if i == 0:
            out.append((np.hstack([w, A.T @ w]), np.concatenate([b, c @ w + b])))
        elif i + 1 < len(layers):
            z = np.zeros_like(w)
            out.append((np.block([[w, z], [z, w]]), np.concatenate([b, b])))
        else:
            w_loc, w_scale = w[:, :n_act], w[:, n_act:]
            b_loc, b_scale = b[:n_act], b[n_act:]
            out.append((np.block([[0.5 * w_loc, w_scale], [0.5 * w_loc @ Q, np.zeros_like(w_scale)]]),
                        np.concatenate([0.5 * (b_loc + b_loc @ Q), b_scale])))
    return [(w.astype(np.float32), b.astype(np.float32)) for w, b in out]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--robot", default=None, help="robot config with the joint mirror map (default: the contract's "
                                                  "robot file, config/robots/g1/g1.yaml)")
    args = ap.parse_args(argv)
    mean, std, layers, contract, meta = load_onnx_actor(args.input)
    robot_yaml = args.robot or os.path.join(repo_root(), "config/robots/g1/g1.yaml")
    obs_map, act_map = actor_maps(pg.joint_space_from_robot_yaml(robot_yaml), OBS_TERMS, LEG)
    if mean.size != len(obs_map[0]):
        raise SystemExit(f"{args.input}: {mean.size} observations; the mirror map has {len(obs_map[0])} "
                         f"(export_onnx.OBS_TERMS)")
    sym = symmetrized_layers(mean, std, layers, obs_map, act_map, LEG)
    rng = np.random.default_rng(0)
    obs = (mean + std * rng.standard_normal((256, mean.size))).astype(np.float32)
    obs_m = mirror(obs, *obs_map).astype(np.float32)
    loc = np.arctanh(np.clip(actor_forward(mean, std, layers, LEG, obs).astype(np.float64), -0.999999, 0.999999))
    loc_m = np.arctanh(np.clip(actor_forward(mean, std, layers, LEG, obs_m).astype(np.float64), -0.999999, 0.999999))
    want = np.tanh(0.5 * (loc + mirror(loc_m, *act_map)))
    got = actor_forward(mean, std, sym, LEG, obs)
    got_m = actor_forward(mean, std, sym, LEG, obs_m)
    err_formula = float(np.abs(got - want).max())
    err_mirror = float(np.abs(got_m - mirror(got, *act_map)).max())
    asym = float(np.abs(actor_forward(mean, std, layers, LEG, obs_m)
                        - mirror(actor_forward(mean, std, layers, LEG, obs), *act_map)).max())
    print(f"{args.input}: the input actor's own asymmetry max |a(M o) - M a(o)| {asym:.4f}; symmetrized: "
          f"formula error {err_formula:.2e}, asymmetry {err_mirror:.2e}")
    if not (err_formula < 1e-5 and err_mirror < 1e-5):
        print("FAIL: the symmetrized actor does not equal the formula or is not symmetric; nothing written")
        return 1
    pairs = obs[:8]
    contract["reference_pairs"] = [{"obs": _floats(o), "action": _floats(a)}
                                   for o, a in zip(pairs, actor_forward(mean, std, sym, LEG, pairs))]
    training = json.loads(meta.get("pmg.training", "{}"))
    training.update({"symmetrized": True, "symmetrized_from": os.path.basename(args.input)})
    extra = {k: v for k, v in meta.items() if k not in (CONTRACT_KEY, "pmg.training")}
    extra["pmg.training"] = json.dumps(training)
    save_onnx(args.output, actor_graph(mean, std, sym, LEG), contract, extra_metadata=extra)
    print("wrote", args.output, f"(hidden widths {[w.shape[1] for w, _ in sym[:-1]]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
