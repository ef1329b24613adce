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

Blending (GeneratorParams::blending; ``GeneratorModel(..., blending=...)``):
  "consistent" (default, as the C++): the command u is first corrected by the library's consistency
      map (5-D multilinear over v_x, v_y, omega, height, pitch; ``consistency_map.yaml`` beside the clips),
      eq. 6 weights / eq. 12 period / eqs. 8-9 contacts come from the corrected u, and the effective
      amplitudes e_i come from KCONSISTENT_SWEEPS Gauss-Seidel sweeps over the per-clip displacement
      tables D = T * implied_motion.velocity (a clip without ``implied_motion`` gets the linear table
      of generator.hpp's makeDisplacementTable). An axis may play the clip of the opposite sign of u_i
      (``clip_direction``) to cancel another clip's drift.
  "paper": eqs. 4-7 (e_i = w_i alpha_i), kept for the ablation.
Both then use the unified form q_d = q_stand + sum_i e_i (q_Di(phi) - q_stand), base velocity
sum_i e_i v_i(phi), height h_stand + sum_i e_i (h_i(phi) - h_stand).
Under JAX everything is traced: fixed loop counts (unrolled at trace time), clips of both signs
evaluated and selected with ``where``, no Python control flow on traced values (jit/vmap-able).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from . import loops

AXES = ("forward", "lateral", "yaw")
BLENDINGS = ("consistent", "paper")
KCONSISTENT_SWEEPS = 4  # pmg::kConsistentSweeps
CONSISTENCY_MAP_FILE = "consistency_map.yaml"
POSTURE_AXES = ("pitch", "roll", "height")
UPRIGHT_JOINTS = ("waist_pitch_joint", "waist_roll_joint")  # GeneratorParams::upright_walking


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
    implied_amplitude: np.ndarray = None  # (K,) implied_motion.amplitude, or None
    implied_velocity: np.ndarray = None   # (K, 3) implied_motion.velocity (v_x, v_y, omega) at period T


@dataclasses.dataclass
class ConsistencyMap:
    """pmg::ConsistencyMap: grid[d] (d = v_x, v_y, omega, height, pitch), delta (prod n_d, 3)."""
    grid: list
    delta: np.ndarray


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
    return dataclasses.replace(c, q=c.q[s].copy(), qd=c.qd[s].copy(), v_base=c.v_base[s].copy(),
                               omega_base=c.omega_base[s].copy(), base_height=c.base_height[s].copy(), contact=contact)


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
    iv = None if c.implied_velocity is None else -c.implied_velocity  # the same stance paths, backwards
    return align_on_left_touchdown(
        Clip(c.name + "_time_reversed", c.axis, -c.direction, c.nominal_scale, c.period, c.q[s].copy(),
             -c.qd[s], -c.v_base[s], -c.omega_base[s], c.base_height[s].copy(), contact,
             c.implied_amplitude, iv))


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
    iv = None
    if c.implied_velocity is not None:  # v_y and omega change sign under the mirror
        iv = c.implied_velocity * np.array([1.0, -1.0, -1.0])[None, :]
    return align_on_left_touchdown(Clip(c.name + "_mirrored", c.axis, direction, c.nominal_scale, c.period, q, qd, v, w,
                                        c.base_height.copy(), contact, c.implied_amplitude, iv))


def displacement_table(c: Clip):
    """GeneratorModel::makeDisplacementTable: (amplitudes (K,), per-cycle displacement (K, 3))."""
    if c.implied_amplitude is not None:
        return np.asarray(c.implied_amplitude, float), np.asarray(c.implied_velocity, float) * c.period
    d = np.zeros((2, 3))
    d[1, 0] = c.v_base[:, 0].mean() * c.period
    d[1, 1] = c.v_base[:, 1].mean() * c.period
    d[1, 2] = c.omega_base[:, 2].mean() * c.period
    d[1, c.axis] = c.direction * c.nominal_scale * c.period
    return np.array([0.0, 1.0]), d


class GeneratorModel:
    """Immutable model: 6 dynamic slots (axis x sign), up to 3 static clips (GeneratorModel)."""

    def __init__(self, dynamic_clips, static_clips, js: JointSpace, epsilon=0.05, max_command=(1.5, 0.8, 1.5),
                 blending="consistent", consistency=None, max_cadence_ratio=1.3, upright_walking=False):
        if blending not in BLENDINGS:
            raise ValueError(f"GeneratorModel.blending = {blending!r}: expected one of {BLENDINGS}")
        if not 1.0 <= max_cadence_ratio <= 2.0:
            raise ValueError(f"GeneratorModel.max_cadence_ratio = {max_cadence_ratio}: expected in [1, 2]")
        self.max_cadence_ratio = float(max_cadence_ratio)
        self.blending = blending
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
        self.upright_walking = bool(upright_walking)
        if self.upright_walking:  # GeneratorParams::upright_walking
            for name in UPRIGHT_JOINTS:
                if name not in js.joint_names:
                    continue
                j = js.joint_names.index(name)
                for k, d in enumerate(self.dynamic):
                    if d is not None:
                        q = np.array(d.q, dtype=np.float64, copy=True)
                        q[:, j] -= q[:, j].mean() - js.q_stand[j]
                        self.dynamic[k] = dataclasses.replace(d, q=q)
        self.static = [None] * 3
        for s in static_clips:
            if self.static[s.axis] is not None:
                raise ValueError(f"static clip '{s.name}': a second clip for the same posture axis")
            self.static[s.axis] = s
        self.tables = [None if d is None else displacement_table(d) for d in self.dynamic]
        for k, t in enumerate(self.tables):
            if t is None:
                continue
            a, d = t
            if d.shape != (a.shape[0], 3) or a.shape[0] < 2 or a[0] != 0.0 or np.any(np.diff(a) <= 0) or \
                    np.any(np.diff(self.dynamic[k].direction * d[:, self.dynamic[k].axis]) <= 0):
                raise ValueError(f"clip '{self.dynamic[k].name}': implied_motion: expected amplitudes from 0, strictly "
                                 f"increasing, and the clip's own axis growing with them (K x 3 velocities)")
        self.consistency = consistency
        if consistency is not None:
            rows = 1
            for g in consistency.grid:
                g = np.asarray(g, float)
                if g.size < 1 or np.any(np.diff(g) <= 0):
                    raise ValueError("consistency map: every grid axis needs >= 1 strictly increasing values")
                rows *= g.size
            if consistency.delta.shape != (rows, 3) or not np.all(np.isfinite(consistency.delta)):
                raise ValueError(f"consistency map: delta is {consistency.delta.shape}, expected ({rows}, 3) finite")
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


def _table_at(xp, table, e, column):
    """MotionGenerator::tableAt: displacement of @p table on @p column at amplitude e (piecewise linear)."""
    a, d = table
    K = a.shape[0]
    k = xp.sum(e > xp.asarray(a[1:K - 1])) if K > 2 else 0
    aa, dd = xp.asarray(a), xp.asarray(d[:, column])
    f = xp.clip((e - aa[k]) / (aa[k + 1] - aa[k]), 0.0, 1.0)
    return (1.0 - f) * dd[k] + f * dd[k + 1]


def _table_inverse(xp, table, target, column, direction):
    """MotionGenerator::tableInverse: amplitude at which @p table reaches |displacement| target on its
    own axis (grows along @p direction). Returns (amplitude, saturated)."""
    a, d = table
    K = a.shape[0]
    dd = direction * np.asarray(d[:, column], float)
    last = dd[K - 1]
    k = xp.sum(target > xp.asarray(dd[1:K - 1])) if K > 2 else 0
    ddx, aa = xp.asarray(dd), xp.asarray(a)
    d0, d1 = ddx[k], ddx[k + 1]
    f = xp.clip((target - d0) / (d1 - d0), 0.0, 1.0)
    e = (1.0 - f) * aa[k] + f * aa[k + 1]
    return xp.where(target >= last, a[K - 1], e), target > last


MAP_KEYS = ("vx", "vy", "wz", "height", "pitch")


def _lookup_correction(xp, cmap: ConsistencyMap, u, height, pitch):
    """MotionGenerator::lookupCorrection: multilinear Δu at (v_x, v_y, omega, height, pitch), inputs clamped to the grid."""
    x = [u[0], u[1], u[2], height, pitch]
    D = len(MAP_KEYS)
    sizes = [int(np.asarray(g).size) for g in cmap.grid]
    lo, frac = [], []
    for dim in range(D):
        g = np.asarray(cmap.grid[dim], float)
        n = sizes[dim]
        if n == 1:
            lo.append(0)
            frac.append(0.0)
            continue
        v = xp.clip(x[dim], g[0], g[n - 1])
        k = xp.sum(v > xp.asarray(g[1:n - 1])) if n > 2 else 0
        gx = xp.asarray(g)
        lo.append(k)
        frac.append((v - gx[k]) / (gx[k + 1] - gx[k]))
    stride = [0] * (D - 1) + [1]
    for dim in range(D - 2, -1, -1):
        stride[dim] = stride[dim + 1] * sizes[dim + 1]
    delta = xp.asarray(cmap.delta)
    corr = 0.0 * xp.asarray(delta[0])
    for corner in range(1 << D):
        bits = [(corner >> dim) & 1 for dim in range(D)]
        if any(b and sizes[dim] == 1 for dim, b in enumerate(bits)):
            continue
        w = 1.0
        row = 0
        for dim in range(D):
            w = w * (frac[dim] if bits[dim] else 1.0 - frac[dim])
            row = row + (lo[dim] + bits[dim]) * stride[dim]
        corr = corr + w * delta[row]
    return corr


def step(model: GeneratorModel, phase, u_d, u_s, dt, xp=np):
    """One generator tick for one robot (MotionGenerator::step). Under JAX, vmap over robots.

    phase: scalar in [0, 1). u_d: (3,) (v_x, v_y, omega) [m/s, m/s, rad/s], heading frame.
    u_s: (3,) (pitch [rad], roll [rad], height [m]; height <= 0 = standing height). dt [s] > 0.
    Returns a dict with the GeneratorOutput fields (phase, next_phase, period, q_ref, qd_ref, alpha,
    weight, amplitude, clip_direction, amplitude_saturated, command_correction, ..., v_base,
    omega_base, yaw_rate, base_height). Non-finite commands are not handled here (training never
    produces them).
    """
    js = model.js
    u = xp.clip(xp.asarray(u_d, dtype=xp.float64 if xp is np else None), -model.max_command, model.max_command)
    zero = 0.0 * u[0]
    # Posture offset (evalPosture).
    q_post = xp.zeros(model.n)
    beta = []
    height_offset = 0.0
    posture_height = js.standing_base_height + zero  # postureHeight()
    for a in range(3):
        s = model.static[a]
        if s is None:
            beta.append(zero)
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
            posture_height = value

    # kConsistent: the residual correction of the consistency map.
    consistent = model.blending == "consistent"
    correction = xp.zeros(3) + zero
    if consistent and model.consistency is not None:
        correction = _lookup_correction(xp, model.consistency, u, posture_height, u_s[0] + zero)
        u = u + correction

    # Weights (eqs. 4, 6) of the clip of each (corrected) command's sign; both signs are evaluated
    # and selected with where (JAX-friendly).
    present = [model.dynamic[2 * i] is not None or model.dynamic[2 * i + 1] is not None for i in range(3)]
    sign = [xp.where(u[i] < 0, -1.0, 1.0) for i in range(3)]

    def per_clip(i, direction, fn):
        pos, neg = model.dynamic[2 * i], model.dynamic[2 * i + 1]
        return xp.where(direction < 0, fn(neg), fn(pos))

    sum_abs = sum(xp.abs(u[i]) for i in range(3) if present[i]) + zero
    weight, alpha = [], []
    for i in range(3):
        if not present[i]:
            weight.append(zero); alpha.append(zero); continue
        nominal = per_clip(i, sign[i], lambda c: c.nominal_scale)
        alpha.append(xp.clip(xp.abs(u[i]) / nominal, 0.0, 1.0))
        weight.append(xp.abs(u[i]) / (sum_abs + model.epsilon))
    sum_w = weight[0] + weight[1] + weight[2]
    w_stand = 1.0 - sum_w

    period = w_stand * model.t_stand
    for i in range(3):
        if present[i]:
            period = period + weight[i] * per_clip(i, sign[i], lambda c: c.period)

    # Effective amplitudes e_i and the clip each axis plays (direction d_i).
    saturated = [xp.asarray(False)] * 3
    cadence_ratio = 1.0 + zero
    if consistent:
        def displacement(j, direction_j, e, column):  # D_j,s_j(e)[column]
            return xp.where(direction_j < 0, _table_at(xp, model.tables[2 * j + 1], e, column),
                            _table_at(xp, model.tables[2 * j], e, column))

        def solve(period):  # solveConsistentAmplitudes: fixed Gauss-Seidel sweeps; returns (amp, direction, sat, rho)
            def sweep(carry):
                amp, direction, sat = (list(c) for c in carry)
                for i in range(3):
                    if not present[i]:
                        amp[i] = zero
                        continue
                    r = u[i] * period
                    for j in range(3):
                        if j == i or not present[j]:
                            continue
                        r = r - xp.where(amp[j] > 0.0, displacement(j, direction[j], amp[j], i), 0.0)
                    target = xp.abs(r)
                    e_pos, s_pos = _table_inverse(xp, model.tables[2 * i], target, i, 1)
                    e_neg, s_neg = _table_inverse(xp, model.tables[2 * i + 1], target, i, -1)
                    neg = r < 0
                    amp[i] = xp.where(neg, e_neg, e_pos)
                    sat[i] = xp.where(neg, s_neg, s_pos)
                    direction[i] = xp.where(neg, -1.0, 1.0)
                return tuple(amp), tuple(direction), tuple(sat)

            carry = ((zero, zero, zero), tuple(sign), (xp.asarray(False),) * 3)
            amp, direction, sat = (list(c) for c in loops.repeat(xp, KCONSISTENT_SWEEPS, sweep, carry))
            rho = 1.0 + zero
            for i in range(3):
                if not present[i]:
                    continue
                need = u[i] * period
                got = zero
                for j in range(3):
                    if present[j]:
                        got = got + xp.where(amp[j] > 0.0, displacement(j, direction[j], amp[j], i), 0.0)
                use = xp.logical_and(sat[i], xp.abs(need) >= 1e-12)
                share = xp.maximum(0.0, got / xp.where(use, need, 1.0))
                rho = xp.where(use, xp.minimum(rho, share), rho)
            return amp, direction, sat, rho

        # A stride at its end steps faster (generator.hpp): a second solve at the period shortened by rho < 1.
        # With rho = 1 that period is the first one (p x 1.0) and the second solve repeats the first bit for bit,
        # so both passes are one loop body (compiled once under JAX) and the last pass's result is the answer.
        def solve_pass(carry):
            p_next = carry[0]
            amp, direction, sat, rho = solve(p_next)
            shorter = p_next * xp.clip(rho, 1.0 / max(model.max_cadence_ratio, 1.0), 1.0)
            return shorter, p_next, tuple(amp), tuple(direction), tuple(sat)

        passes = 2 if model.max_cadence_ratio > 1.0 else 1
        carry = (period, period, (zero, zero, zero), tuple(sign), (xp.asarray(False),) * 3)
        _, period_solved, amp, direction, saturated = loops.repeat(xp, passes, solve_pass, carry)
        amp, direction, saturated = list(amp), list(direction), list(saturated)
        if passes == 2:
            cadence_ratio = xp.where(period_solved < period, period / period_solved, 1.0)
            period = period_solved
        alpha = list(amp)
    else:
        amp = [weight[i] * alpha[i] for i in range(3)]
        direction = list(sign)

    h = 0.5 / model.max_samples
    q_stand = xp.asarray(js.q_stand)
    e_sum = sum(amp[i] for i in range(3) if present[i]) + zero

    def blend(phi):  # blendJoints: q_stand + sum_i e_i (q_Di(phi) - q_stand)
        q = (1.0 - e_sum) * q_stand
        for i in range(3):
            if present[i]:
                q = q + amp[i] * per_clip(i, direction[i], lambda c: _interp_rows(xp, xp.asarray(c.q), phi))
        return q

    if xp is np:
        q_minus, q_plus, q_dyn = blend(phase - h), blend(phase + h), blend(phase)
    else:  # one batched blend (the same arithmetic per phase; traced and compiled once)
        import jax
        q_minus, q_plus, q_dyn = jax.vmap(blend)(xp.stack([phase - h, phase + h, phase + zero]))

    # Contacts (eqs. 8-9); kConsistent splits the walking share sum_w among the played clips by e_i.
    cw, cdir = list(weight), list(sign)
    if consistent:
        big = e_sum > 1e-12
        for i in range(3):
            if present[i]:
                cw[i] = xp.where(big, sum_w * amp[i] / xp.where(big, e_sum, 1.0), weight[i])
                cdir[i] = xp.where(big, direction[i], sign[i])
    mu_f, sigma_f, in_contact = [], [], []
    for f in range(2):
        mu, sigma = 0.0, 0.5 * w_stand
        for i in range(3):
            if present[i]:
                mu = mu + cw[i] * per_clip(i, cdir[i], lambda c: c.contact[f, 0])
                sigma = sigma + cw[i] * per_clip(i, cdir[i], lambda c: c.contact[f, 1])
        m = xp.where(sum_w > 0, wrap_phase(xp, mu / xp.where(sum_w > 0, sum_w, 1.0)), 0.0)
        sg = xp.clip(sigma, 0.0, 0.5)
        mu_f.append(m); sigma_f.append(sg)
        in_contact.append(xp.logical_or(phase_distance(xp, phase, m) < sg, sg >= 0.5))

    v_base = xp.zeros(3)
    omega_base = xp.zeros(3)
    height = js.standing_base_height + zero
    for i in range(3):
        if not present[i]:
            continue
        e = amp[i]
        v_base = v_base + e * per_clip(i, direction[i], lambda c: _interp_rows(xp, xp.asarray(c.v_base), phase))
        omega_base = omega_base + e * per_clip(i, direction[i],
                                               lambda c: _interp_rows(xp, xp.asarray(c.omega_base), phase))
        h_clip = per_clip(i, direction[i], lambda c: _interp_rows(xp, xp.asarray(c.base_height), phase))
        height = height + e * (h_clip - js.standing_base_height)
    base_height = height + height_offset

    q_raw = q_dyn + q_post
    lower, upper = xp.asarray(js.lower), xp.asarray(js.upper)
    q_ref = xp.clip(q_raw, lower, upper)
    clamped = xp.sum(xp.logical_or(q_raw < lower, q_raw > upper))
    qd_ref = (q_plus - q_minus) / (2.0 * h * period)
    next_phase = wrap_phase(xp, phase + dt / period)
    stack = lambda xs: xp.stack([xp.asarray(x) for x in xs])
    return {"phase": phase, "next_phase": next_phase, "period": period, "cadence_ratio": cadence_ratio,
            "q_ref": q_ref, "qd_ref": qd_ref, "q_posture": q_post,
            "alpha": stack(alpha), "weight": stack(weight), "amplitude": stack(amp),
            "clip_direction": stack(direction), "amplitude_saturated": xp.sum(stack(saturated).astype(xp.int32)),
            "command_correction": correction, "standing_weight": w_stand, "beta": stack(beta),
            "contact_mu": xp.stack(mu_f), "contact_sigma": xp.stack(sigma_f), "in_contact": xp.stack(in_contact),
            "v_base": v_base, "omega_base": omega_base, "yaw_rate": omega_base[2], "base_height": base_height,
            "clamped_joints": clamped}


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
    """Reads one clip file (docs/clip_format.md) -> Clip or StaticClip (with its optional implied_motion)."""
    import yaml
    with open(path) as f:
        d = yaml.safe_load(f)
    if d["kind"] == "dynamic":
        ia = iv = None
        im = d.get("implied_motion")
        if im is not None:
            ia, iv = np.array(im["amplitude"], float), np.array(im["velocity"], float)
            if ia.ndim != 1 or iv.shape != (ia.size, 3):
                raise ValueError(f"{path}: implied_motion: expected K amplitudes and K x 3 velocities, got "
                                 f"{ia.shape} and {iv.shape}")
        return Clip(d["name"], AXES.index(d["axis"]), int(d["direction"]), float(d["nominal_scale"]), float(d["period"]),
                    np.array(d["q"], float), np.array(d["qd"], float), np.array(d["v_base"], float),
                    np.array(d["omega_base"], float), np.array(d["base_height"], float),
                    np.array([[d["contact"]["left"]["mu"], d["contact"]["left"]["sigma"]],
                              [d["contact"]["right"]["mu"], d["contact"]["right"]["sigma"]]], float), ia, iv)
    return StaticClip(d["name"], POSTURE_AXES.index(d["axis"]), np.array(d["values"], float), float(d["neutral"]),
                      np.array(d["q"], float))


def load_consistency_map(path):
    """Reads consistency_map.yaml (pmg::readConsistencyMap, docs/clip_format.md) -> ConsistencyMap."""
    import yaml
    with open(path) as f:
        d = yaml.safe_load(f)
    if not isinstance(d, dict) or d.get("kind") != "consistency_map":
        raise ValueError(f"{path}: kind: expected 'consistency_map'")
    grid = [np.atleast_1d(np.array(d[k], float)) for k in MAP_KEYS]
    delta = np.array(d["delta"], float).reshape(-1, 3)
    if delta.shape[0] != int(np.prod([g.size for g in grid])) or np.any(np.abs(delta) > 2.0):
        raise ValueError(f"{path}: delta: expected {int(np.prod([g.size for g in grid]))} rows of 3 values, |value| <= 2")
    return ConsistencyMap(grid, delta)


def load_library(clips, js: JointSpace, blending="consistent", **kwargs):
    """GeneratorModel from a clip folder (every *.yaml, consistency_map.yaml as the map) or a list of
    files (consistency_map.yaml in the list, else beside the clips, is the map; pmg::loadClipLibrary).
    Files are read every call (another tool may regenerate the folder)."""
    import glob
    import os
    if isinstance(clips, str):
        files = sorted(glob.glob(os.path.join(clips, "*.yaml")))
        if not files:
            raise FileNotFoundError(f"{clips}: no clip files (*.yaml)")
    else:
        files = list(clips)
    map_files = [f for f in files if os.path.basename(f) == CONSISTENCY_MAP_FILE]
    clip_files = [f for f in files if os.path.basename(f) != CONSISTENCY_MAP_FILE]
    if not map_files and clip_files:
        beside = os.path.join(os.path.dirname(clip_files[0]), CONSISTENCY_MAP_FILE)
        if os.path.isfile(beside) and all(os.path.dirname(f) == os.path.dirname(clip_files[0]) for f in clip_files):
            map_files = [beside]
    cmap = load_consistency_map(map_files[0]) if map_files else None
    loaded = [load_clip_file(f) for f in clip_files]
    model = GeneratorModel([c for c in loaded if isinstance(c, Clip)], [c for c in loaded if isinstance(c, StaticClip)],
                           js, blending=blending, consistency=cmap, **kwargs)
    model.clip_files = clip_files
    model.map_file = map_files[0] if map_files else None
    return model


def model_from_vectors(v, blending=None, upright_walking=False):
    """GeneratorModel from a pmg_generator_vectors JSON document (its "blending" unless @p blending)."""
    js = JointSpace(v["joint_names"], np.array(v["q_stand"]), np.array(v["lower"]), np.array(v["upper"]),
                    np.array(v["mirror_index"], int), np.array(v["mirror_sign"], float), v["standing_base_height"])

    def implied(c, k):
        im = c.get("implied_motion")
        return None if im is None else np.array(im[k], float)

    dyn = [Clip(c["name"], c["axis"], c["direction"], c["nominal_scale"], c["period"], np.array(c["q"]),
                np.array(c["qd"]), np.array(c["v_base"]), np.array(c["omega_base"]), np.array(c["base_height"]),
                np.array(c["contact"]), implied(c, "amplitude"), implied(c, "velocity")) for c in v["dynamic_clips"]]
    sta = [StaticClip(s["name"], s["axis"], np.array(s["values"]), s["neutral"], np.array(s["q"]))
           for s in v["static_clips"]]
    m = v.get("consistency_map")
    cmap = None if m is None else ConsistencyMap([np.atleast_1d(np.array(m[k], float)) for k in MAP_KEYS],
                                                 np.array(m["delta"], float).reshape(-1, 3))
    return GeneratorModel(dyn, sta, js, v["epsilon"], v["max_command"], blending or v.get("blending", "paper"), cmap,
                          v["max_cadence_ratio"], upright_walking)
