"""Python port of the C++ PMG generator (include/pmg/generator/generator.hpp), for training.

The training observation must hold PMG references exactly as the controller's C++ generator
computes them. This module re-implements MotionGenerator::step line by line, as pure functions of
(phase, commands) that run on NumPy (float64, for the equality test) or on JAX (jit/vmap over
thousands of environments; pass ``xp=jax.numpy``). test/policy runs
``training/tests/test_pmg_port.py`` against vectors emitted by apps/policy/pmg_generator_vectors
(same inputs -> same outputs to 1e-5; in float64 they agree to ~1e-12).

Equations (PMG paper): eq. 4 alpha, eq. 5/7 blend with the standing pose, eq. 6 weights, eqs. 8-9
contacts, eq. 10 posture offset, eq. 11 phase update, eq. 12 period. Conventions (standing
weight, derived clips, finite-difference reference velocity) follow generator.hpp's header.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

AXES = ("forward", "lateral", "yaw")
POSTURE_AXES = ("pitch", "roll", "height")


@dataclasses.dataclass
class Clip:
    name: str
    axis: int
    direction: int
    nominal_scale: float
    period: float
    q: np.ndarray           # (N, n) rad
    qd: np.ndarray          # (N, n) rad/s
    v_base: np.ndarray      # (N, 3) m/s, heading frame
    omega_base: np.ndarray  # (N, 3) rad/s, heading frame
    base_height: np.ndarray # (N,) m
    contact: np.ndarray     # (2, 2): [foot][mu, sigma]


@dataclasses.dataclass
class StaticClip:
    name: str
    axis: int
    values: np.ndarray  # (K,)
    neutral: float
    q: np.ndarray       # (K, n)


@dataclasses.dataclass
class JointSpace:
    joint_names: list
    q_stand: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    mirror_index: np.ndarray
    mirror_sign: np.ndarray
    standing_base_height: float


def _wrap_np(phi):
    phi = phi - math.floor(phi)
    return 0.0 if phi >= 1.0 else phi


def rotate_phase(c: Clip, shift: int) -> Clip:
    """pmg::rotateClipPhase: new sample k = old sample k + shift; contact centres move by -shift/N."""
    n = c.q.shape[0]
    shift %= n
    if shift == 0:
        return c
    s = (np.arange(n) + shift) % n
    contact = c.contact.copy()
    contact[:, 0] = [_wrap_np(mu - shift / n) for mu in c.contact[:, 0]]
    return Clip(c.name, c.axis, c.direction, c.nominal_scale, c.period, c.q[s].copy(), c.qd[s].copy(),
                c.v_base[s].copy(), c.omega_base[s].copy(), c.base_height[s].copy(), contact)


def align_on_left_touchdown(c: Clip) -> Clip:
    """pmg::alignPhaseOnLeftTouchdown: phi = 0 at the left foot's touchdown mu - sigma (std::lround)."""
    n = c.q.shape[0]
    start = c.contact[0, 0] - c.contact[0, 1]
    start -= math.floor(start)
    return rotate_phase(c, int(math.floor(start * n + 0.5)) % n)


def time_reversed(c: Clip) -> Clip:
    """pmg::timeReverseClip (src/clips/clip_transforms.cpp)."""
    n = c.q.shape[0]
    s = (n - np.arange(n)) % n
    contact = c.contact.copy()
    contact[:, 0] = [_wrap_np(1.0 - mu) for mu in c.contact[:, 0]]
    return align_on_left_touchdown(
        Clip(c.name + "_time_reversed", c.axis, -c.direction, c.nominal_scale, c.period, c.q[s].copy(),
             -c.qd[s], -c.v_base[s], -c.omega_base[s], c.base_height[s].copy(), contact))


