// Extended per-joint actuator model: turns a motor driver's PD command into the torque applied to
// the joint, with the effects that bench calibration (pmg_calib_dynamics, issue 6) can name:
// transport delay, torque constant (delivered / commanded torque), zero offset, torque saturation, voltage-limited torque-speed envelope, Coulomb /
// Stribeck / load-dependent friction with true stiction, and viscous friction. Backlash is a
// mechanical dead zone between rotor and link; it needs a second body in the simulator (see
// BenchSimulator for the MuJoCo construction) and is carried here only as a parameter.
//
// Header-only. ActuatorModel::step() is real-time safe: noexcept, no heap allocation, no locks,
// no I/O, O(1) (the delay line is a fixed-size ring buffer inside ActuatorState).
//
// Frames and signs: every angle, velocity and torque is about the joint axis, positive in the
// joint's positive direction; q is the motor-side (encoder-side) joint angle.
//
// Use in a MuJoCo backend (per joint i with dof index v, one ActuatorState per joint, parameters
// from an `actuator:` block, see actuator_yaml.hpp), with the split step so that the friction
// sees this step's inertia and bias forces:
//
//   mj_step1(m, d);
//   JointSample j;
//   j.q_rad = d->qpos[qpos_adr]; j.dq_rad_per_s = d->qvel[v]; j.dt_s = m->opt.timestep;
//   j.inertia_kgm2 = d->qM[m->dof_Madr[v]];               // diagonal of M, includes armature
//   j.tau_other_Nm = -d->qfrc_bias[v] + d->qfrc_passive[v];
//   MotorCommand c{q_des, dq_des, kp * block.kp_scale, kd * block.kd_scale, tau_ff, enabled};
//   d->qfrc_applied[v] = ActuatorModel::step(block.params, state[i], c, j).tau_applied_Nm;
//   mj_step2(m, d);
//   reported_q = ActuatorModel::encoder(block.params, d->qpos[qpos_adr]);
//
// and set m->dof_armature[v] = *block.armature_kgm2 and m->dof_frictionloss[v] = 0 (this model
// replaces MuJoCo's dry friction). With several DOFs the diagonal of M makes stiction approximate
// (exact for one DOF, as on the bench rig).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

namespace pmg::calib {

/// Identified actuator parameters. A value of 0 switches an effect off (torque_limit_Nm: +inf).
/// Units are SI; the names match the catalogue keys of the calibration report.
struct ActuatorParams {
  /// Rate of the driver's PD loop [Hz]; the PD torque is held (zero-order hold) between updates.
  /// 0 = recompute on every step().
  double rate_hz = 0.0;
  /// transport_delay: how late the command reaches the motor [s], in [0, kMaxDelaySteps * dt).
  double delay_s = 0.0;
  /// zero_offset: encoder reading minus true angle [rad].
  double offset_rad = 0.0;
  /// torque_constant: delivered torque = kt_scale x commanded torque (dimensionless, in (0, 5]):
  /// a motor whose torque constant (or current sensing) differs from the driver's assumption. On
  /// position-controlled (PD) data it is indistinguishable from scaling kp and kd together; on
  /// torque-controlled data (feed-forward torque, kp = kd = 0) it is the only torque scale.
  double kt_scale = 1.0;
  /// torque_saturation: symmetric clip of the delivered motor torque [N·m] (+inf = none).
  double torque_limit_Nm = std::numeric_limits<double>::infinity();
  /// torque_speed_limit: voltage-limited envelope
  /// -tau_stall (1 + w/w_max) <= tau <= tau_stall (1 - w/w_max); off when either is 0.
  double tau_stall_Nm = 0.0;
  double w_max_rad_per_s = 0.0;
  /// coulomb_friction: kinetic dry friction [N·m].
  double fc_Nm = 0.0;
  /// stribeck_friction: break-away (static) torque [N·m] (0 = same as fc_Nm) and Stribeck
  /// velocity [rad/s]: F(v) = fc + (fs - fc) exp(-(v/vs)^2).
  double fs_Nm = 0.0;
  double vs_rad_per_s = 0.1;
  /// load_dependent_friction: friction grows with the transmitted motor torque, F += kl |tau_m|
  /// (dimensionless).
  double kl = 0.0;
  /// viscous_friction [N·m·s/rad]: tau_f = -fv * dq.
  double fv_Nms_per_rad = 0.0;
  /// backlash: total dead-zone width between motor and link [rad]. Not applied by step(); the
  /// simulator must model a rotor body with the encoder on it (BenchSimulator does).
  double backlash_gap_rad = 0.0;

