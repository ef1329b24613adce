#!/usr/bin/env python3
"""Roll out an exported actor in MJX on a command schedule (default: the preset sequence,
config/policies/eval_commands.yaml) with nominal parameters (no randomisation, no noise, no latency, no
arm perturbation, no teleop arms, no payloads or hand forces).

  python3 training/eval_mjx.py RUN/actor.npz --out RUN/mjx_eval.npz [--commands S.yaml] [--duration T]

The environment is the run's own: EnvConfig is built from the train_config.json beside the actor (or
--train-config), so its clips, gains, actuator models, command slew and reward widths are the ones it
was trained with, and only the randomisation is switched off (--clips overrides the clip folder). Every
tick the schedule's command (ramped as the schedule says) is the environment's command u and its drawn
goal ("command", "command_goal"), so neither the environment's own draws nor its slew (nor its command envelopes: off here) change it.

--randomized N rolls N robots out at once in the training distribution instead: the run's domain
randomisation (friction, masses and torso payload, armature, frictionloss, joint damping; EnvConfig's
ranges as trained, drawn with --seed), its kp scale, actuation delay, sensor noise and reset noise, but no
pushes, teleoperated arms, hand payloads, hand forces or arm perturbation (the SIL has none of those). It
reports how many robots fell in each segment and the achieved means over the robots still standing: does
the actor fall in its own training simulator where it falls in the SIL, or only there (a sim-to-sim gap)?

--stochastic [SCALE] draws every action from the policy's own distribution, as PPO did while it trained and
explored (Brax's NormalTanhDistribution: tanh of a Gaussian around the actor's mean, the actor's own std times
SCALE, default 1, and the run's --action-noise-scale), instead of playing the mean, which export_onnx.py ships and the runner plays. With
--randomized it is the training's rollout: does a gait survive, and what does it earn, under the noise PPO
judged it by? The metrics add the sampled std (mean over legs and ticks); the npz records it per tick.

--physics mujoco steps the same model with MuJoCo's C engine (mj_step, through a host callback; one nominal
robot, slower) instead of MJX; --pd-damping explicit computes the PD's D term from each physics step's
velocity (EnvConfig.pd_damping), as the SIL's motor-driver emulation does, instead of training's implicit
joint damping; --sim-dt sets the physics step (the SIL's: 0.001 s). Together they tell which of the
engine, the step and the damping an actor's behaviour in the SIL belongs to.

--command-log SEED.csv plays, tick by tick, the command a product-path run gave its generator and actor (a
seed<k>.csv of `pmg_policy_sil --commands S.yaml --out DIR` on the same schedule: after the controller's shaper,
feed-forward and feedback; command_log) instead of the schedule's, whose segments and commanded column stay: does the
actor fall in MJX where the SIL's robot did, given what the SIL gave it (training/device_replay_job.sh)?

--start-reference starts the robot in the PMG reference's pose for the schedule's first command (the
sole on the floor, at rest) instead of standing: whether an actor holds a crouch or a bend it is put in.
--hold-reference replaces the actor by actions that hold the reference's leg pose: what the training
reward gives the reference itself, to set beside the actor's (is the reference the reward's optimum?).

Records the start's pelvis height and, per control tick, the schedule's command, the environment's
command u, leg joint positions, PMG references, pelvis height, velocity in the heading frame, yaw rate,
torso pitch/roll, the gait phase, the feet's x, y (with --randomized, each with a leading robot axis, plus each robot's drawn friction and
total mass, and the robots that fell per segment). Prints the Table I metrics and the foot slip with the definitions
of apps/policy/pmg_policy_sil.cpp (errors against the user's command u, also for the GCO configuration
whose actor observes u') and, per segment of the schedule (those --duration reaches), the commanded and achieved
means and the reward per step over the last 60 % of the segment (pmg_policy_sil's per-segment window), then
term by term (g1_env.REWARD_TERMS: which terms a gait earns or loses; the npz's reward_terms), so
that an actor's behaviour in its training simulator can be set beside the SIL's (`pmg_policy_sil --noise
false`), and over the same windows the gait (segment_gait: the share of ticks in flight and in double
support, contact onsets per second per foot, the speed of a touching foot), which tells a walk from a run,
a hop or a shuffle.
"""
import argparse
import csv
import dataclasses
import functools
import json
import math
import os
import sys

