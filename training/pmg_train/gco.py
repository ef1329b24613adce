"""Python/JAX port of Ground-aware Command Optimization (include/pmg/gco/gco.hpp, PMG eqs. 13-19).

The full-PMG training configuration observes u' (eq. 19) exactly as the C++ controller computes it
(pmg::gco::GeneratorWithGco). This module re-implements Gco::solve for one robot as pure functions
of (generator output, GCO state) that run on NumPy (float64, for the equality test) or JAX (vmap
over environments; pass ``xp=jax.numpy``). ``training/tests/test_gco_port.py`` (ctest
``gco_port_equals_cpp``) steps this port next to the C++ GeneratorWithGco on the vectors of
apps/policy/pmg_generator_vectors and requires u', Δ and the contact weights to agree to 1e-5.

Model (frames as in gco.hpp: H heading frame, B pelvis, F foot, S sole point; the pelvis is held
level, R_HB = I, as fillFromGenerator() does):
  r_f = p_BS_B(q_f)                       (eq. 13, leg forward kinematics, KDL chain pelvis -> sole)
  v_f(x) = v + x_v + (ω + x_ω) e_z × r_f + J_v,f q̇_f      (eq. 14)
  ω_f,z(x) = ω + x_ω + (J_ω,f q̇_f)_z
  z_f(x) = h + x_h + r_f,z − h_ground
Residuals (eqs. 16-18): s_f-weighted foot velocity / yaw-rate / height, prior w_prior x, smoothness
w_smooth (x − x_prev), limit hinges w_limit · (u − bound) where u = base + x is outside the limits.
Every residual is affine in x (the hinges piecewise affine), so the cost is a convex piecewise
quadratic with a unique minimum (the prior makes it strictly convex). The C++ code finds it with
ceres::TinySolver (Levenberg-Marquardt, <= 20 iterations); this port solves the 4x4 normal
equations on the active hinge set and re-solves until the active set is stable (4 passes, which
covers every change of the active set the 4 hinges allow). Both converge to the same point; the
C++ fallback to the last good solution on a solver failure never triggers on finite input of this
linear problem and is not ported. After the solve u' is clamped to the limits and to the per-tick
jump bound, as in C++.

Leg kinematics: the KDL chain exported by pmg_generator_vectors (per segment the pose at q = 0,
the joint axis and a point on it, both in the segment's base frame). A revolute segment at angle q
is the rotation by q about that axis line followed by its q = 0 pose.
"""
from __future__ import annotations

import dataclasses
import json

import numpy as np

from . import loops

NUM_FEET = 2
LEG_DOFS = 6
# StrideAdaptationOptions{} (stride_adaptation.hpp), for model files written before it existed.
# standing_hold: False for files written before it existed (2026-12-04), whose C++ decayed every offset standing.
STRIDE_DEFAULTS = {"touchdown_lead": 0.5, "return_fraction": 0.7, "standing_time_constant": 0.3, "standing_hold": False,
                   "stepping_margin": 0.02,
                   "max_offset": 0.15, "max_offset_height": 0.03, "max_offset_yaw": 0.4, "max_offset_speed": 1.0,
                   "max_offset_yaw_rate": 3.0, "iterations": 3, "max_correction": 0.6, "height_weight": 0.3,
                   "damping": 1e-3, "max_correction_rate": 4.0, "sole_half_length": 0.085, "rolling_slope": 0.05}


@dataclasses.dataclass
class LegChains:
    """Per foot: list of segments (pose0 (4,4), axis (3,), origin (3,), revolute bool)."""
    segments: list
    leg_joint_index: np.ndarray  # (2, 6) column of each chain joint in the robot joint vector

    @staticmethod
    def from_doc(doc):
        segs = []
        for chain in doc["leg_chains"]:
            segs.append([(np.array(s["pose0"], float), np.array(s["axis"], float), np.array(s["origin"], float),
                          bool(s["revolute"])) for s in chain])
        return LegChains(segs, np.array(doc["leg_joint_index"], int))