  /// Throws std::invalid_argument naming the field and the expected range.
  void validate() const {
    auto check = [](bool ok, const char* field, const std::string& range) {
      if (!ok) throw std::invalid_argument(std::string("ActuatorParams.") + field + " must be " + range);
    };
    check(std::isfinite(rate_hz) && rate_hz >= 0.0, "rate_hz", ">= 0 Hz");
    check(std::isfinite(delay_s) && delay_s >= 0.0 && delay_s <= 0.25, "delay_s", "in [0, 0.25] s");
    check(std::isfinite(offset_rad) && std::abs(offset_rad) <= 0.5, "offset_rad", "in [-0.5, 0.5] rad");
    check(std::isfinite(kt_scale) && kt_scale > 0.0 && kt_scale <= 5.0, "kt_scale", "in (0, 5]");
    check(torque_limit_Nm > 0.0, "torque_limit_Nm", "> 0 N·m (or +inf)");
    check(std::isfinite(tau_stall_Nm) && tau_stall_Nm >= 0.0, "tau_stall_Nm", ">= 0 N·m");
    check(std::isfinite(w_max_rad_per_s) && w_max_rad_per_s >= 0.0, "w_max_rad_per_s", ">= 0 rad/s");
    check(std::isfinite(fc_Nm) && fc_Nm >= 0.0, "fc_Nm", ">= 0 N·m");
    check(std::isfinite(fs_Nm) && fs_Nm >= 0.0, "fs_Nm", ">= 0 N·m");
    check(std::isfinite(vs_rad_per_s) && vs_rad_per_s > 0.0, "vs_rad_per_s", "> 0 rad/s");
    check(std::isfinite(kl) && kl >= 0.0 && kl < 1.0, "kl", "in [0, 1)");
    check(std::isfinite(fv_Nms_per_rad) && fv_Nms_per_rad >= 0.0, "fv_Nms_per_rad", ">= 0 N·m·s/rad");
    check(std::isfinite(backlash_gap_rad) && backlash_gap_rad >= 0.0 && backlash_gap_rad <= 0.5,
          "backlash_gap_rad", "in [0, 0.5] rad");
  }
};

/// The command a joint driver receives (Unitree / Mini-Cheetah style):
/// tau = kp (q_des - r) + kd (dq_des - dq) + tau_ff, with r the encoder reading.
/// A pure torque command is {0, 0, 0, 0, tau}. `enabled == false` means torque off.
struct MotorCommand {
  double q_des_rad = 0.0;
  double dq_des_rad_per_s = 0.0;
  double kp_Nm_per_rad = 0.0;
  double kd_Nms_per_rad = 0.0;
  double tau_ff_Nm = 0.0;
  bool enabled = true;
};

/// What step() needs to know about the joint this physics step (motor side).
struct JointSample {
  double q_rad = 0.0;            ///< true motor-side angle (the encoder reads q_rad + offset_rad)
  double dq_rad_per_s = 0.0;     ///< motor-side velocity
  /// Effective inertia of the DOF [kg·m²] (e.g. MuJoCo qM diagonal incl. armature) and the sum of
  /// all other generalized forces on it [N·m] (e.g. -qfrc_bias + qfrc_passive). They let the
  /// friction model hold a stuck joint exactly (implicit stiction); inertia <= 0 disables that and
  /// leaves kinetic friction only.
  double inertia_kgm2 = 0.0;
  double tau_other_Nm = 0.0;
  double dt_s = 0.0;             ///< physics step [s], > 0
};

/// Torques produced by one step() (N·m, about the joint axis).
struct ActuatorOutput {
  double tau_motor_Nm = 0.0;     ///< delivered torque: kt_scale x driver torque, after delay, saturation, envelope
  double tau_friction_Nm = 0.0;  ///< dry + viscous friction
  double tau_applied_Nm = 0.0;   ///< tau_motor + tau_friction: write this to qfrc_applied / ctrl
  bool stuck = false;            ///< the dry friction held the joint this step
};

/// Mutable per-joint state (preallocated; no heap). Call reset() before a new rollout.
struct ActuatorState {
  static constexpr std::size_t kMaxDelaySteps = 512;
  std::array<MotorCommand, kMaxDelaySteps> fifo{};
  std::size_t head = 0;        ///< index of the newest command
  std::size_t count = 0;       ///< number of valid entries
  double pd_timer_s = 0.0;     ///< time since the last PD update
  double held_tau_Nm = 0.0;    ///< PD torque held between driver updates
  bool has_pd = false;

