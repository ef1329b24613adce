#!/usr/bin/env python3
"""Export a trained actor (actor.npz from train_pmg.py) to ONNX with its pmg.contract.

  python3 training/export_onnx.py RUN/actor.npz config/policies/g1_pmg_policy.onnx
Needs numpy, pyyaml, onnx (no JAX/Brax). The contract's robot fields come from
config/robots/g1/g1.yaml, the observation layout from pmg_train/g1_env.py (OBS_TERMS, kept
import-free here), reference pairs from a float32 NumPy forward pass of the exported graph.
Check the result as the controller would: build*/bin/pmg_policy_check --model <onnx>.
"""
import argparse
import glob
import json
import os
import sys

import numpy as np
import yaml

# Run in place (python3 training/export_onnx.py) as well as installed (pmg-export-onnx): pmg_train sits beside this file.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pmg_train.contract import actor_forward, actor_graph, clips_digest, make_contract, save_onnx  # noqa: E402
from pmg_train.paths import repo_root  # noqa: E402

LEG = 12
# Must equal pmg_train.g1_env.OBS_TERMS (that module imports JAX/MuJoCo; this one must not).
OBS_TERMS = [("base_ang_vel_B", 3, 0.25), ("projected_gravity_B", 3, 1.0),
             ("command", 6, [2.0, 2.0, 0.25, 1.0, 1.0, 1.0]), ("joint_pos_rel", LEG, 1.0), ("joint_vel", LEG, 0.05),
             ("last_action", LEG, 1.0), ("pmg_ref_q_rel", LEG, 1.0), ("pmg_phase", 2, 1.0)]
OBS_CLIP = 100.0
CONTROL_PERIOD = 0.01
EPSILON = 0.05


def load_actor(path):
    z = np.load(path)
    n = len([k for k in z.files if k.startswith("w")])
    layers = [(z[f"w{i}"], z[f"b{i}"]) for i in range(n)]
    mode = str(z["mode"]) if "mode" in z.files else "pmg"  # actors saved before the ablation modes: PMG w/o GCO
    return z["obs_mean"], z["obs_std"], layers, z["action_scale"], [str(c) for c in z["clips"]], mode


def load_reference_settings(path, clips_dir=None):
    """The actor's reference settings beyond the paper, as contract keys: upright_walking and
    sole_levelling (False for actors saved before 2026-11-27, which were trained without both),
    stride_adaptation (False before 2026-12-04), stride_standing_hold (the stride adaptation keeping the feet where
    they landed while standing; False for actors saved before it, 2026-12-04, and for those without the adaptation),
    upper_body_ff (the controller's waist feed-forward in the environment; False before 2026-11-29), and
    clips_digest, the digest of the clips it was trained on (saved with the actor since 2026-11-27;
    for an older actor, computed from @p clips_dir when given, else left out: the controller then
    does not check the clips)."""
    z = np.load(path)
    out = {k: bool(z[k]) if k in z.files else False
           for k in ("upright_walking", "sole_levelling", "stride_adaptation", "stride_standing_hold", "upper_body_ff")}
    saved = str(z["clips_digest"]) if "clips_digest" in z.files else None
    if clips_dir:
        files = sorted(glob.glob(os.path.join(clips_dir, "*.yaml")))
        if not files:
            raise SystemExit(f"--clips {clips_dir}: no clip files (*.yaml) there")
        given = clips_digest(files)
        if saved is not None and given != saved:
            raise SystemExit(f"--clips {clips_dir}: not the clips {path} was trained on (digest differs)")
        saved = given
    if saved is not None:
        out["clips_digest"] = saved
    return out


def export(npz, out_path, brax_check=None, robot_yaml=None, training=None, clips_dir=None):
    """Writes the ONNX actor with its contract; robot_yaml: default config/robots/g1/g1.yaml of the
    checkout (relative paths: to the checkout). The contract's kp / kd are the robot config's: a policy
    trained with physically informed gains is exported with config/robots/g1/g1_pig.yaml. @p training:
    extra entries of the `pmg.training` metadata (gains, actuators)."""
    robot_yaml = robot_yaml or "config/robots/g1/g1.yaml"
    if not os.path.isabs(robot_yaml):
        robot_yaml = os.path.join(repo_root(), robot_yaml)
    mean, std, layers, action_scale, clips, mode = load_actor(npz)
    with np.load(npz) as z:
        offset = str(z["action_offset"]) if "action_offset" in z.files else "default"  # older actors: the standing pose
    if offset != "default":
        # The contract's action offset is a constant (the standing pose); the controller has no
        # residual-on-reference targets, so such an actor would be deployed with the wrong targets.
        raise SystemExit(f"{npz}: action_offset {offset!r}: the controller deploys actors whose targets are the "
                         f"standing pose plus scale x action only (EnvConfig.action_offset 'default'); not exported")
    reference = load_reference_settings(npz, clips_dir)
    with open(robot_yaml) as f:
        robot = yaml.safe_load(f)
    joints = robot["joints"]
    names = [j["name"] for j in joints]
    default = np.array([j["default"] for j in joints])
    rng = np.random.default_rng(0)
    obs = (mean + std * rng.standard_normal((8, mean.size))).astype(np.float32)
    act = actor_forward(mean, std, layers, LEG, obs)
    contract = make_contract(
        robot=robot["robot"]["name"], joint_names=names, actuated_joints=names[:LEG], controls_waist=False,
        control_period=CONTROL_PERIOD, default_pose=default, kp=[j["kp"] for j in joints],
        kd=[j["kd"] for j in joints], action_scale=action_scale, action_offset=default[:LEG], action_clip=1.0,
        obs_terms=OBS_TERMS, history_length=1, obs_clip=OBS_CLIP,
        pmg={"enabled": True, "gco": mode == "pmg_gco", "mode": "single_gait" if mode == "single_gait" else "pmg",
             "clips": ",".join(clips), "epsilon": EPSILON, **reference},
        reference_pairs=list(zip(obs, act)))
    info = {"brax_vs_numpy_max_abs": brax_check, "source": os.path.basename(npz),
            "robot": os.path.relpath(robot_yaml, repo_root())}
    info.update(training or {})
    meta = {"pmg.training": json.dumps(info)}
    save_onnx(out_path, actor_graph(mean, std, layers, LEG), contract, extra_metadata=meta)
    print("wrote", out_path)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="pmg-export-onnx", description="actor.npz -> ONNX with its pmg.contract")
    ap.add_argument("npz")
    ap.add_argument("out")
    ap.add_argument("--robot", default=None,
                    help="robot config whose kp/kd the contract carries (default config/robots/g1/g1.yaml; "
                         "config/robots/g1/g1_pig.yaml for a policy trained with --gains physically_informed)")
    ap.add_argument("--clips", default=None, metavar="DIR",
                    help="the clip folder the actor was trained on: its digest goes into the contract "
                         "(pmg.clips_digest) for an actor saved without one, and is checked against one saved")
    a = ap.parse_args(argv)
    export(a.npz, a.out, robot_yaml=a.robot, clips_dir=a.clips)


if __name__ == "__main__":
    main()