def mirrored(c: Clip, js: JointSpace) -> Clip:
    """pmg::mirrorClip (src/clips/clip_transforms.cpp)."""
    q = c.q[:, js.mirror_index] * js.mirror_sign[None, :]
    qd = c.qd[:, js.mirror_index] * js.mirror_sign[None, :]
    v = c.v_base.copy()
    v[:, 1] = -c.v_base[:, 1]
    w = c.omega_base.copy()
    w[:, 0] = -c.omega_base[:, 0]
    w[:, 2] = -c.omega_base[:, 2]
    contact = c.contact[::-1].copy()
    direction = c.direction if c.axis == 0 else -c.direction
    return align_on_left_touchdown(Clip(c.name + "_mirrored", c.axis, direction, c.nominal_scale, c.period, q, qd, v, w,
                                        c.base_height.copy(), contact))


class GeneratorModel:
    """Immutable model: 6 dynamic slots (axis x sign), up to 3 static clips (GeneratorModel)."""

    def __init__(self, dynamic_clips, static_clips, js: JointSpace, epsilon=0.05, max_command=(1.5, 0.8, 1.5)):
        self.js = js
        self.epsilon = float(epsilon)
        self.max_command = np.asarray(max_command, dtype=np.float64)
        self.dynamic = [None] * 6  # slot 2*axis + (direction < 0)
        for c in dynamic_clips:
            slot = 2 * c.axis + (1 if c.direction < 0 else 0)
            if self.dynamic[slot] is not None:
                raise ValueError(f"clip '{c.name}': a second clip for the same axis and direction")
            self.dynamic[slot] = c
        for a in range(3):
            pos, neg = self.dynamic[2 * a], self.dynamic[2 * a + 1]
            derive = time_reversed if a == 0 else (lambda c: mirrored(c, js))
            if pos is not None and neg is None:
                self.dynamic[2 * a + 1] = derive(pos)
            if neg is not None and pos is None:
                self.dynamic[2 * a] = derive(neg)
        self.static = [None] * 3
        for s in static_clips:
            if self.static[s.axis] is not None:
                raise ValueError(f"static clip '{s.name}': a second clip for the same posture axis")
            self.static[s.axis] = s
        self.t_stand = self.dynamic[0].period if self.dynamic[0] is not None else 1.0
        self.max_samples = max([2] + [d.q.shape[0] for d in self.dynamic if d is not None])
        self.n = len(js.joint_names)


def _phase_sample(xp, phi, n_samples):
    x = wrap_phase(xp, phi) * n_samples
    fl = xp.floor(x)
    k0 = fl.astype(np.int32) % n_samples if hasattr(fl, "astype") else int(fl) % n_samples
    k1 = (k0 + 1) % n_samples
    return k0, k1, x - fl


def wrap_phase(xp, phi):
    phi = phi - xp.floor(phi)
    return xp.where(phi >= 1.0, 0.0, phi)


def phase_distance(xp, a, b):
    d = xp.abs(wrap_phase(xp, a) - wrap_phase(xp, b))
    return xp.minimum(d, 1.0 - d)


def _interp_rows(xp, table, phi):
    """Linear interpolation of a periodic (N, ...) table at phase phi (scalar)."""
    n = table.shape[0]
    k0, k1, t = _phase_sample(xp, phi, n)
    return (1.0 - t) * table[k0] + t * table[k1]


def _interp_static(xp, s: StaticClip, value):
    k = s.values.shape[0]
    i = xp.sum(value > xp.asarray(s.values[1:k - 1])) if k > 2 else 0
    v0 = xp.asarray(s.values)[i]
    v1 = xp.asarray(s.values)[i + 1]
    t = xp.clip((value - v0) / (v1 - v0), 0.0, 1.0)
    q = xp.asarray(s.q)
    return (1.0 - t) * q[i] + t * q[i + 1]


