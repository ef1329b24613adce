"""NumPy / JAX port of the extended per-joint actuator model ``pmg::calib::ActuatorModel``
(include/pmg/calib/actuator_model.hpp), vectorised over joints.

The model turns a motor driver's PD command into the torque applied to the joint, with the effects
bench calibration names (docs/calibration.md): transport delay (delay line with linear
interpolation between physics steps), the driver's PD at its own rate with zero-order hold, an
encoder zero offset, the torque constant (kt_scale: delivered / commanded torque), symmetric torque
saturation, the voltage-limited torque-speed envelope, Coulomb / Stribeck / load-dependent dry
friction with implicit stiction, and viscous friction. Backlash is a parameter only (it needs a
rotor body, as in the C++ model).

Everything is a pure function of (params, state, inputs) -> (state, output); ``xp`` selects NumPy
(float64, what ``training/tests/test_actuator_port.py`` compares with the C++ model to 1e-9) or
``jax.numpy`` (jit-able, any float dtype). The state has a fixed size (the delay line is a ring
buffer of ``max_delay_steps`` rows), so ``step`` traces once and runs inside ``lax.scan``.

Shapes: every parameter, command and joint-sample field is an array of shape (n,) -- one entry
per joint (broadcasting scalars is allowed for the joint sample's ``dt_s``). Units are SI:

  params (``make_params`` / ``params_from_blocks``; the keys of the C++ ``ActuatorParams`` and of the
  robot config's ``actuator:`` block, include/pmg/calib/actuator_yaml.hpp):
    rate_hz            driver PD rate [Hz] (0 = recompute every step)
    delay_s            command transport delay [s], in [0, max_delay_steps * dt)
    offset_rad         encoder reading - true angle [rad]
    kt_scale           delivered / commanded torque [-], in (0, 5]
    torque_limit_Nm    symmetric saturation of the delivered torque [N m] (inf = none)
    tau_stall_Nm, w_max_rad_per_s
                       torque-speed envelope -tau_stall (1 + w/w_max) <= tau <= tau_stall (1 - w/w_max)
                       [N m], [rad/s]; off when either is 0
    fc_Nm              Coulomb (kinetic) friction [N m]
    fs_Nm              break-away torque [N m] (0 = fc_Nm)
    vs_rad_per_s       Stribeck velocity [rad/s], > 0
    kl                 load-dependent friction, F += kl |tau_motor| [-], in [0, 1)
    fv_Nms_per_rad     viscous friction [N m s/rad]
    backlash_gap_rad   dead zone [rad] (not applied by step, as in C++)
  command (``MotorCommand``): q_des_rad [rad], dq_des_rad_per_s [rad/s], kp_Nm_per_rad [N m/rad],
    kd_Nms_per_rad [N m s/rad], tau_ff_Nm [N m], enabled (bool)
  joint sample (``JointSample``): q_rad (true motor-side angle) [rad], dq_rad_per_s [rad/s],
    inertia_kgm2 (effective inertia of the DOF incl. armature; <= 0 disables implicit stiction)
    [kg m^2], tau_other_Nm (all other generalized forces on the DOF) [N m], dt_s (physics step) [s]
  output: tau_motor_Nm (delivered, after delay, kt_scale, saturation, envelope), tau_friction_Nm
    (dry + viscous), tau_applied_Nm (their sum: what goes to qfrc_applied) [N m], stuck (bool)
"""
from __future__ import annotations

import math

import numpy as np

MAX_DELAY_STEPS = 512  # ActuatorState::kMaxDelaySteps

PARAM_DEFAULTS = {  # ActuatorParams' defaults: every effect off
    "rate_hz": 0.0,
    "delay_s": 0.0,
    "offset_rad": 0.0,
    "kt_scale": 1.0,
    "torque_limit_Nm": math.inf,
    "tau_stall_Nm": 0.0,
    "w_max_rad_per_s": 0.0,
    "fc_Nm": 0.0,
    "fs_Nm": 0.0,
    "vs_rad_per_s": 0.1,
    "kl": 0.0,
    "fv_Nms_per_rad": 0.0,
    "backlash_gap_rad": 0.0,
}
PARAM_KEYS = tuple(PARAM_DEFAULTS)
# The robot config's `actuator:` block = the parameters + what belongs to the simulator's joint or
# to the driver configuration (ActuatorBlock): armature [kg m^2] (None = not identified), gain scales.
BLOCK_DEFAULTS = dict(PARAM_DEFAULTS, armature_kgm2=None, kp_scale=1.0, kd_scale=1.0)
BLOCK_KEYS = tuple(BLOCK_DEFAULTS)
COMMAND_KEYS = ("q_des_rad", "dq_des_rad_per_s", "kp_Nm_per_rad", "kd_Nms_per_rad", "tau_ff_Nm")