@dataclasses.dataclass
class GcoOptions:
    dt: float
    ground_height: float
    w_foot_velocity: float
    w_foot_yaw_rate: float
    w_foot_height: float
    w_prior: np.ndarray    # (4,) v_x, v_y, ω, h
    w_smooth: np.ndarray   # (4,)
    w_limit: float
    lo: np.ndarray         # (4,) limits of (v'_x, v'_y, ω', h')
    hi: np.ndarray
    contact_ramp_time: float
    jump: np.ndarray       # (4,) per-tick bound on the change of u'
    # Stance sole levelling of the reference (sole_levelling.hpp; SoleLevellingOptions). `enabled`
    # is the training's choice (EnvConfig.sole_levelling), not the file's.
    level_edge_fraction: float = 0.5
    level_iterations: int = 3
    level_max_correction: float = 0.4
    # Stride adaptation of the reference (stride_adaptation.hpp; StrideAdaptationOptions, same names).
    # `enabled` is the training's choice (EnvConfig.stride_adaptation), not the file's.
    stride: dict = dataclasses.field(default_factory=lambda: dict(STRIDE_DEFAULTS))

    @staticmethod
    def from_doc(doc):
        o = doc["gco_options"]
        return GcoOptions(o["dt"], o["ground_height"], o["w_foot_velocity"], o["w_foot_yaw_rate"], o["w_foot_height"],
                          np.array([o["w_prior_velocity"], o["w_prior_velocity"], o["w_prior_yaw_rate"],
                                    o["w_prior_height"]]),
                          np.array([o["w_smooth_velocity"], o["w_smooth_velocity"], o["w_smooth_yaw_rate"],
                                    o["w_smooth_height"]]),
                          o["w_limit"], np.array(o["limits_lo"], float), np.array(o["limits_hi"], float),
                          o["contact_ramp_time"],
                          np.array([o["max_jump_velocity"], o["max_jump_velocity"], o["max_jump_yaw_rate"],
                                    o["max_jump_height"]]),
                          *((o["sole_levelling"]["edge_fraction"], int(o["sole_levelling"]["iterations"]),
                             o["sole_levelling"]["max_correction"]) if "sole_levelling" in o else (0.5, 3, 0.4)),
                          dict(STRIDE_DEFAULTS, **o.get("stride_adaptation", {})))


def load_model(path):
    """(LegChains, GcoOptions) from a JSON written by pmg_generator_vectors (--gco-model-out)."""
    with open(path) as f:
        doc = json.load(f)
    return LegChains.from_doc(doc), GcoOptions.from_doc(doc)


