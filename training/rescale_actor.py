#!/usr/bin/env python3
"""Carry a trained actor over to a wider leg action scale, for fine-tuning it there.

An actor's leg target is q_stand + scale * a with a = tanh(mean output) (Brax's tanh-normal policy; the ONNX export
and the controller use the mean). A fine-tune cannot change the scale (graft_actor refuses a mismatch), yet the
default actor's scale cannot command the deep crouch (training/results/fidelity/action_range/README.md). This writes
the actor with the new scale and, per leg joint with r = old / new scale:
- the mean outputs' last layer (weights and bias) times r: a small action a becomes about r a, the same target;
  near the clamp the target grows (a linear layer cannot map tanh(x) to r tanh(x): an old 0.96 becomes
  tanh(r atanh(0.96)) > 0.96 r), which is the reach the fine-tune is for;
- the standard deviation outputs' bias plus ln r: Brax's scale is softplus(x) + 0.001, about e^x for the trained
  actors' x < -1, so the exploration noise stays the same in radians;
- the observation normaliser of the last_action term (the actor's previous a) times r, so the network sees the
  same normalised input for the same previous target.
It prints, on the actor's own observation statistics (N samples from its normaliser), the largest change of the
leg targets [rad] among samples whose old |a| < 0.7 on that joint, and among all.

    .venv-training/bin/python training/rescale_actor.py ACTOR_NPZ --action-scale posture \\
        --command-range height=0.59,0.78 --command-range pitch=-0.1,0.5 [--clips DIR] --out NEW_ACTOR_NPZ
    .venv-training/bin/python training/rescale_actor.py ACTOR_NPZ --action-scale factor --factor knee=1.2 ... --out F
"""
import argparse
import glob
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
ROOT = os.path.dirname(HERE)
from pmg_train.contract import actor_forward  # noqa: E402
from train_pmg import LEG_JOINT_KINDS, axis_bounds, joint_action_factors  # noqa: E402
LEG = 12
LAST_ACTION = slice(36, 48)  # OBS_TERMS: gyro 3, gravity 3, command 6, joint_pos_rel 12, joint_vel 12, last_action 12


def last_layer(actor):
    """Index of the last dense layer (w{i}, b{i}) of @p actor (dict of arrays)."""
    return max(int(k[1:]) for k in actor if k.startswith("w") and k[1:].isdigit())


def mean_action(actor, obs, last=None):
    """(N, LEG) deterministic actions tanh(mean output) of @p actor (dict of arrays; @p last its last dense layer's
    index, last_layer(actor) when None) on observations @p obs (N, 62): the exported graph's float32 forward pass
    (pmg_train.contract.actor_forward)."""
    last = last_layer(actor) if last is None else last
    layers = [(actor[f"w{i}"], actor[f"b{i}"]) for i in range(last + 1)]
    return actor_forward(actor["obs_mean"], actor["obs_std"], layers, LEG, obs)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("actor", help="actor.npz of the trained actor")
    ap.add_argument("--action-scale", required=True, choices=["posture", "factor"],
                    help="the new scale: posture = train_pmg.py's rule (for a fine-tune with --action-scale posture); "
                         "factor = the actor's own times --factor per joint kind (both legs; for trying a reach in the SIL)")
    ap.add_argument("--factor", action="append", default=[], metavar="JOINT=F",
                    help="with --action-scale factor: JOINT one of hip_pitch, hip_roll, hip_yaw, knee, ankle_pitch, "
                         "ankle_roll; F in (0, 2]")
    ap.add_argument("--command-range", action="append", default=[], metavar="AXIS=LO,HI",
                    help="the fine-tune's pitch, roll and height ranges (as train_pmg.py; defaults EnvConfig's)")
    ap.add_argument("--clips", default="config/clips/g1_walking_height")
    ap.add_argument("--samples", type=int, default=4096)
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    from pmg_train import pmg_generator as pg
    from pmg_train.g1_env import EnvConfig, posture_action_scale
    cfg = EnvConfig()
    ranges = {"pitch": cfg.pitch, "roll": cfg.roll, "height": cfg.height}
    try:
        ranges.update(axis_bounds("--command-range", args.command_range, strict=True, axes=tuple(ranges)))
    except ValueError as e:
        ap.error(str(e))
    try:
        factors = joint_action_factors(args.factor)
    except ValueError as e:
        ap.error(str(e))
    if args.factor and args.action_scale != "factor":
        ap.error("--factor needs --action-scale factor")

    try:
        with np.load(args.actor) as z:
            actor = {k: z[k] for k in z.files}
    except (OSError, ValueError) as e:
        ap.error(f"{args.actor}: cannot read an actor.npz ({e})")
    for field, shape in (("obs_mean", (62,)), ("obs_std", (62,)), ("action_scale", (LEG,))):
        if field not in actor or actor[field].shape != shape:
            ap.error(f"{args.actor}: {field} should have shape {shape} (a G1 leg actor.npz of train_pmg.py)")
    old_scale = np.asarray(actor["action_scale"], np.float64)
    if args.action_scale == "posture":
        js = pg.joint_space_from_robot_yaml(os.path.join(ROOT, "config/robots/g1/g1.yaml"))
        clips = sorted(glob.glob(os.path.join(ROOT, args.clips, "*.yaml")))
        new_scale = posture_action_scale(pg.load_library(clips, js), js,
                                         {0: ranges["pitch"], 1: ranges["roll"], 2: ranges["height"]}).astype(np.float32)
    else:
        new_scale = (old_scale * factors).astype(np.float32)
    r = old_scale / new_scale
    last = last_layer(actor)
    rng = np.random.default_rng(0)
    obs = actor["obs_mean"] + actor["obs_std"] * rng.standard_normal((args.samples, actor["obs_mean"].shape[0]))
    new = dict(actor)
    w, b = actor[f"w{last}"].astype(np.float64).copy(), actor[f"b{last}"].astype(np.float64).copy()
    w[:, :LEG] *= r
    b[:LEG] *= r
    b[LEG:] += np.log(r)
    new[f"w{last}"], new[f"b{last}"] = w.astype(actor[f"w{last}"].dtype), b.astype(actor[f"b{last}"].dtype)
    mean, std = actor["obs_mean"].astype(np.float64).copy(), actor["obs_std"].astype(np.float64).copy()
    mean[LAST_ACTION] *= r
    std[LAST_ACTION] *= r
    new["obs_mean"], new["obs_std"] = mean.astype(actor["obs_mean"].dtype), std.astype(actor["obs_std"].dtype)
    new["action_scale"] = new_scale
    np.savez(args.out, **new)

    a_old = mean_action(actor, obs, last)
    obs_new = obs.copy()
    obs_new[:, LAST_ACTION] *= r  # the same previous targets, in the new action's units
    a_new = mean_action(new, obs_new, last)
    d = np.abs(a_new * new_scale - a_old * old_scale)
    small = np.abs(a_old) < 0.7
    print(f"old scale {np.round(old_scale[:6], 3).tolist()}\nnew scale {np.round(new_scale[:6], 3).tolist()}\n"
          f"r {np.round(r[:6], 3).tolist()}")
    for j in range(6):
        ds = d[:, [j, j + 6]][small[:, [j, j + 6]]]
        print(f"{LEG_JOINT_KINDS[j]:12s} target change [rad]: |a|<0.7 max {ds.max() if ds.size else 0:.4f}, all max "
              f"{d[:, [j, j + 6]].max():.4f}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
