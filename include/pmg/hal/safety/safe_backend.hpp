#pragma once
/// @file safe_backend.hpp
/// @brief Puts the SafetySupervisor between the HAL and any backend, without changing the HAL:
/// SafeBackend is itself a pmg::HalBackend that wraps the real one (CanBackend, MujocoBackend):
///
///   HalRunner(std::make_unique<SafeBackend>(std::make_unique<CanBackend>(...), options), n)
///
/// Each exchange() (one 2 ms HAL cycle, noexcept, allocation-free):
///  1. builds the SafetyInput from the previous cycle's LowState (motor replies with valid = true
///     refresh their watchdog; the IMU likewise; base height from simulation truth when valid, else
///     unknown) and from the loop's LowCommand (a new `sequence` refreshes the command watchdog;
///     the policy watchdog follows the command, and a non-finite command counts as invalid policy
///     output);
///  2. takes the pending mode request from requests() (gamepad / LCM threads post there);
///  3. steps the supervisor and sends only its clamped command to the wrapped backend;
///  4. a reply (or IMU sample) with a non-finite value counts as missing (nonfinite_replies); with
///     SafeBackendOptions::hold_missing, hands the loop the last valid reply of a motor (and the
///     last IMU sample) for a cycle in which it did not arrive, as long as that input's watchdog
///     has not expired: a single lost CAN frame is the HAL's business, not the loop's. Once the
///     watchdog expires the loop sees valid = false (and the HAL is already in damping). A cycle
///     with no reply at all whose values could all be held is returned as kPartial, not kFault;
///  4b. with SafeBackendOptions::imu_acc_lowpass_s > 0, low-passes the IMU's specific force it hands
///     the loop (first order, at the HAL rate; the supervisor still sees the raw samples);
///  5. writes the supervisor's mode, fault and stand progress into the LowState the loop reads, and
///     publishes a SafetyStatus for telemetry through a lock-free LatestValue;
///  6. a cycle whose wrapped backend returned kFault (after step 4) is a backend fault for the
///     supervisor on the next cycle (FaultCode::kBackend → damping while torque is applied).
/// Time is counted in HAL cycles (now = cycle * period), so lockstep runs are deterministic and
/// the watchdogs measure "cycles without news" exactly.

#include <memory>

#include "pmg/hal/backend.hpp"
#include "pmg/hal/latest_value.hpp"
#include "pmg/hal/safety/mode_requests.hpp"
#include "pmg/hal/safety/supervisor.hpp"

namespace pmg::hal::safety {

/// Telemetry snapshot (trivially copyable).
struct SafetyStatus {
  Mode mode = Mode::kPassive;
  Fault fault;
  double time_s = 0.0;                 ///< HAL time of this snapshot [s].
  double stand_progress = 0.0;
  /// max over joints of |predicted PD torque of the command sent| / tau_max this cycle (<= 1 by
  /// construction; telemetry proof that no torque beyond limits was commanded).
  double max_tau_ratio = 0.0;
  std::uint64_t ticks = 0;
  std::uint64_t refused_requests = 0;
  std::uint64_t clamped_joint_ticks = 0;
  /// Joint-cycles whose q or tau_ff the slew limit (EnvelopeOptions::q_rate_max, tau_rate_max) held
  /// back: where it counts, the motors follow the loop's command late.
  std::uint64_t slew_clamped_joint_ticks = 0;
  std::uint64_t nonfinite_commands = 0;  ///< Loop commands that contained NaN/Inf.
  std::uint64_t held_replies = 0;        ///< Missing motor replies / IMU samples replaced by the last valid one.
  std::uint64_t nonfinite_replies = 0;   ///< Replies / IMU samples with NaN/Inf, treated as missing.
  std::array<std::uint32_t, kNumFaultCodes> fault_counts{};
};

struct SafeBackendOptions {
  bool hold_missing = true;  ///< See step 4 above.
  /// Time constant [s] of a first-order low-pass on the IMU's specific force (ImuState::acc, IMU
  /// frame, m/s²) handed to the loop, run on every HAL cycle: y += T / (τ + T) · (acc − y), with T
  /// the cycle period; it starts from the first valid sample. 0 (the default): the raw samples. Why:
  /// the 100 Hz loop takes one HAL sample in five, and the base-velocity estimator integrates it; the
  /// foot impacts' acceleration spikes, phase-locked to the gait, then alias into a bias. In the SIL
  /// (MuJoCo's point accelerations at 1 kHz) H10a's fast crouched walks drifted the estimate 0.06-0.2
  /// m/s above the truth (docs/controller.md "The accelerometer aliased into the velocity estimate").
  /// Valid: 0 or in [T, 0.1] s (checked by makeHalStack()).
  double imu_acc_lowpass_s = 0.0;
};

class SafeBackend final : public pmg::HalBackend {
 public:
  /// Throws std::invalid_argument if `inner` is null or the options are invalid.
  SafeBackend(std::unique_ptr<pmg::HalBackend> inner, SafetyOptions options, SafeBackendOptions backend_options = {});
  const char* name() const noexcept override { return "safe"; }
  double cyclePeriod() const noexcept override { return inner_->cyclePeriod(); }
  pmg::BackendStatus exchange(const pmg::LowCommand& command, pmg::LowState& state) noexcept override;

  /// Gamepad / LCM threads post mode requests here (lock-free).
  ModeRequestMailbox& requests() noexcept { return requests_; }
  /// Reporting side: newest status (wait-free).
  bool status(SafetyStatus& out) noexcept { return status_.read(out); }
  pmg::HalBackend& inner() noexcept { return *inner_; }
  const SafetySupervisor& supervisor() const noexcept { return sup_; }
  /// Last command sent to the wrapped backend (HAL thread / lockstep caller only).
  const pmg::LowCommand& lastSafeCommand() const noexcept { return safe_; }

 private:
  std::unique_ptr<pmg::HalBackend> inner_;
  SafetySupervisor sup_;
  SafetyInput in_;
  SafetyOutput out_;
  pmg::LowCommand safe_{};
  pmg::LowState last_{};
  ModeRequestMailbox requests_;
  pmg::LatestValue<SafetyStatus> status_;
  std::uint64_t cycles_ = 0;
  std::uint64_t last_sequence_ = ~0ull;
  std::uint64_t nonfinite_ = 0;
  SafeBackendOptions bopt_;
  pmg::LowState held_{};                ///< Last valid value per motor and of the IMU.
  std::array<double, pmg::kMaxMotors> held_at_{};  ///< When each was valid [s] (cycle time).
  double imu_held_at_ = -1e9;
  std::array<double, 3> acc_lowpass_{};  ///< imu_acc_lowpass_s's state (IMU frame) [m/s²]
  bool acc_lowpass_started_ = false;
  std::uint64_t held_count_ = 0;
  std::uint64_t nonfinite_replies_ = 0;
  pmg::BackendStatus last_status_ = pmg::BackendStatus::kOk;
};

}  // namespace pmg::hal::safety
