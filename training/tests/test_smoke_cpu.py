#!/usr/bin/env python3
"""CPU smoke run of the training code, in the installed training environment (ctest training_smoke_cpu).

Usage: test_smoke_cpu.py [--part env|ppo|all] [--workdir DIR] [--steps 60] [--envs 8]
Any python3 may start it: it re-runs itself with the training environment's interpreter,
$PMG_TRAINING_PYTHON or else <repo>/.venv-training/bin/python (scripts/setup.sh makes it:
pip install -e 'training[cpu]'), on the CPU with two XLA host devices (so Brax's multi-device
path runs), XLA's backend optimisation off and its older fusion emitters, and tcmalloc preloaded
(compile_allocator) (compiling MJX takes most of the time; these few steps run fast enough without).
It installs nothing. A missing environment is
a failure (exit 1); PMG_SKIP_TRAINING_TESTS=1 disables the test: a skip (exit 77, ctest
SKIP_RETURN_CODE).
Compiled programs go to JAX's persistent cache, $PMG_JAX_CACHE_DIR (default
${XDG_CACHE_HOME:-~/.cache}/pmg-training-jax; ctest sets build/training_jax_cache; "off" disables
it): a re-run with unchanged code skips most of the compile time. ctest runs the parts as three tests
(training_smoke_env: 1 to 1h, training_smoke_ppo: 2, training_smoke_eval: 2b on part 2's actor, after
it) so that the environment's compiles run beside the other two. Compiling an
env's reset and step takes most of the time, so parts 1 to 1e share one env with every training
option on (make_smoke_env), compiled once; the default configuration is the PPO run's (2).

0. The environment holds the versions training/pyproject.toml pins.
1. The MJX environment (the training configuration: full PMG with GCO, randomised reset and
   commands, pushes; with 1b's calibrated robot and physically informed gains and 1c-1e's hand
   forces, command slew and stops): --envs environments x --steps control steps with zero action
   (legs held at the default pose by the PD), one compiled reset and step (un-batched, each env
   stepped in turn). Checks: every observation, privileged
   observation and reward finite; no episode ends and the pelvis stays above 0.65 m with the trunk
   within 0.3 rad of upright; rewards at most the sum of the positive reward weights, mean > 0;
   the references in the observation equal the float64 NumPy ports (pmg_generator.step at the
   env's phase and command, then gco.level_soles: q_ref to 1e-4 rad; gco.step from the env's
   previous GCO state: u' to 1e-3) and the phase advances by the port's own update; the foot_slip
   metric equals the recorded feet's horizontal speed while touching (and stays below 0.05 m/s
   standing); with EnvConfig.w["foot_slip"] = -1, w["lin_vel_abs"] = -1, w["yaw_rate_abs"] = -0.5 and
   w["flight"] = -1 (one compiled step) a state shoved at 0.8 m/s loses exactly its slip plus its
   velocity error plus half its yaw-rate error, and lifted 5 cm off the floor 1 more; the metrics
   reward_<term> (g1_env.REWARD_TERMS) sum to the reward, the optional terms 0 at weight 0 and each
   penalty's own value when on.
1b. Actuator models and gains (issue 15): the JAX float32 actuator port (pmg_train/actuator.py) equals
   the float64 NumPy port (itself = C++, ctest actuator_port_equals_cpp) on random sequences with every
   effect on; part 1's env is built with a calibrated robot config written into the workdir (left
   knee inline {kp_scale 0.8, delay 4 ms, fc 1 N m, offset 0.02 rad}, right hip pitch from an
   actuator file {kt_scale 0.9, limit 60 N m, fv 0.3, armature 0.02, Stribeck, kl}, a zero_offsets
   map) and gains=physically_informed (its rollout: finite and upright, part 1); the DR widths are
   sized from the knee's actuator_uncertainty (z u / |value|, floored) and are actuator_dr where none is
   given; the identified parameters are drawn within those widths, unnamed effects stay off, offsets
   are not applied; with the identified values (one physics substep per env.step) the knee's and the
   hip's motor torque equal the NumPy port's prediction (kp x 0.8 with the 4 ms delay interpolated
   between 5 ms substeps; kt 0.9, 60 N m saturation) and differ from the nominal PD, the implicit
   damping, armature and the knee's friction row (1 N m) are the model's; PIG kp / kd equal
   config/robots/g1/g1_pig.yaml and the armature is the reflected inertia.
1c. External hand forces (issue 14, in part 1's env: EnvConfig.p_hand_force = 1, teleop on every arm,
   segments of 25 steps; one episode of 50 steps, before the first push): xfrc_applied at the two hand bodies equals the env's slewed force,
   nothing elsewhere; per-step change within hand_force_rate x dt; targets within their ranges and
   redrawn per segment; the same episode without forces ends in a different state.
1d. Command slew (EnvConfig.command_slew, in 1c's env): every step the command the generator, the
   observation and the rewards get moves towards the drawn goal by exactly the slew-limited step
   (max_accel [m/s^2, rad/s^2] and posture/height rates x dt), and the goals are redrawn per segment.
   With the controller's envelopes on (EnvConfig.command_envelopes; every walking goal crouched to
   0.59-0.62 m): the step is exactly shape_with_envelopes' (the port test_command_envelopes.py proves
   equal to the controller's shaper), and the walking height floor or an envelope moved the command
   away from the plain slew on some step.
1e. Stops (EnvConfig.p_stop = 1, p_stop_keep_posture = 1, in 1c's env): every goal drawn after a
   walking goal has zero velocity and keeps the walking goal's posture (pitch, roll, height).
1f. Residual actions (EnvConfig.action_offset = "reference", its own env, one physics substep from a
   deterministic reset, an action on one knee): the leg torques equal kp (q_ref + scale a - q), the PMG
   reference of the step, not the standing pose; an unknown action_offset is refused. The same env
   has the upper-body feed-forward on (EnvConfig.upper_body_ff, issue 14), with the waist joints
   moving: their torques equal the PD plus MuJoCo's own gravity torque (mj_rne at zero velocity on
   the CPU model, nominal masses) minus 5 N m s/rad x qd, clamped; with a calibrated robot config
   that identifies a waist joint it is refused (the actuator model has no feed-forward term).
1g. Reference state initialisation (EnvConfig.p_reset_reference = 0.5, its own env): of 12 resets some
   stand (0.79 m, the standing pose) and some start in the PMG reference's pose for their first command
   and phase (joints within the reset noise of ref_q, the lowest sole sphere on the floor to 0.1 mm, at
   rest, the pelvis within 0.04 m of the commanded height); from each of those, 50 steps of actions
   holding the reference end no episode and move the pelvis by less than 0.06 m.
1h. PD damping (EnvConfig.pd_damping, no compile): "implicit" puts kd into the joints' damping (0.05 + kd)
   and the DR draws it within kd_scale; "explicit" leaves 0.05 in the model and in every draw; others
   are refused.
2. The reward-width warm-up's staging (--warmup-steps 400 of 1000, train_pmg.main with Brax's ppo.train
   replaced by a recorder, nothing compiled): the warm-up environment (its widths, the run's other fields)
   trains 400 steps without evaluations, then the run's environment the remaining 600 from the
   warm-up's parameters with seed + 1; progress.jsonl marks the stages; Brax's Evaluator and loss are
   restored. Then one tiny PPO run through the real entry point (train_pmg.main: 8 envs on both host
   devices, two training steps of 80 env steps in one stage (a warm-up would compile it all twice), 32-32 MLPs,
   no evaluation rollouts, half the episodes from the reference's pose (--p-reset-reference 0.5), the
   mirror-symmetry loss at
   weight 0.5): checkpoint, actor.npz and ONNX
   export written; the exported actor equals Brax's inference (the export check, < 1e-4); the ONNX
   model passes onnx.checker and carries the pmg.contract, whose pmg.clips_digest names the clips
   trained on; progress.jsonl reached the step count
   with finite metrics, the mirror loss among them (> 0: Brax ran the patched loss); both devices were used; the same actor marked as trained with residual
   actions (action_offset "reference") is refused by the export.
2b. eval_mjx.py on that actor over a two-segment schedule (0.4 s) (its per-segment flight and double
   support equal the recorded contacts): the environment runs the schedule's
   command every tick and reports both segments' commanded means; it is the run's environment
   (train_config.json beside the actor: the run's reward widths and clips) made nominal; with
   --start-reference it starts in the first command's reference pose (pelvis within 0.04 m of its height);
   with --hold-reference (the same schedule: the actor's compiled rollout, the flag its input) the legs
   follow the reference over the first 0.1 s (mean |q - q_ref| below 0.1 rad and half the untrained
   actor's), and the rewards are finite; with --randomized 3 (0.2 s) three robots run in the
   run's training distribution (three different frictions within its range and three masses, its delay
   and noise, no pushes or teleop arms), and only the segment the duration reaches is reported; with
   --physics mujoco --pd-damping explicit --sim-dt 0.001 (0.2 s) MuJoCo's C engine steps the same model
   and the legs stay within 30 % of their motion of MJX's rollout.
Prints one line per check and "N passed, N failed"; exit code 0 iff every check passed.
"""
import argparse
import copy
import dataclasses
import glob
import json
import math
import os
import shutil
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TRAINING = os.path.dirname(HERE)
REPO = os.path.dirname(TRAINING)
CHILD = "PMG_TRAINING_SMOKE_CHILD"
SKIP = 77


TCMALLOC = "libtcmalloc_minimal.so.4"


def compile_allocator(env):
    """The allocator library the relaunched interpreter preloads (LD_PRELOAD), or None for glibc's.

    XLA's CPU compiler spends about a sixth of its time in glibc's malloc and free (perf, the smoke env's
    step); with gperftools' tcmalloc (Debian libtcmalloc-minimal4, which scripts/setup.sh installs) one
    compile of that step took 15-20 s against 28-30 s, the env part 236 s against 270 s (docs/ci_timing.md,
    "The allocator, and one serial test less"). The results
    do not depend on the allocator. PMG_TRAINING_ALLOCATOR: "tcmalloc" (the default; glibc's with a note
    when the library is not installed), "system" (glibc's), or the path of another allocator library;
    unknown values and missing paths are errors."""
    want = env.get("PMG_TRAINING_ALLOCATOR", "tcmalloc")
    if want == "system":
        return None
    if want == "tcmalloc":
        import ctypes.util
        if ctypes.util.find_library("tcmalloc_minimal") is None:
            print(f"note: {TCMALLOC} not found (Debian: libtcmalloc-minimal4, which scripts/setup.sh installs): "
                  f"XLA compiles with glibc's malloc (one compile of the smoke env's step 1.5-2 times slower)")
            return None
        return TCMALLOC
    if os.path.sep in want and os.path.isfile(want):
        return want
    print(f"FAIL: PMG_TRAINING_ALLOCATOR={want!r}: expected 'tcmalloc', 'system' or the path of an existing "
          f"allocator library")
    sys.exit(1)