import numpy as np
import yaml

# Run in place (python3 training/eval_mjx.py) as well as installed (pmg-eval-mjx): pmg_train sits beside this file.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


KEYS = ["vx", "vy", "wz", "pitch", "roll", "height"]


def schedule(path):
    """(command at time t (6,), duration [s], segments [(name, start [s], end [s])]) of a schedule file."""
    with open(path) as f:
        s = yaml.safe_load(f)
    segs = [(g["t"], np.array([g[k] for k in KEYS], float)) for g in s["segments"]]
    names = [g.get("name", f"segment_{i}") for i, g in enumerate(s["segments"])]
    ends = [t0 for t0, _ in segs[1:]] + [s["duration"]]
    spans = [(n, t0, t1) for n, (t0, _), t1 in zip(names, segs, ends)]

    def at(t):
        k = max(i for i, (t0, _) in enumerate(segs) if t >= t0)
        prev = segs[k - 1][1] if k > 0 else segs[0][1]
        a = np.clip((t - segs[k][0]) / s["ramp"], 0, 1) if s["ramp"] > 0 else 1.0
        return prev + a * (segs[k][1] - prev)
    return at, s["duration"], spans


LOG_COLUMNS = ["vx_fb", "vy_fb", "wz_fb", "pitch_fb", "roll_fb", "height_fb"]
LOG_LIMITS = (np.array([-2.0, -2.0, -3.0, -1.0, -1.0, 0.3]), np.array([2.0, 2.0, 3.0, 1.0, 1.0, 1.0]))


def command_log(path, ticks, dt, schedule_at):
    """The command the product path gave its generator and actor, (ticks, 6) at control tick k (t = k dt [s]):
    from `pmg_policy_sil --out DIR`'s DIR/seed<k>.csv (one row per loop tick) the command after the
    controller's shaper, feed-forward and feedback, LOG_COLUMNS (v_x, v_y [m/s], omega [rad/s], pitch, roll [rad],
    height [m]; heading frame), of the first episode (episode 0: until the first fall). Each tick takes the last
    row at or before its time (t: the schedule's time); ticks before the controller is active (the columns
    nan), and past the log's end (the run fell), take the schedule's command @p schedule_at(t).
    Raises ValueError naming the file, the row or column and what was expected: a missing column, t not a
    number or not increasing, or a command outside LOG_LIMITS (|v| <= 2 m/s, |omega| <= 3 rad/s, |pitch|,
    |roll| <= 1 rad, height in [0.3, 1.0] m)."""
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None:
            raise ValueError(f"{path}: empty; expected a seed<k>.csv of pmg_policy_sil --out")
        missing = [c for c in ["t", "episode"] + LOG_COLUMNS if c not in header]
        if missing:
            raise ValueError(f"{path}: no column {', '.join(missing)}; expected a seed<k>.csv of pmg_policy_sil --out "
                             f"(t, episode and {', '.join(LOG_COLUMNS)})")
        it, ie, ic = header.index("t"), header.index("episode"), [header.index(c) for c in LOG_COLUMNS]
        times, rows = [], []
        lo, hi = LOG_LIMITS
        for n, row in enumerate(reader, start=2):
            try:
                if int(float(row[ie])) != 0:
                    break  # after the first fall: a restarted robot, not this run's command
                t = float(row[it])
                c = np.array([float(row[i]) for i in ic])
            except (ValueError, IndexError):
                raise ValueError(f"{path}: row {n}: t, episode or {'/'.join(LOG_COLUMNS)} is not a number") from None
            if not math.isfinite(t) or (times and t <= times[-1]):
                raise ValueError(f"{path}: row {n}: t = {t} s{f' after {times[-1]} s' if times else ''}; expected "
                                 f"finite, increasing times")
            bad = np.isfinite(c) & ((c < lo) | (c > hi))
            if bad.any():
                k = int(np.argmax(bad))
                raise ValueError(f"{path}: row {n}: {LOG_COLUMNS[k]} = {c[k]:.4g}; expected in [{lo[k]:g}, {hi[k]:g}] "
                                 f"(or nan before the controller is active)")
            times.append(t)
            rows.append(c)
    out = np.stack([schedule_at(k * dt) for k in range(ticks)]).astype(float)
    if rows:
        k = np.searchsorted(np.asarray(times), np.arange(ticks) * dt + 1e-9, side="right") - 1
        inside = (k >= 0) & (np.arange(ticks) * dt <= times[-1] + 1e-9)
        logged = np.asarray(rows)[np.clip(k, 0, len(rows) - 1)]
        use = inside[:, None] & np.all(np.isfinite(logged), axis=1, keepdims=True)
        out = np.where(use, logged, out)
    return out


