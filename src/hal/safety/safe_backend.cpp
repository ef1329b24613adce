#include "pmg/hal/safety/safe_backend.hpp"

#include <cmath>
#include <stdexcept>

namespace pmg::hal::safety {

SafeBackend::SafeBackend(std::unique_ptr<pmg::HalBackend> inner, SafetyOptions options,
                         SafeBackendOptions backend_options)
    : inner_(std::move(inner)), sup_(std::move(options)), bopt_(backend_options) {
  held_at_.fill(-1e9);
  if (!inner_) throw std::invalid_argument("SafeBackend: wrapped backend is null");
  if (sup_.numJoints() > static_cast<std::size_t>(pmg::kMaxMotors))
    throw std::invalid_argument("SafeBackend: more joints than pmg::kMaxMotors");
  in_ = sup_.makeInput();
  out_ = sup_.makeOutput();
  safe_.num_motors = static_cast<int>(sup_.numJoints());
}

pmg::BackendStatus SafeBackend::exchange(const pmg::LowCommand& command, pmg::LowState& state) noexcept {
  const std::size_t n = sup_.numJoints();
  const double now = static_cast<double>(cycles_) * inner_->cyclePeriod();
  in_.now_s = now;
  in_.request = requests_.take();
  for (std::size_t j = 0; j < n; ++j) {
    const pmg::MotorState& m = last_.motors[j];
    if (cycles_ > 0 && m.valid) {
      in_.q[j] = m.q;
      in_.qd[j] = m.qd;
      in_.tau[j] = m.tau;
      in_.motor_stamp_s[j] = now;
    }
  }
  if (cycles_ > 0 && last_.imu.valid) {
    for (int i = 0; i < 4; ++i) in_.imu.quat_WB[i] = last_.imu.quat_wxyz[static_cast<std::size_t>(i)];
    for (int i = 0; i < 3; ++i) {
      in_.imu.omega_B[i] = last_.imu.gyro[static_cast<std::size_t>(i)];
      in_.imu.acc_B[i] = last_.imu.acc[static_cast<std::size_t>(i)];
    }
    in_.imu.stamp_s = now;
  }
  in_.base_height_m = last_.base_truth_valid ? last_.base_position[2] : std::nan("");
  bool finite = true;
  for (std::size_t j = 0; j < n; ++j) {
    const pmg::MotorCommand& c = command.motors[j];
    in_.cmd_q[j] = c.q;
    in_.cmd_qd[j] = c.qd;
    in_.cmd_kp[j] = c.kp;
    in_.cmd_kd[j] = c.kd;
    in_.cmd_tau[j] = c.tau_ff;
    finite = finite && std::isfinite(c.q) && std::isfinite(c.qd) && std::isfinite(c.kp) && std::isfinite(c.kd) &&
             std::isfinite(c.tau_ff);
  }
  if (command.sequence != last_sequence_) {
    last_sequence_ = command.sequence;
    in_.command_stamp_s = now;
    in_.policy_stamp_s = now;
    if (!finite) ++nonfinite_;
  }
  in_.policy_valid = finite;
  in_.backend_fault = last_status_ == pmg::BackendStatus::kFault;

  sup_.step(in_, out_);

  double max_tau = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    pmg::MotorCommand& s = safe_.motors[j];
    s.q = out_.cmd_q[j];
    s.qd = out_.cmd_qd[j];
    s.kp = out_.cmd_kp[j];
    s.kd = out_.cmd_kd[j];
    s.tau_ff = out_.cmd_tau[j];
    const JointSetpoint sp{s.q, s.qd, s.kp, s.kd, s.tau_ff};
    max_tau = std::max(max_tau, std::fabs(predictedTorque(sp, in_.q[j], in_.qd[j])) / sup_.options().joints[j].tau_max);
  }
  safe_.sequence = command.sequence;
  pmg::BackendStatus st = inner_->exchange(safe_, state);
  // A reply with a non-finite value is no reply (a corrupted frame): counted, then held or timed
  // out like a missing one.
  for (std::size_t j = 0; j < n; ++j) {
    pmg::MotorState& m = state.motors[j];
    if (m.valid && !(std::isfinite(m.q) && std::isfinite(m.qd) && std::isfinite(m.tau))) {
      m.valid = false;
      ++nonfinite_replies_;
    }
  }
  if (state.imu.valid) {
    bool imu_finite = true;
    for (double v : state.imu.quat_wxyz) imu_finite = imu_finite && std::isfinite(v);
    for (double v : state.imu.gyro) imu_finite = imu_finite && std::isfinite(v);
    for (double v : state.imu.acc) imu_finite = imu_finite && std::isfinite(v);
    if (!imu_finite) {
      state.imu.valid = false;
      ++nonfinite_replies_;
    }
  }
  last_ = state;  // the supervisor sees the raw replies (its watchdogs count the missing ones)
  if (bopt_.hold_missing) {
    const WatchdogOptions& w = sup_.options().watchdog;
    for (std::size_t j = 0; j < n; ++j) {
      pmg::MotorState& m = state.motors[j];
      if (m.valid) {
        held_.motors[j] = m;
        held_at_[j] = now;
      } else if (now - held_at_[j] <= w.motor_timeout_s) {
        m = held_.motors[j];
        ++held_count_;
      }
    }
    if (state.imu.valid) {
      held_.imu = state.imu;
      imu_held_at_ = now;
    } else if (now - imu_held_at_ <= w.imu_timeout_s) {
      state.imu = held_.imu;
      ++held_count_;
    }
    // A cycle in which nothing arrived but every value could be held is a partial cycle for the
    // loop, not a backend fault; once a watchdog expires the fault passes through.
    if (st == pmg::BackendStatus::kFault) {
      bool all = true;
      for (std::size_t j = 0; j < n; ++j) all = all && state.motors[j].valid;
      if (all) st = pmg::BackendStatus::kPartial;
    }
  }
  if (bopt_.imu_acc_lowpass_s > 0.0 && state.imu.valid) {
    const double T = inner_->cyclePeriod();
    const double a = acc_lowpass_started_ ? T / (bopt_.imu_acc_lowpass_s + T) : 1.0;
    for (std::size_t i = 0; i < 3; ++i) {
      acc_lowpass_[i] += a * (state.imu.acc[i] - acc_lowpass_[i]);
      state.imu.acc[i] = acc_lowpass_[i];
    }
    acc_lowpass_started_ = true;
  }
  ++cycles_;
  last_status_ = st;
  state.mode = out_.mode;
  state.fault = out_.fault.code;
  state.stand_progress = out_.stand_progress;

  SafetyStatus s;
  s.mode = out_.mode;
  s.fault = out_.fault;
  s.time_s = now;
  s.stand_progress = out_.stand_progress;
  s.max_tau_ratio = max_tau;
  s.ticks = out_.ticks;
  s.refused_requests = out_.refused_requests;
  s.clamped_joint_ticks = out_.clamped_joint_ticks;
  s.slew_clamped_joint_ticks = out_.slew_clamped_joint_ticks;
  s.nonfinite_commands = nonfinite_;
  s.held_replies = held_count_;
  s.nonfinite_replies = nonfinite_replies_;
  s.fault_counts = out_.fault_counts;
  status_.write(s);
  return st;
}

}  // namespace pmg::hal::safety