def relaunch(script=__file__):
    """Re-run @p script (default: this one) with the training environment's interpreter (never returns)."""
    if os.environ.get("PMG_SKIP_TRAINING_TESTS") == "1":
        print("SKIPPED: PMG_SKIP_TRAINING_TESTS=1 (the training tests are disabled)")
        sys.exit(SKIP)
    py = os.environ.get("PMG_TRAINING_PYTHON") or os.path.join(REPO, ".venv-training", "bin", "python")
    if not os.access(py, os.X_OK):
        print(f"FAIL: training environment missing: no interpreter at {py} (scripts/setup.sh creates it: "
              f"python3 -m venv .venv-training && .venv-training/bin/pip install -e 'training[cpu]'); "
              f"set PMG_SKIP_TRAINING_TESTS=1 to disable the training tests on purpose")
        sys.exit(1)
    env = dict(os.environ)
    env[CHILD] = "1"
    env["JAX_PLATFORMS"] = "cpu"
    env["XLA_FLAGS"] = " ".join([env.get("XLA_FLAGS", ""), "--xla_force_host_platform_device_count=2",
                                 "--xla_backend_optimization_level=0",
                                 "--xla_llvm_disable_expensive_passes=true",
                                 # XLA's older LLVM fusion emitters: the env's reset and step compile in about
                                 # three quarters of the time (docs/ci_timing.md, "Where the time goes")
                                 "--xla_cpu_use_fusion_emitters=false"]).strip()
    env.setdefault("MUJOCO_GL", "disable")
    allocator = compile_allocator(env)
    if allocator:
        env["LD_PRELOAD"] = " ".join([allocator, env.get("LD_PRELOAD", "")]).strip()
        # tcmalloc's report of single allocations over 1 GiB would only be noise in the test's output
        env.setdefault("TCMALLOC_LARGE_ALLOC_REPORT_THRESHOLD", str(1 << 40))
    cache = env.get("PMG_JAX_CACHE_DIR") or os.path.join(
        env.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "pmg-training-jax")
    if cache != "off":
        env["JAX_COMPILATION_CACHE_DIR"] = cache
    sys.stdout.flush()
    os.execve(py, [py, os.path.abspath(script)] + sys.argv[1:], env)


class Checks:
    def __init__(self):
        self.passed, self.failed = 0, 0

    def __call__(self, ok, what):
        ok = bool(ok)
        print(f"{'ok  ' if ok else 'FAIL'} {what}", flush=True)
        if ok:
            self.passed += 1
        else:
            self.failed += 1
        return ok


def term_slices(obs_terms):
    out, i = {}, 0
    for name, size, _ in obs_terms:
        out[name] = slice(i, i + size)
        i += size
    return out, i


def pin_checks(check):
    """The environment holds exactly the versions training/pyproject.toml pins (a stale venv fails)."""
    import importlib.metadata
    import tomllib
    with open(os.path.join(TRAINING, "pyproject.toml"), "rb") as f:
        project = tomllib.load(f)["project"]
    pins = [r for r in project["dependencies"] + project["optional-dependencies"]["cpu"] if "==" in r]
    wrong = []
    for req in pins:
        name, version = req.split("==")
        name = name.split("[")[0]
        try:
            have = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            have = None
        if have != version:
            wrong.append(f"{name} {have} (pinned {version})")
    check(pins and not wrong, f"{len(pins)} pinned packages at their pinned versions"
                              + (f"; differ: {', '.join(wrong)} (re-run scripts/setup.sh)" if wrong else ""))


def make_smoke_env(workdir):
    """The env of parts 1-1e (module docstring): the training configuration (full PMG with GCO, the
    clips as train_pmg.py passes them, upright walking and levelled stance soles) with a calibrated
    robot config written into @p workdir, physically informed gains and HAND_FORCE_CFG. Returns (env, the calibrated config's path)."""
    import jax
    from pmg_train import g1_env
    t0 = time.time()
    cal_path = write_calibrated_robot(workdir)
    cfg = g1_env.EnvConfig(actuators=cal_path, gains="physically_informed", upright_walking=True, sole_levelling=True,
                           **HAND_FORCE_CFG)
    env = g1_env.G1PmgEnv(cfg, sorted(glob.glob("config/clips/g1/*.yaml")))
    print(f"env built in {time.time() - t0:.1f} s: mode {cfg.mode}, clips {len(env.clip_files)}, "
          f"{len(jax.local_devices())} host devices", flush=True)
    return env, cal_path