  void reset() noexcept {
    head = 0;
    count = 0;
    pd_timer_s = 0.0;
    held_tau_Nm = 0.0;
    has_pd = false;
  }
};

class ActuatorModel {
 public:
  /// Encoder reading [rad] for a true motor-side angle.
  static double encoder(const ActuatorParams& p, double q_true_rad) noexcept { return q_true_rad + p.offset_rad; }

  /// Clip a motor torque [N·m] by the saturation and the torque-speed envelope at velocity w [rad/s].
  static double limit_torque(const ActuatorParams& p, double tau, double w) noexcept {
    tau = std::clamp(tau, -p.torque_limit_Nm, p.torque_limit_Nm);
    if (p.tau_stall_Nm > 0.0 && p.w_max_rad_per_s > 0.0) {
      const double r = w / p.w_max_rad_per_s;
      tau = std::clamp(tau, -p.tau_stall_Nm * (1.0 + r), p.tau_stall_Nm * (1.0 - r));
    }
    return tau;
  }

  /// Break-away torque [N·m] (static friction) for a motor torque tau_m.
  static double static_friction(const ActuatorParams& p, double tau_m) noexcept {
    return std::max(p.fs_Nm, p.fc_Nm) + p.kl * std::abs(tau_m);
  }

  /// Kinetic dry-friction magnitude [N·m] at velocity v (Stribeck curve + load term).
  static double kinetic_friction(const ActuatorParams& p, double v, double tau_m) noexcept {
    const double fs = std::max(p.fs_Nm, p.fc_Nm);
    const double x = v / p.vs_rad_per_s;
    return p.fc_Nm + (fs - p.fc_Nm) * std::exp(-x * x) + p.kl * std::abs(tau_m);
  }

