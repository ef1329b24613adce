#!/usr/bin/env python3
"""An exported actor back to actor.npz (the inverse of export_onnx.py), so that eval_mjx.py can roll out a
shipped policy whose training run kept no actor.npz (the default, config/policies/g1_pmg_policy_wh6g.onnx,
was fine-tuned before actors were saved with their runs).

  python3 training/actor_from_onnx.py config/policies/g1_pmg_policy_wh6g.onnx --out /tmp/wh6g/actor.npz
  python3 training/eval_mjx.py /tmp/wh6g/actor.npz --train-config RUN/train_config.json --commands S.yaml --out o.npz

The weights and the observation normaliser are the graph's initializers (obs_mean, obs_std, w0.., b0..);
the action scale, clips, mode (pmg_gco when the contract's pmg.gco is set), upright_walking,
sole_levelling, upper_body_ff and clips_digest are the pmg.contract's. The contract's action offset must be
its default pose (export_onnx.py exports no other). eval_mjx.py also needs the environment the actor is
to be rolled out in (--train-config): the ONNX does not carry the training run's EnvConfig.
Needs numpy, pyyaml and onnx (no JAX). Errors name the file and what is missing."""
import argparse
import os
import sys

import numpy as np
import yaml


def actor_arrays(path):
    """The actor.npz arrays of the ONNX actor at @p path (dict of numpy arrays)."""
    import onnx
    from onnx import numpy_helper
    model = onnx.load(path)
    init = {i.name: numpy_helper.to_array(i) for i in model.graph.initializer}
    meta = {p.key: p.value for p in model.metadata_props}
    if "pmg.contract" not in meta:
        raise SystemExit(f"{path}: no pmg.contract metadata (not an actor export_onnx.py wrote)")
    contract = yaml.safe_load(meta["pmg.contract"])
    n = len([k for k in init if k.startswith("w") and k[1:].isdigit()])
    missing = [k for k in ["obs_mean", "obs_std"] + [f"{p}{i}" for i in range(n) for p in "wb"] if k not in init]
    if n == 0 or missing:
        raise SystemExit(f"{path}: initializers {missing or ['w0']} missing (expected obs_mean, obs_std, w0.., b0..)")
    action = contract["action"]
    if not np.allclose(action["offset"], contract["default_pose"][:len(action["offset"])]):
        raise SystemExit(f"{path}: pmg.contract action.offset is not the default pose; actor.npz has no such offset")
    pmg = contract["pmg"]
    mode = "single_gait" if pmg["mode"] == "single_gait" else ("pmg_gco" if pmg["gco"] else "pmg")
    out = {"obs_mean": init["obs_mean"].reshape(-1), "obs_std": init["obs_std"].reshape(-1),
           "action_scale": np.asarray(action["scale"], np.float32),
           "clips": np.array(pmg["clips"].split(",")), "mode": np.array(mode),
           "upright_walking": np.array(bool(pmg.get("upright_walking", False))),
           "sole_levelling": np.array(bool(pmg.get("sole_levelling", False))),
           "stride_adaptation": np.array(bool(pmg.get("stride_adaptation", False))),
           "stride_standing_hold": np.array(bool(pmg.get("stride_standing_hold", False))),
           "upper_body_ff": np.array(bool(pmg.get("upper_body_ff", False))),
           "action_offset": np.array("default")}
    if "clips_digest" in pmg:
        out["clips_digest"] = np.array(pmg["clips_digest"])
    for i in range(n):
        out[f"w{i}"] = init[f"w{i}"]
        out[f"b{i}"] = init[f"b{i}"].reshape(-1)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(prog="pmg-actor-from-onnx", description="ONNX actor -> actor.npz")
    ap.add_argument("onnx", help="an actor written by export_onnx.py")
    ap.add_argument("--out", required=True, help="actor.npz to write")
    args = ap.parse_args(argv)
    if not os.path.isfile(args.onnx):
        raise SystemExit(f"{args.onnx}: no such file")
    arrays = actor_arrays(args.onnx)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    np.savez(args.out, **arrays)
    print(f"wrote {args.out} ({len([k for k in arrays if k.startswith('w')])} layers, mode {arrays['mode']})")


if __name__ == "__main__":
    sys.exit(main())
