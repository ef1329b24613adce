#pragma once
/// @file supervisor.hpp
/// @brief The HAL's mode state machine, per-input watchdogs and safety envelope in one object that
/// the 500 Hz HAL thread steps once per tick. Nothing here depends on the policy or the generator.
///
/// Modes (issue 5):
///   kPassive   zero torque (kp = kd = tau_ff = 0). Start-up mode.
///   kSoftStand interpolate from the pose measured on entry to the standing pose over
///              Options::soft_stand_duration_s (quintic smoothstep), stand gains.
///   kActive    the 100 Hz loop's command (PMG / policy), through the envelope and slew limits.
///   kDamping   latched e-stop: kp = 0, qd = 0, kd = damping_kd, tau_ff = 0.
///
/// Transitions (each one is unit-tested in test/hal/safety/test_supervisor.cpp):
///   kPassive   -> kSoftStand  request kSoftStand, if every motor and the IMU are fresh and finite
///   kSoftStand -> kActive     request kActive, if the stand is complete and the command stream and
///                             the policy output are fresh and valid
///   kActive    -> kSoftStand  request kSoftStand (blend back to the standing pose from where it is)
///   kSoftStand -> kPassive    request kPassive (robot held by a gantry/hoist)
///   kPassive/kSoftStand/kActive -> kDamping  request kDamping (e-stop)
///   kSoftStand/kActive -> kDamping  any fault: watchdog timeout or invalid value, joint position/
///                             velocity/torque beyond the fault thresholds, fall (tilt or height)
///   kSoftStand/kActive -> kDamping  backend fault reported by the wrapped backend (SafeBackend)
///   kDamping   -> kPassive    request kReset, only after reset_min_damping_s in damping and with
///                             every |qd| < reset_qd_max; clears the latched fault
/// Any other request is refused and counted in SafetyOutput::refused_requests (not a fault).
/// This is the only mode state machine of pmg: the 100 Hz loop reads the mode from the HAL state
/// (LowState::mode) and computes a command only for kActive.
///
/// How the HAL calls it, each 2 ms tick, in the HAL thread:
///   1. read the buses; for each joint j write input.q[j], qd[j], tau[j] (joint side) and, if a
///      valid reply arrived this tick, input.motor_stamp_s[j] = now;
///   2. write the IMU sample (input.imu, with stamp_s = arrival time) and, if an estimator provides
///      it, input.base_height_m (NaN = unknown: the height check is skipped);
///   3. copy the latest command from the lock-free hand-over of the 100 Hz loop into input.cmd_*
///      with input.command_stamp_s = when the loop published it, and input.policy_stamp_s /
///      input.policy_valid for the policy output it was computed from;
///   4. input.request = pending gamepad/LCM request (ModeRequest::kNone otherwise), input.now_s =
///      CLOCK_MONOTONIC time;
///   5. supervisor.step(input, output);
///   6. send output.cmd_* to the motors (they are already clamped: never send anything else), and
///      publish output.mode / output.fault / counters in telemetry.
/// step() is noexcept, allocation-free and O(n); input/output come from makeInput()/makeOutput()
/// (sized at setup, reused every tick).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pmg/hal/modes.hpp"
#include "pmg/hal/safety/envelope.hpp"

namespace pmg {
struct RobotConfig;
}