def env_checks(check, env, n_envs, n_steps):
    """Part 1 on @p env. Returns (the rollout's observations (T+1, n, 62), the reset states, the jitted
    reset and step)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    import export_onnx
    from pmg_train import gco
    from pmg_train import g1_env
    from pmg_train import pmg_generator as pg

    cfg = env.cfg
    sl, n_obs = term_slices(g1_env.OBS_TERMS)
    check([(n, s) for n, s, _ in export_onnx.OBS_TERMS] == [(n, s) for n, s, _ in g1_env.OBS_TERMS] and
          all(np.allclose(a, b) for (_, _, a), (_, _, b) in zip(export_onnx.OBS_TERMS, g1_env.OBS_TERMS)),
          "export_onnx.OBS_TERMS equals g1_env.OBS_TERMS (the exported contract describes the env's observation)")
    check(env.observation_size["state"] == (n_obs,) and n_obs == 62,
          f"actor observation has the contract's {n_obs} values (expected 62)")

    # One compiled reset and one compiled step (un-batched: the same programs serve 1b-1e), each env
    # stepped in a Python loop; the trajectory stacked to (T+1, n, ...).
    reset, step = jax.jit(env.reset), jax.jit(env.step)
    zero = jnp.zeros(env.action_size)
    t0 = time.time()
    starts, per_env = [], []
    for key in jax.random.split(jax.random.PRNGKey(3), n_envs):
        st = reset(key)
        starts.append(st)
        seq = [st]
        for _ in range(n_steps):
            st = step(st, zero)
            seq.append(st)
        per_env.append(jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *seq))
    traj = jax.tree_util.tree_map(lambda *xs: np.stack(xs, axis=1), *per_env)
    print(f"reset + {n_steps} steps x {n_envs} envs: {time.time() - t0:.1f} s (compile included)", flush=True)
    obs = np.asarray(traj.obs["state"], np.float64)            # (T+1, n, 62)
    priv = np.asarray(traj.obs["privileged_state"], np.float64)
    reward = np.asarray(traj.reward, np.float64)[1:]           # (T, n)
    done = np.asarray(traj.done)[1:]
    qpos = np.asarray(traj.pipeline_state.qpos, np.float64)
    info = traj.info

    check(np.isfinite(obs).all() and np.isfinite(priv).all() and np.isfinite(qpos).all(),
          f"observations, privileged observations and qpos finite ({obs.shape[0]} x {n_envs})")
    check(priv.shape[-1] == env.observation_size["privileged_state"][0], "privileged observation size as declared")
    check(np.isfinite(reward).all(), "rewards finite")
    check(not done.any(), f"no episode ended in {n_steps} steps with the legs held (done count {int(done.sum())})")
    height = qpos[:, :, 2]
    w, x, y = qpos[:, :, 3], qpos[:, :, 4], qpos[:, :, 5]
    up = 1.0 - 2.0 * (x * x + y * y)                            # R_WB[2, 2]: cos(tilt of the pelvis)
    tilt = np.degrees(np.arccos(np.clip(up, -1, 1)))
    check(height.min() > 0.65, f"pelvis above 0.65 m throughout (min {height.min():.3f} m)")
    check(tilt.max() < np.degrees(0.3), f"pelvis within 0.3 rad of upright (max tilt {tilt.max():.1f} deg)")
    w_pos = sum(v for v in cfg.w.values() if v > 0)
    check(reward.max() <= w_pos + 1e-4 and reward.mean() > 0.0,
          f"reward per step in (.., {w_pos:.2f}] (sum of positive weights), mean > 0 "
          f"(min {reward.min():.3f}, mean {reward.mean():.3f}, max {reward.max():.3f})")

    # The reward term by term (g1_env.REWARD_TERMS, the metrics "reward_<term>", which eval_mjx.py reports per
    # segment): the weighted terms sum to the step's reward, and the optional terms, whose weights are 0 here,
    # are 0.
    by_term = np.stack([np.asarray(traj.metrics[f"reward_{k}"], np.float64)[1:] for k in g1_env.REWARD_TERMS], -1)
    optional = [g1_env.REWARD_TERMS.index(k) for k in g1_env.OPTIONAL_REWARD_TERMS]
    alive_term = by_term[..., g1_env.REWARD_TERMS.index("alive")]
    check(np.abs(by_term.sum(-1) - reward).max() < 1e-4 and not by_term[..., optional].any() and
          np.allclose(alive_term, cfg.w["alive"]),
          f"reward_<term> metrics ({len(g1_env.REWARD_TERMS)} terms) sum to the reward (max |diff| "
          f"{np.abs(by_term.sum(-1) - reward).max():.1e}); the optional terms 0 at weight 0; alive {alive_term.mean():.3f}")
    # Foot slip (EnvConfig.w["foot_slip"]): the metric is the summed horizontal speed of the ankle_roll_link
    # origins touching the floor, from the recorded poses; standing with the legs held, the feet stay put.
    feet_xy = np.asarray(traj.pipeline_state.xpos, np.float64)[:, :, env.foot_bodies, :2]   # (T+1, n, 2, 2)
    touching = np.asarray(info["measured"], np.float64)[1:, :, 4:6]                            # (T, n, 2)
    slip = np.sum(touching * np.linalg.norm(np.diff(feet_xy, axis=0), axis=-1), axis=-1) / cfg.control_dt
    slip_metric = np.asarray(traj.metrics["foot_slip"], np.float64)[1:]
    check(np.abs(slip_metric - slip).max() < 1e-4 and touching.mean() > 0.5 and slip.mean() < 0.05,
          f"foot_slip metric = recorded feet's speed while touching (max |diff| {np.abs(slip_metric - slip).max():.1e} m/s; "
          f"touching {touching.mean():.2f} of foot-steps, mean slip {slip.mean():.4f} m/s < 0.05 standing)")
    # The penalty weights, in one compiled step (foot_slip = -1, lin_vel_abs = -1, yaw_rate_abs = -0.5,
    # flight = -1; each step of a differently weighted env is a compile of its own, 40 s here): the
    # pushed state (feet on the floor, sliding) loses exactly its slip [m/s] plus its velocity error
    # [m/s] plus half its yaw-rate error [rad/s], from the step's own metrics; a state lifted 5 cm off
    # the floor (neither foot touching at the end of the step, so no slip) loses 1 more than its errors
    # cost.
    st = jax.tree_util.tree_map(lambda a: jnp.asarray(a[-1, 0]), traj)
    st = st.replace(pipeline_state=st.pipeline_state.replace(qvel=st.pipeline_state.qvel.at[0].add(0.8)))
    extra = copy.copy(env)
    extra.cfg = dataclasses.replace(cfg, w=dict(cfg.w, foot_slip=-1.0, lin_vel_abs=-1.0, yaw_rate_abs=-0.5,
                                                 flight=-1.0))
    step_extra = jax.jit(extra.step)

    def terms(state):
        m = state.metrics
        return float(m["foot_slip"]), float(m["lin_vel_err"]), float(m["yaw_rate_err"])
    plain = step(st, zero)
    slip_p, lin_p, yaw_p = terms(plain)
    pushed = step_extra(st, zero)
    lost = float(plain.reward - pushed.reward)
    got = {k: float(pushed.metrics[f"reward_{k}"]) for k in g1_env.OPTIONAL_REWARD_TERMS}
    check(abs(got["foot_slip"] + slip_p) < 1e-5 and abs(got["lin_vel_abs"] + lin_p) < 1e-5 and
          abs(got["yaw_rate_abs"] + 0.5 * yaw_p) < 1e-5 and got["flight"] == 0.0 and
          abs(sum(float(pushed.metrics[f"reward_{k}"]) for k in g1_env.REWARD_TERMS) - float(pushed.reward)) < 1e-4,
          f"reward_<term> with the penalties on: {got} (−slip, −error, −0.5 × yaw error, 0 on the floor), "
          f"summing to the reward {float(pushed.reward):.4f}")
    check(slip_p > 0.05 and lin_p > 0.3 and abs(lost - (slip_p + lin_p + 0.5 * yaw_p)) < 1e-4,
          f"foot_slip -1, lin_vel_abs -1, yaw_rate_abs -0.5: a robot shoved at 0.8 m/s slides {slip_p:.3f} m/s "
          f"(> 0.05), misses its command by {lin_p:.3f} m/s (> 0.3) and {yaw_p:.3f} rad/s, and its reward drops by "
          f"{lost:.4f} (their weighted sum {slip_p + lin_p + 0.5 * yaw_p:.4f})")
    lifted = st.replace(pipeline_state=st.pipeline_state.replace(qpos=st.pipeline_state.qpos.at[2].add(0.05)))
    lifted_plain = step(lifted, zero)
    slip_l, lin_l, yaw_l = terms(lifted_plain)
    lifted_extra = step_extra(lifted, zero)
    lost_air = float(lifted_plain.reward - lifted_extra.reward) - (slip_l + lin_l + 0.5 * yaw_l)
    check(slip_l == 0.0 and abs(lost_air - 1.0) < 1e-4 and float(lifted_extra.metrics["reward_flight"]) == -1.0,
          f"flight -1: a robot lifted 5 cm (no foot touching, slip {slip_l}) loses {lost_air:.4f} (1) beyond its "
          f"tracking errors; on the floor, 0 (above)")

    # References in the (noise-free) privileged observation against the float64 NumPy ports.
    phase = np.asarray(info["phase"], np.float64)                # (T+1, n)
    command = np.asarray(info["command"], np.float64)            # (T+1, n, 6)
    gco_states = jax.tree_util.tree_map(np.asarray, info["gco"])
    scale_cmd = np.asarray(g1_env.OBS_TERMS[[n for n, _, _ in g1_env.OBS_TERMS].index("command")][2], np.float64)
    q_default = np.asarray(env.q_default, np.float64)
    worst = {"q_ref": 0.0, "phase_sincos": 0.0, "next_phase": 0.0, "u_opt": 0.0}
    for t in range(obs.shape[0]):
        for i in range(n_envs):
            ref = pg.step(env.pmg, phase[t, i], command[t, i, :3], command[t, i, 3:], cfg.control_dt)
            if t == 0:
                state = gco.initial_state()
            else:
                state = {k: np.asarray(v[t - 1, i]).astype(bool if v.dtype == bool else np.float64)
                         for k, v in gco_states.items()}
            if cfg.sole_levelling:
                ref, _, _, state = gco.level_soles(env.gco_chains, env.gco_opt, ref, env.js.q_stand, env.js.lower,
                                                   env.js.upper, state)
            if cfg.stride_adaptation:
                ref, _, _, state = gco.adapt_strides(env.gco_chains, env.gco_opt, ref, command[t, i, :3], env.js.lower,
                                                     env.js.upper, state)
            q_rel = np.asarray(ref["q_ref"])[:g1_env.LEG] - q_default[:g1_env.LEG]
            worst["q_ref"] = max(worst["q_ref"], float(np.abs(priv[t, i, sl["pmg_ref_q_rel"]] - q_rel).max()))
            ph = 2 * math.pi * phase[t, i]
            worst["phase_sincos"] = max(worst["phase_sincos"], float(np.abs(
                priv[t, i, sl["pmg_phase"]] - [math.sin(ph), math.cos(ph)]).max()))
            if t + 1 < obs.shape[0]:
                d = abs(float(ref["next_phase"]) - phase[t + 1, i])
                worst["next_phase"] = max(worst["next_phase"], min(d, 1.0 - d))
            u_opt, _, _, _ = gco.step(env.gco_chains, env.gco_opt, ref, command[t, i, 3:], state)
            worst["u_opt"] = max(worst["u_opt"], float(np.abs(priv[t, i, sl["command"]] / scale_cmd - u_opt).max()))
    check(worst["q_ref"] < 1e-4, f"leg references in the observation = NumPy generator port "
                                 f"(max |diff| {worst['q_ref']:.2e} rad < 1e-4)")
    check(worst["phase_sincos"] < 1e-5, f"phase term = sin/cos of the env's phase (max |diff| {worst['phase_sincos']:.2e})")
    check(worst["next_phase"] < 1e-5, f"phase advances by the port's update (max |diff| {worst['next_phase']:.2e})")
    check(worst["u_opt"] < 1e-3, f"observed command u' = NumPy GCO port (max |diff| {worst['u_opt']:.2e} < 1e-3)")
    moved = np.abs(np.angle(np.exp(2j * np.pi * (phase[-1] - phase[0])))).min()
    check(moved > 0.05, f"every env's phase moved over the rollout (least {moved:.2f} rad)")

    # Pushes: nothing until the timer runs out, then a horizontal base-velocity change within
    # EnvConfig.push_vel and a new interval within EnvConfig.push_interval.
    data = traj.pipeline_state
    last = jax.tree_util.tree_map(lambda a: a[-1, 0], data)
    push = jax.jit(env._push)
    quiet, timer_q = push(last, jnp.int32(5), jax.random.PRNGKey(1))
    kicks, timers = [], []
    for i in range(32):
        pushed, timer = push(last, jnp.int32(1), jax.random.PRNGKey(100 + i))
        dv = np.asarray(pushed.qvel - last.qvel, np.float64)
        check_dv = np.abs(dv[2:]).max()
        kicks.append((float(np.hypot(dv[0], dv[1])), check_dv))
        timers.append(int(timer))
    lo, hi = cfg.push_interval
    quiet_dv = float(np.abs(np.asarray(quiet.qvel - last.qvel)).max())
    check(quiet_dv == 0.0 and int(timer_q) == 4, f"no push before the timer runs out (|dqvel| {quiet_dv:.1e})")
    speeds = np.array([k[0] for k in kicks])
    check(speeds.max() <= cfg.push_vel[1] + 1e-6 and speeds.max() > 0.5 * cfg.push_vel[1] and
          max(k[1] for k in kicks) == 0.0,
          f"a due push changes only the horizontal base velocity, by {speeds.min():.3f}..{speeds.max():.3f} m/s "
          f"(push_vel {cfg.push_vel})")
    check(min(timers) >= round(lo / cfg.control_dt) and max(timers) <= round(hi / cfg.control_dt),
          f"next push in {min(timers)}..{max(timers)} control steps (push_interval {lo}..{hi} s)")
    return obs, starts, reset, step


# 1c-1e: hand forces on both teleoperated arms, 25-step segments, command slew, stops (pushes as in
# training: the first comes after push_interval, 4 s at least, beyond these episodes).
HAND_FORCE_CFG = dict(p_hand_force=1.0, p_teleop=1.0, p_teleop_arm=1.0, command_resample=25, command_slew=True,
                      p_stop=1.0, p_stop_keep_posture=1.0,
                      # 1d's envelopes: every walking goal crouched below the walking height floor
                      command_envelopes=True, height=(0.59, 0.62), p_posture_walk=1.0, p_posture_axis=1.0)
CAL_KNEE = {"kp_scale": 0.8, "delay_s": 0.004, "fc_Nm": 1.0, "offset_rad": 0.02}
CAL_KNEE_UNCERTAINTY = {"kp_scale": 0.02, "delay_s": 0.0004, "fc_Nm": 0.001}  # pmg_calib_joints-style
CAL_HIP_FILE = {"kt_scale": 0.9, "torque_limit_Nm": 60.0, "fv_Nms_per_rad": 0.3, "armature_kgm2": 0.02,
                "fs_Nm": 0.5, "vs_rad_per_s": 0.05, "kl": 0.01}


def write_calibrated_robot(workdir):
    """A calibrated robot config as pmg_calib_joints writes it: g1.yaml with an inline `actuator:` flow
    block on the left knee, an actuator-file path on the right hip pitch, and a zero_offsets map."""
    import yaml
    with open("config/robots/g1/g1.yaml") as f:
        text = f.read()

    def flow(d):
        return "{" + ", ".join(f"{k}: {v}" for k, v in d.items()) + "}"
    for name, block in (("left_knee_joint", flow(CAL_KNEE)), ("right_hip_pitch_joint", "rhp.actuator.yaml")):
        lines = text.splitlines(keepends=True)
        for i, line in enumerate(lines):
            if line.lstrip().startswith(f"- {{name: {name},"):
                extra = f", actuator_uncertainty: {flow(CAL_KNEE_UNCERTAINTY)}" if name == "left_knee_joint" else ""
                lines[i] = line.rstrip().rstrip("}") + f", actuator: {block}{extra}}}\n"
        text = "".join(lines)
    text += "zero_offsets: {left_ankle_pitch_joint: 0.03}\n"
    path = os.path.join(workdir, "g1_calibrated.yaml")
    with open(path, "w") as f:
        f.write(text)
    with open(os.path.join(workdir, "rhp.actuator.yaml"), "w") as f:
        f.write("actuator: " + flow(CAL_HIP_FILE) + "\n")
    yaml.safe_load(open(path))  # still YAML
    return path


def actuator_port_jax_checks(check):
    """JAX float32 port (jit + scan) = float64 NumPy port on random sequences with every effect on."""
    import jax
    import jax.numpy as jnp
    import numpy as np
    from pmg_train import actuator as act
    rng = np.random.default_rng(7)
    n, T, dt = 16, 300, 0.005
    # Driver rates 0 / 500 Hz (a PD every 5 ms step, as in the env): at rates whose period is not a
    # multiple of dt the zero-order hold's firing test (timer >= period - 1e-9 s) sits within float32
    # rounding of the threshold, so float32 and float64 fire on different steps (the C++ model's
    # own threshold; test_actuator_port.py --jax32 measures it on the C++ vectors).
    vals = {"rate_hz": rng.choice([0.0, 500.0], n), "delay_s": rng.uniform(0, 0.03, n),
            "offset_rad": rng.uniform(-0.05, 0.05, n), "kt_scale": rng.uniform(0.7, 1.3, n),
            "torque_limit_Nm": rng.uniform(5, 50, n), "tau_stall_Nm": rng.uniform(10, 60, n) * (rng.random(n) < 0.5),
            "w_max_rad_per_s": rng.uniform(5, 20, n), "fc_Nm": rng.uniform(0, 1.5, n), "fs_Nm": rng.uniform(0, 2, n),
            "vs_rad_per_s": rng.uniform(0.02, 0.3, n), "kl": rng.uniform(0, 0.2, n),
            "fv_Nms_per_rad": rng.uniform(0, 0.4, n)}
    cmd = np.stack([np.cumsum(rng.normal(0, 0.02, (T, n)), 0), rng.normal(0, 1, (T, n)),
                    np.repeat(rng.uniform(20, 200, (1, n)), T, 0), np.repeat(rng.uniform(0.5, 5, (1, n)), T, 0),
                    rng.normal(0, 2, (T, n)), (rng.random((T, n)) > 0.03).astype(float)], -1)
    dq = np.where(rng.random((T, n)) < 0.3, 0.0, rng.normal(0, 2, (T, n)))
    joint = np.stack([np.cumsum(rng.normal(0, 0.01, (T, n)), 0), dq, np.full((T, n), 0.05),
                      rng.normal(0, 3, (T, n))], -1)

    def inputs(t, xp, c, j):
        cm = {k: c[t][:, i] for i, k in enumerate(act.COMMAND_KEYS)}
        cm["enabled"] = c[t][:, 5] != 0
        return cm, {"q_rad": j[t][:, 0], "dq_rad_per_s": j[t][:, 1], "inertia_kgm2": j[t][:, 2],
                    "tau_other_Nm": j[t][:, 3], "dt_s": dt}
    p64 = act.make_params(n, **vals)
    s = act.init_state(n, 16)
    ref = []
    for t in range(T):
        s, o = act.step(p64, s, *inputs(t, np, cmd, joint))
        ref.append(o["tau_applied_Nm"])
    ref = np.array(ref)
    p32 = act.make_params(n, xp=jnp, **vals)

    @jax.jit
    def run(c, j):
        def body(s, x):
            cm = {k: x[0][:, i] for i, k in enumerate(act.COMMAND_KEYS)}
            cm["enabled"] = x[0][:, 5] != 0
            jj = {"q_rad": x[1][:, 0], "dq_rad_per_s": x[1][:, 1], "inertia_kgm2": x[1][:, 2],
                  "tau_other_Nm": x[1][:, 3], "dt_s": jnp.float32(dt)}
            s, o = act.step(p32, s, cm, jj, xp=jnp)
            return s, o["tau_applied_Nm"]
        return jax.lax.scan(body, act.init_state(n, 16, xp=jnp), (c, j))[1]
    ours = np.asarray(run(jnp.asarray(cmd, jnp.float32), jnp.asarray(joint, jnp.float32)), np.float64)
    err = np.abs(ours - ref)
    ok = err <= 1e-3 * (1.0 + np.abs(ref))
    check(ok.mean() >= 0.995, f"JAX float32 actuator port (jit, scan) = NumPy float64 port: {ok.mean() * 100:.2f} % of "
                              f"{err.size} steps within 1e-3 (1 + |tau|), median {np.median(err):.1e} N m "
                              f"(stiction / driver-rate branch flips at thresholds allowed in 0.5 %)")


def actuator_env_checks(check, env, cal_path, states):
    """Calibrated robot and physically informed gains (docstring 1b) in @p env (make_smoke_env), whose
    reset states part 1 returned as @p states."""
    import jax
    import jax.numpy as jnp
    import numpy as np
    import yaml
    from pmg_train import actuator as act
    from pmg_train import g1_env
    from pmg_train import gains

    clips = sorted(glob.glob("config/clips/g1/*.yaml"))
    cfg = env.cfg
    knee, hip = 3, 6
    c = env.act_center
    check(list(env.act_idx) == [knee, hip] and np.allclose(c["kp_scale"], [0.8, 1.0]) and
          np.allclose(c["delay_s"], [0.004, 0.0]) and np.allclose(c["fc_Nm"], [1.0, 0.0]) and
          np.allclose(c["kt_scale"], [1.0, 0.9]) and np.allclose(c["torque_limit_Nm"], [139.0, 60.0]) and
          list(env.act_has_armature) == [False, True],
          f"calibrated robot config read: blocks on {[env.joint_names[i] for i in env.act_idx]} (inline and "
          f"file), torque limit = min(block, joint)")

    draws = [{k: np.asarray(v, np.float64) for k, v in st.info["act"].items()} for st in states]
    dr = cfg.actuator_dr
    # Widths from the knee's actuator_uncertainty: z u / |value| (kp_scale 2 x 0.02 / 0.8 = 0.05, delay
    # 2 x 0.0004 / 0.004 = 0.2, fc 2 x 0.001 / 1.0 -> the 0.02 floor); the hip's keys get actuator_dr.
    want_w = {"kp_scale": 0.05, "delay_s": 0.2, "fc_Nm": cfg.actuator_dr_min}
    widths_ok = all(abs(env.act_dr[k][0] - w) < 1e-9 for k, w in want_w.items()) and \
        abs(env.act_dr["kd_scale"][0] - dr) < 1e-9 and abs(env.act_dr["kp_scale"][1] - dr) < 1e-9 and \
        env.act_dr["armature_kgm2"][0] == 0.0
    check(widths_ok, f"DR widths sized from the calibration's uncertainty: knee kp_scale "
                     f"{env.act_dr['kp_scale'][0]:.3f} (want 0.05), delay {env.act_dr['delay_s'][0]:.3f} (0.2), "
                     f"fc {env.act_dr['fc_Nm'][0]:.3f} (floor {cfg.actuator_dr_min}); no uncertainty: {dr}")
    within = all(np.all(np.abs(d[k] - c[k]) <= env.act_dr[k] * np.abs(c[k]) + 1e-6)
                 for d in draws for k in g1_env.ACT_DR_KEYS)
    moved = any(abs(d["kp_scale"][0] - 0.8) > 1e-4 and abs(d["delay_s"][0] - 0.004) > 1e-7 for d in draws)
    off = all(d["kt_scale"][0] == 1.0 and d["delay_s"][1] == 0.0 and d["fc_Nm"][1] == 0.0 for d in draws)
    kps = ", ".join("%.3f" % d["kp_scale"][0] for d in draws)
    delays = ", ".join("%.2f" % (d["delay_s"][0] * 1e3) for d in draws)
    check(within and moved and off,
          f"identified parameters drawn within their widths of the file's values (knee kp_scale {kps}, delay {delays} "
          f"ms); unnamed effects stay off")

    # One physics substep per env.step, the identified values: the motor torques equal the port's.
    probe = g1_env.G1PmgEnv(g1_env.EnvConfig(actuators=cal_path, deterministic_reset=True, push_vel=(0.0, 0.0)), clips)
    probe.n_substeps = 1
    step1 = jax.jit(probe.step)
    st = states[0]
    centre = {k: jnp.asarray(v, jnp.float32) for k, v in c.items()}
    info = dict(st.info, act=centre, delay=jnp.float32(0.0), push_timer=jnp.int32(10 ** 6))
    st = st.replace(info=info)
    p = act.make_params(2, **{k: c[k] for k in act.PARAM_KEYS if k in c})  # offset_rad: not applied (0)
    ps = act.init_state(2, probe.act_rows)
    kp_e = probe.kp[[knee, hip]].astype(np.float64) * c["kp_scale"]
    kd_e = probe.kd[[knee, hip]].astype(np.float64) * c["kd_scale"]
    worst, nominal_gap, fric_worst, damp_worst = 0.0, 0.0, 0.0, 0.0
    t0 = time.time()
    for k in range(8):
        a = np.zeros(12, np.float32)
        a[knee], a[hip] = (0.6, -0.4) if k < 4 else (-0.5, 0.3)
        q = np.asarray(st.pipeline_state.qpos[7:], np.float64)
        dq = np.asarray(st.pipeline_state.qvel[6:], np.float64)
        q_des = probe.q_default[:12].astype(np.float64) + probe.action_scale.astype(np.float64) * a
        q_des = np.clip(q_des, probe.q_lower[:12], probe.q_upper[:12])  # EnvConfig.clamp_targets (k >= 4: the knee's)
        ps, o = act.step(p, ps, {"q_des_rad": q_des[[knee, hip]], "dq_des_rad_per_s": np.zeros(2),
                                 "kp_Nm_per_rad": kp_e, "kd_Nms_per_rad": kd_e, "tau_ff_Nm": np.zeros(2),
                                 "enabled": np.ones(2, bool)},
                         {"q_rad": q[[knee, hip]], "dq_rad_per_s": dq[[knee, hip]], "inertia_kgm2": np.zeros(2),
                          "tau_other_Nm": np.zeros(2), "dt_s": cfg.sim_dt})
        st = step1(st, jnp.asarray(a))
        ctrl = np.asarray(st.pipeline_state.ctrl, np.float64)[[knee, hip]]
        worst = max(worst, float(np.max(np.abs(ctrl - o["tau_motor_Nm"]) / (1.0 + np.abs(o["tau_motor_Nm"])))))
        nominal = np.clip(probe.kp[[knee, hip]] * (q_des[[knee, hip]] - q[[knee, hip]]), -probe.tau_max[[knee, hip]],
                          probe.tau_max[[knee, hip]])
        nominal_gap = max(nominal_gap, float(abs(nominal[0] - ctrl[0])))
        applied = np.asarray(st.pipeline_state.qfrc_applied, np.float64)[6 + np.array([knee, hip])]
        damp_worst = max(damp_worst, float(np.max(np.abs(applied - c["kt_scale"] * kd_e * dq[[knee, hip]]))))
        efc = np.asarray(st.pipeline_state._impl.efc_frictionloss, np.float64)
        ne = int(st.pipeline_state._impl.ne)
        fl = efc[ne + np.array([knee, hip])]  # friction rows follow the equality rows, in dof order
        fric = np.maximum(act.kinetic_friction(p, dq[[knee, hip]], o["tau_motor_Nm"]), g1_env.FRICTIONLOSS_FLOOR)
        fric_worst = max(fric_worst, float(np.max(np.abs(fl - fric))))
    print(f"identified-model probe: 8 substeps {time.time() - t0:.1f} s (compile included)", flush=True)
    check(worst < 1e-3 and nominal_gap > 1.0,
          f"with the identified values the knee and hip motor torques (ctrl) equal the NumPy port's (kp x 0.8, "
          f"4 ms delay over 5 ms substeps; kt 0.9, 60 N m limit): max rel. diff {worst:.1e} < 1e-3; the knee's "
          f"differs from the nominal PD by up to {nominal_gap:.1f} N m")
    sys_c = probe.actuator_sys(probe.sys, centre)
    v = 6 + np.array([knee, hip])
    want_damp = 0.05 + c["kt_scale"] * kd_e + c["fv_Nms_per_rad"]
    check(damp_worst < 1e-3 and np.allclose(np.asarray(sys_c.dof_damping)[v], want_damp, rtol=1e-5) and
          abs(float(sys_c.dof_armature[v[1]]) - 0.02) < 1e-7 and abs(float(sys_c.dof_armature[v[0]]) - 0.01) < 1e-7
          and fric_worst < 1e-4,
          f"implicit D term 0.05 + kt kd + fv = {np.round(want_damp, 3).tolist()} N m s/rad with its explicit part "
          f"in qfrc_applied (max diff {damp_worst:.1e}); armature 0.02 where identified; friction rows = the "
          f"port's kinetic friction (knee {fl[0]:.3f} N m; max diff {fric_worst:.1e})")
    sl, _ = term_slices(g1_env.OBS_TERMS)
    q_meas = float(st.obs["privileged_state"][sl["joint_pos_rel"]][knee])  # noise-free, scale 1
    check(abs(q_meas - float(st.pipeline_state.qpos[7 + knee] - probe.q_default[knee])) < 1e-5,
          "encoder offsets of the file (offset_rad, zero_offsets) are not applied: the observed knee angle is the "
          "true one")

    # Physically informed gains.
    pig = g1_env.G1PmgEnv(g1_env.EnvConfig(gains="physically_informed"), clips)
    with open("config/robots/g1/g1_pig.yaml") as f:
        pig_yaml = yaml.safe_load(f)["joints"]
    kp, kd, inertia = gains.pig_gains(pig.joint_names)
    arm = np.asarray(pig.mj_model.dof_armature[6:])
    check(np.allclose(pig.kp, [j["kp"] for j in pig_yaml]) and np.allclose(pig.kd, [j["kd"] for j in pig_yaml]) and
          np.allclose(arm, inertia) and np.allclose(pig.kp, np.asarray(inertia) * (20 * math.pi) ** 2, rtol=1e-4) and
          np.allclose(pig.kd, 4.0 * np.asarray(inertia) * 20 * math.pi, rtol=1e-3),
          f"physically informed gains: kp = I w_n^2, kd = 2 zeta I w_n (w_n 2 pi 10 Hz, zeta 2) = g1_pig.yaml, "
          f"armature = I (knee kp {pig.kp[knee]:.2f}, kd {pig.kd[knee]:.3f}, I {arm[knee]:.5f})")
    sys_r, _ = g1_env.make_randomization_fn(pig)(pig.sys, jax.random.split(jax.random.PRNGKey(0), 8))
    ratio = np.asarray(sys_r.dof_armature)[:, 6:] / np.asarray(inertia)[None]
    check(ratio.min() >= 0.8 - 1e-6 and ratio.max() <= 1.5 + 1e-6,
          f"PIG armature DR = I x U(0.8, 1.5) (ratios {ratio.min():.3f}..{ratio.max():.3f})")
    pig_tm = g1_env.G1PmgEnv(g1_env.EnvConfig(gains="physically_informed", action_scale_rule="torque_matched"), clips)
    nominal_kp = np.array([j["kp"] for j in yaml.safe_load(open("config/robots/g1/g1.yaml"))["joints"]][:12])
    authority_tm, authority_nom = pig_tm.action_scale * pig_tm.kp[:12], pig.action_scale * nominal_kp
    check(np.allclose(authority_tm, authority_nom, rtol=1e-5) and pig_tm.action_scale[0] > 3 * pig.action_scale[0],
          f"torque-matched action scale: kp x scale = the nominal's per leg joint (hip pitch "
          f"{authority_tm[0]:.1f} vs {authority_nom[0]:.1f} N m/unit action; motion rule {pig.action_scale[0] * pig.kp[0]:.1f})")
    check(np.allclose(env.kp, pig.kp) and np.allclose(env.kd, pig.kd) and
          np.isclose(float(env.mj_model.dof_armature[6 + knee]), inertia[knee]),
          "the rolled-out env has the physically informed gains (kp, kd, armature) where nothing is identified")


def hand_force_checks(check, env, reset, step, n_steps=50):
    """External hand forces (docstring 1c) in @p env (HAND_FORCE_CFG); @p reset, @p step: its jitted
    reset and step (compiled once, in part 1)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    c = env.cfg
    hands = env.hand_bodies
    others = [b for b in range(env.mj_model.nbody) if b not in hands]
    st = reset(jax.random.PRNGKey(3))
    # The twin: the same episode (same env, compiled once, same random stream) with its hand-force
    # target and applied force zeroed before every step, so it never gets a force.
    zero = jnp.zeros((2, 3))

    def unforced(s):
        return s.replace(info=dict(s.info, hf_tgt=zero, hf=zero))

    st0 = st
    prev = np.zeros((2, 3))
    applied_ok, slew, bounds_ok, largest, targets, twin_free = True, 0.0, True, 0.0, set(), True
    # Command slew (docstring 1d): each step the command moves towards the drawn goal by at most the
    # per-axis rate x dt, exactly cmd + clip(goal - cmd, +-rate dt).
    rate = np.array([*c.command_max_accel, c.command_posture_rate, c.command_posture_rate, c.command_height_rate]) * c.control_dt
    cmd_err, cmd_moved, goals = 0.0, 0.0, set()
    from pmg_train.g1_env import shape_with_envelopes
    since, enveloped = float(st.info["since_walk"]), 0  # the port's own clock; steps the envelopes changed
    stops, stop_ok = 0, True  # Stops (docstring 1e): resamples after a walking goal, and whether each stood
    for _ in range(n_steps):
        tgt = np.asarray(st.info["hf_tgt"], np.float64)
        cmd_before = np.asarray(st.info["command"], np.float64)
        goal_before = np.asarray(st.info["command_goal"], np.float64)
        st, st0 = step(st, jnp.zeros(env.action_size)), step(unforced(st0), jnp.zeros(env.action_size))
        goal, cmd = np.asarray(st.info["command_goal"], np.float64), np.asarray(st.info["command"], np.float64)
        shaped, since = shape_with_envelopes(np, cmd_before, goal, since, env.envelope_limits)
        cmd_err = max(cmd_err, float(np.abs(cmd - shaped).max()))
        enveloped += bool(np.abs(cmd - (cmd_before + np.clip(goal - cmd_before, -rate, rate))).max() > 1e-4)
        cmd_moved = max(cmd_moved, float(np.abs(cmd - cmd_before).max()))
        goals.add(tuple(np.round(goal, 4)))
        if int(st.info["step"]) % c.command_resample == 0 and np.any(goal_before[:3] != 0.0):
            stops += 1
            stop_ok &= bool(np.all(goal[:3] == 0.0) and np.all(goal[3:] == goal_before[3:]))
        twin_free &= bool(np.all(np.asarray(st0.pipeline_state.xfrc_applied) == 0.0))
        hf = np.asarray(st.info["hf"], np.float64)
        xf = np.asarray(st.pipeline_state.xfrc_applied, np.float64)
        applied_ok &= bool(np.allclose(xf[hands, :3], hf, atol=1e-4) and np.all(xf[hands, 3:] == 0.0) and
                           np.all(xf[others] == 0.0))
        slew = max(slew, float(np.abs(hf - prev).max()))
        bounds_ok &= bool(np.all(np.hypot(tgt[:, 0], tgt[:, 1]) <= c.hand_force_xy + 1e-4) and
                          np.all(tgt[:, 2] >= c.hand_force_z[0] - 1e-4) and np.all(tgt[:, 2] <= c.hand_force_z[1] + 1e-4))
        targets.add(tuple(np.round(tgt.ravel(), 3)))
        largest = max(largest, float(np.abs(hf).max()))
        prev = hf
    q, q0 = np.asarray(st.pipeline_state.qpos), np.asarray(st0.pipeline_state.qpos)
    check(cmd_err < 1e-5 and cmd_moved > 0.5 * rate.min() and len(goals) >= 2 and enveloped >= 1,
          f"command slew with the controller's envelopes: command = shape_with_envelopes(command, goal) every step "
          f"(max |diff| {cmd_err:.1e}), largest step {cmd_moved:.4f} <= rate dt {np.round(rate, 4).tolist()}, "
          f"{len(goals)} goals drawn, the floor or an envelope changed {enveloped} of the steps")
    check(stops >= 1 and stop_ok,
          f"stops (p_stop = 1, p_stop_keep_posture = 1): {stops} resample(s) after a walking goal, each new goal's "
          f"velocity zero and its posture the walking goal's: {stop_ok}")
    check(applied_ok and largest > 1.0,
          f"hand forces: xfrc_applied on the two wrist_yaw_link bodies = the env's applied force (largest "
          f"{largest:.1f} N after {n_steps} steps), zero torque, zero on every other body")
    check(slew <= c.hand_force_rate * c.control_dt + 1e-4 and bounds_ok and len(targets) >= 2,
          f"hand forces continuous (largest step {slew:.2f} N <= {c.hand_force_rate * c.control_dt:.2f}), targets "
          f"within |F_xy| <= {c.hand_force_xy} N and F_z in {c.hand_force_z}, redrawn with the segment "
          f"({len(targets)} targets)")
    check(twin_free and float(np.abs(q - q0).max()) > 1e-3 and np.isfinite(q).all(),
          f"hand forces act: the same episode without them (no force applied: {twin_free}) differs by "
          f"{float(np.abs(q - q0).max()):.4f} in qpos")


