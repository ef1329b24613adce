#!/usr/bin/env python3
"""Roll out an exported actor in MJX on the preset command sequence (config/policies/eval_commands.yaml)
with nominal parameters (no randomisation, no noise, no latency, no arm perturbation, no teleop arms).

  python3 training/eval_mjx.py RUN/actor.npz --out RUN/mjx_eval.npz
Records per control tick: command, leg joint positions, PMG references, pelvis height, velocity in
the heading frame, yaw rate, torso pitch/roll; prints the Table I metrics with the definitions of
apps/policy/pmg_policy_sil.cpp (errors against the user's command u, also for the GCO configuration
whose actor observes u'). training/compare_sim2sim.py compares it with the MuJoCo 2.2 SIL log.
"""
import argparse
import glob
import os
import sys

import numpy as np
import yaml

# Run in place (python3 training/eval_mjx.py) as well as installed (pmg-eval-mjx): pmg_train sits beside this file.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def schedule(path):
    with open(path) as f:
        s = yaml.safe_load(f)
    keys = ["vx", "vy", "wz", "pitch", "roll", "height"]
    segs = [(g["t"], np.array([g[k] for k in keys], float)) for g in s["segments"]]

    def at(t):
        k = max(i for i, (t0, _) in enumerate(segs) if t >= t0)
        prev = segs[k - 1][1] if k > 0 else segs[0][1]
        a = np.clip((t - segs[k][0]) / s["ramp"], 0, 1) if s["ramp"] > 0 else 1.0
        return prev + a * (segs[k][1] - prev)
    return at, s["duration"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("actor")
    ap.add_argument("--out", required=True)
    ap.add_argument("--commands", default=None, help="command schedule (default: config/policies/eval_commands.yaml)")
    ap.add_argument("--duration", type=float, default=None)
    ap.add_argument("--repo", default=None, help="pmg checkout (default: $PMG_REPO, the package's checkout, cwd)")
    args = ap.parse_args()
    from pmg_train.paths import repo_root
    args.actor, args.out = os.path.abspath(args.actor), os.path.abspath(args.out)
    args.commands = os.path.abspath(args.commands) if args.commands else None
    os.chdir(repo_root(args.repo))  # the environment's files are named relative to the checkout
    args.commands = args.commands or "config/policies/eval_commands.yaml"
    import jax
    import jax.numpy as jnp
    from export_onnx import load_actor
    from pmg_train.g1_env import EnvConfig, G1PmgEnv, LEG, _quat_to_rot
    mean, std, layers, action_scale, _, mode = load_actor(args.actor)
    cfg = EnvConfig(mode=mode, deterministic_reset=True, arm_perturb=0.0, p_teleop=0.0, p_delay=0.0,
                    command_resample=10 ** 9,
                    episode_length=10 ** 9, noise={"gyro": 0.0, "gravity": 0.0, "q": 0.0, "qd": 0.0})
    env = G1PmgEnv(cfg, sorted(glob.glob("config/clips/g1/*.yaml")), action_scale=action_scale)
    at, duration = schedule(args.commands)
    duration = args.duration or duration
    ticks = int(round(duration / cfg.control_dt))
    cmds = jnp.asarray(np.stack([at(k * cfg.control_dt) for k in range(ticks)]), jnp.float32)
    W = [(jnp.asarray(w), jnp.asarray(b)) for w, b in layers]

    def actor(o):
        h = (o - mean) / std
        for i, (w, b) in enumerate(W):
            h = h @ w + b
            if i + 1 < len(W):
                h = h * jax.nn.sigmoid(h)
        return jnp.tanh(h[:LEG])

    def body(state, cmd):
        info = dict(state.info)
        info["command"] = cmd
        state = state.replace(info=info)
        a = actor(state.obs["state"])
        state = env.step(state, a)
        m = state.info["measured"]  # v_H (3), height, contacts (2), pitch, roll
        ps = state.pipeline_state
        wz = (_quat_to_rot(ps.qpos[3:7]) @ ps.qvel[3:6])[2]  # pelvis yaw rate, world z
        rec = {"q": ps.qpos[7:7 + LEG], "q_ref": state.info["ref_q"][:LEG], "measured": m,
               "ref_height": state.info["ref_height"], "wz": wz, "done": state.done}
        return state, rec

    state = jax.jit(env.reset)(jax.random.PRNGKey(0))
    run = jax.jit(lambda s, c: jax.lax.scan(body, s, c))
    _, rec = run(state, cmds)
    rec = {k: np.asarray(v) for k, v in rec.items()}
    cm = np.asarray(cmds)
    t = np.arange(ticks) * cfg.control_dt
    alive = np.cumsum(rec["done"] > 0) == 0
    sel = alive & (t >= 1.0)
    meas = rec["measured"]
    metrics = {"lin_vel": float(np.mean(np.hypot(cm[sel, 0] - meas[sel, 0], cm[sel, 1] - meas[sel, 1]))),
               "yaw_vel": float(np.mean(np.abs(cm[sel, 2] - rec["wz"][sel]))),
               "roll": float(np.mean(np.abs(cm[sel, 4] - meas[sel, 7]))),
               "pitch": float(np.mean(np.abs(cm[sel, 3] - meas[sel, 6]))),
               "height": float(np.mean(np.abs(cm[sel, 5] - meas[sel, 3]))),
               "fell": bool(not alive.all()), "survived_s": float(alive.sum() * cfg.control_dt)}
    print("MJX rollout:", metrics)
    np.savez(args.out, t=t, command=cm, **rec, metrics=np.array([str(metrics)]))


if __name__ == "__main__":
    main()