namespace pmg::hal::safety {

// The mode vocabulary is pmg's one (include/pmg/hal/modes.hpp), shared with LCM and the loop.
using pmg::FaultCode;
using pmg::kNumFaultCodes;
using pmg::Mode;
using pmg::ModeRequest;
using pmg::toString;

/// The latched reason for damping.
struct Fault {
  FaultCode code = FaultCode::kNone;
  int index = -1;      ///< Joint index for per-joint faults, else -1.
  double value = 0.0;  ///< Offending value (age [s], angle [rad], height [m], q/qd/tau), NaN if not finite.
  double time_s = 0.0; ///< input.now_s when detected.
};

/// IMU sample: orientation of the base frame B in world W and body-frame rates.
struct ImuSample {
  double quat_WB[4] = {1, 0, 0, 0};  ///< q_WB (w, x, y, z), unit.
  double omega_B[3] = {0, 0, 0};     ///< Angular velocity of B in W, expressed in B [rad/s].
  double acc_B[3] = {0, 0, 9.81};    ///< Specific force in B [m/s^2].
  double stamp_s = -1e9;             ///< Arrival time (same clock as now_s) [s].
};

/// Watchdog timeouts and validity ranges.
struct WatchdogOptions {
  double command_timeout_s = 0.05;  ///< 5 periods of the 100 Hz loop [s].
  double policy_timeout_s = 0.05;   ///< [s]
  double motor_timeout_s = 0.01;    ///< 5 HAL ticks [s]; >= 2 periods behind an EtherCAT bridge.
  double imu_timeout_s = 0.01;      ///< [s]
  int imu_frozen_samples = 100;     ///< This many consecutive new IMU samples bit-identical = frozen.
  double imu_omega_max = 35.0;      ///< Largest plausible |omega_B| [rad/s] (gyro range).
  double imu_acc_max = 160.0;       ///< Largest plausible |acc_B| [m/s^2] (16 g).
  double imu_quat_norm_tol = 0.05;  ///< Allowed | |q_WB| - 1 |.
};

/// Fault thresholds on measurements and the command slew limits.
struct EnvelopeOptions {
  double q_fault_margin = 0.1;      ///< Measured q beyond a limit by more than this: fault [rad].
  double qd_fault_factor = 1.5;     ///< Measured |qd| > factor * qd_max: fault.
  double tau_fault_factor = 1.5;    ///< Measured |tau| > factor * tau_max: fault.
  /// Slew limit on the commanded q [rad/s], applied every HAL cycle (2 ms: 1.2 rad a cycle at 600).
  /// An actor's position targets are PD set-points that step every loop tick, as in training (which
  /// has no slew); the shipped actor steps a leg target by up to 1.15 rad a tick over the envelope
  /// grid. The former 20 rad/s (0.04 rad a cycle) held back leg targets in 93 % of its ticks and made
  /// the SIL walk 20-40 % slower than the actor's own environment, and fall at 1 m/s
  /// (training/README.md "The HAL's slew limit"). What a step can do is bounded by the torque clamp
  /// (clampSetpoint); references are bounded upstream (ReferenceRateLimiter, 6 rad/s).
  double q_rate_max = 600.0;
  double tau_rate_max = 5000.0;     ///< Slew limit on the commanded tau_ff [N m/s].
  double max_tilt_rad = 0.9;        ///< Fall: base tilt above this (about 52 deg) [rad].
  double min_base_height_m = 0.35;  ///< Fall: base height below this [m] (when known).
};

/// Everything the supervisor needs; immutable after construction.
struct SafetyOptions {
  double period_s = 0.002;                 ///< HAL period [s].
  std::vector<JointLimits> joints;         ///< (n)
  std::vector<double> stand_q;             ///< Standing pose (n) [rad].
  std::vector<double> stand_kp;            ///< Soft-stand stiffness (n) [N m/rad].
  std::vector<double> stand_kd;            ///< Soft-stand damping (n) [N m s/rad].
  std::vector<double> damping_kd;          ///< Damping-mode kd (n) [N m s/rad].
  double soft_stand_duration_s = 3.0;      ///< [s]
  double reset_min_damping_s = 1.0;        ///< Minimum time in damping before reset [s].
  double reset_qd_max = 0.5;               ///< Every |qd| below this to reset [rad/s].
  WatchdogOptions watchdog;
  EnvelopeOptions envelope;