def policy_action(h, eps=None, noise=1.0):
    """The action in [-1, 1] of an actor whose last layer put out @p h (..., 2 LEG), the parameters of Brax's
    NormalTanhDistribution (the policy PPO trained and explored with; its loc and std are Brax's own).
    Without @p eps, tanh(loc): the distribution's mode, which export_onnx.py ships and the runner plays. With
    @p eps ~ N(0, 1) (..., LEG), a draw tanh(loc + noise std eps) (@p noise 1: the training's spread; 0: the
    mode). Returns (action (..., LEG), the Gaussian's std (..., LEG) before tanh, times noise)."""
    import jax.numpy as jnp
    from brax.training.distribution import NormalTanhDistribution
    from pmg_train.g1_env import LEG
    gaussian = NormalTanhDistribution(event_size=LEG).create_dist(h)
    std = noise * gaussian.scale
    return jnp.tanh(gaussian.loc if eps is None else gaussian.loc + std * eps), std


def segment_window(t, t0, t1):
    """The ticks of @p t (s) a segment [t0, t1) is judged on: its last 60 % (pmg_policy_sil's window)."""
    return (t >= t0 + 0.4 * (t1 - t0)) & (t < t1)


def segment_means(t, command, achieved, spans, alive):
    """Per segment: (name, commanded (6,), achieved (k,) or None where no tick of its window is alive),
    means over the last 60 % of the segment, pooled over the robots. command (ticks, 6); achieved
    (robots, ticks, k), e.g. k = 6: vx, vy [m/s] heading frame, wz [rad/s], torso pitch, roll [rad], pelvis
    height [m]; alive (robots, ticks) bool."""
    out = []
    for name, t0, t1 in spans:
        window = segment_window(t, t0, t1)
        sel = window[None, :] & alive
        out.append((name, command[window].mean(0) if window.any() else np.full(6, np.nan),
                    achieved[sel].mean(0) if sel.any() else None))
    return out


def segment_gait(t, contact, foot_speed, spans, alive, dt):
    """Per segment: the gait over the last 60 % of the segment (pmg_policy_sil's window), pooled over the
    robots alive there, as a dict, or None where none is: "flight" and "double" (share of ticks with no foot
    and with both feet touching the floor), "touchdowns_per_s" (contact onsets per second per foot, both
    feet pooled) and "slip" (mean horizontal speed [m/s] of a touching foot). contact (robots, ticks, 2)
    bool, the environment's foot contacts (left, right); foot_speed (robots, ticks, 2) [m/s], each foot's
    ankle_roll_link origin speed over the tick that ends there, NaN where it is unknown (the first tick;
    left out of "slip"); alive (robots, ticks) bool; dt [s] the tick.
    A walk that follows a PMG gait has no flight; an actor that hops or runs has flight, and one that
    shuffles has double support most of the time and slips (training/README.md "The runaway is a run",
    where this found V20e's crouched backward run: 45 % flight)."""
    onset = np.zeros_like(contact)
    onset[:, 1:] = contact[:, 1:] & ~contact[:, :-1]
    out = []
    for name, t0, t1 in spans:
        window = segment_window(t, t0, t1)
        sel = window[None, :] & alive
        if not sel.any():
            out.append(None)
            continue
        c = contact[sel]  # (ticks pooled, 2)
        touching = c & np.isfinite(foot_speed[sel])
        out.append({"flight": float(np.mean(~c.any(axis=1))), "double": float(np.mean(c.all(axis=1))),
                    "touchdowns_per_s": float(onset[sel].sum() / (2 * sel.sum() * dt)),
                    "slip": float(foot_speed[sel][touching].mean()) if touching.any() else float("nan")})
    return out


def segment_falls(t, done, spans):
    """Robots whose first fall (done (robots, ticks)) came within each segment [t0, t1)."""
    fell = done.any(axis=1)
    t_fall = np.where(fell, t[np.argmax(done, axis=1)], np.inf)
    return [int(np.sum((t_fall >= t0) & (t_fall < t1))) for _, t0, t1 in spans]