def ppo_checks(check, workdir, obs):
    import jax
    import numpy as np
    import onnx

    import export_onnx
    import train_pmg
    from pmg_train.contract import actor_forward

    out = os.path.join(workdir, "ppo")
    n_dev = len(jax.local_devices())
    # Two training steps (batch 8 x 2 minibatches x unroll 5 = 80 env steps each), in one ppo.train. The
    # reward-width warm-up (--warmup-steps) would compile the whole training step a second time (160 s on
    # this 2-core machine); its staging is checked without compiling (warmup_staging_checks).
    timesteps = 160
    argv = ["--out", out, "--num-envs", "8", "--batch-size", "8", "--num-minibatches", "2", "--unroll-length", "5",
            "--timesteps", str(timesteps), "--num-evals", "2", "--num-eval-envs", "0", "--episode-length", "20",
            "--hidden", "32,32", "--seed", "1", "--mirror-loss", "0.5", "--tracking-sigma", "0.05",
            "--p-reset-reference", "0.5", "--keep-actors"]
    if os.path.exists(os.path.join(out, "actors")):
        shutil.rmtree(os.path.join(out, "actors"))
    if os.path.exists(os.path.join(out, "progress.jsonl")):
        os.remove(os.path.join(out, "progress.jsonl"))
    t0 = time.time()
    cwd = os.getcwd()
    try:
        train_pmg.main(argv)
    finally:
        os.chdir(cwd)
    print(f"tiny PPO run through train_pmg.main: {time.time() - t0:.1f} s (compile included)", flush=True)
    with open(os.path.join(out, "train_config.json")) as f:
        tc = json.load(f)
    check(len(tc["devices"]) == n_dev == 2, f"PPO trained on all {n_dev} local devices ({tc['devices']})")
    with open(os.path.join(out, "progress.jsonl")) as f:
        recs = [json.loads(line) for line in f if line.strip()]
    last = recs[-1] if recs else {}
    check(last.get("step", 0) >= timesteps and all(math.isfinite(v) for v in last.values() if not isinstance(v, str)),
          f"progress.jsonl reached step {last.get('step')} >= {timesteps} with finite metrics "
          f"(policy loss {last.get('training/policy_loss')}, value loss {last.get('training/v_loss')})")
    check(last.get("training/mirror_loss", 0.0) > 0 and tc.get("mirror_loss") == 0.5,
          f"the mirror-symmetry loss ran inside Brax's PPO (--mirror-loss 0.5): training/mirror_loss "
          f"{last.get('training/mirror_loss')}")
    stages = [(r.get("stage"), r.get("step")) for r in recs]
    check(all(st == "main" for st, _ in stages) and tc.get("warmup") is None and
          tc["env"]["lin_vel_sigma"] == 0.05 and tc["env"]["p_reset_reference"] == 0.5,
          f"without --warmup-steps one stage with the run's widths (stage, step): {stages}; "
          f"train_config warmup {tc.get('warmup')}, env lin_vel_sigma {tc['env']['lin_vel_sigma']}, "
          f"p_reset_reference {tc['env']['p_reset_reference']}")
    check(os.path.getsize(os.path.join(out, "params.pkl")) > 0, "checkpoint params.pkl written")
    # --keep-actors: one actor per checkpoint (steps 0 and the last), named by step; the last is the final actor.
    kept = sorted(os.listdir(os.path.join(out, "actors"))) if os.path.isdir(os.path.join(out, "actors")) else []
    steps = [int(k[len("actor_"):-len(".npz")]) for k in kept]
    first, final = (np.load(os.path.join(out, "actors", k)) for k in (kept[0], kept[-1])) if len(kept) >= 2 else (None, None)
    z_final = np.load(os.path.join(out, "actor.npz"))
    check(len(kept) == 2 and steps[0] == 0 and steps[-1] >= timesteps and
          np.array_equal(final["w0"], z_final["w0"]) and not np.array_equal(first["w0"], final["w0"]),
          f"--keep-actors: actors/{kept} (the untrained actor at step 0 and the last checkpoint's, which is actor.npz)")
    mean, std, layers, action_scale, clips, mode = export_onnx.load_actor(os.path.join(out, "actor.npz"))
    check([w.shape for w, _ in layers] == [(62, 32), (32, 32), (32, 24)] and mode == "pmg_gco" and len(clips) > 0,
          f"actor.npz: 62-32-32-24 MLP, mode {mode}, {len(clips)} clips")
    model = onnx.load(os.path.join(out, "g1_pmg_policy.onnx"))
    onnx.checker.check_model(model)
    meta = {p.key: p.value for p in model.metadata_props}
    brax_diff = json.loads(meta.get("pmg.training", "{}")).get("brax_vs_numpy_max_abs")
    check("pmg.contract" in meta and brax_diff is not None and brax_diff < 1e-4,
          f"ONNX export: checker passes, pmg.contract present, exported actor = Brax inference "
          f"(max |diff| {brax_diff})")
    import glob
    import yaml
    from pmg_train.contract import clips_digest
    digest = (yaml.safe_load(meta.get("pmg.contract", "{}")) or {}).get("pmg", {}).get("clips_digest")
    want = clips_digest(sorted(glob.glob(os.path.join(REPO, "config", "clips", "g1", "*.yaml"))))
    check(digest == want, f"the contract names the clips trained on: pmg.clips_digest {digest} (config/clips/g1: {want})")
    if obs is None:  # PPO part alone: observations around the normaliser's statistics
        obs = mean + std * np.random.default_rng(0).standard_normal((4,) + mean.shape)
        where = "observations drawn from the normaliser's statistics"
    else:
        obs, where = obs[-1], "the rollout's last observations"
    act = actor_forward(mean, std, layers, 12, obs.astype(np.float32))
    check(np.isfinite(act).all() and np.abs(act).max() <= 1.0,
          f"exported actor on {where}: finite, within [-1, 1] (max |a| {np.abs(act).max():.3f})")
    # An actor trained with residual actions (action_offset "reference") is not exported: the
    # contract's offset is the standing pose, and the controller would apply its actions to that.
    z = dict(np.load(os.path.join(out, "actor.npz")))
    z["action_offset"] = np.array("reference")
    np.savez(os.path.join(out, "actor_residual.npz"), **z)
    try:
        export_onnx.export(os.path.join(out, "actor_residual.npz"), os.path.join(out, "residual.onnx"))
        msg = ""
    except SystemExit as e:
        msg = str(e)
    check("action_offset" in msg and not os.path.exists(os.path.join(out, "residual.onnx")),
          f"a residual actor is refused by the export, naming action_offset ({msg[:60]}...)")