  /// Empty when valid, else a message naming the first bad field and the expected range.
  std::string validate() const;
  /// Joint limits, standing pose and gains from the robot config (stand gains = config kp/kd,
  /// damping kd = config kd, kp_max = 2 kp, kd_max = 4 kd). Setup only.
  static SafetyOptions fromRobot(const pmg::RobotConfig& robot);
};

/// Per-tick input, sized by SafetySupervisor::makeInput(). Joint-side, robot joint order.
struct SafetyInput {
  double now_s = 0.0;                   ///< CLOCK_MONOTONIC [s].
  ModeRequest request = ModeRequest::kNone;
  std::vector<double> q, qd, tau;       ///< Measured (n) [rad, rad/s, N m].
  std::vector<double> motor_stamp_s;    ///< Time of the last valid reply per joint (n) [s].
  ImuSample imu;
  double base_height_m = 0.0;           ///< Pelvis height above ground [m]; NaN = unknown.
  std::vector<double> cmd_q, cmd_qd, cmd_kp, cmd_kd, cmd_tau;  ///< Loop command (n).
  double command_stamp_s = -1e9;        ///< When the loop published cmd_* [s].
  double policy_stamp_s = -1e9;         ///< When the policy output behind cmd_* was produced [s].
  bool policy_valid = false;            ///< Policy output finite and within its contract.
  bool backend_fault = false;           ///< The wrapped backend reported kFault this tick.
};

/// Per-tick output, sized by SafetySupervisor::makeOutput().
struct SafetyOutput {
  Mode mode = Mode::kPassive;
  bool mode_changed = false;            ///< Mode differs from the previous tick.
  double time_in_mode_s = 0.0;          ///< [s]
  double stand_progress = 0.0;          ///< Soft-stand interpolation 0..1.
  Fault fault;                          ///< Latched cause of the current damping (kNone otherwise).
  std::vector<double> cmd_q, cmd_qd, cmd_kp, cmd_kd, cmd_tau;  ///< To the motors (n), clamped.
  std::vector<std::uint8_t> clamp_bits; ///< ClampBits per joint this tick (n).
  std::uint64_t ticks = 0;
  std::uint64_t refused_requests = 0;
  std::uint64_t clamped_joint_ticks = 0;               ///< Sum over ticks of joints with clamp bits.
  std::uint64_t slew_clamped_joint_ticks = 0;          ///< The same, kClampSlew only (q or tau_ff slew-limited).
  std::array<std::uint32_t, kNumFaultCodes> fault_counts{};  ///< Faults detected, by code.
};

/// The state machine. Construct at setup (validates, throws std::invalid_argument naming the
/// field); step() in the HAL thread.
class SafetySupervisor {
 public:
  explicit SafetySupervisor(SafetyOptions options);
  const SafetyOptions& options() const noexcept { return opt_; }
  std::size_t numJoints() const noexcept { return n_; }
  SafetyInput makeInput() const;
  SafetyOutput makeOutput() const;
  /// One HAL tick. `in` and `out` must come from makeInput()/makeOutput() of this supervisor.
  void step(const SafetyInput& in, SafetyOutput& out) noexcept;
  Mode mode() const noexcept { return mode_; }

 private:
  bool inputsHealthy(const SafetyInput& in, bool need_command, Fault& f) const noexcept;
  bool envelopeHealthy(const SafetyInput& in, Fault& f) const noexcept;
  void enter(Mode m, const SafetyInput& in) noexcept;
  void writeCommand(const SafetyInput& in, SafetyOutput& out) noexcept;

  SafetyOptions opt_;
  std::size_t n_ = 0;
  Mode mode_ = Mode::kPassive;
  double mode_since_s_ = 0.0;
  bool started_ = false;
  Fault fault_;
  std::vector<double> q_start_;   ///< Pose at soft-stand entry (n).
  std::vector<double> prev_q_;    ///< Previous tick's commanded q (n).
  std::vector<double> prev_tau_;  ///< Previous tick's commanded tau_ff (n).
  void updateImuFrozen(const SafetyInput& in) noexcept;
  double imu_last_[6] = {0, 0, 0, 0, 0, 0};
  double imu_last_stamp_s_ = -1e300;
  int imu_same_ticks_ = 0;
};

}  // namespace pmg::hal::safety