def _rot(xp, axis, q):
    """Rotation matrix by angle q about the unit vector axis (Rodrigues)."""
    k = xp.asarray(axis)
    K = xp.asarray([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    c, s = xp.cos(q), xp.sin(q)
    return c * xp.eye(3) + s * K + (1.0 - c) * xp.outer(k, k)


def _chain_fk(chains: LegChains, foot: int, q, xp=np):
    """Sole position p_BS_B, foot orientation R_BF and, per revolute joint, its axis and a point on
    it, all in the pelvis frame B. q: (6,) chain order [rad]."""
    R = xp.eye(3)
    p = xp.zeros(3)
    axes, points = [], []
    i = 0
    for pose0, axis, origin, revolute in chains.segments[foot]:
        if revolute:
            axes.append(R @ xp.asarray(axis))           # joint axis in B
            points.append(p + R @ xp.asarray(origin))   # a point on the axis in B
            Rq = _rot(xp, axis, q[i])
            Rs = Rq @ xp.asarray(pose0[:3, :3])
            ps = Rq @ (xp.asarray(pose0[:3, 3]) - xp.asarray(origin)) + xp.asarray(origin)
            i += 1
        else:
            Rs, ps = xp.asarray(pose0[:3, :3]), xp.asarray(pose0[:3, 3])
        p = p + R @ ps
        R = R @ Rs
    return p, R, axes, points


def foot_kinematics(chains: LegChains, foot: int, q, qd, xp=np):
    """Sole position p_BS_B [m], sole velocity J_v q̇ [m/s] and foot angular velocity J_ω q̇
    [rad/s] relative to the pelvis, pelvis frame B. q, qd: (6,) chain order [rad], [rad/s]."""
    p, _, axes, points = _chain_fk(chains, foot, q, xp)
    v = xp.zeros(3)
    w = xp.zeros(3)
    for k in range(len(axes)):
        w = w + axes[k] * qd[k]
        v = v + xp.cross(axes[k], p - points[k]) * qd[k]
    return p, v, w


def sole_levelling_weight(mu, sigma, phase, edge_fraction, xp=np):
    """λ_f = clamp((σ − d) / (edge_fraction σ), 0, 1), d = circular |φ − μ| (SoleLevelling::weightAt)."""
    wrap = lambda x: x - xp.floor(x)
    d0 = xp.abs(wrap(phase) - wrap(mu))
    d = xp.minimum(d0, 1.0 - d0)
    ramp = edge_fraction * sigma
    return xp.where(ramp > 0.0, xp.clip((sigma - d) / xp.where(ramp > 0.0, ramp, 1.0), 0.0, 1.0), 0.0)


def level_soles(chains: LegChains, opt: GcoOptions, gen_out, q_stand, lower, upper, state, xp=np):
    """Stance sole levelling of one generator tick (pmg::gco::SoleLevelling::apply, sole_levelling.hpp).

    gen_out: the generator port's output (q_ref, qd_ref, q_posture, phase, contact_mu, contact_sigma);
    q_stand, lower, upper: (n) standing pose and joint limits [rad]; state: the GCO state dict (its
    "lev_applied" (2, 2) and "have_prev"). Per foot: `level_iterations` Gauss-Newton steps on the
    ankle pitch/roll offsets δ that turn the sole normal R_BF e_z onto the one of the posture-only
    pose q_stand + q_posture, bounded to ±level_max_correction and the joint limits; the reference
    gets λ_f δ_f added (and its finite difference / dt added to q̇, 0 on the first tick).
    Returns (gen_out with q_ref/qd_ref replaced, δ (2, 2), λ (2,), new state)."""
    q_ref, qd_ref = xp.asarray(gen_out["q_ref"]), xp.asarray(gen_out["qd_ref"])
    q_post = xp.asarray(q_stand) + xp.asarray(gen_out["q_posture"])
    lower, upper = xp.asarray(lower), xp.asarray(upper)
    deltas, weights = [], []
    for f in range(NUM_FEET):
        idx = chains.leg_joint_index[f]
        q = q_ref[idx]
        _, R_t, _, _ = _chain_fk(chains, f, q_post[idx], xp)
        n_target = R_t[:, 2]
        lo = xp.maximum(-opt.level_max_correction, lower[idx[4:]] - q[4:])
        hi = xp.minimum(opt.level_max_correction, upper[idx[4:]] - q[4:])
        def gauss_newton(delta, f=f, q=q, n_target=n_target, lo=lo, hi=hi):
            qc = xp.concatenate([q[:4], q[4:] + delta])
            _, R, axes, _ = _chain_fk(chains, f, qc, xp)
            n = R[:, 2]
            J = xp.stack([xp.cross(axes[4], n), xp.cross(axes[5], n)], axis=1)  # (3, 2)
            H = J.T @ J + 1e-9 * xp.eye(2)
            delta = delta - xp.linalg.solve(H, J.T @ (n - n_target))
            return xp.where(lo <= hi, xp.clip(delta, lo, hi), 0.0)
        deltas.append(loops.repeat(xp, opt.level_iterations, gauss_newton, xp.zeros_like(q[4:])))
        weights.append(sole_levelling_weight(gen_out["contact_mu"][f], gen_out["contact_sigma"][f], gen_out["phase"],
                                             opt.level_edge_fraction, xp))
    delta = xp.stack(deltas)
    lam = xp.stack(weights)
    applied = lam[:, None] * delta
    rate = xp.where(state["have_prev"], (applied - state["lev_applied"]) / opt.dt, 0.0)
    idx = xp.asarray(chains.leg_joint_index)[:, 4:]  # (2, 2): ankle pitch, ankle roll of each foot
    q_new = q_ref.at[idx.ravel()].add(applied.ravel()) if hasattr(q_ref, "at") else _add_np(q_ref, idx, applied)
    qd_new = qd_ref.at[idx.ravel()].add(rate.ravel()) if hasattr(qd_ref, "at") else _add_np(qd_ref, idx, rate)
    out = dict(gen_out)
    out["q_ref"], out["qd_ref"] = q_new, qd_new
    new_state = dict(state)
    new_state["lev_applied"] = applied
    return out, delta, lam, new_state


def _add_np(x, idx, values):
    y = np.array(x, dtype=float, copy=True)
    y[np.asarray(idx).ravel()] += np.asarray(values).ravel()
    return y


def initial_state(xp=np):
    """GCO state after construction / reset(): no contact ramps, no previous solution; the
    stride adaptation's offsets zero (its "sa_*" entries, StrideAdaptation's members)."""
    return {"s": xp.zeros(2), "x": xp.zeros(4), "u_prev": xp.zeros(4), "have_prev": xp.asarray(False),
            "lev_applied": xp.zeros((2, 2)),
            "sa_started": xp.asarray(False), "sa_height": xp.asarray(0.0), "sa_contact": xp.ones(2, bool),
            "sa_offset": xp.zeros((2, 3)), "sa_yaw": xp.zeros(2), "sa_lo_offset": xp.zeros((2, 3)),
            "sa_lo_yaw": xp.zeros(2), "sa_p": xp.zeros((2, 3)), "sa_R": xp.stack([xp.eye(3), xp.eye(3)]),
            "sa_applied": xp.zeros((2, 6))}


def _leg_jacobian(chains: LegChains, foot: int, q, xp=np):
    """Sole pose (p_BS_B, R_BF) and the geometric Jacobian of S in B, rows (v; ω), (6, 6)."""
    p, R, axes, points = _chain_fk(chains, foot, q, xp)
    Jv = xp.stack([xp.cross(axes[k], p - points[k]) for k in range(len(axes))], axis=1)
    Jw = xp.stack(axes, axis=1)
    return p, R, xp.concatenate([Jv, Jw], axis=0)


def _rotation_vector(M, xp=np):
    """θ·axis of the rotation matrix M (Eigen::AngleAxisd(M): angle · axis), for |θ| < π."""
    s = 0.5 * xp.stack([M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]])  # sin θ · axis
    n = xp.sqrt(xp.sum(s * s))
    theta = xp.arctan2(n, 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0))
    return s * xp.where(n > 1e-300, theta / xp.where(n > 1e-300, n, 1.0), 1.0)