_RANGES = {  # ActuatorParams::validate / ActuatorBlock::validate
    "rate_hz": (lambda v: math.isfinite(v) and v >= 0.0, ">= 0 Hz"),
    "delay_s": (lambda v: math.isfinite(v) and 0.0 <= v <= 0.25, "in [0, 0.25] s"),
    "offset_rad": (lambda v: math.isfinite(v) and abs(v) <= 0.5, "in [-0.5, 0.5] rad"),
    "kt_scale": (lambda v: math.isfinite(v) and 0.0 < v <= 5.0, "in (0, 5]"),
    "torque_limit_Nm": (lambda v: v > 0.0, "> 0 N m (or .inf)"),
    "tau_stall_Nm": (lambda v: math.isfinite(v) and v >= 0.0, ">= 0 N m"),
    "w_max_rad_per_s": (lambda v: math.isfinite(v) and v >= 0.0, ">= 0 rad/s"),
    "fc_Nm": (lambda v: math.isfinite(v) and v >= 0.0, ">= 0 N m"),
    "fs_Nm": (lambda v: math.isfinite(v) and v >= 0.0, ">= 0 N m"),
    "vs_rad_per_s": (lambda v: math.isfinite(v) and v > 0.0, "> 0 rad/s"),
    "kl": (lambda v: math.isfinite(v) and 0.0 <= v < 1.0, "in [0, 1)"),
    "fv_Nms_per_rad": (lambda v: math.isfinite(v) and v >= 0.0, ">= 0 N m s/rad"),
    "backlash_gap_rad": (lambda v: math.isfinite(v) and 0.0 <= v <= 0.5, "in [0, 0.5] rad"),
    "armature_kgm2": (lambda v: math.isfinite(v) and v >= 0.0, ">= 0 kg m^2"),
    "kp_scale": (lambda v: math.isfinite(v) and v > 0.0, "> 0"),
    "kd_scale": (lambda v: math.isfinite(v) and v > 0.0, "> 0"),
}


def parse_block(block, where="actuator"):
    """One `actuator:` block (a dict as yaml.safe_load gives it) -> dict over BLOCK_KEYS with the
    defaults filled in. Unknown keys and out-of-range values raise ValueError naming @p where and the
    key (as pmg::calib::parse_actuator_block does)."""
    if block is None:
        block = {}
    if not isinstance(block, dict):
        raise ValueError(f"{where}: expected a map of actuator parameters, got {block!r}")
    out = dict(BLOCK_DEFAULTS)
    for key, value in block.items():
        if key not in BLOCK_DEFAULTS:
            import difflib
            near = difflib.get_close_matches(str(key), BLOCK_KEYS, n=1)
            raise ValueError(f"{where}.{key}: unknown actuator key" + (f" (did you mean '{near[0]}'?)" if near else ""))
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{where}.{key} = {value!r}: expected a number") from None
        ok, rng = _RANGES[key]
        if not ok(v):
            raise ValueError(f"{where}.{key} = {v}: expected {rng}")
        out[key] = v
    return out


def make_params(n, xp=np, dtype=None, **values):
    """Parameter dict of (n,) arrays: ActuatorParams' defaults, overridden by @p values (scalars or
    (n,) sequences)."""
    dtype = dtype or (np.float64 if xp is np else xp.float32)
    p = {}
    for k, d in PARAM_DEFAULTS.items():
        v = values.pop(k, d)
        p[k] = xp.broadcast_to(xp.asarray(v, dtype), (n,)) + xp.zeros((n,), dtype)
    if values:
        raise ValueError(f"make_params: unknown keys {sorted(values)} (expected {PARAM_KEYS})")
    return p