class _MainStageReached(Exception):
    pass


def run_stages(out):
    """A run folder's (stage, step) per progress.jsonl record, and its train_config.json."""
    with open(os.path.join(out, "progress.jsonl")) as f:
        stages = [(r["stage"], r["step"]) for r in map(json.loads, f)]
    with open(os.path.join(out, "train_config.json")) as f:
        return stages, json.load(f)


def main_with_recorded_train(argv, recorder):
    """train_pmg.main(@p argv) with Brax's ppo.train replaced by @p recorder, which raises _MainStageReached where the
    check has seen enough (nothing compiles). True iff it was raised; Brax's ppo.train and the cwd are restored."""
    import train_pmg
    from brax.training.agents.ppo import train as ppo
    train, cwd = ppo.train, os.getcwd()
    ppo.train = recorder
    try:
        train_pmg.main(argv)
    except _MainStageReached:
        return True
    finally:
        ppo.train = train
        os.chdir(cwd)
    return False


def warmup_staging_checks(check, workdir):
    """2. The reward-width warm-up's staging in train_pmg.main (--warmup-steps), with Brax's ppo.train
    replaced by a recorder, so nothing compiles: the first call trains the warm-up environment (the
    warm-up widths, every other field the run's) for --warmup-steps without evaluations; the second
    trains the run's environment for the remaining steps from the first call's parameters with the
    next seed; progress.jsonl marks the stages and numbers the second's steps from the warm-up's end;
    Brax's Evaluator and PPO loss are Brax's own again afterwards."""
    from brax.training.agents.ppo import train as ppo

    out = os.path.join(workdir, "staging")
    calls = []
    warmup_params = {"warm-up": "params"}

    def recorder(environment, **kw):
        calls.append({"cfg": environment.cfg, "evaluator": ppo.acting.Evaluator, **kw})
        kw["progress_fn"](kw["num_timesteps"], {"training/policy_loss": 0.5})
        if len(calls) == 1:
            return None, warmup_params, {}
        raise _MainStageReached()

    argv = ["--out", out, "--num-envs", "8", "--batch-size", "8", "--num-minibatches", "2", "--unroll-length", "5",
            "--timesteps", "1000", "--num-evals", "2", "--num-eval-envs", "4", "--episode-length", "20",
            "--hidden", "32,32", "--seed", "7", "--mirror-loss", "0.5", "--tracking-sigma", "0.05",
            "--warmup-steps", "400", "--warmup-tracking-sigma", "0.3", "--warmup-height-sigma", "0.03",
            "--p-posture-walk", "0.6", "--warmup-p-posture-walk", "0.0", "--warmup-evals", "3",
            "--action-noise-scale", "0.5"]
    evaluator, loss = ppo.acting.Evaluator, ppo.ppo_losses.compute_ppo_loss
    if os.path.exists(os.path.join(out, "progress.jsonl")):
        os.remove(os.path.join(out, "progress.jsonl"))
    reached = main_with_recorded_train(argv, recorder)
    check(reached and len(calls) == 2, f"--warmup-steps: train_pmg.main calls ppo.train twice ({len(calls)} calls)")
    if len(calls) != 2:
        return
    w, m = calls
    same = [k for k in ("clips", "friction", "p_reset_reference", "noise", "push_vel")
            if getattr(w["cfg"], k) == getattr(m["cfg"], k)]
    check(w["num_timesteps"] == 400 and not w["run_evals"] and w["num_evals"] == 3 and w["restore_params"] is None and
          (w["cfg"].lin_vel_sigma, w["cfg"].yaw_rate_sigma, w["cfg"].height_sigma) == (0.3, 0.3, 0.03) and
          w["cfg"].p_posture_walk == 0.0 and len(same) == 5 and w["evaluator"] is not evaluator,
          f"warm-up stage: {w['num_timesteps']} steps, {w['num_evals']} checkpoints (--warmup-evals 3) and no "
          f"evaluations (a stand-in Evaluator), widths "
          f"{(w['cfg'].lin_vel_sigma, w['cfg'].yaw_rate_sigma, w['cfg'].height_sigma)}, p_posture_walk "
          f"{w['cfg'].p_posture_walk} (--warmup-p-posture-walk 0), the run's {same}")
    check(m["num_timesteps"] == 600 and m["restore_params"] is warmup_params and m["seed"] == 8 and m["run_evals"] and
          (m["cfg"].lin_vel_sigma, m["cfg"].yaw_rate_sigma) == (0.05, 0.05) and m["cfg"].p_posture_walk == 0.6 and
          m["evaluator"] is evaluator,
          f"main stage: the remaining {m['num_timesteps']} steps from the warm-up's parameters, seed {m['seed']} "
          f"(the run's 7 + 1), widths {(m['cfg'].lin_vel_sigma, m['cfg'].yaw_rate_sigma)}, p_posture_walk "
          f"{m['cfg'].p_posture_walk} (the run's 0.6), Brax's Evaluator")
    # --action-noise-scale 0.5: both stages' networks draw with half the std; the policy network is Brax's own.
    import jax.numpy as jnp
    import numpy as np
    nets = [c["network_factory"](62, 12) for c in calls]
    zero_std = [float(np.asarray(n.parametric_action_distribution.create_dist(jnp.zeros(24)).scale).mean()) for n in nets]
    want_std = 0.5 * (math.log(2.0) + 0.001)
    check(all(abs(v - want_std) < 1e-6 for v in zero_std) and
          nets[0].policy_network.init is not None and nets[0].parametric_action_distribution.param_size == 24,
          f"--action-noise-scale 0.5: at a zero scale logit both stages' policies draw with std {zero_std} "
          f"(Brax's own: {2 * want_std:.4f}), 12 actions from 24 outputs")
    stages, tc = run_stages(out)
    check(stages == [("warmup", 400), ("main", 1000)] and
          tc["warmup"] == {"steps": 400, "lin_vel_sigma": 0.3, "yaw_rate_sigma": 0.3, "height_sigma": 0.03,
                           "orientation_sigma": 0.05, "p_posture_walk": 0.0, "evals": 3} and
          tc["env"]["lin_vel_sigma"] == 0.05 and tc["env"]["p_posture_walk"] == 0.6 and ppo.acting.Evaluator is evaluator and
          ppo.ppo_losses.compute_ppo_loss is loss and tc["action_noise_scale"] == 0.5,
          f"progress.jsonl (stage, step) {stages}; train_config warmup {tc['warmup']}; Brax's Evaluator and "
          f"PPO loss restored")