def _bound_norm(v, bound, xp=np):
    n = xp.sqrt(xp.sum(v * v))
    return xp.where(n > bound, v * (bound / xp.where(n > bound, n, 1.0)), v)


def adapt_strides(chains: LegChains, opt: GcoOptions, gen_out, u_d, lower, upper, state, xp=np):
    """Stride adaptation of one reference tick (pmg::gco::StrideAdaptation::apply, stride_adaptation.hpp):
    the stance soles held still in the world under the command u_d = (v_x, v_y, ω), the swing foot
    landing ahead by touchdown_lead times its lift-off offset, by damped inverse kinematics of each leg.

    gen_out: the generator (and levelling) output (q_ref, qd_ref, phase, contact_mu, contact_sigma,
    in_contact, base_height); lower, upper: (n) joint limits [rad]; state: the GCO state dict (its
    "sa_*" entries). The failure paths of the C++ (non-finite input, KDL errors) are not ported.
    Returns (gen_out with q_ref/qd_ref replaced, δ (2, 6), e (2, 3), new state)."""
    o = opt.stride
    dt = opt.dt
    q_ref, qd_ref = xp.asarray(gen_out["q_ref"]), xp.asarray(gen_out["qd_ref"])
    lower, upper = xp.asarray(lower), xp.asarray(upper)
    first = ~xp.asarray(state["sa_started"])
    h = gen_out["base_height"]
    height_rate = xp.where(first, 0.0, (h - state["sa_height"]) / dt)
    vx, vy, wz = u_d[0], u_d[1], u_d[2]
    contact = xp.asarray(gen_out["in_contact"]).astype(bool)
    lead = o["touchdown_lead"]
    offsets, yaws, lo_offsets, lo_yaws, ps, Rs, deltas = [], [], [], [], [], [], []
    for f in range(NUM_FEET):
        idx = chains.leg_joint_index[f]
        q = q_ref[idx]
        p_S, R, _, _ = _chain_fk(chains, f, q, xp)
        p_prev = xp.where(first, p_S, state["sa_p"][f])
        R_prev = xp.where(first, R, state["sa_R"][f])
        e, psi = state["sa_offset"][f], state["sa_yaw"][f]
        # Stance: hold the point the foot rolls on still under the command.
        sigma, mu, phase = gen_out["contact_sigma"][f], gen_out["contact_mu"][f], gen_out["phase"]
        walking = xp.clip((0.5 - sigma) / o["stepping_margin"], 0.0, 1.0)
        toe_down = -R[2, 0]
        c_x = o["sole_half_length"] * xp.clip(toe_down / o["rolling_slope"], -1.0, 1.0)
        c_now = p_S + R[:, 0] * c_x
        moved = c_now - (p_prev + R_prev[:, 0] * c_x)
        p = c_now + e
        still = xp.stack([-vx + wz * p[1], -vy - wz * p[0], -height_rate])
        d_yaw = xp.arctan2(R[1, 0], R[0, 0]) - xp.arctan2(R_prev[1, 0], R_prev[0, 0])
        d_yaw = d_yaw - 2.0 * np.pi * xp.round(d_yaw / (2.0 * np.pi))
        tau = o["standing_time_constant"]
        # Standing: with standing_hold only the height part decays (the feet stay where they landed).
        decay_xy = 0.0 if o["standing_hold"] else 1.0
        standing_decay = e * xp.array([decay_xy, decay_xy, 1.0])
        rate_st = walking * (still - moved / dt) - (1.0 - walking) * standing_decay / tau
        yaw_rate_st = walking * (-wz - d_yaw / dt) - (1.0 - walking) * decay_xy * psi / tau
        # Swing: from the lift-off offset toward −lead times it (height to 0).
        lifting = state["sa_contact"][f] | first
        lo_e = xp.where(lifting, e, state["sa_lo_offset"][f])
        lo_psi = xp.where(lifting, psi, state["sa_lo_yaw"][f])
        s = phase - mu - xp.floor(phase - mu)
        in_window = (s < sigma) | (s > 1.0 - sigma)
        prog = xp.where((sigma < 0.5) & ~in_window,
                        xp.clip((s - sigma) / xp.where(sigma < 0.5, 1.0 - 2.0 * sigma, 1.0), 0.0, 1.0), 0.0)
        a = xp.clip(prog / o["return_fraction"], 0.0, 1.0)
        a = a * a * (3.0 - 2.0 * a)
        touchdown = xp.stack([-lead * lo_e[0], -lead * lo_e[1], 0.0 * lo_e[2]])
        target = lo_e + a * (touchdown - lo_e)
        target_yaw = lo_psi + a * (-lead * lo_psi - lo_psi)
        rate_sw = (target - e) / dt
        yaw_rate_sw = (target_yaw - psi) / dt
        rate = xp.where(contact[f], rate_st, rate_sw)
        yaw_rate = xp.where(contact[f], yaw_rate_st, yaw_rate_sw)
        rate = _bound_norm(rate, o["max_offset_speed"], xp)
        yaw_rate = xp.clip(yaw_rate, -o["max_offset_yaw_rate"], o["max_offset_yaw_rate"])
        e = e + rate * dt
        psi = psi + yaw_rate * dt
        e = xp.concatenate([e[:2], xp.clip(e[2:], -o["max_offset_height"], o["max_offset_height"])])
        e = _bound_norm(e, o["max_offset"], xp)
        psi = xp.clip(psi, -o["max_offset_yaw"], o["max_offset_yaw"])
        # Inverse kinematics to the target pose (p_S + e, Rz(ψ) R), from the last tick's δ.
        c, sn = xp.cos(psi), xp.sin(psi)
        Rz = xp.stack([xp.stack([c, -sn, 0.0 * c]), xp.stack([sn, c, 0.0 * c]), xp.stack([0.0 * c, 0.0 * c, 1.0 + 0.0 * c])])
        p_t, R_t = p_S + e, Rz @ R
        last = state["sa_applied"][f]
        max_step = o["max_correction_rate"] * xp.where(first, 1e9, dt)
        lo = xp.maximum(xp.maximum(-o["max_correction"], lower[idx] - q), last - max_step)
        hi = xp.minimum(xp.minimum(o["max_correction"], upper[idx] - q), last + max_step)
        wvec = xp.asarray([1.0, 1.0, o["height_weight"], 1.0, 1.0, 1.0])
        def lm_step(delta, f=f, q=q, p_t=p_t, R_t=R_t, lo=lo, hi=hi, last=last, max_step=max_step):
            p_c, R_c, J = _leg_jacobian(chains, f, q + delta, xp)
            err = xp.concatenate([p_t - p_c, _rotation_vector(R_t @ R_c.T, xp)]) * wvec
            J = J * wvec[:, None]
            H = J.T @ J + (xp.sum(err * err) + o["damping"]) * xp.eye(LEG_DOFS)
            delta = delta + xp.linalg.solve(H, J.T @ err)
            return xp.where(lo <= hi, xp.clip(delta, lo, hi), xp.clip(0.0, last - max_step, last + max_step))
        deltas.append(loops.repeat(xp, int(o["iterations"]), lm_step, last))
        offsets.append(e)
        yaws.append(psi)
        lo_offsets.append(lo_e)
        lo_yaws.append(lo_psi)
        ps.append(p_S)
        Rs.append(R)
    delta = xp.stack(deltas)
    rate_added = xp.where(first, 0.0, (delta - state["sa_applied"]) / dt)
    idx = xp.asarray(chains.leg_joint_index)
    q_new = q_ref.at[idx.ravel()].add(delta.ravel()) if hasattr(q_ref, "at") else _add_np(q_ref, idx, delta)
    qd_new = qd_ref.at[idx.ravel()].add(rate_added.ravel()) if hasattr(qd_ref, "at") else _add_np(qd_ref, idx, rate_added)
    out = dict(gen_out)
    out["q_ref"], out["qd_ref"] = q_new, qd_new
    new_state = dict(state)
    new_state.update({"sa_started": xp.asarray(True), "sa_height": xp.asarray(h, float), "sa_contact": contact,
                      "sa_offset": xp.stack(offsets), "sa_yaw": xp.stack(yaws), "sa_lo_offset": xp.stack(lo_offsets),
                      "sa_lo_yaw": xp.stack(lo_yaws), "sa_p": xp.stack(ps), "sa_R": xp.stack(Rs), "sa_applied": delta})
    return out, delta, new_state["sa_offset"], new_state


