#include "pmg/hal/safety/supervisor.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pmg/common/robot_config.hpp"

namespace pmg::hal::safety {

// ---------------------------------------------------------------- options
std::string SafetyOptions::validate() const {
  std::ostringstream os;
  const std::size_t n = joints.size();
  if (n == 0) return "joints: at least one joint is required";
  auto sized = [&](const std::vector<double>& v, const char* name) {
    if (v.size() != n) os << name << ": expected " << n << " values (one per joint), got " << v.size();
    return v.size() == n;
  };
  if (!sized(stand_q, "stand_q") || !sized(stand_kp, "stand_kp") || !sized(stand_kd, "stand_kd") ||
      !sized(damping_kd, "damping_kd"))
    return os.str();
  for (std::size_t j = 0; j < n; ++j) {
    const JointLimits& L = joints[j];
    const std::string w = "joints[" + std::to_string(j) + "]";
    if (!(std::isfinite(L.q_min) && std::isfinite(L.q_max) && L.q_min < L.q_max))
      return w + ".q_min/q_max: expected finite with q_min < q_max";
    if (!(L.qd_max > 0 && std::isfinite(L.qd_max))) return w + ".qd_max: expected > 0";
    if (!(L.tau_max > 0 && std::isfinite(L.tau_max))) return w + ".tau_max: expected > 0";
    if (!(L.kp_max >= 0 && std::isfinite(L.kp_max))) return w + ".kp_max: expected >= 0";
    if (!(L.kd_max >= 0 && std::isfinite(L.kd_max))) return w + ".kd_max: expected >= 0";
    if (!(stand_q[j] >= L.q_min && stand_q[j] <= L.q_max))
      return "stand_q[" + std::to_string(j) + "]: expected within [q_min, q_max] of the joint";
    if (!(stand_kp[j] >= 0 && stand_kp[j] <= L.kp_max))
      return "stand_kp[" + std::to_string(j) + "]: expected 0..kp_max";
    if (!(stand_kd[j] >= 0 && stand_kd[j] <= L.kd_max))
      return "stand_kd[" + std::to_string(j) + "]: expected 0..kd_max";
    if (!(damping_kd[j] >= 0 && damping_kd[j] <= L.kd_max))
      return "damping_kd[" + std::to_string(j) + "]: expected 0..kd_max";
  }
  if (!(period_s > 0 && period_s <= 0.1)) return "period_s: expected (0, 0.1] s";
  if (!(soft_stand_duration_s > 0 && soft_stand_duration_s <= 60)) return "soft_stand_duration_s: expected (0, 60] s";
  if (!(reset_min_damping_s >= 0)) return "reset_min_damping_s: expected >= 0 s";
  if (!(reset_qd_max > 0)) return "reset_qd_max: expected > 0 rad/s";
  const WatchdogOptions& w = watchdog;
  if (!(w.command_timeout_s > 0 && w.policy_timeout_s > 0 && w.motor_timeout_s > 0 && w.imu_timeout_s > 0))
    return "watchdog.*_timeout_s: expected > 0 s";
  if (w.imu_frozen_samples < 2) return "watchdog.imu_frozen_samples: expected >= 2";
  if (!(w.imu_omega_max > 0 && w.imu_acc_max > 0 && w.imu_quat_norm_tol > 0 && w.imu_quat_norm_tol < 1))
    return "watchdog.imu_omega_max/imu_acc_max > 0 and imu_quat_norm_tol in (0, 1) expected";
  const EnvelopeOptions& e = envelope;
  if (!(e.q_fault_margin >= 0)) return "envelope.q_fault_margin: expected >= 0 rad";
  if (!(e.qd_fault_factor >= 1 && e.tau_fault_factor >= 1)) return "envelope.*_fault_factor: expected >= 1";
  if (!(e.q_rate_max > 0 && e.tau_rate_max > 0)) return "envelope.q_rate_max/tau_rate_max: expected > 0";
  if (!(e.max_tilt_rad > 0 && e.max_tilt_rad < M_PI)) return "envelope.max_tilt_rad: expected (0, pi) rad";
  if (!std::isfinite(e.min_base_height_m)) return "envelope.min_base_height_m: expected finite";
  return {};
}

SafetyOptions SafetyOptions::fromRobot(const pmg::RobotConfig& robot) {
  SafetyOptions o;
  for (const pmg::JointConfig& j : robot.joints) {
    JointLimits L;
    L.q_min = j.lower;
    L.q_max = j.upper;
    L.qd_max = j.velocity_limit;
    L.tau_max = j.torque_limit;
    L.kp_max = 2.0 * j.kp;
    L.kd_max = 4.0 * j.kd;
    o.joints.push_back(L);
    o.stand_q.push_back(j.default_position);
    o.stand_kp.push_back(j.kp);
    o.stand_kd.push_back(j.kd);
    o.damping_kd.push_back(j.kd);
  }
  return o;
}

// ---------------------------------------------------------------- supervisor
SafetySupervisor::SafetySupervisor(SafetyOptions options) : opt_(std::move(options)) {
  const std::string msg = opt_.validate();
  if (!msg.empty()) throw std::invalid_argument("safety options: " + msg);
  n_ = opt_.joints.size();
  q_start_.assign(n_, 0.0);
  prev_q_.assign(n_, std::nan(""));
  prev_tau_.assign(n_, 0.0);
}

SafetyInput SafetySupervisor::makeInput() const {
  SafetyInput in;
  for (auto* v : {&in.q, &in.qd, &in.tau, &in.cmd_q, &in.cmd_qd, &in.cmd_kp, &in.cmd_kd, &in.cmd_tau})
    v->assign(n_, 0.0);
  in.motor_stamp_s.assign(n_, -1e9);
  in.base_height_m = std::nan("");
  return in;
}

SafetyOutput SafetySupervisor::makeOutput() const {
  SafetyOutput out;
  for (auto* v : {&out.cmd_q, &out.cmd_qd, &out.cmd_kp, &out.cmd_kd, &out.cmd_tau}) v->assign(n_, 0.0);
  out.clamp_bits.assign(n_, 0);
  return out;
}

namespace {
bool finite3(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }
double norm3(const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }
Fault make(FaultCode c, int index, double value, double t) { return Fault{c, index, value, t}; }
}  // namespace

void SafetySupervisor::updateImuFrozen(const SafetyInput& in) noexcept {
  if (in.imu.stamp_s == imu_last_stamp_s_) return;  // no new sample this tick
  imu_last_stamp_s_ = in.imu.stamp_s;
  const double v[6] = {in.imu.omega_B[0], in.imu.omega_B[1], in.imu.omega_B[2],
                       in.imu.acc_B[0],   in.imu.acc_B[1],   in.imu.acc_B[2]};
  bool same = true;
  for (int i = 0; i < 6; ++i) same = same && (v[i] == imu_last_[i]);
  imu_same_ticks_ = same ? imu_same_ticks_ + 1 : 0;
  std::copy(v, v + 6, imu_last_);
}

bool SafetySupervisor::inputsHealthy(const SafetyInput& in, bool need_command, Fault& f) const noexcept {
  const double t = in.now_s;
  const WatchdogOptions& w = opt_.watchdog;
  for (std::size_t j = 0; j < n_; ++j) {
    if (!std::isfinite(in.q[j]) || !std::isfinite(in.qd[j]) || !std::isfinite(in.tau[j])) {
      f = make(FaultCode::kMotorInvalid, static_cast<int>(j), std::nan(""), t);
      return false;
    }
    const double age = t - in.motor_stamp_s[j];
    if (!(age <= w.motor_timeout_s)) {
      f = make(FaultCode::kMotorStale, static_cast<int>(j), age, t);
      return false;
    }
  }
  const ImuSample& imu = in.imu;
  const double imu_age = t - imu.stamp_s;
  if (!(imu_age <= w.imu_timeout_s)) {
    f = make(FaultCode::kImuStale, -1, imu_age, t);
    return false;
  }
  const double* qv = imu.quat_WB;
  const double qn = std::sqrt(qv[0] * qv[0] + qv[1] * qv[1] + qv[2] * qv[2] + qv[3] * qv[3]);
  if (!std::isfinite(qn) || std::fabs(qn - 1.0) > w.imu_quat_norm_tol) {
    f = make(FaultCode::kImuInvalid, -1, qn, t);
    return false;
  }
  if (!finite3(imu.omega_B) || norm3(imu.omega_B) > w.imu_omega_max) {
    f = make(FaultCode::kImuInvalid, -1, norm3(imu.omega_B), t);
    return false;
  }
  if (!finite3(imu.acc_B) || norm3(imu.acc_B) > w.imu_acc_max) {
    f = make(FaultCode::kImuInvalid, -1, norm3(imu.acc_B), t);
    return false;
  }
  if (imu_same_ticks_ >= w.imu_frozen_samples) {
    f = make(FaultCode::kImuFrozen, -1, imu_same_ticks_, t);
    return false;
  }
  if (!need_command) return true;
  const double cmd_age = t - in.command_stamp_s;
  if (!(cmd_age <= w.command_timeout_s)) {
    f = make(FaultCode::kCommandStale, -1, cmd_age, t);
    return false;
  }
  for (std::size_t j = 0; j < n_; ++j) {
    if (!std::isfinite(in.cmd_q[j]) || !std::isfinite(in.cmd_qd[j]) || !std::isfinite(in.cmd_kp[j]) ||
        !std::isfinite(in.cmd_kd[j]) || !std::isfinite(in.cmd_tau[j])) {
      f = make(FaultCode::kCommandInvalid, static_cast<int>(j), std::nan(""), t);
      return false;
    }
  }
  if (!in.policy_valid) {
    f = make(FaultCode::kPolicyInvalid, -1, 0.0, t);
    return false;
  }
  const double pol_age = t - in.policy_stamp_s;
  if (!(pol_age <= w.policy_timeout_s)) {
    f = make(FaultCode::kPolicyStale, -1, pol_age, t);
    return false;
  }
  return true;
}

bool SafetySupervisor::envelopeHealthy(const SafetyInput& in, Fault& f) const noexcept {
  const double t = in.now_s;
  const EnvelopeOptions& e = opt_.envelope;
  for (std::size_t j = 0; j < n_; ++j) {
    const JointLimits& L = opt_.joints[j];
    if (in.q[j] < L.q_min - e.q_fault_margin || in.q[j] > L.q_max + e.q_fault_margin) {
      f = make(FaultCode::kJointPosition, static_cast<int>(j), in.q[j], t);
      return false;
    }
    if (std::fabs(in.qd[j]) > e.qd_fault_factor * L.qd_max) {
      f = make(FaultCode::kJointVelocity, static_cast<int>(j), in.qd[j], t);
      return false;
    }
    if (std::fabs(in.tau[j]) > e.tau_fault_factor * L.tau_max) {
      f = make(FaultCode::kJointTorque, static_cast<int>(j), in.tau[j], t);
      return false;
    }
  }
  const double tilt = baseTilt(in.imu.quat_WB);
  if (!(tilt <= e.max_tilt_rad)) {
    f = make(FaultCode::kFallTilt, -1, tilt, t);
    return false;
  }
  if (std::isfinite(in.base_height_m) && in.base_height_m < e.min_base_height_m) {
    f = make(FaultCode::kFallHeight, -1, in.base_height_m, t);
    return false;
  }
  return true;
}

void SafetySupervisor::enter(Mode m, const SafetyInput& in) noexcept {
  // Soft stand blends from where the motors were commanded to be (active -> soft stand: the last
  // command, so the reference stays continuous), or from the measured pose when nothing was
  // commanded (passive -> soft stand).
  const bool from_command = mode_ == Mode::kActive;
  mode_ = m;
  mode_since_s_ = in.now_s;
  if (m == Mode::kSoftStand) {
    for (std::size_t j = 0; j < n_; ++j) {
      const double start = from_command && std::isfinite(prev_q_[j]) ? prev_q_[j] : in.q[j];
      q_start_[j] = std::isfinite(start) ? start : opt_.stand_q[j];
    }
  }
}

void SafetySupervisor::step(const SafetyInput& in, SafetyOutput& out) noexcept {
  if (!started_) {
    started_ = true;
    mode_since_s_ = in.now_s;
  }
  const Mode before = mode_;
  ++out.ticks;
  updateImuFrozen(in);

  // 1. Faults (only where torque is applied: soft stand and active).
  if (mode_ == Mode::kSoftStand || mode_ == Mode::kActive) {
    Fault f;
    if (in.backend_fault) f = make(FaultCode::kBackend, -1, 0.0, in.now_s);
    if (in.backend_fault || !inputsHealthy(in, mode_ == Mode::kActive, f) || !envelopeHealthy(in, f)) {
      fault_ = f;
      ++out.fault_counts[static_cast<std::size_t>(f.code)];
      enter(Mode::kDamping, in);
    }
  }

  // 2. Requests (a fault this tick takes precedence).
  if (mode_ == before && in.request != ModeRequest::kNone) {
    bool accepted = false;
    Fault ignored;
    const double in_mode = in.now_s - mode_since_s_;
    switch (in.request) {
      case ModeRequest::kDamping:
        if (mode_ != Mode::kDamping) {
          fault_ = make(FaultCode::kEstop, -1, 0.0, in.now_s);
          ++out.fault_counts[static_cast<std::size_t>(FaultCode::kEstop)];
          enter(Mode::kDamping, in);
          accepted = true;
        }
        break;
      case ModeRequest::kSoftStand:
        if ((mode_ == Mode::kPassive && inputsHealthy(in, false, ignored)) || mode_ == Mode::kActive) {
          enter(Mode::kSoftStand, in);
          accepted = true;
        }
        break;
      case ModeRequest::kActive:
        if (mode_ == Mode::kSoftStand && in_mode >= opt_.soft_stand_duration_s &&
            inputsHealthy(in, true, ignored)) {
          enter(Mode::kActive, in);
          accepted = true;
        }
        break;
      case ModeRequest::kPassive:
        if (mode_ == Mode::kSoftStand) {
          enter(Mode::kPassive, in);
          accepted = true;
        }
        break;
      case ModeRequest::kReset:
        if (mode_ == Mode::kDamping && in_mode >= opt_.reset_min_damping_s) {
          bool slow = true;
          for (std::size_t j = 0; j < n_; ++j) slow = slow && std::fabs(in.qd[j]) < opt_.reset_qd_max;
          if (slow) {
            fault_ = Fault{};
            enter(Mode::kPassive, in);
            accepted = true;
          }
        }
        break;
      case ModeRequest::kNone: break;
    }
    if (!accepted) ++out.refused_requests;
  }

  writeCommand(in, out);
  out.mode = mode_;
  out.mode_changed = mode_ != before;
  out.time_in_mode_s = in.now_s - mode_since_s_;
  out.fault = fault_;
}

void SafetySupervisor::writeCommand(const SafetyInput& in, SafetyOutput& out) noexcept {
  const double t = in.now_s - mode_since_s_;
  const double T = opt_.soft_stand_duration_s;
  const double s = std::clamp(t / T, 0.0, 1.0);
  const double blend = s * s * s * (10.0 + s * (-15.0 + 6.0 * s));     // quintic smoothstep
  const double dblend = (s < 1.0) ? 30.0 * s * s * (1.0 - s) * (1.0 - s) / T : 0.0;  // d/dt [1/s]
  out.stand_progress = mode_ == Mode::kSoftStand ? s : (mode_ == Mode::kActive ? 1.0 : 0.0);
  const double dq_max = opt_.envelope.q_rate_max * opt_.period_s;
  const double dtau_max = opt_.envelope.tau_rate_max * opt_.period_s;
  for (std::size_t j = 0; j < n_; ++j) {
    const double q = in.q[j], qd = in.qd[j];
    JointSetpoint sp;
    std::uint8_t bits = 0;
    switch (mode_) {
      case Mode::kPassive:
        sp.q = std::isfinite(q) ? q : 0.0;
        break;
      case Mode::kDamping:
        sp.q = std::isfinite(q) ? q : 0.0;
        sp.kd = opt_.damping_kd[j];
        bits = clampSetpoint(opt_.joints[j], q, qd, sp);
        break;
      case Mode::kSoftStand: {
        const double d = opt_.stand_q[j] - q_start_[j];
        sp.q = q_start_[j] + blend * d;
        sp.qd = dblend * d;
        sp.kp = opt_.stand_kp[j];
        sp.kd = opt_.stand_kd[j];
        bits = clampSetpoint(opt_.joints[j], q, qd, sp);
        break;
      }
      case Mode::kActive:
        sp = JointSetpoint{in.cmd_q[j], in.cmd_qd[j], in.cmd_kp[j], in.cmd_kd[j], in.cmd_tau[j]};
        bits = slewLimit(prev_q_[j], prev_tau_[j], dq_max, dtau_max, sp);
        bits |= clampSetpoint(opt_.joints[j], q, qd, sp);
        break;
    }
    out.cmd_q[j] = sp.q;
    out.cmd_qd[j] = sp.qd;
    out.cmd_kp[j] = sp.kp;
    out.cmd_kd[j] = sp.kd;
    out.cmd_tau[j] = sp.tau_ff;
    out.clamp_bits[j] = bits;
    if (bits) ++out.clamped_joint_ticks;
    if (bits & kClampSlew) ++out.slew_clamped_joint_ticks;
    prev_q_[j] = sp.q;
    prev_tau_[j] = sp.tau_ff;
  }
}

}  // namespace pmg::hal::safety