def run_eval_mjx(args):
    """eval_mjx.py with @p args, in an interpreter of its own (this one's environment: the XLA flags, the allocator
    and JAX's persistent cache). Runs that differ only in an input of the compiled programs (--hold-reference,
    --stochastic) then compile to the same programs, and the cache serves the first run's compiles: one process
    traces each later eval_mjx.main into a module with its own private function names (JAX numbers them per
    process), which the cache keys on, so in-process every run compiled its reset and rollout anew (about 45 s of
    compile in this part, docs/ci_timing.md "Stop 122"). A failing run fails the part."""
    import subprocess
    subprocess.run([sys.executable, os.path.join(TRAINING, "eval_mjx.py")] + list(args), check=True)


def mjx_eval_checks(check, workdir, run_dir, tc):
    """2b. eval_mjx.py on the tiny run's actor: the environment is the run's own (its train_config.json
    beside the actor) made nominal, the schedule's command is the one the environment runs and reports
    per segment, --start-reference starts in the reference pose, --hold-reference holds it. (It once set only the environment's command u, which each step replaced by the
    environment's own drawn goal, so every rollout commanded standing.)"""
    import numpy as np
    import yaml

    import eval_mjx

    sched = os.path.join(workdir, "mjx_schedule.yaml")
    segs = [{"name": "walk", "t": 0.0, "vx": 0.4, "vy": -0.1, "wz": 0.3, "pitch": 0.1, "roll": 0.0, "height": 0.7},
            {"name": "back", "t": 0.2, "vx": -0.2, "vy": 0.0, "wz": 0.0, "pitch": 0.0, "roll": 0.05, "height": 0.75}]
    with open(sched, "w") as f:
        yaml.safe_dump({"ramp": 0.0, "duration": 0.4, "segments": segs}, f)
    out = os.path.join(workdir, "mjx_eval.npz")
    run_eval_mjx([os.path.join(run_dir, "actor.npz"), "--out", out, "--commands", sched, "--start-reference"])
    z = np.load(out)
    want = np.array([[s[k] for k in eval_mjx.KEYS] for s in segs])
    check(z["command"].shape[0] == 40 and np.allclose(z["command_env"], z["command"], atol=1e-6) and
          np.allclose(z["command_env"][0], want[0], atol=1e-6) and np.allclose(z["command_env"][-1], want[1], atol=1e-6),
          f"eval_mjx: the environment runs the schedule's command ({z['command'].shape[0]} ticks; first "
          f"{np.round(z['command_env'][0], 3)}, last {np.round(z['command_env'][-1], 3)})")
    check(list(z["segment_names"]) == ["walk", "back"] and np.allclose(z["segment_command"], want, atol=1e-6) and
          z["segment_achieved"].shape == (2, 6),
          f"eval_mjx: per-segment commanded means {np.round(z['segment_command'], 3).tolist()}")
    # The gait columns (flight, double support) equal the recorded contacts over each segment's window.
    contact = z["measured"][:, 4:6] > 0.5
    t = z["t"]
    want_gait = []
    for t0, t1 in ((0.0, 0.2), (0.2, 0.4)):
        w = (t >= t0 + 0.4 * (t1 - t0)) & (t < t1)
        want_gait.append([np.mean(~contact[w].any(axis=1)), np.mean(contact[w].all(axis=1))])
    check(z["segment_gait"].shape == (2, 4) and np.allclose(z["segment_gait"][:, :2], want_gait),
          f"eval_mjx: per-segment flight and double support {np.round(z['segment_gait'][:, :2], 3).tolist()} = "
          f"the recorded contacts' {np.round(want_gait, 3).tolist()}")
    env = json.loads(str(z["env_config"]))
    check(env["lin_vel_sigma"] == tc["env"]["lin_vel_sigma"] == 0.05 and env["clips"] == tc["env"]["clips"] and
          env["deterministic_reset"] and env["p_delay"] == 0.0 and not any(env["noise"].values()),
          f"eval_mjx: the run's environment (lin_vel_sigma {env['lin_vel_sigma']}, clips {env['clips']}) made "
          f"nominal (deterministic reset, no delay, noise {env['noise']})")
    hold_out = os.path.join(workdir, "mjx_hold.npz")
    run_eval_mjx([os.path.join(run_dir, "actor.npz"), "--out", hold_out, "--commands", sched, "--start-reference",
                 "--hold-reference"])  # the actor's rollout's program, the flag an input (JAX's cache serves it)
    h = np.load(hold_out)
    dev_hold, dev_actor = np.abs(h["q"][:10] - h["q_ref"][:10]).mean(), np.abs(z["q"][:10] - z["q_ref"][:10]).mean()
    check(np.isfinite(h["reward"]).all() and np.isfinite(z["reward"]).all() and dev_hold < 0.1 and
          dev_hold < 0.5 * dev_actor and len(h["segment_reward"]) == 2,
          f"eval_mjx --hold-reference: the legs follow the reference (mean |q - q_ref| {dev_hold:.3f} rad over the "
          f"first 0.1 s, the untrained actor {dev_actor:.3f}); rewards finite and reported for both segments")
    # --stochastic: the actions PPO explored with. policy_action draws as Brax's NormalTanhDistribution does (the
    # same key, the same action), and the rollout with the flag (an input of the same program) leaves the mean's.
    import jax
    from brax.training.distribution import NormalTanhDistribution
    h = jax.random.normal(jax.random.PRNGKey(3), (5, 24)) * 2.0
    key = jax.random.PRNGKey(4)
    dist = NormalTanhDistribution(event_size=12)
    brax_a = np.asarray(dist.postprocess(dist.sample_no_postprocessing(h, key)))
    ours_a, _ = eval_mjx.policy_action(h, jax.random.normal(key, (5, 12)))
    mode_a, _ = eval_mjx.policy_action(h, jax.random.normal(key, (5, 12)), noise=0.0)
    check(np.abs(np.asarray(ours_a) - brax_a).max() < 1e-6 and
          np.array_equal(np.asarray(mode_a), np.asarray(dist.mode(h))) and  # Brax's mode is tanh(loc)
          np.abs(np.asarray(ours_a) - np.asarray(mode_a)).max() > 0.05,
          f"eval_mjx.policy_action: a draw equals Brax's NormalTanhDistribution's for the same key (max |diff| "
          f"{np.abs(np.asarray(ours_a) - brax_a).max():.1e}); noise 0 is its mode, tanh(loc), bit for bit")
    stoch_out = os.path.join(workdir, "mjx_stochastic.npz")
    run_eval_mjx([os.path.join(run_dir, "actor.npz"), "--out", stoch_out, "--commands", sched, "--start-reference",
                 "--stochastic"])  # the actor's rollout's program again, the noise's scale an input
    st = np.load(stoch_out)
    apart_st = float(np.abs(st["q"] - z["q"]).max())
    check(not z["action_std"].any() and float(st["action_std"].min()) > 0.01 and apart_st > 0.01 and
          np.isfinite(st["reward"]).all(),
          f"eval_mjx --stochastic: the legs leave the mean action's rollout by {apart_st:.3f} rad, the sampled std "
          f"{float(st['action_std'].mean()):.3f} (the mean action's rollout records 0)")
    # --physics mujoco: MuJoCo's C engine steps the same model; with the SIL's 1 ms step and explicit PD damping the
    # first 0.2 s stay close to MJX's 5 ms implicit ones (a sign error in the explicit D term, or a physics step
    # whose result is dropped, would not).
    cpu_out = os.path.join(workdir, "mjx_mujoco.npz")
    run_eval_mjx([os.path.join(run_dir, "actor.npz"), "--out", cpu_out, "--commands", sched, "--start-reference",
                 "--physics", "mujoco", "--pd-damping", "explicit", "--sim-dt", "0.001", "--duration", "0.2"])
    c = np.load(cpu_out)
    cenv = json.loads(str(c["env_config"]))
    moved = float(np.abs(z["q"][:20] - z["q"][0]).max())
    apart = float(np.abs(c["q"] - z["q"][:20]).max())
    check(cenv["pd_damping"] == "explicit" and cenv["sim_dt"] == 0.001 and c["q"].shape == (20, 12) and
          apart < 0.3 * moved and np.isfinite(c["reward"]).all(),
          f"eval_mjx --physics mujoco (C engine, 1 ms, explicit PD): the legs follow MJX's 5 ms implicit rollout to "
          f"{apart:.4f} rad over 0.2 s, while they move {moved:.3f} rad")
    start = float(z["start_height"])
    check(env["p_reset_reference"] == 1.0 and tc["env"]["p_reset_reference"] == 0.5 and abs(start - want[0][5]) < 0.04,
          f"eval_mjx --start-reference: started in the first command's reference pose, pelvis {start:.3f} m for "
          f"{want[0][5]} m commanded (standing: 0.79; p_reset_reference {env['p_reset_reference']}, the run's "
          f"{tc['env']['p_reset_reference']})")
    rand_out = os.path.join(workdir, "mjx_randomized.npz")
    run_eval_mjx([os.path.join(run_dir, "actor.npz"), "--out", rand_out, "--commands", sched, "--randomized", "3",
                 "--seed", "1", "--duration", "0.2"])
    r = np.load(rand_out)
    renv = json.loads(str(r["env_config"]))
    lo, hi = tc["env"]["friction"]
    check(r["q"].shape == (3, 20, 12) and r["start_height"].shape == (3,) and list(r["segment_names"]) == ["walk"] and
          r["segment_falls"].shape == (1,) and len(set(np.round(r["drawn_friction"], 6))) == 3 and
          bool(np.all((r["drawn_friction"] >= lo) & (r["drawn_friction"] <= hi))) and
          len(set(np.round(r["drawn_mass"], 4))) == 3 and not renv["deterministic_reset"] and
          renv["p_delay"] == tc["env"]["p_delay"] and renv["noise"] == tc["env"]["noise"] and
          tuple(renv["push_vel"]) == (0.0, 0.0) and renv["p_teleop"] == 0.0 and renv["p_hand_force"] == 0.0 and
          r["foot_xy"].shape == (3, 20, 2, 2) and 0.1 < float(np.abs(r["foot_xy"][:, 0, 0, 1] - r["foot_xy"][:, 0, 1, 1]).min())
          and float(np.abs(r["foot_xy"][:, 0, 0, 1] - r["foot_xy"][:, 0, 1, 1]).max()) < 0.4,
          f"eval_mjx --randomized 3: three robots in the run's training distribution (friction "
          f"{np.round(r['drawn_friction'], 3).tolist()} within {[lo, hi]}, masses {np.round(r['drawn_mass'], 2).tolist()} kg; "
          f"the run's delay {renv['p_delay']} and noise; no pushes, teleop arms or hand forces); --duration 0.2 "
          f"reports only the segment it reaches ({list(r['segment_names'])}); the feet recorded for the foot slip "
          f"{np.round(np.abs(r['foot_xy'][:, 0, 0, 1] - r['foot_xy'][:, 0, 1, 1]), 3).tolist()} m apart")


