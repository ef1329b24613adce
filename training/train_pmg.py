#!/usr/bin/env python3
"""Train the G1 PMG-tracking policy with Brax PPO on MuJoCo MJX, export it to ONNX with its contract.

Installed (training/pyproject.toml) as `pmg-train`; training/README.md has the commands:
  pip install -e 'training[cuda]' && pmg-train --out runs/x --mode pmg_gco [--timesteps 150000000]
Trains on every local JAX device (Brax PPO pmaps over jax.local_devices(): the environments are
split evenly, gradients averaged); --devices N uses the first N. The device list is printed first.
Writes into --out: progress.jsonl (eval + training metrics vs env steps and wall time),
params.pkl (normaliser, policy, value: resume with --restore; written at every eval), actor.npz
(the actor's arrays), train_config.json, g1_pmg_policy.onnx (actor + pmg.contract, export_onnx.py).
--warmup-steps N: the first N steps with wide tracking rewards, then the run's own widths (two ppo.train
calls in one process; progress.jsonl names each record's "stage").
--restore-actor RUN/actor.npz --restore-critic OTHER/params.pkl [--critic-warmup-steps N]: fine-tune a kept actor whose
params.pkl is gone, the critic lent by another run and fitted alone for the first N steps (pmg_train/restore.py).
--smoke: imports, env reset/step timing, JAX PMG port vs the committed C++ vectors; no training.
"""
import argparse
import dataclasses
import glob
import json
import math
import os
import pickle
import shutil
import sys
import time

# Run in place (python3 training/train_pmg.py) as well as installed: pmg_train sits beside this file.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

PINNED_JAX = "0.10.2"  # training/pyproject.toml
COMMAND_AXES = ("vx", "vy", "wz", "pitch", "roll", "height")  # EnvConfig command ranges (--command-range)


def axis_bounds(flag, items, strict, axes=COMMAND_AXES):
    """{axis: (lo, hi)} from repeated AXIS=LO,HI command-line items of @p flag (e.g. --command-range height=0.59,0.78;
    units of the command: m/s, rad/s, rad, m). AXIS must be one of @p axes, LO and HI finite with LO < HI when
    @p strict (else LO <= HI), and a height's LO >= 0.3 m. Raises ValueError with a message that names the flag,
    the item and what was expected (the caller passes it to argparse's error)."""
    out = {}
    for item in items:
        axis, _, value = item.partition("=")
        axis = axis.strip()
        try:
            lo, hi = (float(x) for x in value.split(","))
        except ValueError:
            lo = hi = math.nan
        ordered = lo < hi if strict else lo <= hi
        if axis not in axes or not (math.isfinite(lo) and math.isfinite(hi) and ordered):
            raise ValueError(f"{flag} {item!r}: expected AXIS=LO,HI with AXIS one of {', '.join(axes)} "
                             f"and finite LO {'<' if strict else '<='} HI")
        out[axis] = (lo, hi)
    if "height" in out and not 0.3 <= out["height"][0]:
        raise ValueError(f"{flag} height={out['height'][0]},{out['height'][1]}: expected LO >= 0.3 m")
    return out


def log(*a):
    print(f"[{time.strftime('%H:%M:%S')}]", *a, flush=True)


def smoke(env, out):
    import jax
    import jax.numpy as jnp
    from pmg_train import pmg_generator as pg
    log("devices", jax.devices())
    # JAX (float32) port against the C++ vectors, evaluated at the C++ phase of each tick.
    with open("test/data/policy/pmg_vectors_synthetic.json") as f:
        v = json.load(f)
    model = pg.model_from_vectors(v)
    step = jax.jit(lambda ph, ud, us: pg.step(model, ph, ud, us, v["dt"], xp=jnp))
    worst = {}
    for t in v["ticks"]:
        o = step(jnp.float32(t["phase"]), jnp.asarray(t["u_d"], jnp.float32), jnp.asarray(t["u_s"], jnp.float32))
        for k in ("q_ref", "qd_ref", "period", "base_height", "in_contact"):
            worst[k] = max(worst.get(k, 0.0), float(np.max(np.abs(np.asarray(o[k], float) - np.asarray(t[k], float)))))
    log("JAX float32 port vs C++ (max abs):", worst)
    reset = jax.jit(jax.vmap(env.reset))
    stepf = jax.jit(jax.vmap(env.step))
    n = 4096
    s = reset(jax.random.split(jax.random.PRNGKey(0), n))
    a = jnp.zeros((n, env.action_size))
    t0 = time.time(); s = stepf(s, a); jax.block_until_ready(s.obs); log("step compile", time.time() - t0)
    t0 = time.time()
    for _ in range(50):
        s = stepf(s, a)
    jax.block_until_ready(s.obs)
    dt = time.time() - t0
    log(f"{n * 50 / dt:.0f} control steps/s ({n} envs), done frac {float(s.done.mean()):.3f}, "
        f"reward {float(s.reward.mean()):.3f}, height {float(s.pipeline_state.qpos[:, 2].mean()):.3f}")
    with open(os.path.join(out, "smoke.json"), "w") as f:
        json.dump({"jax_port_max_abs": worst, "control_steps_per_s": n * 50 / dt}, f)


def export_robot_yaml(cfg):
    """The robot config whose kp / kd the exported contract carries (the controller refuses a policy
    whose contract gains differ from its robot config's): g1_pig.yaml for physically informed gains."""
    return "config/robots/g1/g1_pig.yaml" if cfg.gains == "physically_informed" else cfg.robot_yaml


def save_params(params, out, env, clip_names):
    """params.pkl (full Brax tree, numpy leaves: resume) + actor.npz (plain arrays: export; with the
    digest of the clips trained on, the contract's pmg.clips_digest)."""
    import jax
    from pmg_train.contract import clips_digest
    params_np = jax.tree_util.tree_map(np.asarray, params)
    with open(os.path.join(out, "params.pkl"), "wb") as f:
        pickle.dump(params_np, f)
    norm, policy = params_np[0], params_np[1]
    p = policy["params"]
    arrays = {"obs_mean": norm.mean["state"], "obs_std": norm.std["state"], "action_scale": env.action_scale,
              "clips": np.array(clip_names), "mode": np.array(env.cfg.mode),
              "upright_walking": np.array(env.cfg.upright_walking), "sole_levelling": np.array(env.cfg.sole_levelling),
              "stride_adaptation": np.array(env.cfg.stride_adaptation),
              "stride_standing_hold": np.array(bool(env.cfg.stride_adaptation and env.gco_opt.stride["standing_hold"])),
              "clips_digest": np.array(clips_digest(env.clip_files)), "action_offset": np.array(env.cfg.action_offset),
              "upper_body_ff": np.array(env.cfg.upper_body_ff)}
    for i in range(len(p)):
        arrays[f"w{i}"] = p[f"hidden_{i}"]["kernel"]
        arrays[f"b{i}"] = p[f"hidden_{i}"]["bias"]
    np.savez(os.path.join(out, "actor.npz"), **arrays)