def params_from_blocks(blocks, xp=np, dtype=None):
    """A list of parsed blocks (parse_block) -> parameter dict of (len(blocks),) arrays."""
    return make_params(len(blocks), xp, dtype, **{k: [b[k] for b in blocks] for k in PARAM_KEYS})


def init_state(n, max_delay_steps=MAX_DELAY_STEPS, xp=np, dtype=None):
    """ActuatorState for n joints, reset: delay line ``fifo`` (max_delay_steps, 5, n) [the five
    COMMAND_KEYS], ``fifo_enabled`` (max_delay_steps, n), ``head`` (index of the newest row) and
    ``count`` (valid rows), int32 scalars shared by the joints, ``pd_timer_s`` (n,) [s],
    ``held_tau_Nm`` (n,) [N m], ``has_pd`` (n,) bool."""
    dtype = dtype or (np.float64 if xp is np else xp.float32)
    return {
        "fifo": xp.zeros((max_delay_steps, len(COMMAND_KEYS), n), dtype),
        "fifo_enabled": xp.zeros((max_delay_steps, n), bool),
        "head": xp.asarray(0, xp.int32),
        "count": xp.asarray(0, xp.int32),
        "pd_timer_s": xp.zeros((n,), dtype),
        "held_tau_Nm": xp.zeros((n,), dtype),
        "has_pd": xp.zeros((n,), bool),
    }


def encoder(p, q_true_rad):
    """Encoder reading [rad] for a true motor-side angle [rad]."""
    return q_true_rad + p["offset_rad"]


def limit_torque(p, tau, w, xp=np):
    """Motor torque [N m] clipped by the saturation and the torque-speed envelope at velocity w [rad/s]."""
    lim = p["torque_limit_Nm"]
    tau = xp.minimum(xp.maximum(tau, -lim), lim)
    stall, wmax = p["tau_stall_Nm"], p["w_max_rad_per_s"]
    on = (stall > 0.0) & (wmax > 0.0)
    r = w / xp.where(on, wmax, 1.0)
    env = xp.minimum(xp.maximum(tau, -stall * (1.0 + r)), stall * (1.0 - r))
    return xp.where(on, env, tau)


def static_friction(p, tau_m, xp=np):
    """Break-away torque [N m] for a motor torque tau_m [N m]."""
    return xp.maximum(p["fs_Nm"], p["fc_Nm"]) + p["kl"] * xp.abs(tau_m)


def kinetic_friction(p, v, tau_m, xp=np):
    """Kinetic dry-friction magnitude [N m] at velocity v [rad/s] (Stribeck curve + load term)."""
    fs = xp.maximum(p["fs_Nm"], p["fc_Nm"])
    x = v / p["vs_rad_per_s"]
    return p["fc_Nm"] + (fs - p["fc_Nm"]) * xp.exp(-x * x) + p["kl"] * xp.abs(tau_m)


def _set_row(xp, a, i, v):
    if xp is np:
        a = a.copy()
        a[i] = v
        return a
    return a.at[i].set(v)


def push_command(s, cmd, xp=np):
    """The delay line with @p cmd (dict over COMMAND_KEYS + 'enabled', (n,) each) as its newest entry."""
    k = s["fifo"].shape[0]
    head = (s["head"] + 1) % k
    row = xp.stack([xp.asarray(cmd[c], s["fifo"].dtype) for c in COMMAND_KEYS])
    s = dict(s)
    s["fifo"] = _set_row(xp, s["fifo"], head, row)
    s["fifo_enabled"] = _set_row(xp, s["fifo_enabled"], head, xp.asarray(cmd["enabled"], bool))
    s["head"] = xp.asarray(head, xp.int32)
    s["count"] = xp.asarray(xp.minimum(s["count"] + 1, k), xp.int32)
    return s