def pd_damping_checks(check):
    """1h. EnvConfig.pd_damping (no compile: the models and the DR draws only): "implicit" puts the PD's kd into
    the joints' damping (0.05 + kd) and the DR scales it; "explicit" leaves the joints' own 0.05 in the model and
    in every draw (the step computes kd (qd_des - qd)); anything else is refused."""
    import jax
    import numpy as np
    from pmg_train import g1_env
    drawn = {}
    for pd in ("implicit", "explicit"):
        env = g1_env.G1PmgEnv(g1_env.EnvConfig(pd_damping=pd))
        sys_v, _ = g1_env.make_randomization_fn(env)(env.sys, jax.random.split(jax.random.PRNGKey(0), 4))
        drawn[pd] = (np.asarray(env.mj_model.dof_damping[6:]), np.asarray(sys_v.dof_damping[:, 6:]), np.asarray(env.kd))
    (m_i, d_i, kd), (m_e, d_e, _) = drawn["implicit"], drawn["explicit"]
    lo, hi = g1_env.EnvConfig().kd_scale
    scale = (d_i - 0.05) / kd
    check(np.allclose(m_i, 0.05 + kd, atol=1e-6) and np.all((scale >= lo - 1e-5) & (scale <= hi + 1e-5)) and
          np.allclose(m_e, 0.05) and np.allclose(d_e, 0.05),
          f"pd_damping: implicit knee damping {m_i[3]:.2f} N m s/rad (0.05 + kd), drawn {[f'{x:.2f}' for x in d_i[:, 3]]}; "
          f"explicit {m_e[3]:.2f}, drawn {[f'{x:.2f}' for x in d_e[:, 3]]}")
    try:
        g1_env.G1PmgEnv(g1_env.EnvConfig(pd_damping="semi"))
        refused = ""
    except ValueError as e:
        refused = str(e)
    check("pd_damping" in refused and "'explicit'" in refused, f"pd_damping 'semi' refused: {refused}")