  /// One physics step. Pushes `cmd` into the delay line, runs the driver's PD on the delayed
  /// command and the (offset) encoder reading at rate_hz, scales it by kt_scale (delivered torque),
  /// limits it, then adds friction.
  /// Stiction is implicit: if the dry friction can bring the joint to rest within this step
  /// (semi-implicit Euler, v+ = v + dt/I * tau_total) without exceeding the break-away torque, it
  /// does exactly that. Requires p.validate() to have passed and j.dt_s > 0.
  static ActuatorOutput step(const ActuatorParams& p, ActuatorState& s, const MotorCommand& cmd,
                             const JointSample& j) noexcept {
    // Delay line: newest at head.
    s.head = (s.head + 1) % ActuatorState::kMaxDelaySteps;
    s.fifo[s.head] = cmd;
    s.count = std::min(s.count + 1, ActuatorState::kMaxDelaySteps);
    const MotorCommand c = delayed(p, s, j.dt_s);

    // Driver PD at its own rate (zero-order hold).
    const double period = p.rate_hz > 0.0 ? 1.0 / p.rate_hz : 0.0;
    s.pd_timer_s += j.dt_s;
    if (!s.has_pd || s.pd_timer_s >= period - 1e-9) {
      s.pd_timer_s = s.has_pd ? std::fmod(s.pd_timer_s, std::max(period, 1e-12)) : 0.0;
      if (period <= 0.0) s.pd_timer_s = 0.0;
      s.has_pd = true;
      const double r = encoder(p, j.q_rad);
      s.held_tau_Nm = c.enabled ? c.kp_Nm_per_rad * (c.q_des_rad - r) +
                                      c.kd_Nms_per_rad * (c.dq_des_rad_per_s - j.dq_rad_per_s) + c.tau_ff_Nm
                                : 0.0;
    }
    ActuatorOutput out;
    out.tau_motor_Nm = c.enabled ? limit_torque(p, p.kt_scale * s.held_tau_Nm, j.dq_rad_per_s) : 0.0;

    // Friction.
    const double tau_visc = -p.fv_Nms_per_rad * j.dq_rad_per_s;
    double tau_dry = 0.0;
    const double f_static = static_friction(p, out.tau_motor_Nm);
    if (f_static > 0.0) {
      const double drive = out.tau_motor_Nm + tau_visc + j.tau_other_Nm;
      if (j.inertia_kgm2 > 0.0 && j.dt_s > 0.0) {
        const double hold = -j.inertia_kgm2 * j.dq_rad_per_s / j.dt_s - drive;
        if (std::abs(hold) <= f_static) {
          tau_dry = hold;
          out.stuck = true;
        } else {
          tau_dry = std::copysign(kinetic_friction(p, j.dq_rad_per_s, out.tau_motor_Nm), hold);
        }
      } else if (j.dq_rad_per_s != 0.0) {
        tau_dry = -std::copysign(kinetic_friction(p, j.dq_rad_per_s, out.tau_motor_Nm), j.dq_rad_per_s);
      }
    }
    out.tau_friction_Nm = tau_visc + tau_dry;
    out.tau_applied_Nm = out.tau_motor_Nm + out.tau_friction_Nm;
    return out;
  }

 private:
  /// The command delayed by p.delay_s, linearly interpolated between the two neighbouring steps of
  /// the delay line (keeps the response continuous in delay_s, which optimisers need).
  static MotorCommand delayed(const ActuatorParams& p, const ActuatorState& s, double dt) noexcept {
    if (p.delay_s <= 0.0 || dt <= 0.0) return s.fifo[s.head];
    const double lag = p.delay_s / dt;
    std::size_t k = static_cast<std::size_t>(lag);
    double frac = lag - static_cast<double>(k);
    const std::size_t oldest = s.count - 1;
    if (k >= oldest) {
      k = oldest;
      frac = 0.0;
    }
    const std::size_t n = ActuatorState::kMaxDelaySteps;
    const MotorCommand& a = s.fifo[(s.head + n - k) % n];
    if (frac <= 0.0) return a;
    const MotorCommand& b = s.fifo[(s.head + n - k - 1) % n];
    MotorCommand c;
    auto mix = [frac](double x, double y) { return (1.0 - frac) * x + frac * y; };
    c.q_des_rad = mix(a.q_des_rad, b.q_des_rad);
    c.dq_des_rad_per_s = mix(a.dq_des_rad_per_s, b.dq_des_rad_per_s);
    c.kp_Nm_per_rad = mix(a.kp_Nm_per_rad, b.kp_Nm_per_rad);
    c.kd_Nms_per_rad = mix(a.kd_Nms_per_rad, b.kd_Nms_per_rad);
    c.tau_ff_Nm = mix(a.tau_ff_Nm, b.tau_ff_Nm);
    c.enabled = frac < 0.5 ? a.enabled : b.enabled;
    return c;
  }
};

}  // namespace pmg::calib