def delayed_command(p, s, dt, xp=np):
    """The command delayed by p['delay_s'] [s] at physics step dt [s], linearly interpolated between
    the two neighbouring entries of the delay line (continuous in delay_s); the oldest entry when the
    line holds fewer. Returns (values (5, n) in COMMAND_KEYS order, enabled (n,))."""
    fifo = s["fifo"]
    k_rows, n = fifo.shape[0], fifo.shape[2]
    dt = xp.broadcast_to(xp.asarray(dt, fifo.dtype), (n,))
    on = (p["delay_s"] > 0.0) & (dt > 0.0)
    lag = xp.where(on, p["delay_s"] / xp.where(dt > 0.0, dt, 1.0), 0.0)
    k = xp.floor(lag)
    frac = lag - k
    k = k.astype(xp.int32)
    oldest = s["count"] - 1
    clamp = k >= oldest
    k = xp.where(clamp, oldest, k)
    frac = xp.where(clamp, 0.0, frac)
    cols = xp.arange(n)
    ia = (s["head"] - k) % k_rows
    ib = (s["head"] - k - 1) % k_rows
    a = fifo[ia, :, cols].T                 # (5, n)
    b = fifo[ib, :, cols].T
    mixed = (1.0 - frac) * a + frac * b
    vals = xp.where(frac > 0.0, mixed, a)
    ea = s["fifo_enabled"][ia, cols]
    eb = s["fifo_enabled"][ib, cols]
    enabled = xp.where((frac > 0.0) & (frac >= 0.5), eb, ea)
    return vals, enabled


def step(p, s, cmd, joint, xp=np):
    """One physics step of ActuatorModel::step for every joint: pushes @p cmd into the delay line,
    runs the driver's PD on the delayed command and the (offset) encoder reading at rate_hz (held in
    between), scales it by kt_scale, limits it, adds friction. Implicit stiction: if the dry friction
    can bring the joint to rest within this step (semi-implicit Euler, v+ = v + dt/I tau_total)
    without exceeding the break-away torque, it does exactly that.

    @p cmd: dict over COMMAND_KEYS + 'enabled'; @p joint: dict q_rad, dq_rad_per_s, inertia_kgm2,
    tau_other_Nm, dt_s (module docstring for units). Returns (new state, output dict)."""
    s = push_command(s, cmd, xp)
    dt = xp.asarray(joint["dt_s"], s["fifo"].dtype)
    c, enabled = delayed_command(p, s, dt, xp)
    q_des, dq_des, kp, kd, tau_ff = c[0], c[1], c[2], c[3], c[4]
    q, dq = joint["q_rad"], joint["dq_rad_per_s"]

    # Driver PD at its own rate (zero-order hold).
    rate = p["rate_hz"]
    period = xp.where(rate > 0.0, 1.0 / xp.where(rate > 0.0, rate, 1.0), 0.0)
    timer = s["pd_timer_s"] + dt
    has_pd = s["has_pd"]
    fire = xp.logical_not(has_pd) | (timer >= period - 1e-9)
    wrapped = xp.where(has_pd, xp.fmod(timer, xp.maximum(period, 1e-12)), 0.0)
    wrapped = xp.where(period <= 0.0, 0.0, wrapped)
    r = encoder(p, q)
    pd = kp * (q_des - r) + kd * (dq_des - dq) + tau_ff
    held = xp.where(fire, xp.where(enabled, pd, 0.0), s["held_tau_Nm"])
    s = dict(s)
    s["pd_timer_s"] = xp.where(fire, wrapped, timer)
    s["held_tau_Nm"] = held
    s["has_pd"] = xp.ones_like(has_pd)

    tau_m = xp.where(enabled, limit_torque(p, p["kt_scale"] * held, dq, xp), 0.0)

    # Friction: viscous, then dry with implicit stiction.
    tau_visc = -p["fv_Nms_per_rad"] * dq
    f_static = static_friction(p, tau_m, xp)
    drive = tau_m + tau_visc + joint["tau_other_Nm"]
    inertia = joint["inertia_kgm2"]
    implicit = (inertia > 0.0) & (dt > 0.0)
    hold = -inertia * dq / xp.where(dt > 0.0, dt, 1.0) - drive
    holds = xp.abs(hold) <= f_static
    kin = kinetic_friction(p, dq, tau_m, xp)
    dry_implicit = xp.where(holds, hold, xp.copysign(kin, hold))
    dry_explicit = xp.where(dq != 0.0, -xp.copysign(kin, dq), 0.0)
    tau_dry = xp.where(f_static > 0.0, xp.where(implicit, dry_implicit, dry_explicit), 0.0)
    stuck = (f_static > 0.0) & implicit & holds
    tau_f = tau_visc + tau_dry
    out = {"tau_motor_Nm": tau_m, "tau_friction_Nm": tau_f, "tau_applied_Nm": tau_m + tau_f, "stuck": stuck}
    return s, out