def mujoco_physics_step(env):
    """A physics step (sys, data) -> data for G1PmgEnv.physics_step that runs MuJoCo's C engine (mj_step) on
    the environment's own model (env.mj_model: the same geoms, contacts, solver settings, damping and
    timestep) instead of MJX, then MJX's forward pass on the new state for what the environment reads
    (bodies, contacts). One robot: the C state (warm start) lives in this closure, so the rollout must be
    sequential (the callback's vmap_method)."""
    import jax
    import jax.numpy as jnp
    import mujoco
    from mujoco import mjx
    m = env.mj_model
    d = mujoco.MjData(m)

    def host(qpos, qvel, ctrl, qfrc_applied, xfrc_applied):
        d.qpos[:], d.qvel[:], d.ctrl[:] = qpos, qvel, ctrl
        d.qfrc_applied[:], d.xfrc_applied[:] = qfrc_applied, xfrc_applied
        mujoco.mj_step(m, d)
        return d.qpos.astype(np.float32), d.qvel.astype(np.float32)

    def step(sys, data):
        shapes = (jax.ShapeDtypeStruct(data.qpos.shape, jnp.float32), jax.ShapeDtypeStruct(data.qvel.shape, jnp.float32))
        qpos, qvel = jax.pure_callback(host, shapes, data.qpos, data.qvel, data.ctrl, data.qfrc_applied,
                                       data.xfrc_applied, vmap_method="sequential")
        return mjx.forward(sys, data.replace(qpos=qpos, qvel=qvel, time=data.time + m.opt.timestep))
    return step