def step(chains: LegChains, opt: GcoOptions, gen_out, u_s, state, xp=np):
    """One GCO tick after one generator tick (GeneratorWithGco::step without the generator).

    gen_out: the generator port's output dict (q_ref, qd_ref, in_contact, v_base, yaw_rate,
    base_height); u_s: posture command (pitch, roll, height) [rad, rad, m]; state: dict from
    initial_state() or the previous call. Returns (u_opt (6,) = (v'_x, v'_y, ω', pitch, roll, h')
    in H [m/s, m/s, rad/s, rad, rad, m], delta (4,), s (2,), new state).
    """
    q_ref, qd_ref = gen_out["q_ref"], gen_out["qd_ref"]
    v = xp.asarray(gen_out["v_base"])
    wz = gen_out["yaw_rate"]
    h = gen_out["base_height"]
    contact = xp.asarray(gen_out["in_contact"]).astype(bool)
    have_prev = state["have_prev"]

    # Contact weights s_f (ramp after touchdown, 0 at lift-off).
    if opt.contact_ramp_time > 0:
        ramped = xp.minimum(1.0, state["s"] + opt.dt / opt.contact_ramp_time)
        s_on = xp.where(have_prev, ramped, 1.0)
    else:
        s_on = xp.ones(2)
    s = xp.where(contact, s_on, 0.0)

    rows, consts = [], []
    for f in range(NUM_FEET):
        idx = chains.leg_joint_index[f]
        r, v_rel, w_rel = foot_kinematics(chains, f, q_ref[idx], qd_ref[idx], xp=xp)
        v0 = v + xp.asarray([-wz * r[1], wz * r[0], 0.0]) + v_rel
        wz0 = wz + w_rel[2]
        z0 = h + r[2] - opt.ground_height
        sv, sy, sh = s[f] * opt.w_foot_velocity, s[f] * opt.w_foot_yaw_rate, s[f] * opt.w_foot_height
        rows += [sv * xp.asarray([1.0, 0.0, -r[1], 0.0]), sv * xp.asarray([0.0, 1.0, r[0], 0.0]),
                 sy * xp.asarray([0.0, 0.0, 1.0, 0.0]), sh * xp.asarray([0.0, 0.0, 0.0, 1.0])]
        consts += [sv * v0[0], sv * v0[1], sy * wz0, sh * z0]
    A = xp.stack(rows)                 # (8, 4)
    b = xp.stack(consts)               # (8,)
    w_prior, w_smooth = xp.asarray(opt.w_prior), xp.asarray(opt.w_smooth)
    H0 = A.T @ A + xp.diag(w_prior ** 2 + w_smooth ** 2)
    g0 = A.T @ b - w_smooth ** 2 * state["x"]
    base = xp.stack([v[0], v[1], wz, h])
    lo, hi = xp.asarray(opt.lo), xp.asarray(opt.hi)
    wl2 = opt.w_limit ** 2

    def solve(active_hi, active_lo):
        act = (active_hi | active_lo).astype(H0.dtype)
        bound = xp.where(active_hi, hi, lo)
        H = H0 + xp.diag(wl2 * act)
        g = g0 + wl2 * act * (base - bound)
        return -xp.linalg.solve(H, g)

    x = solve(xp.zeros(4, bool), xp.zeros(4, bool))
    x = loops.repeat(xp, 4, lambda x: solve(base + x >= hi, base + x <= lo), x)

    u = xp.clip(base + x, lo, hi)
    jump = xp.asarray(opt.jump)
    u = xp.where(have_prev, xp.clip(u, state["u_prev"] - jump, state["u_prev"] + jump), u)
    x = u - base
    u_opt = xp.stack([u[0], u[1], u[2], xp.asarray(u_s[0], u.dtype), xp.asarray(u_s[1], u.dtype), u[3]])
    new_state = dict(state)
    new_state.update({"s": s, "x": x, "u_prev": u, "have_prev": xp.asarray(True)})
    return u_opt, x, s, new_state