def check_against_brax(params, make_inference_fn, env, out):
    """The exported graph's NumPy twin equals Brax's deterministic inference."""
    import jax
    import jax.numpy as jnp
    from export_onnx import load_actor
    from pmg_train.contract import actor_forward
    mean, std, layers, _, _, _ = load_actor(os.path.join(out, "actor.npz"))
    rng = np.random.default_rng(0)
    obs = (mean + std * rng.standard_normal((64, mean.size))).astype(np.float32)
    ours = actor_forward(mean, std, layers, env.action_size, obs)
    infer = make_inference_fn(params, deterministic=True)
    priv = np.zeros((64, env.observation_size["privileged_state"][0]), np.float32)
    theirs = np.asarray(jax.vmap(lambda o, q: infer({"state": o, "privileged_state": q}, jax.random.PRNGKey(0))[0])(
        jnp.asarray(obs), jnp.asarray(priv)))
    diff = float(np.max(np.abs(ours - theirs)))
    log("export check: NumPy actor vs Brax inference max |diff|", diff)
    return diff


class _NoEvaluator:
    """Stands in for brax.training.acting.Evaluator with --num-eval-envs 0 (run_evals=False: Brax never
    calls it)."""

    def __init__(self, *args, **kwargs):
        pass

    def run_evaluation(self, *args, **kwargs):
        raise RuntimeError("pmg-train: --num-eval-envs 0 runs no evaluation rollouts")


def _positive_ints(text):
    """'512,256,128' -> (512, 256, 128); argparse type for layer sizes."""
    try:
        sizes = tuple(int(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected comma-separated positive integers, e.g. 512,256,128")
    if not sizes or min(sizes) < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: expected comma-separated positive integers, e.g. 512,256,128")
    return sizes


def _scale_factor(text):
    """argparse type of --action-scale-factor: a finite number in (0, 2]."""
    try:
        f = float(text)
    except ValueError:
        f = float("nan")
    if not (0.0 < f <= 2.0):
        raise argparse.ArgumentTypeError(f"{text!r}: expected a number in (0, 2]")
    return f


LEG_JOINT_KINDS = ("hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll")  # per leg, left then right


def joint_action_factors(items, flag="--factor"):
    """Per-joint factors (12,) of the leg action scale from JOINT=F items (JOINT one of LEG_JOINT_KINDS, F in
    (0, 2]); each applies to that joint of both legs, joints not named keep 1.0, a joint named twice takes its last
    factor. Raises ValueError naming @p flag, the item and the expected form."""
    factors = np.ones(12)
    for item in items:
        name, _, value = item.partition("=")
        try:
            f = float(value)
        except ValueError:
            f = float("nan")
        if name not in LEG_JOINT_KINDS or not 0.0 < f <= 2.0:
            raise ValueError(f"{flag} {item!r}: expected JOINT=F with JOINT one of {', '.join(LEG_JOINT_KINDS)} "
                             "and F in (0, 2]")
        k = LEG_JOINT_KINDS.index(name)
        factors[k] = factors[k + 6] = f
    return factors


def leg_action_scale(scale, args):
    """The run's leg action scale (12,) [rad per unit action]: @p scale (the rule's or --action-scale-from's) times
    --action-scale-factor, then times --action-scale-joint-factor's per-joint factors (both legs)."""
    factors = joint_action_factors(args.action_scale_joint_factor, "--action-scale-joint-factor")
    return (np.asarray(scale, np.float64) * args.action_scale_factor * factors).astype(np.float32)


def action_scale_from(path):
    """The leg action scale (12,) of an earlier run, from its train_config.json ("action_scale").
    Raises SystemExit naming --action-scale-from, the file and the expected form."""
    try:
        with open(path) as f:
            scale = json.load(f).get("action_scale")
    except (OSError, ValueError, AttributeError) as e:
        raise SystemExit(f"--action-scale-from {path}: cannot read a train_config.json ({e})")
    if not (isinstance(scale, list) and len(scale) == 12
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v <= 2 for v in scale)):
        raise SystemExit(f"--action-scale-from {path}: action_scale must be a list of 12 numbers in (0, 2]")
    return np.asarray(scale, np.float32)


# `commands:` key of a controller config -> EnvConfig field (--command-envelopes).
ENVELOPE_KEYS = {"max_velocity": "envelope_max_velocity", "max_acceleration": "command_max_accel",
                 "posture_rate": "command_posture_rate", "height_rate": "command_height_rate",
                 "crouched_height": "crouched_height", "crouched_max_velocity": "crouched_max_velocity",
                 "bent_pitch": "bent_pitch", "bent_max_velocity": "bent_max_velocity",
                 "walking_min_height": "walking_min_height", "walking_min_height_hold_s": "walking_min_height_hold_s"}


def command_envelopes_from(path):
    """EnvConfig fields (command_envelopes on) from a controller config's `commands:` block. Every key of
    ENVELOPE_KEYS must be there, finite and > 0 (the envelopes and the floor on; the controller's own
    validation checks the rest), except crouched_height, which may be 0: the crouched envelope off, as in
    the controller (CommandLimits::crouched_height), for an actor trained on crouched walks at any speed
    of the box; SystemExit naming the file and the key otherwise."""
    import yaml
    try:
        with open(path) as f:
            block = (yaml.safe_load(f) or {}).get("commands")
    except (OSError, yaml.YAMLError) as e:
        raise SystemExit(f"--command-envelopes {path}: cannot read: {e}")
    if not isinstance(block, dict):
        raise SystemExit(f"--command-envelopes {path}: no `commands:` block")
    out = {"command_envelopes": True}
    if block.get("crouched_per_axis", False) is not False:  # the environment has the L1 rule only (g1_env.envelope_scales)
        raise SystemExit(f"--command-envelopes {path}: commands.crouched_per_axis is {block['crouched_per_axis']!r}; "
                         "training has only the L1 rule (false); train with crouched_height 0 for a per-axis box")
    for key, field in ENVELOPE_KEYS.items():
        v = block.get(key)
        vals = v if isinstance(v, list) else [v]
        n = 3 if field.endswith(("velocity", "accel")) else 1
        may_be_off = key == "crouched_height"
        if len(vals) != n or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                                     and (x > 0 or (may_be_off and x == 0)) for x in vals):
            raise SystemExit(f"--command-envelopes {path}: commands.{key} is {v!r}; expected "
                             f"{'3 finite values' if n == 3 else 'a finite value'} > 0 (the envelopes on)"
                             + (" or 0 (the crouched envelope off)" if may_be_off else ""))
        out[field] = tuple(float(x) for x in vals) if n == 3 else float(vals[0])
    return out