def step(model: GeneratorModel, phase, u_d, u_s, dt, xp=np):
    """One generator tick for one robot (MotionGenerator::step). Under JAX, vmap over robots.

    phase: scalar in [0, 1). u_d: (3,) (v_x, v_y, omega) [m/s, m/s, rad/s], heading frame.
    u_s: (3,) (pitch [rad], roll [rad], height [m]; height <= 0 = standing height). dt [s] > 0.
    Returns a dict with the GeneratorOutput fields (phase, next_phase, period, q_ref, qd_ref, ...).
    Non-finite commands are not handled here (training never produces them).
    """
    js = model.js
    u = xp.clip(xp.asarray(u_d, dtype=xp.float64 if xp is np else None), -model.max_command, model.max_command)
    # Posture offset (evalPosture).
    q_post = xp.zeros(model.n)
    beta = []
    height_offset = 0.0
    for a in range(3):
        s = model.static[a]
        if s is None:
            beta.append(0.0 * u[0])
            continue
        value = u_s[a]
        if a == 2:
            value = xp.where(value <= 0.0, s.neutral, value)
        lo, hi = float(s.values[0]), float(s.values[-1])
        value = xp.clip(value, lo, hi)
        span = xp.where(value >= s.neutral, hi - s.neutral, s.neutral - lo)
        beta.append(xp.where(span > 0, (value - s.neutral) / xp.where(span > 0, span, 1.0), 0.0))
        q_post = q_post + _interp_static(xp, s, value) - _interp_static(xp, s, s.neutral)
        if a == 2:
            height_offset = value - s.neutral

    # Per axis: the clip of the command's sign; both evaluated, selected with where (JAX-friendly).
    present = [model.dynamic[2 * i] is not None or model.dynamic[2 * i + 1] is not None for i in range(3)]
    sum_abs = sum(xp.abs(u[i]) for i in range(3) if present[i])
    weight, alpha = [], []
    for i in range(3):
        if not present[i]:
            weight.append(0.0 * u[0]); alpha.append(0.0 * u[0]); continue
        pos, neg = model.dynamic[2 * i], model.dynamic[2 * i + 1]
        nominal = xp.where(u[i] < 0, neg.nominal_scale, pos.nominal_scale)
        alpha.append(xp.clip(xp.abs(u[i]) / nominal, 0.0, 1.0))
        weight.append(xp.abs(u[i]) / (sum_abs + model.epsilon))
    sum_w = weight[0] + weight[1] + weight[2]
    w_stand = 1.0 - sum_w

    def per_clip(i, fn):
        pos, neg = model.dynamic[2 * i], model.dynamic[2 * i + 1]
        return xp.where(u[i] < 0, fn(neg), fn(pos))

    period = w_stand * model.t_stand
    for i in range(3):
        if present[i]:
            period = period + weight[i] * per_clip(i, lambda c: c.period)
    h = 0.5 / model.max_samples
    q_stand = xp.asarray(js.q_stand)

    def blend(phi):
        ws = w_stand
        for i in range(3):
            if present[i]:
                ws = ws + weight[i] * (1.0 - alpha[i])
        q = ws * q_stand
        for i in range(3):
            if present[i]:
                qi = per_clip(i, lambda c: _interp_rows(xp, xp.asarray(c.q), phi))
                q = q + weight[i] * alpha[i] * qi
        return q

    q_minus = blend(phase - h)
    q_plus = blend(phase + h)
    q_dyn = blend(phase)

    mu_f, sigma_f, in_contact = [], [], []
    for f in range(2):
        mu, sigma = 0.0, 0.5 * w_stand
        for i in range(3):
            if present[i]:
                mu = mu + weight[i] * per_clip(i, lambda c: c.contact[f, 0])
                sigma = sigma + weight[i] * per_clip(i, lambda c: c.contact[f, 1])
        m = xp.where(sum_w > 0, wrap_phase(xp, mu / xp.where(sum_w > 0, sum_w, 1.0)), 0.0)
        sg = xp.clip(sigma, 0.0, 0.5)
        mu_f.append(m); sigma_f.append(sg)
        in_contact.append(xp.logical_or(phase_distance(xp, phase, m) < sg, sg >= 0.5))

    v_base = xp.zeros(3)
    yaw_rate = 0.0
    height = w_stand * js.standing_base_height
    for i in range(3):
        if not present[i]:
            continue
        wa = weight[i] * alpha[i]
        v_base = v_base + wa * per_clip(i, lambda c: _interp_rows(xp, xp.asarray(c.v_base), phase))
        yaw_rate = yaw_rate + wa * per_clip(i, lambda c: _interp_rows(xp, xp.asarray(c.omega_base[:, 2]), phase))
        h_clip = per_clip(i, lambda c: _interp_rows(xp, xp.asarray(c.base_height), phase))
        height = height + weight[i] * (alpha[i] * h_clip + (1.0 - alpha[i]) * js.standing_base_height)
    base_height = height + height_offset

    q_raw = q_dyn + q_post
    lower, upper = xp.asarray(js.lower), xp.asarray(js.upper)
    q_ref = xp.clip(q_raw, lower, upper)
    clamped = xp.sum(xp.logical_or(q_raw < lower, q_raw > upper))
    qd_ref = (q_plus - q_minus) / (2.0 * h * period)
    next_phase = wrap_phase(xp, phase + dt / period)
    return {"phase": phase, "next_phase": next_phase, "period": period, "q_ref": q_ref, "qd_ref": qd_ref,
            "alpha": xp.stack([xp.asarray(a) for a in alpha]), "weight": xp.stack([xp.asarray(w) for w in weight]),
            "standing_weight": w_stand, "beta": xp.stack([xp.asarray(b) for b in beta]),
            "contact_mu": xp.stack(mu_f), "contact_sigma": xp.stack(sigma_f), "in_contact": xp.stack(in_contact),
            "v_base": v_base, "yaw_rate": yaw_rate, "base_height": base_height, "clamped_joints": clamped}