def reset_reference_checks(check, n_resets=12, hold_steps=50):
    """1g. Reference state initialisation (EnvConfig.p_reset_reference = 0.5, its own env, randomised
    reset): a reset either stands (pelvis at 0.79 m, legs within the reset noise of the standing pose)
    or starts in the PMG reference's pose for its first command and phase (every joint within the
    noise of ref_q, the lowest sole sphere on the floor to 0.1 mm, at rest, the pelvis within 0.04 m of
    the commanded height); both occur. From a reference start, actions that hold the reference keep
    the robot up for hold_steps (0.5 s) with the pelvis within 0.06 m of where it started."""
    import jax
    import numpy as np
    from pmg_train import g1_env
    t0 = time.time()
    env = g1_env.G1PmgEnv(g1_env.EnvConfig(p_reset_reference=0.5), sorted(glob.glob("config/clips/g1/*.yaml")))
    reset, step = jax.jit(env.reset), jax.jit(env.step)
    standing, reference, bad, held = 0, 0, [], []
    for seed in range(n_resets):
        st = reset(jax.random.PRNGKey(seed))
        ps = st.pipeline_state
        q, ref_q = np.asarray(ps.qpos[7:]), np.asarray(st.info["ref_q"])
        z0, cmd = float(ps.qpos[2]), np.asarray(st.info["command"])
        if abs(z0 - 0.79) < 1e-6 and np.abs(q - env.q_default).max() <= 0.05 + 1e-6:
            standing += 1
            continue
        reference += 1
        bottom = float(np.min(np.asarray(ps.geom_xpos)[env.sole_spheres, 2] - env.sole_radius))
        if not (np.abs(q - ref_q).max() <= 0.05 + 1e-5 and abs(bottom) < 1e-4 and
                float(np.abs(np.asarray(ps.qvel)).max()) == 0.0 and abs(z0 - cmd[5]) < 0.04):
            bad.append((seed, float(np.abs(q - ref_q).max()), bottom, z0, float(cmd[5])))
            continue
        for _ in range(hold_steps):
            st = step(st, env.hold_action(st.info["ref_q"][:g1_env.LEG]))
        held.append((seed, z0, float(st.pipeline_state.qpos[2]), float(st.done)))
    print(f"reference-pose resets {time.time() - t0:.1f} s (compile included): standing {standing}, "
          f"reference {reference}; held (seed, z0, z, done): {held}", flush=True)
    check(standing > 0 and reference > 0 and not bad,
          f"p_reset_reference 0.5: {standing} standing and {reference} reference-pose resets of {n_resets}; "
          f"every reference start in ref_q's pose, a sole on the floor, at rest, at the commanded height "
          f"(off: {bad})")
    check(len(held) == reference - len(bad) and all(d == 0.0 and abs(z - z0) < 0.06 for _, z0, z, d in held),
          f"held at the reference for {hold_steps} steps from each reference start: no episode ended, pelvis "
          f"within 0.06 m of its start (largest change "
          f"{max((abs(z - z0) for _, z0, z, _ in held), default=float('nan')):.3f} m)")


def action_offset_checks(check):
    """Residual actions (EnvConfig.action_offset = "reference"): the leg PD targets are the PMG reference
    of the step plus scale x action, not the standing pose plus it. One physics substep from a
    deterministic reset, with an action on one knee: the leg torques equal kp (q_ref + scale a - q)."""
    import jax
    import jax.numpy as jnp
    import numpy as np
    from pmg_train import g1_env
    t0 = time.time()
    import mujoco
    env = g1_env.G1PmgEnv(g1_env.EnvConfig(deterministic_reset=True, push_vel=(0.0, 0.0), action_offset="reference",
                                           upper_body_ff=True), sorted(glob.glob("config/clips/g1/*.yaml")))
    env.n_substeps = 1
    st = jax.jit(env.reset)(jax.random.PRNGKey(3))
    st = st.replace(info=dict(st.info, delay=jnp.float32(0.0)))  # the action of this step applies (no latency)
    qd_waist = np.array([0.3, -0.4, 0.5])
    st = st.replace(pipeline_state=st.pipeline_state.replace(
        qvel=st.pipeline_state.qvel.at[env.ub_dof].set(jnp.asarray(qd_waist, jnp.float32))))
    knee = 3
    a = np.zeros(12, np.float32)
    a[knee] = 0.5
    q = np.asarray(st.pipeline_state.qpos[7:19], np.float64)
    ref = np.asarray(st.info["ref_q"], np.float64)[:12]
    ctrl_all = np.asarray(jax.jit(env.step)(st, jnp.asarray(a)).pipeline_state.ctrl, np.float64)
    ctrl = ctrl_all[:12]
    kp = env.kp[:12].astype(np.float64) * np.asarray(st.info["kp_scale"], np.float64)
    tau = lambda base: np.clip(kp * (np.clip(base + env.action_scale * a, env.q_lower[:12], env.q_upper[:12]) - q),
                               -env.tau_max[:12], env.tau_max[:12])
    err, err_default = np.abs(ctrl - tau(ref)).max(), np.abs(ctrl - tau(env.q_default[:12])).max()
    print(f"residual-action probe {time.time() - t0:.1f} s (compile included)", flush=True)
    check(err < 1e-3 and err_default > 1.0 and np.abs(ref - env.q_default[:12]).max() > 0.1,
          f"action_offset reference: leg torques = kp (q_ref + scale a - q) (max diff {err:.1e} N m); against the "
          f"standing pose they would differ by {err_default:.1f} N m")
    try:
        g1_env.G1PmgEnv(g1_env.EnvConfig(action_offset="reference_q"), sorted(glob.glob("config/clips/g1/*.yaml")))
        refused = False
    except ValueError as e:
        refused = "action_offset" in str(e)
    check(refused, "an unknown action_offset is refused, naming the field")

    # Upper-body feed-forward: the waist torques of the same substep.
    m = env.mj_model
    d = mujoco.MjData(m)
    d.qpos[:] = np.asarray(st.pipeline_state.qpos, np.float64)
    mujoco.mj_forward(m, d)  # qvel 0: qfrc_bias is the gravity torque alone
    grav = d.qfrc_bias[env.ub_dof]
    ff = np.clip(grav - 5.0 * qd_waist, -env.ub_limit, env.ub_limit)
    w = env.ub_q
    q_w = np.asarray(st.pipeline_state.qpos, np.float64)[7 + w]
    ref_all = np.asarray(st.info["ref_q"], np.float64)
    refd_all = np.asarray(st.info["ref_qd"], np.float64)
    kp_w = env.kp[w].astype(np.float64) * np.broadcast_to(np.asarray(st.info["kp_scale"], np.float64), (29,))[w]
    pd = kp_w * (ref_all[w] - q_w) + env.kd[w] * refd_all[w]
    want = np.clip(pd + ff, -env.tau_max[w], env.tau_max[w])
    err = np.abs(ctrl_all[w] - want).max()
    check(err < 1e-3 and np.abs(ff).min() > 1.0,
          f"upper_body_ff: waist torques = PD + MuJoCo's gravity torque - 5 qd, clamped (max diff {err:.1e} N m; "
          f"feed-forward {np.round(ff, 2).tolist()} N m, gravity {np.round(grav, 2).tolist()} N m)")
    # A calibrated robot config that identifies a waist joint: its actuator model has no feed-forward
    # term, so the combination is refused rather than the feed-forward silently dropped.
    with open("config/robots/g1/g1.yaml") as f:
        lines = f.read().splitlines(keepends=True)
    for i, line in enumerate(lines):
        if line.lstrip().startswith("- {name: waist_pitch_joint,"):
            lines[i] = line.rstrip().rstrip("}") + ", actuator: {kp_scale: 0.9}}\n"
    cal = os.path.join(tempfile.mkdtemp(prefix="pmg_smoke_ub_"), "g1_waist_calibrated.yaml")
    with open(cal, "w") as f:
        f.write("".join(lines))
    try:
        g1_env.G1PmgEnv(g1_env.EnvConfig(upper_body_ff=True, actuators=cal), sorted(glob.glob("config/clips/g1/*.yaml")))
        msg = ""
    except ValueError as e:
        msg = str(e)
    check("upper_body_ff" in msg and "waist" in msg,
          f"upper_body_ff with an identified waist joint is refused, naming both ({msg[:70]}...)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--workdir", default=None, help="outputs (default: a temporary directory)")
    ap.add_argument("--envs", type=int, default=8)
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--part", choices=["env", "ppo", "eval", "all"], default="all",
                    help="env: the environment checks (1, 1b, 1c, 1d, 1e, 1f, 1g, 1h: rollout, actuator models, gains, "
                         "hand forces, command slew, stops, residual actions, reference-pose resets, PD damping); ppo: "
                         "the warm-up's staging and the tiny PPO run (2); eval: eval_mjx.py on that run's actor (2b, "
                         "--run-dir); all: every part")
    ap.add_argument("--run-dir", default=None,
                    help="eval: the tiny PPO run's output directory (the ppo part's <workdir>/ppo; default "
                         "<workdir>/ppo)")
    args = ap.parse_args()
    if os.environ.get(CHILD) != "1":
        relaunch()
    t_start = time.time()
    sys.path.insert(0, TRAINING)
    os.chdir(REPO)
    workdir = os.path.abspath(args.workdir) if args.workdir else tempfile.mkdtemp(prefix="pmg_smoke_")
    os.makedirs(workdir, exist_ok=True)
    import jax
    print(f"{sys.executable}: JAX {jax.__version__} ({jax.default_backend()}), devices {jax.local_devices()}; "
          f"workdir {workdir}", flush=True)
    check = Checks()
    pin_checks(check)
    obs = None
    if args.part in ("env", "all"):
        actuator_port_jax_checks(check)
        env, cal_path = make_smoke_env(workdir)
        obs, starts, reset, step = env_checks(check, env, args.envs, args.steps)
        actuator_env_checks(check, env, cal_path, starts)
        hand_force_checks(check, env, reset, step)
        action_offset_checks(check)
        pd_damping_checks(check)
        reset_reference_checks(check)
    if args.part in ("ppo", "all"):
        warmup_staging_checks(check, workdir)
        ppo_checks(check, workdir, obs)
    if args.part in ("eval", "all"):
        run_dir = os.path.abspath(args.run_dir) if args.run_dir else os.path.join(workdir, "ppo")
        if check(os.path.exists(os.path.join(run_dir, "actor.npz")) and
                 os.path.exists(os.path.join(run_dir, "train_config.json")),
                 f"the tiny PPO run's actor.npz and train_config.json in {run_dir} (the ppo part writes them)"):
            with open(os.path.join(run_dir, "train_config.json")) as f:
                mjx_eval_checks(check, workdir, run_dir, json.load(f))
    print(f"smoke run {time.time() - t_start:.1f} s")
    print(f"{check.passed} passed, {check.failed} failed")
    return 0 if check.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