def parse_args(argv=None):
    ap = argparse.ArgumentParser(prog="pmg-train", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter, allow_abbrev=False)
    ap.add_argument("--out", required=True, help="run directory (created; progress.jsonl is appended to)")
    ap.add_argument("--timesteps", type=int, default=50_000_000, help="environment steps to train for")
    ap.add_argument("--num-envs", type=int, default=8192,
                    help="parallel environments in all (split evenly over the devices)")
    ap.add_argument("--num-evals", type=int, default=8, help="evaluations (and checkpoints), the first at step 0")
    ap.add_argument("--num-eval-envs", type=int, default=256,
                    help="environments of each evaluation rollout (0: no evaluation rollouts, progress.jsonl then "
                         "holds the training metrics only)")
    ap.add_argument("--batch-size", type=int, default=256, help="PPO minibatch size (unrolls)")
    ap.add_argument("--discounting", type=float, default=0.97, metavar="GAMMA",
                    help="PPO discount per control step, in (0, 1) (default 0.97: a horizon 1/(1 - gamma) of 33 "
                         "steps, 0.33 s at 100 Hz)")
    ap.add_argument("--mirror-loss", type=float, default=0.0, metavar="W",
                    help="weight of the mirror-symmetry loss on the actor's mean action (pmg_train/symmetry.py; "
                         "default 0 = off, PPO's loss unchanged), finite and >= 0")
    ap.add_argument("--reward-scaling", type=float, default=1.0, metavar="S",
                    help="PPO reward scaling, finite and > 0 (Brax: rewards x S in the loss; S = (1 - gamma) / 0.03 "
                         "keeps the returns at gamma 0.97's scale)")
    ap.add_argument("--warmup-steps", type=int, default=0, metavar="N",
                    help="reward-width warm-up: the first N of --timesteps train with wide tracking rewards "
                         "(--warmup-tracking-sigma, --warmup-height-sigma), then PPO continues from those parameters "
                         "with the run's own widths (a second ppo.train: a fresh optimiser, one more compile, "
                         "evaluations in the second stage only). 0 = off. A narrow reward exp(-err^2/S) has almost no "
                         "gradient far from its target: a policy that does not yet turn or crouch learns nothing "
                         "from it (training/README.md \"wide tracking rewards\")")
    ap.add_argument("--warmup-tracking-sigma", type=float, default=None, metavar="S",
                    help="width of both velocity-tracking rewards during the warm-up [(m/s)^2, (rad/s)^2] "
                         "(default 0.25, EnvConfig's own); needs --warmup-steps")
    ap.add_argument("--warmup-height-sigma", type=float, default=None, metavar="S",
                    help="width of the pelvis height reward during the warm-up [m^2] (default 0.02: a 0.16 m "
                         "shortfall keeps 28 %% of the term); needs --warmup-steps")
    ap.add_argument("--warmup-orientation-sigma", type=float, default=None, metavar="S",
                    help="width of the torso pitch/roll reward during the warm-up [rad^2] (default: the run's own, "
                         "--orientation-sigma): a narrow orientation reward from the first step, before the robot "
                         "walks at all, is the likeliest reason N24i fell (training/README.md \"A narrow orientation "
                         "reward on top, from scratch\"); needs --warmup-steps")
    ap.add_argument("--warmup-p-posture-walk", type=float, default=None, metavar="P",
                    help="EnvConfig.p_posture_walk during the warm-up (default: the run's own, --p-posture-walk): 0 "
                         "trains the warm-up's walks at the standing posture, so walking crouched, bent or leaning starts "
                         "from a gait that already walks at its command (a posture curriculum; training/README.md "
                         "\"A posture curriculum\"); needs --warmup-steps")
    ap.add_argument("--action-noise-scale", type=float, default=1.0, metavar="V",
                    help="the exploration noise's scale: each action is drawn as tanh(loc + (softplus(s) + 0.001) V eps), "
                         "Brax NormalTanhDistribution's var_scale (default 1, Brax's own), finite and > 0. The deployed "
                         "action is tanh(loc) whatever V; V < 1 trains, from the first step, with less noise than the "
                         "actor's own std (training/README.md \"The runaway under the training's noise\")")
    ap.add_argument("--warmup-evals", type=int, default=1, metavar="K",
                    help="checkpoints of the warm-up (Brax's num_evals for its ppo.train, no evaluation rollouts; the "
                         "first at its step 0, the last at its end): with --keep-actors, the warm-up's actors; needs "
                         "--warmup-steps")
    ap.add_argument("--keep-actors", action="store_true",
                    help="every checkpoint also writes actors/actor_<step>.npz, the actor at that step (the warm-up's "
                         "included): when a gait forms, rolled out with eval_mjx.py ACTOR --train-config "
                         "RUN/train_config.json")
    ap.add_argument("--num-minibatches", type=int, default=32)
    ap.add_argument("--unroll-length", type=int, default=20)
    ap.add_argument("--episode-length", type=int, default=None,
                    help="control steps per episode (default: EnvConfig.episode_length)")
    ap.add_argument("--hidden", type=_positive_ints, default=(512, 256, 128),
                    help="hidden layer sizes of the actor and the critic MLPs")
    ap.add_argument("--devices", type=int, default=0,
                    help="use the first N local JAX devices (0: all of them)")
    ap.add_argument("--restore", default=None, help="params.pkl of an earlier run to start from")
    ap.add_argument("--restore-actor", default=None, metavar="ACTOR_NPZ",
                    help="fine-tune an actor whose params.pkl was not kept: its actor.npz (layers and observation "
                         "normaliser), with the critic of --restore-critic (pmg_train/restore.py)")
    ap.add_argument("--restore-critic", default=None, metavar="PARAMS_PKL",
                    help="with --restore-actor: a params.pkl (same observation layout and --hidden) lending the value "
                         "network and the privileged observations' normaliser")
    ap.add_argument("--critic-warmup-steps", type=int, default=0, metavar="N",
                    help="with --restore or --restore-actor: the first N steps fit the critic alone (the actor's "
                         "gradient stopped, so it stays as restored), then PPO trains both (a second ppo.train)")
    ap.add_argument("--action-scale-from", default=None, metavar="TRAIN_CONFIG_JSON",
                    help="take the leg action scale from this run's train_config.json instead of deriving it from the "
                         "clips (fine-tuning a restored actor on changed clips keeps the actor's own scale)")
    ap.add_argument("--clips", default="config/clips/g1", metavar="DIR",
                    help="clip folder (clips, implied-motion tables, consistency_map.yaml), relative to the checkout")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repo", default=None, help="pmg checkout (default: $PMG_REPO, the package's checkout, cwd)")
    ap.add_argument("--smoke", action="store_true")
    ap.add_argument("--mode", default="pmg_gco", choices=["pmg_gco", "pmg", "single_gait"],
                    help="Table I configuration: full PMG (GCO), PMG without GCO, single-gait imitation")
    ap.add_argument("--upright-walking", action="store_true",
                    help="remove the walking clips' mean waist lean (GeneratorParams::upright_walking)")
    ap.add_argument("--sole-levelling", action="store_true",
                    help="level the reference's stance soles before GCO (GcoOptions::sole_levelling; pmg_gco only)")
    ap.add_argument("--stride-adaptation", action="store_true",
                    help="hold the reference's stance soles still under the command before GCO "
                         "(GcoOptions::stride_adaptation; pmg_gco only)")
    ap.add_argument("--blending", default=None, choices=["consistent", "paper"],
                    help="generator blending (default: EnvConfig.blending); paper = the PMG paper's, for the ablation")
    ap.add_argument("--arms", default="teleop", choices=["teleop", "perturb"],
                    help="arm targets in training: teleop = VR teleoperation envelope + hand payloads (issue 13, "
                         "EnvConfig.p_teleop), perturb = only the PMG arm reference +-0.3 rad (the Table I runs)")
    ap.add_argument("--gains", default="nominal", choices=["nominal", "physically_informed"],
                    help="PD gains: nominal = the robot config's kp/kd (Baseline); physically_informed = kp = I w_n^2, "
                         "kd = 2 zeta I w_n with the reflected rotor inertia I (also the armature; "
                         "pmg_train/gains.py, config/robots/g1/g1_pig.yaml, which the ONNX contract then carries)")
    ap.add_argument("--action-scale", default="motion", choices=["motion", "torque_matched", "posture"],
                    help="leg action scale: motion = from the walking clips' joint ranges; torque_matched = that x "
                         "kp_nominal/kp, the same PD torque per unit action whatever --gains; posture = motion widened "
                         "to the static clips' offsets over the --command-range pitch, roll and height, so that the "
                         "deep crouch lies inside the actor's reach (EnvConfig.action_scale_rule)")
    ap.add_argument("--action-offset", default="default", choices=["default", "reference"],
                    help="leg targets: default = standing pose + scale x action; reference = the PMG reference + scale x "
                         "action, a residual on the generated motion (EnvConfig.action_offset; not exported to ONNX: the "
                         "controller deploys standing-pose offsets only)")
    ap.add_argument("--action-scale-factor", type=_scale_factor, default=1.0, metavar="F",
                    help="multiplies the leg action scale (the rule's or --action-scale-from's), e.g. 0.5 for residual actions")
    ap.add_argument("--action-scale-joint-factor", action="append", default=[], metavar="JOINT=F",
                    help="multiplies one joint's action scale on both legs (after --action-scale-factor); JOINT one of "
                         "hip_pitch, hip_roll, hip_yaw, knee, ankle_pitch, ankle_roll, F in (0, 2]; repeatable, e.g. "
                         "--action-scale-from N24b.json --action-scale-joint-factor knee=1.2 for a reach between that "
                         "run's and the posture rule's")
    ap.add_argument("--tracking-sigma", type=float, default=None, metavar="S",
                    help="width of both velocity-tracking rewards exp(-err^2/S) (EnvConfig.lin_vel_sigma, yaw_rate_sigma; "
                         "default 0.25)")
    ap.add_argument("--orientation-sigma", type=float, default=None, metavar="S",
                    help="width of the torso pitch/roll reward exp(-err^2/S) [rad^2] (EnvConfig.orientation_sigma; default 0.05)")
    ap.add_argument("--height-sigma", type=float, default=None, metavar="S",
                    help="width of the pelvis height reward exp(-err^2/S) [m^2] (EnvConfig.height_sigma; default 0.005)")
    ap.add_argument("--yaw-rate-weight", type=float, default=None, metavar="W",
                    help="weight of the yaw-rate tracking reward (EnvConfig.w['yaw_rate']; default 0.8, lin_vel 1.5); the same as --reward-weight yaw_rate=W")
    ap.add_argument("--reward-weight", action="append", default=[], metavar="NAME=W",
                    help="set one reward term's weight (EnvConfig.w: lin_vel, yaw_rate, orientation, height, ref_q, "
                         "ref_qd, contact, energy, action_rate, alive, termination); repeatable; an unknown NAME is an error")
    ap.add_argument("--command-range", action="append", default=[], metavar="AXIS=LO,HI",
                    help="training command range of one axis (EnvConfig: vx, vy [m/s], wz [rad/s], pitch, roll [rad], "
                         "height [m]; default the issue-12 envelope); repeatable. Wider than the user's envelope, it "
                         "leaves the controller's tracking feedback room (velocity_feedback.envelope_min/max)")
    ap.add_argument("--p-stop", type=float, default=None, metavar="P",
                    help="probability that a command drawn after a walking one stands still (EnvConfig.p_stop, "
                         "default 0: stops from a fast walk are rare)")
    ap.add_argument("--stop-keeps-posture", type=float, default=None, metavar="P",
                    help="probability that a stop (--p-stop) keeps the walking goal's posture, so the robot stops "
                         "where it is crouched or bent (EnvConfig.p_stop_keep_posture, default 0: drawn anew)")
    ap.add_argument("--p-reset-reference", type=float, default=None, metavar="P",
                    help="probability that an episode starts in the PMG reference's pose for its first command and "
                         "phase instead of standing (reference state initialisation; EnvConfig.p_reset_reference, "
                         "default 0: every episode starts standing)")
    ap.add_argument("--push-vel", default=None, metavar="LO,HI",
                    help="range of the pushes' horizontal velocity change [m/s] (EnvConfig.push_vel, default 0,0.4)")
    ap.add_argument("--p-posture-walk", type=float, default=None, metavar="P",
                    help="probability that a walking command also commands a posture, so walking crouched, bent or "
                         "leaning (EnvConfig.p_posture_walk, default 0.4)")
    ap.add_argument("--p-combined", type=float, default=None, metavar="P",
                    help="probability that a drawn command combines velocity axes (EnvConfig.p_combined, default 0.4; "
                         "with p_single_axis 0.4 the rest stands still, so at most 0.6)")
    ap.add_argument("--command-focus", action="append", default=[], metavar="AXIS=LO,HI",
                    help="one axis of a focus box (EnvConfig.command_focus; axes as --command-range, each inside its "
                         "range); repeatable; an axis not named is zero (velocity) or neutral (posture). Needs --p-focus")
    ap.add_argument("--p-focus", type=float, default=None, metavar="P",
                    help="probability that a drawn goal is uniform in the --command-focus box instead of the plain "
                         "mix (EnvConfig.p_focus, default 0), e.g. --command-focus vx=-0.6,-0.3 --command-focus "
                         "height=0.66,0.72 --p-focus 0.1 for backward walks crouched")
    ap.add_argument("--joint-stop-timeconst", type=float, default=None, metavar="S",
                    help="time constant [s] of every joint's stop (its limit constraint's solref, EnvConfig."
                         "joint_stop_timeconst; default 0 = the MJCF's, MuJoCo's 0.02 s, soft enough that a crouched "
                         "walk presses the ankles 0.06 rad past their range); at least 2 physics steps (0.01 at 5 ms). "
                         "The SIL's are 0.004 (mujoco.joint_stops, docs/controller.md \"Joint stops\")")
    ap.add_argument("--command-slew", action="store_true",
                    help="shape the drawn commands as the controller does (EnvConfig.command_slew: slew limits "
                         "1.0 / 1.0 m/s^2, 2.0 rad/s^2, posture 0.5 rad/s, height 0.2 m/s, config/controller/g1_sil_policy.yaml "
                         "`commands:`); default off: a drawn command applies at once")
    ap.add_argument("--command-envelopes", default=None, metavar="CONTROLLER_YAML",
                    help="with --command-slew: the controller's crouched and bent velocity envelopes and walking "
                         "height floor on the shaped command, with that config's `commands:` values "
                         "(EnvConfig.command_envelopes; e.g. config/controller/g1_sil_policy.yaml); default off: "
                         "crouched and bent walks the product path never commands are trained too")
    ap.add_argument("--actuators", default="",
                    help="calibrated robot config (pmg_calib_joints --out): the env applies its identified `actuator:` "
                         "blocks per joint (EnvConfig.actuators; zero offsets are not applied)")
    ap.add_argument("--actuator-dr", type=float, default=None,
                    help="relative half-width of the domain randomisation around each identified actuator parameter "
                         "the calibration gives no uncertainty for (default: EnvConfig.actuator_dr)")
    ap.add_argument("--actuator-dr-z", type=float, default=None,
                    help="a parameter with a calibrated uncertainty u (`actuator_uncertainty:`) is drawn within +- z u "
                         "(default: EnvConfig.actuator_dr_z)")
    ap.add_argument("--hand-forces", type=float, default=None, metavar="P",
                    help="external hand forces in the domain randomisation (issue 14): probability per teleoperated hand "
                         "and segment (EnvConfig.p_hand_force; default 0 = off); needs --arms teleop")
    ap.add_argument("--upper-body-ff", action="store_true",
                    help="the controller's upper-body gravity compensation at the waist joints in the environment "
                         "(EnvConfig.upper_body_ff: nominal-model gravity torque - 5 N m s/rad x qd, once per tick; "
                         "deploy with `upper_body: {enabled: true}`, docs/controller.md)")
    args = ap.parse_args(argv)
    if not 0.0 < args.discounting < 1.0:
        ap.error(f"--discounting = {args.discounting}: expected in (0, 1)")
    if not (math.isfinite(args.reward_scaling) and args.reward_scaling > 0):
        ap.error(f"--reward-scaling = {args.reward_scaling}: expected a finite value > 0")
    if not (math.isfinite(args.mirror_loss) and args.mirror_loss >= 0):
        ap.error(f"--mirror-loss = {args.mirror_loss}: expected a finite weight >= 0")
    if (args.restore_actor is None) != (args.restore_critic is None):
        ap.error("--restore-actor and --restore-critic: give both (an actor.npz holds no critic) or neither")
    if args.restore_actor is not None and args.restore is not None:
        ap.error("--restore-actor with --restore: expected one of them")
    if args.critic_warmup_steps < 0 or (args.critic_warmup_steps > 0 and (
            args.critic_warmup_steps >= args.timesteps or (args.restore is None and args.restore_actor is None))):
        ap.error(f"--critic-warmup-steps = {args.critic_warmup_steps}: expected 0 (off) or fewer than --timesteps = "
                 f"{args.timesteps}, with --restore or --restore-actor")
    if args.critic_warmup_steps > 0 and args.warmup_steps > 0:
        ap.error("--critic-warmup-steps with --warmup-steps: expected one of them (a restored actor needs no reward-width "
                 "warm-up)")
    if args.warmup_steps < 0 or (args.warmup_steps > 0 and args.warmup_steps >= args.timesteps):
        ap.error(f"--warmup-steps = {args.warmup_steps}: expected 0 (off) or fewer than --timesteps = {args.timesteps}")
    for flag, default in (("warmup_tracking_sigma", 0.25), ("warmup_height_sigma", 0.02)):
        value = getattr(args, flag)
        name = "--" + flag.replace("_", "-")
        if value is not None and args.warmup_steps == 0:
            ap.error(f"{name} = {value}: has no effect without --warmup-steps N > 0")
        if value is not None and not (math.isfinite(value) and value > 0):
            ap.error(f"{name} = {value}: expected a finite width > 0")
        if value is None:
            setattr(args, flag, default)
    if args.warmup_orientation_sigma is not None:
        if args.warmup_steps == 0:
            ap.error(f"--warmup-orientation-sigma = {args.warmup_orientation_sigma}: has no effect without --warmup-steps N > 0")
        if not (math.isfinite(args.warmup_orientation_sigma) and args.warmup_orientation_sigma > 0):
            ap.error(f"--warmup-orientation-sigma = {args.warmup_orientation_sigma}: expected a finite width > 0")
    if args.warmup_p_posture_walk is not None:
        if args.warmup_steps == 0:
            ap.error(f"--warmup-p-posture-walk = {args.warmup_p_posture_walk}: has no effect without --warmup-steps N > 0")
        if not 0.0 <= args.warmup_p_posture_walk <= 1.0:
            ap.error(f"--warmup-p-posture-walk = {args.warmup_p_posture_walk}: expected in [0, 1]")
    if args.action_scale_joint_factor:
        try:
            joint_action_factors(args.action_scale_joint_factor, "--action-scale-joint-factor")
        except ValueError as e:
            ap.error(str(e))
    if not (math.isfinite(args.action_noise_scale) and args.action_noise_scale > 0):
        ap.error(f"--action-noise-scale = {args.action_noise_scale}: expected a finite scale > 0")
    if args.warmup_evals != 1 and args.warmup_steps == 0:
        ap.error(f"--warmup-evals = {args.warmup_evals}: has no effect without --warmup-steps N > 0")
    if args.warmup_evals < 1:
        ap.error(f"--warmup-evals = {args.warmup_evals}: expected 1 or more checkpoints")
    if args.orientation_sigma is not None and not args.orientation_sigma > 0:
        ap.error(f"--orientation-sigma = {args.orientation_sigma}: expected > 0")
    if args.height_sigma is not None and not args.height_sigma > 0:
        ap.error(f"--height-sigma = {args.height_sigma}: expected > 0")
    if args.tracking_sigma is not None and not args.tracking_sigma > 0:
        ap.error(f"--tracking-sigma = {args.tracking_sigma}: expected > 0")
    if args.yaw_rate_weight is not None and not args.yaw_rate_weight >= 0:
        ap.error(f"--yaw-rate-weight = {args.yaw_rate_weight}: expected >= 0")
    if args.command_envelopes and not args.command_slew:
        ap.error("--command-envelopes: needs --command-slew (the envelopes act on the shaped command)")
    if args.p_stop is not None and not 0.0 <= args.p_stop <= 1.0:
        ap.error(f"--p-stop = {args.p_stop}: expected in [0, 1]")
    if args.p_reset_reference is not None and not 0.0 <= args.p_reset_reference <= 1.0:
        ap.error(f"--p-reset-reference = {args.p_reset_reference}: expected in [0, 1]")
    if args.stop_keeps_posture is not None and not 0.0 <= args.stop_keeps_posture <= 1.0:
        ap.error(f"--stop-keeps-posture = {args.stop_keeps_posture}: expected in [0, 1]")
    if args.joint_stop_timeconst is not None and not 0.01 - 1e-12 <= args.joint_stop_timeconst <= 1.0:
        ap.error(f"--joint-stop-timeconst = {args.joint_stop_timeconst}: expected in [0.01, 1] s (2 physics steps of 5 ms)")
    if args.push_vel is not None:
        try:
            lo, hi = (float(x) for x in args.push_vel.split(","))
        except ValueError:
            lo = hi = math.nan
        if not 0.0 <= lo <= hi <= 2.0:
            ap.error(f"--push-vel = {args.push_vel}: expected LO,HI with 0 <= LO <= HI <= 2 m/s")
        args.push_vel = (lo, hi)
    if args.p_posture_walk is not None and not 0.0 <= args.p_posture_walk <= 1.0:
        ap.error(f"--p-posture-walk = {args.p_posture_walk}: expected in [0, 1]")
    if args.p_combined is not None and not 0.0 <= args.p_combined <= 0.6:
        ap.error(f"--p-combined = {args.p_combined}: expected in [0, 0.6] (p_single_axis 0.4 + p_combined <= 1)")
    weights = {}
    for item in args.reward_weight:
        name, _, value = item.partition("=")
        try:
            w = float(value)
        except ValueError:
            w = math.nan
        if not name.strip() or not math.isfinite(w):
            ap.error(f"--reward-weight {item!r}: expected NAME=W with a finite number W")
        weights[name.strip()] = w
    if args.yaw_rate_weight is not None:  # the older spelling of --reward-weight yaw_rate=W
        weights["yaw_rate"] = args.yaw_rate_weight
    args.reward_weight = weights
    try:
        args.command_range = axis_bounds("--command-range", args.command_range, strict=True)
        args.command_focus = axis_bounds("--command-focus", args.command_focus, strict=False)
    except ValueError as e:
        ap.error(str(e))
    if args.p_focus is not None and not 0.0 <= args.p_focus <= 1.0:
        ap.error(f"--p-focus = {args.p_focus}: expected in [0, 1]")
    if bool(args.command_focus) != bool(args.p_focus):
        ap.error("--command-focus and --p-focus: give both (a box and a probability > 0) or neither")
    if args.hand_forces is not None and not (0.0 <= args.hand_forces <= 1.0 and args.arms == "teleop"):
        ap.error(f"--hand-forces = {args.hand_forces}: expected a probability in [0, 1], with --arms teleop")
    if args.actuator_dr is not None and not 0.0 <= args.actuator_dr < 1.0:
        ap.error(f"--actuator-dr = {args.actuator_dr}: expected a relative half-width in [0, 1)")
    if args.actuators:
        if not os.path.isfile(args.actuators):
            ap.error(f"--actuators = {args.actuators!r}: no such file")
        args.actuators = os.path.abspath(args.actuators)
    for name in ("timesteps", "num_envs", "num_evals", "batch_size", "num_minibatches",
                 "unroll_length", "episode_length"):
        value = getattr(args, name)
        if value is not None and value < 1:
            ap.error(f"--{name.replace('_', '-')} = {value}: expected >= 1")
    if args.num_eval_envs < 0:
        ap.error(f"--num-eval-envs = {args.num_eval_envs}: expected >= 0 (0: no evaluation rollouts)")
    if args.devices < 0:
        ap.error(f"--devices = {args.devices}: expected >= 0 (0: all local devices)")
    if (args.batch_size * args.num_minibatches) % args.num_envs:
        ap.error(f"--batch-size x --num-minibatches = {args.batch_size * args.num_minibatches} must be a multiple "
                 f"of --num-envs = {args.num_envs} (Brax PPO collects batch_size x num_minibatches unrolls per "
                 f"update from num_envs environments)")
    return args


def warmup_config(cfg, args):
    """The warm-up stage's EnvConfig (--warmup-steps): @p cfg with the velocity-tracking widths
    (lin_vel_sigma, yaw_rate_sigma) set to --warmup-tracking-sigma, height_sigma to
    --warmup-height-sigma and, when given, orientation_sigma to --warmup-orientation-sigma and p_posture_walk
    to --warmup-p-posture-walk, every other field as it is; None when --warmup-steps is 0."""
    if args.warmup_steps <= 0:
        return None
    posture = {} if args.warmup_p_posture_walk is None else {"p_posture_walk": args.warmup_p_posture_walk}
    if args.warmup_orientation_sigma is not None:
        posture["orientation_sigma"] = args.warmup_orientation_sigma
    return dataclasses.replace(cfg, lin_vel_sigma=args.warmup_tracking_sigma, yaw_rate_sigma=args.warmup_tracking_sigma,
                               height_sigma=args.warmup_height_sigma, **posture)


def select_devices(args):
    """The local JAX devices this run trains on (printed); checks that the work splits evenly."""
    import jax
    local = jax.local_devices()
    if args.devices > len(local):
        raise SystemExit(f"pmg-train: --devices = {args.devices}, but JAX sees only {len(local)} local device(s): "
                         f"{local}")
    used = local[:args.devices] if args.devices else local
    n = len(used)
    log(f"JAX {jax.__version__}, backend {jax.default_backend()}, {len(local)} local device(s):",
        ", ".join(str(d) for d in local))
    version = tuple(int(x) for x in jax.__version__.split(".")[:2])
    if version == (0, 11) and n > 1:
        # Measured with 0.11.2 on 2 H200s and on 2 XLA host devices: compiling a pmap over several
        # devices of MJX's constraint solver (mjx._src.solver.solve) segfaults; 0.10.2 runs.
        raise SystemExit(f"pmg-train: JAX {jax.__version__} segfaults compiling Brax's multi-device pmap of the "
                         f"MJX step; install the pinned JAX (pip install -e 'training[cuda]': 0.10.2) or train on "
                         f"one device (--devices 1)")
    if jax.__version__ != PINNED_JAX:
        log(f"warning: JAX {jax.__version__} is not the pinned {PINNED_JAX} (training/pyproject.toml)")
    if args.num_envs % n:
        raise SystemExit(f"pmg-train: --num-envs = {args.num_envs} is not divisible by the {n} device(s) used; "
                         f"pick a multiple of {n} (or --devices)")
    per_device = args.batch_size * args.num_minibatches // n
    if per_device * n != args.batch_size * args.num_minibatches or per_device % args.num_minibatches:
        raise SystemExit(f"pmg-train: batch_size x num_minibatches = {args.batch_size * args.num_minibatches} "
                         f"unrolls do not split into {args.num_minibatches} minibatches on each of {n} devices; "
                         f"make --batch-size a multiple of {n}")
    log(f"training on {n} device(s): {args.num_envs // n} environments and {args.batch_size // n} unrolls per "
        f"minibatch on each")
    if jax.default_backend() == "cpu" and args.num_envs >= 1024:
        log("warning: JAX runs on the CPU (no GPU found: install with [cuda] on a machine with an NVIDIA driver)")
    return used


def main(argv=None):
    args = parse_args(argv)
    from pmg_train.paths import repo_root
    args.out = os.path.abspath(args.out)
    for flag in ("restore", "restore_actor", "restore_critic"):
        if getattr(args, flag):
            setattr(args, flag, os.path.abspath(getattr(args, flag)))
    os.chdir(repo_root(args.repo))  # the environment's files are named relative to the checkout
    os.makedirs(args.out, exist_ok=True)

    import jax
    try:  # brax 0.14.2 still calls jax.device_put_replicated, removed in JAX 0.11 (pinned: 0.10.2)
        jax.device_put_replicated
    except AttributeError:
        def _device_put_replicated(x, devices):
            return jax.pmap(lambda _: x, devices=devices)(np.arange(len(devices)))
        jax.device_put_replicated = _device_put_replicated
    devices = select_devices(args)
    from brax.training.agents.ppo import networks as ppo_networks
    from brax.training.agents.ppo import train as ppo
    from pmg_train.g1_env import EnvConfig, G1PmgEnv, focus_box, make_randomization_fn
    from pmg_train.symmetry import env_maps, with_mirror_loss

    clip_files = sorted(glob.glob(os.path.join(args.clips, "*.yaml")))
    if not clip_files:
        raise SystemExit(f"--clips {args.clips}: no clip files (*.yaml) there")
    log("clips:", clip_files)
    cfg = EnvConfig(mode=args.mode) if args.arms == "teleop" else EnvConfig(mode=args.mode, p_teleop=0.0, p_payload=0.0)
    if args.episode_length:
        cfg = dataclasses.replace(cfg, episode_length=args.episode_length)
    if args.blending:
        cfg = dataclasses.replace(cfg, blending=args.blending)
    cfg = dataclasses.replace(cfg, upright_walking=args.upright_walking, sole_levelling=args.sole_levelling,
                              stride_adaptation=args.stride_adaptation)
    cfg = dataclasses.replace(cfg, gains=args.gains, actuators=args.actuators, action_scale_rule=args.action_scale,
                              action_offset=args.action_offset)
    if args.tracking_sigma is not None:
        cfg = dataclasses.replace(cfg, lin_vel_sigma=args.tracking_sigma, yaw_rate_sigma=args.tracking_sigma)
    if args.orientation_sigma is not None:
        cfg = dataclasses.replace(cfg, orientation_sigma=args.orientation_sigma)
    if args.height_sigma is not None:
        cfg = dataclasses.replace(cfg, height_sigma=args.height_sigma)
    if args.command_range:
        cfg = dataclasses.replace(cfg, **args.command_range)
        log("command ranges:", {a: getattr(cfg, a) for a in COMMAND_AXES})
    if args.command_focus:
        cfg = dataclasses.replace(cfg, command_focus=dict(args.command_focus), p_focus=args.p_focus)
        try:
            focus_box(cfg, standing_height=0.0)  # the box inside the ranges (the env resolves the neutral height)
        except ValueError as e:
            raise SystemExit(f"pmg-train: --command-focus: {e}")
        log("command focus:", cfg.command_focus, "p_focus", cfg.p_focus)
    unknown = sorted(set(args.reward_weight) - set(cfg.w))
    if unknown:
        raise SystemExit(f"pmg-train: --reward-weight {unknown}: unknown reward term(s); known: {sorted(cfg.w)}")
    if args.reward_weight:
        cfg = dataclasses.replace(cfg, w={**cfg.w, **args.reward_weight})
        log("reward weights:", cfg.w)
    if args.actuator_dr is not None:
        cfg = dataclasses.replace(cfg, actuator_dr=args.actuator_dr)
    if args.actuator_dr_z is not None:
        cfg = dataclasses.replace(cfg, actuator_dr_z=args.actuator_dr_z)
    if args.hand_forces is not None:
        cfg = dataclasses.replace(cfg, p_hand_force=args.hand_forces)
    if args.upper_body_ff:
        cfg = dataclasses.replace(cfg, upper_body_ff=True)
        log("upper-body feed-forward at the waist: damping", cfg.upper_body_damping, "N m s/rad, bound",
            cfg.upper_body_max_torque, "N m")
    # Command-mix and push overrides (flag -> EnvConfig field), logged as set.
    for flag, field in (("p_stop", "p_stop"), ("stop_keeps_posture", "p_stop_keep_posture"), ("push_vel", "push_vel"),
                        ("p_reset_reference", "p_reset_reference"),
                        ("p_posture_walk", "p_posture_walk"), ("p_combined", "p_combined"),
                        ("joint_stop_timeconst", "joint_stop_timeconst")):
        if getattr(args, flag) is not None:
            cfg = dataclasses.replace(cfg, **{field: getattr(args, flag)})
            log(f"{field}:", getattr(cfg, field))
    if args.command_slew:
        cfg = dataclasses.replace(cfg, command_slew=True)
        log("command slew:", cfg.command_max_accel, cfg.command_posture_rate, cfg.command_height_rate)
    if args.command_envelopes:
        cfg = dataclasses.replace(cfg, **command_envelopes_from(args.command_envelopes))
        log("command envelopes:", {k: getattr(cfg, k) for k in ENVELOPE_KEYS.values()})
    cfg = dataclasses.replace(cfg, clips=args.clips)
    action_scale = action_scale_from(args.action_scale_from) if args.action_scale_from else None
    env = G1PmgEnv(cfg, clip_files, action_scale=action_scale)
    env.action_scale = leg_action_scale(env.action_scale, args)  # scaled before any step is traced
    log("leg action scale (left leg):", [round(float(v), 3) for v in env.action_scale[:6]])
    clip_files = env.clip_files
    if args.smoke:
        smoke(env, args.out)
        return
    warmup_cfg = warmup_config(cfg, args)
    warmup_env = None if warmup_cfg is None else G1PmgEnv(warmup_cfg, clip_files, action_scale=env.action_scale)

    ppo_cfg = dict(num_timesteps=args.timesteps, num_envs=args.num_envs, episode_length=cfg.episode_length,
                   unroll_length=args.unroll_length, batch_size=args.batch_size, num_minibatches=args.num_minibatches,
                   num_updates_per_batch=4, discounting=args.discounting, learning_rate=3e-4, entropy_cost=5e-3,
                   reward_scaling=args.reward_scaling, clipping_epsilon=0.2, gae_lambda=0.95, max_grad_norm=1.0,
                   normalize_observations=True, num_evals=args.num_evals, num_eval_envs=max(args.num_eval_envs, 1),
                   run_evals=args.num_eval_envs > 0,
                   seed=args.seed, action_repeat=1, max_devices_per_host=len(devices))
    net_cfg = dict(policy_hidden_layer_sizes=args.hidden, value_hidden_layer_sizes=args.hidden,
                   policy_obs_key="state", value_obs_key="privileged_state")
    with open(os.path.join(args.out, "train_config.json"), "w") as f:
        json.dump({"ppo": ppo_cfg, "networks": net_cfg, "env": dataclasses.asdict(cfg), "clips": clip_files,
                   "action_scale": env.action_scale.tolist(), "restore": args.restore,
                   "restore_actor": args.restore_actor, "restore_critic": args.restore_critic,
                   "critic_warmup_steps": args.critic_warmup_steps, "argv": sys.argv,
                   "devices": [str(d) for d in devices], "jax": jax.__version__, "mirror_loss": args.mirror_loss,
                   "action_noise_scale": args.action_noise_scale,
                   "warmup": None if warmup_env is None else {
                       "steps": args.warmup_steps, "lin_vel_sigma": args.warmup_tracking_sigma,
                       "yaw_rate_sigma": args.warmup_tracking_sigma, "height_sigma": args.warmup_height_sigma,
                       "orientation_sigma": warmup_cfg.orientation_sigma,
                       "p_posture_walk": warmup_cfg.p_posture_walk, "evals": args.warmup_evals},
                   "gains": {"mode": cfg.gains, "kp": env.kp.tolist(), "kd": env.kd.tolist(),
                             "armature": env.armature.tolist(), "robot_yaml": export_robot_yaml(cfg)},
                   "actuators": {"file": cfg.actuators, "dr": cfg.actuator_dr,
                                 "blocks": {n: {k: (None if isinstance(v, float) and math.isinf(v) else v)
                                                for k, v in b.items() if not k.startswith("_") and v is not None}
                                            for n, b in env.actuator_blocks.items()},
                                 "uncertainty": {n: b["_uncertainty"] for n, b in env.actuator_blocks.items()},
                                 "dr_relative": {env.joint_names[i]: {k: float(env.act_dr[k][r])
                                                                      for k in env.act_dr if env.act_dr[k][r] > 0}
                                                 for r, i in enumerate(env.act_idx)}}}, f, indent=1)
    restore = None
    if args.restore:
        with open(args.restore, "rb") as f:
            restore = pickle.load(f)
        log("restoring", args.restore)
    elif args.restore_actor:
        from pmg_train.restore import graft_actor
        restore = graft_actor(args.restore_actor, args.restore_critic, args.hidden,
                              env.observation_size["state"][0], len(env.action_scale),
                              env.observation_size["privileged_state"][0],
                              action_scale=env.action_scale, mode=cfg.mode)
        log("restoring: actor from", args.restore_actor, "- critic and privileged normaliser from", args.restore_critic)
    t_start = time.time()
    progress = open(os.path.join(args.out, "progress.jsonl"), "a")
    stage = {"name": "main", "offset": 0, "last": 0}

    def progress_fn(step, metrics):
        stage["last"] = int(step)
        rec = {"step": int(step) + stage["offset"], "wall_s": time.time() - t_start, "stage": stage["name"]}
        rec.update({k: float(np.asarray(v)) for k, v in metrics.items() if np.asarray(v).size == 1})
        progress.write(json.dumps(rec) + "\n")
        progress.flush()
        log(f"step {rec['step']:>10d}  eval reward {rec.get('eval/episode_reward', float('nan')):8.2f}  "
            f"len {rec.get('eval/avg_episode_length', float('nan')):6.1f}" + (f"  ({stage['name']})" if warmup_env else ""))

    clip_names = [os.path.splitext(os.path.basename(c))[0] for c in clip_files]

    def policy_params_fn(step, make_policy, params):  # checkpoint at every eval
        save_params(params, args.out, env, clip_names)
        if args.keep_actors:  # the actor at this step beside the latest (zero-padded: the names sort by step)
            os.makedirs(os.path.join(args.out, "actors"), exist_ok=True)
            shutil.copyfile(os.path.join(args.out, "actor.npz"),
                            os.path.join(args.out, "actors", f"actor_{step + stage['offset']:011d}.npz"))
        log(f"checkpoint at step {step + stage['offset']}")

    # Brax builds its Evaluator even with run_evals=False, and the Evaluator compiles the evaluation env's
    # reset when built (brax 0.14.2: acting.Evaluator.__init__; 32 s on a CPU). Where nothing evaluates
    # (--num-eval-envs 0, the warm-up) a stand-in that compiles nothing is built instead.
    evaluator_cls = ppo.acting.Evaluator
    ppo_loss = ppo.ppo_losses.compute_ppo_loss
    if args.mirror_loss > 0:  # brax 0.14.2: train() binds ppo_losses.compute_ppo_loss when called
        ppo.ppo_losses.compute_ppo_loss = with_mirror_loss(ppo_loss, args.mirror_loss, net_cfg["policy_obs_key"],
                                                           *env_maps(env))
        log("mirror-symmetry loss, weight", args.mirror_loss)

    def network_factory(observation_size, action_size, **kw):  # Brax's networks; the noise's scale (--action-noise-scale)
        nets = ppo_networks.make_ppo_networks(observation_size, action_size, **kw, **net_cfg)
        if args.action_noise_scale != 1.0:
            from brax.training import distribution
            nets = nets.replace(parametric_action_distribution=distribution.NormalTanhDistribution(
                event_size=action_size, var_scale=args.action_noise_scale))
        return nets

    def train(environment, **overrides):
        run_cfg = {**ppo_cfg, **overrides}
        ppo.acting.Evaluator = evaluator_cls if run_cfg["run_evals"] else _NoEvaluator
        return ppo.train(environment=environment,
                         network_factory=network_factory,
                         randomization_fn=make_randomization_fn(environment), progress_fn=progress_fn,
                         policy_params_fn=policy_params_fn, **run_cfg)

    try:
        if args.critic_warmup_steps > 0:  # stage 1: the critic alone, the restored actor held (restore.with_frozen_policy)
            from pmg_train.restore import with_frozen_policy
            stage["name"] = "critic"
            log(f"critic warm-up: {args.critic_warmup_steps} steps with the actor's gradient stopped")
            loss_before = ppo.ppo_losses.compute_ppo_loss
            ppo.ppo_losses.compute_ppo_loss = with_frozen_policy(loss_before)
            try:
                _, restore, _ = train(env, num_timesteps=args.critic_warmup_steps, num_evals=1, run_evals=False,
                                      restore_params=restore)
            finally:
                ppo.ppo_losses.compute_ppo_loss = loss_before
            stage.update(name="main", offset=stage["last"])
            log(f"critic warm-up done after {stage['offset']} steps, {time.time() - t_start:.0f} s; actor and critic from here")
        if warmup_env is not None:  # stage 1: wide rewards, no evaluations; checkpoints at its start and end (--warmup-evals)
            stage["name"] = "warmup"
            log(f"warm-up: {args.warmup_steps} steps with tracking sigma {args.warmup_tracking_sigma}, "
                f"height sigma {args.warmup_height_sigma}, orientation sigma {warmup_cfg.orientation_sigma}, "
                f"p_posture_walk {warmup_cfg.p_posture_walk}")
            _, restore, _ = train(warmup_env, num_timesteps=args.warmup_steps, num_evals=args.warmup_evals,
                                  run_evals=False,
                                  restore_params=restore)
            stage.update(name="main", offset=stage["last"])
            log(f"warm-up done after {stage['offset']} steps, {time.time() - t_start:.0f} s; the run's own widths from here")
        make_inference_fn, params, _ = train(env, num_timesteps=args.timesteps - stage["offset"],
                                             seed=args.seed + (1 if warmup_env is not None or args.critic_warmup_steps > 0
                                                               else 0),
                                             restore_params=restore)
    finally:
        ppo.acting.Evaluator = evaluator_cls
        ppo.ppo_losses.compute_ppo_loss = ppo_loss
    log("training done in", time.time() - t_start, "s")
    save_params(params, args.out, env, clip_names)
    diff = check_against_brax(params, make_inference_fn, env, args.out)
    if cfg.action_offset != "default":
        log(f"not exported to ONNX: action_offset {cfg.action_offset!r} (the controller deploys standing-pose offsets "
            "only); actor.npz and params.pkl are kept")
        return
    from export_onnx import export
    export(os.path.join(args.out, "actor.npz"), os.path.join(args.out, "g1_pmg_policy.onnx"), brax_check=diff,
           robot_yaml=export_robot_yaml(cfg),
           training={"gains": cfg.gains, "actuators": cfg.actuators, "actuator_dr": cfg.actuator_dr})


if __name__ == "__main__":
    main()