# ---- loading -------------------------------------------------------------------------------

def joint_space_from_robot_yaml(path):
    import yaml
    with open(path) as f:
        r = yaml.safe_load(f)
    joints = r["joints"]
    names = [j["name"] for j in joints]
    return JointSpace(names, np.array([j["default"] for j in joints], float), np.array([j["lower"] for j in joints], float),
                      np.array([j["upper"] for j in joints], float), np.array([names.index(j["mirror"]) for j in joints]),
                      np.array([j["mirror_sign"] for j in joints], float), float(r["robot"]["standing_base_height"]))


def load_clip_file(path):
    """Reads one clip file (docs/clip_format.md) -> Clip or StaticClip."""
    import yaml
    with open(path) as f:
        d = yaml.safe_load(f)
    if d["kind"] == "dynamic":
        return Clip(d["name"], AXES.index(d["axis"]), int(d["direction"]), float(d["nominal_scale"]), float(d["period"]),
                    np.array(d["q"], float), np.array(d["qd"], float), np.array(d["v_base"], float),
                    np.array(d["omega_base"], float), np.array(d["base_height"], float),
                    np.array([[d["contact"]["left"]["mu"], d["contact"]["left"]["sigma"]],
                              [d["contact"]["right"]["mu"], d["contact"]["right"]["sigma"]]], float))
    return StaticClip(d["name"], POSTURE_AXES.index(d["axis"]), np.array(d["values"], float), float(d["neutral"]),
                      np.array(d["q"], float))


def model_from_vectors(v):
    """GeneratorModel from a pmg_generator_vectors JSON document."""
    js = JointSpace(v["joint_names"], np.array(v["q_stand"]), np.array(v["lower"]), np.array(v["upper"]),
                    np.array(v["mirror_index"], int), np.array(v["mirror_sign"], float), v["standing_base_height"])
    dyn = [Clip(c["name"], c["axis"], c["direction"], c["nominal_scale"], c["period"], np.array(c["q"]),
                np.array(c["qd"]), np.array(c["v_base"]), np.array(c["omega_base"]), np.array(c["base_height"]),
                np.array(c["contact"])) for c in v["dynamic_clips"]]
    sta = [StaticClip(s["name"], s["axis"], np.array(s["values"]), s["neutral"], np.array(s["q"]))
           for s in v["static_clips"]]
    return GeneratorModel(dyn, sta, js, v["epsilon"], v["max_command"])