def env_from_train_config(path):
    """EnvConfig keyword arguments of a training run, from its train_config.json ("env"); {} without one.
    Lists come back from JSON where the config holds tuples and are restored."""
    if path is None:
        return {}
    try:
        with open(path) as f:
            env = dict(json.load(f)["env"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise SystemExit(f"--train-config {path}: cannot read a train_config.json with an 'env' entry ({e})")
    return {k: tuple(v) if isinstance(v, list) else v for k, v in env.items()}


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("actor")
    ap.add_argument("--out", required=True)
    ap.add_argument("--commands", default=None, help="command schedule (default: config/policies/eval_commands.yaml)")
    ap.add_argument("--duration", type=float, default=None)
    ap.add_argument("--command-log", default=None, metavar="SEED.csv",
                    help="play the command a product-path run gave its generator and actor instead of the schedule's: "
                         "a seed<k>.csv of `pmg_policy_sil --commands S.yaml --out DIR` on the same schedule (the "
                         "command after the controller's shaper, feed-forward and feedback, each tick of the first "
                         "episode: command_log). The schedule still names the segments and is the commanded column "
                         "of the report and the metrics (the user's command u)")
    ap.add_argument("--train-config", default=None,
                    help="the run's train_config.json: the environment is built as trained, then made nominal "
                         "(default: train_config.json beside the actor if there is one, else EnvConfig's defaults)")
    ap.add_argument("--clips", default=None,
                    help="clip folder (default: the train config's, else EnvConfig's: config/clips/g1)")
    ap.add_argument("--start-reference", action="store_true",
                    help="start in the PMG reference's pose for the schedule's first command (EnvConfig."
                         "p_reset_reference; the sole on the floor, at rest) instead of standing: does the actor "
                         "hold a crouch or a bend it is put in?")
    ap.add_argument("--hold-reference", action="store_true",
                    help="instead of the actor, actions that hold the PMG reference's leg pose (the PD targets at "
                         "ref_q, within the actor's action range): what the reward gives the reference itself")
    ap.add_argument("--stochastic", type=float, nargs="?", const=1.0, default=0.0, metavar="SCALE",
                    help="sample each action from the policy's own distribution, as PPO did while training "
                         "(tanh of a Gaussian around the actor's mean, its std the actor's times SCALE, default 1, and "
                         "the run's --action-noise-scale; the noise drawn with --seed) "
                         "instead of playing the mean (the deployed actor): does the gait PPO explored survive?")
    ap.add_argument("--randomized", type=int, default=0, metavar="N",
                    help="N robots in the run's training distribution (domain randomisation, kp scale, delay, noise, "
                         "reset noise; no pushes, teleop arms, payloads or hand forces) instead of one nominal robot")
    ap.add_argument("--seed", type=int, default=0, help="the draws' seed: --randomized's robots, --stochastic's noise")
    ap.add_argument("--physics", choices=["mjx", "mujoco"], default="mjx",
                    help="the physics step: MJX's (training's), or MuJoCo's C engine (mj_step on the same model, "
                         "through a host callback; one nominal robot): which engine an actor's behaviour belongs to")
    ap.add_argument("--pd-damping", choices=["implicit", "explicit"], default=None,
                    help="the PD's D term (EnvConfig.pd_damping; default: as trained): explicit computes kd (qd_des - qd) "
                         "from each physics step's qd, as the SIL's motor-driver emulator does")
    ap.add_argument("--sim-dt", type=float, default=None, metavar="S",
                    help="physics step [s] (EnvConfig.sim_dt; default: as trained, 0.005); the SIL's is 0.001")
    ap.add_argument("--repo", default=None, help="pmg checkout (default: $PMG_REPO, the package's checkout, cwd)")
    args = ap.parse_args(argv)
    if args.stochastic < 0:
        ap.error(f"--stochastic {args.stochastic}: expected a scale >= 0 of the policy's std")
    if args.stochastic and args.hold_reference:
        ap.error("--stochastic samples the actor's actions; --hold-reference plays no actor")
    if args.randomized < 0:
        ap.error(f"--randomized {args.randomized}: expected 0 (one nominal robot) or a number of robots")
    if args.physics == "mujoco" and args.randomized:
        ap.error("--physics mujoco runs one nominal robot: leave out --randomized")
    if args.sim_dt is not None and not 0.0 < args.sim_dt <= 0.01:
        ap.error(f"--sim-dt {args.sim_dt}: expected a physics step in (0, 0.01] s")
    from pmg_train.paths import repo_root
    args.actor, args.out = os.path.abspath(args.actor), os.path.abspath(args.out)
    args.commands = os.path.abspath(args.commands) if args.commands else None
    args.clips = os.path.abspath(args.clips) if args.clips else None
    if args.train_config is None:
        beside = os.path.join(os.path.dirname(args.actor), "train_config.json")
        args.train_config = beside if os.path.exists(beside) else None
    args.train_config = os.path.abspath(args.train_config) if args.train_config else None
    os.chdir(repo_root(args.repo))  # the environment's files are named relative to the checkout
    args.commands = args.commands or "config/policies/eval_commands.yaml"
    import jax
    import jax.numpy as jnp
    from export_onnx import load_actor
    from pmg_train.g1_env import EnvConfig, G1PmgEnv, LEG, REWARD_TERMS, _quat_to_rot, make_randomization_fn
    mean, std, layers, action_scale, _, mode = load_actor(args.actor)
    nominal = dict(mode=mode, arm_perturb=0.0, p_teleop=0.0, p_payload=0.0, p_hand_force=0.0,
                   p_reset_reference=1.0 if args.start_reference else 0.0, command_resample=10 ** 9,
                   episode_length=10 ** 9,
                   command_envelopes=False)  # the schedule's command is the actor's, unshaped (module docstring)
    if args.randomized:
        nominal.update(push_vel=(0.0, 0.0))
    else:
        nominal.update(deterministic_reset=True, p_delay=0.0, noise={"gyro": 0.0, "gravity": 0.0, "q": 0.0, "qd": 0.0})
    if args.pd_damping:
        nominal["pd_damping"] = args.pd_damping
    if args.sim_dt:
        nominal["sim_dt"] = args.sim_dt
    trained = env_from_train_config(args.train_config)
    var_scale = 1.0  # the run's --action-noise-scale (Brax's var_scale): --stochastic draws with the noise it trained with
    if args.train_config:
        with open(args.train_config) as f:
            var_scale = json.load(f).get("action_noise_scale", 1.0)
        if not (isinstance(var_scale, (int, float)) and math.isfinite(var_scale) and var_scale > 0):
            raise SystemExit(f"--train-config {args.train_config}: 'action_noise_scale' is {var_scale!r}; expected a "
                             f"finite scale > 0 (train_pmg.py --action-noise-scale)")
    if args.clips:
        nominal["clips"] = args.clips
    unknown = sorted(set(trained) - {f.name for f in dataclasses.fields(EnvConfig)})
    if unknown:
        raise SystemExit(f"--train-config {args.train_config}: 'env' has keys this EnvConfig does not know: "
                         f"{', '.join(unknown)} (a run from another version of pmg_train)")
    cfg = EnvConfig(**{**trained, **nominal})
    env = G1PmgEnv(cfg, action_scale=action_scale)  # the clip folder EnvConfig.clips
    at, duration, spans = schedule(args.commands)
    duration = args.duration or duration
    spans = [(name, t0, min(t1, duration)) for name, t0, t1 in spans if t0 < duration]  # --duration: the segments run
    ticks = int(round(duration / cfg.control_dt))
    cmds = jnp.asarray(np.stack([at(k * cfg.control_dt) for k in range(ticks)]), jnp.float32)
    actor_cmds = cmds  # the command the environment plays (the schedule's, or --command-log's)
    if args.command_log:
        try:
            actor_cmds = jnp.asarray(command_log(args.command_log, ticks, cfg.control_dt, at), jnp.float32)
        except (OSError, ValueError) as e:
            raise SystemExit(f"--command-log: {e}")
        print(f"command: the product path's actor command from {args.command_log} (largest |difference| from the "
              f"schedule's per axis: {np.round(np.abs(np.asarray(actor_cmds) - np.asarray(cmds)).max(axis=0), 3).tolist()})")
    W = [(jnp.asarray(w), jnp.asarray(b)) for w, b in layers]

    if W[-1][0].shape[1] != 2 * LEG:
        raise SystemExit(f"{args.actor}: the last layer puts out {W[-1][0].shape[1]} values; expected {2 * LEG} "
                         f"(the mean and the scale of {LEG} leg actions)")
    # The actor's weights are inputs of the compiled rollout, not constants folded into it: another actor of the
    # same shapes (a run's other checkpoints, another seed) is served the same compile by JAX's persistent cache.
    params = (jnp.asarray(mean), jnp.asarray(std), W)

    def actor(p, o, eps, noise):
        o_mean, o_std, layers_p = p
        h = (o - o_mean) / o_std
        for i, (w, b) in enumerate(layers_p):
            h = h @ w + b
            if i + 1 < len(layers_p):
                h = h * jax.nn.sigmoid(h)
        return policy_action(h, eps, noise)

    n = max(1, args.randomized)
    if args.physics == "mujoco":
        env.physics_step = mujoco_physics_step(env)
    if args.start_reference:  # the reset's command (its reference pose) is the schedule's first, not a draw
        env._sample_command = lambda rng: cmds[0]
    if args.randomized:  # one randomised model per robot, as in training (Brax's wrapper vmaps over them)
        from brax.envs.wrappers.training import DomainRandomizationVmapWrapper
        k_sys, k_reset = jax.random.split(jax.random.PRNGKey(args.seed))
        sys_v, in_axes = make_randomization_fn(env)(env.sys, jax.random.split(k_sys, n))
        venv = DomainRandomizationVmapWrapper(env, lambda sys: (sys_v, in_axes))
        reset, step, keys = venv.reset, venv.step, jax.random.split(k_reset, n)
        drawn = {"friction": np.asarray(sys_v.geom_friction[:, 0, 0]),  # sliding friction of every geom
                 "mass": np.asarray(sys_v.body_mass.sum(axis=1))}     # total mass [kg], payloads included
    else:
        reset, step, keys = jax.vmap(env.reset), jax.vmap(env.step), jax.random.PRNGKey(0)[None]
        drawn = {}
    yaw_rate = jax.vmap(lambda qpos, qvel: (_quat_to_rot(qpos[3:7]) @ qvel[3:6])[2])  # pelvis yaw rate, world z
    feet = jnp.asarray(env.foot_bodies)  # the ankle_roll_links, left and right

    def body(p, hold, noise, state, xs):
        cmd, key = xs
        info = dict(state.info)
        info["command"] = jnp.broadcast_to(cmd, (n, 6))
        info["command_goal"] = info["command"]  # the step shapes "command" towards "command_goal" (command_slew)
        state = state.replace(info=info)
        # --hold-reference is an input of the compiled rollout, not a Python branch: the actor's rollout and the
        # reference's compile to one program (JAX's persistent cache serves a later run the first's compile, when
        # each run is its own process: main() called twice in one process traces a differently named module).
        # --stochastic likewise: the noise's scale is an input (0: the mean action, bit for bit).
        a_actor, a_std = actor(p, state.obs["state"], jax.random.normal(key, (n, LEG)), noise)
        a = jnp.where(hold, jax.vmap(env.hold_action)(state.info["ref_q"][:, :LEG]), a_actor)
        state = step(state, a)
        ps = state.pipeline_state
        rec = {"command_env": state.info["command"], "q": ps.qpos[:, 7:7 + LEG], "q_ref": state.info["ref_q"][:, :LEG],
               "measured": state.info["measured"],  # v_H (3), height, contacts (2), pitch, roll
               "ref_height": state.info["ref_height"], "wz": yaw_rate(ps.qpos, ps.qvel), "done": state.done,
               "reward": state.reward, "foot_xy": ps.xpos[:, feet, :2],  # ankle_roll_link origins, world x, y [m]
               "action_std": a_std.mean(axis=-1),  # the sampled Gaussian's std, mean over the legs (0: the mean)
               "phase": state.info["phase"],  # the gait phase in [0, 1) the step's reference was generated at
               # the reward's weighted terms (g1_env.REWARD_TERMS order), whose sum is "reward"
               "reward_terms": jnp.stack([state.metrics[f"reward_{k}"] for k in REWARD_TERMS], axis=-1)}
        return state, rec

    state = jax.jit(reset)(keys)
    start = np.asarray(state.pipeline_state.qpos[:, 2])
    import mujoco
    print(f"physics: {'MuJoCo C engine (mj_step)' if args.physics == 'mujoco' else 'MJX'} {mujoco.__version__}, "
          f"step {cfg.sim_dt * 1e3:g} ms, PD damping {cfg.pd_damping}")
    print(f"start: pelvis {start.min():.3f}{'' if n == 1 else f' to {start.max():.3f}'} m "
          f"({'the reference pose of the first command' if args.start_reference else 'standing'})"
          + (f"; {n} robots in the training distribution (seed {args.seed})" if args.randomized else ""))
    run = jax.jit(lambda p, h, z, s, c, k: jax.lax.scan(functools.partial(body, p, h, z), s, (c, k)))
    _, rec = run(params, jnp.asarray(args.hold_reference), jnp.float32(args.stochastic * var_scale), state, actor_cmds,
                 jax.random.split(jax.random.PRNGKey(1000 + args.seed), ticks))
    rec = {k: np.swapaxes(np.asarray(v), 0, 1) for k, v in rec.items()}  # (robots, ticks, ...)
    cm = np.asarray(cmds)
    t = np.arange(ticks) * cfg.control_dt
    done = rec["done"] > 0
    alive = np.cumsum(done, axis=1) == 0
    sel = alive & (t >= 1.0)[None, :]
    meas = rec["measured"]
    c_sel, m_sel = np.broadcast_to(cm, (n,) + cm.shape)[sel], meas[sel]
    metrics = {"lin_vel": float(np.mean(np.hypot(c_sel[:, 0] - m_sel[:, 0], c_sel[:, 1] - m_sel[:, 1]))),
               "yaw_vel": float(np.mean(np.abs(c_sel[:, 2] - rec["wz"][sel]))),
               "roll": float(np.mean(np.abs(c_sel[:, 4] - m_sel[:, 7]))),
               "pitch": float(np.mean(np.abs(c_sel[:, 3] - m_sel[:, 6]))),
               "height": float(np.mean(np.abs(c_sel[:, 5] - m_sel[:, 3])))}
    # Foot slip as pmg_policy_sil defines it: the mean horizontal speed of a foot (ankle_roll_link origin)
    # while it touches the floor (the environment's contact flags, measured[4:6]), from t = 1 s while standing.
    foot_speed = np.linalg.norm(np.diff(rec["foot_xy"], axis=1), axis=-1) / cfg.control_dt  # (robots, ticks - 1, 2)
    touching = (meas[:, 1:, 4:6] > 0.5) & sel[:, 1:, None]
    metrics["foot_slip"] = float(foot_speed[touching].mean()) if touching.any() else float("nan")
    survived = alive.sum(axis=1) * cfg.control_dt
    if args.randomized:
        metrics.update(robots=n, fell=int((~alive[:, -1]).sum()), survived_s=[round(float(x), 2) for x in survived])
    else:
        metrics.update(fell=bool(not alive.all()), survived_s=float(survived[0]))
    if args.stochastic:
        metrics["action_std"] = float(rec["action_std"][alive].mean())
    print(f"{args.physics} rollout{f' (actions drawn from the policy, std x {args.stochastic:g})' if args.stochastic else ''}:",
          metrics)
    achieved = np.stack([meas[..., 0], meas[..., 1], rec["wz"], meas[..., 6], meas[..., 7], meas[..., 3]], axis=-1)
    per_segment = segment_means(t, cm, achieved, spans, alive)
    reward = [r for _, _, r in segment_means(t, cm, rec["reward"][..., None], spans, alive)]
    falls = segment_falls(t, done, spans)
    print(f"per segment (means over the last 60 % of each segment{'' if n == 1 else ' and the robots standing'}): "
          f"commanded / achieved, and the reward per step "
          f"({'actions holding the reference' if args.hold_reference else 'the actor'})"
          + ("" if n == 1 else "; robots that fell in the segment"))
    print(f"{'segment':14s} " + " ".join(f"{k:>15s}" for k in KEYS) + "  reward" + ("" if n == 1 else "  fell"))
    for (name, c_seg, a_seg), r, f in zip(per_segment, reward, falls):
        cells = [f"{c:7.3f} {'   fell' if a_seg is None else f'{a:7.3f}'}" for c, a in
                 zip(c_seg, a_seg if a_seg is not None else c_seg)]
        print(f"{name:14s} " + " ".join(cells) + ("    fell" if r is None else f" {r[0]:7.3f}")
              + ("" if n == 1 else f"  {f:4d}"))
    # The reward term by term over the same windows: which terms a gait earns or loses (the terms whose
    # weight is 0 in this environment are left out of the table; the npz keeps them all).
    term_means = [r for _, _, r in segment_means(t, cm, rec["reward_terms"], spans, alive)]
    shown = [i for i, k in enumerate(REWARD_TERMS) if cfg.w.get(k, 0.0) != 0.0]
    print("reward per step by term (same windows; weighted, summing to the reward column)")
    print(f"{'segment':14s} " + " ".join(f"{REWARD_TERMS[i][:11]:>11s}" for i in shown))
    for (name, _, _), r in zip(per_segment, term_means):
        print(f"{name:14s} " + ("   fell" if r is None else " ".join(f"{r[i]:11.3f}" for i in shown)))
    contact = meas[..., 4:6] > 0.5
    speed = np.concatenate([np.full_like(foot_speed[:, :1], np.nan), foot_speed], axis=1)  # (robots, ticks, 2)
    gait = segment_gait(t, contact, speed, spans, alive, cfg.control_dt)
    print("gait per segment (same windows): share of ticks with no foot / both feet on the floor, "
          "contact onsets per second per foot, speed of a touching foot [m/s]")
    print(f"{'segment':14s}  flight  double  onsets/s   slip")
    for (name, _, _), g in zip(per_segment, gait):
        print(f"{name:14s} " + ("   fell" if g is None else
                                f" {g['flight']:6.2f}  {g['double']:6.2f}  {g['touchdowns_per_s']:8.2f}  {g['slip']:5.3f}"))
    if n == 1:  # one nominal robot: the arrays without the robot axis, as before --randomized
        rec, start = {k: v[0] for k, v in rec.items()}, start[0]
    np.savez(args.out, t=t, command=cm, **rec, metrics=np.array([str(metrics)]),
             env_config=np.array(json.dumps(dataclasses.asdict(cfg))), start_height=np.array(start),
             segment_falls=np.array(falls), **{f"drawn_{k}": v for k, v in drawn.items()},
             segment_names=np.array([n for n, _, _ in per_segment]),
             segment_command=np.array([c for _, c, _ in per_segment]),
             segment_achieved=np.array([a if a is not None else np.full(6, np.nan) for _, _, a in per_segment]),
             segment_reward=np.array([r[0] if r is not None else np.nan for r in reward]),
             reward_term_names=np.array(REWARD_TERMS),
             segment_reward_terms=np.array([r if r is not None else np.full(len(REWARD_TERMS), np.nan)
                                            for r in term_means]),
             segment_gait=np.array([[np.nan] * 4 if g is None else [g["flight"], g["double"], g["touchdowns_per_s"],
                                     g["slip"]] for g in gait]))  # columns: flight, double, onsets/s, slip
    return metrics


if __name__ == "__main__":
    main()
