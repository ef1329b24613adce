#pragma once
/// @file telemetry.hpp
/// Telemetry of the 100 Hz loop: the loop pushes one TelemetryFrame per tick into a lock-free
/// SPSC ring (noexcept, allocation-free, drops and counts when full); the publisher thread drains
/// it, records the loop and HAL timing, and writes PMG_STATE (pmg_lcm::controller_state_t) and,
/// once a second, PMG_TIMING to LCM and/or an LCM event log.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "pmg/controller/spsc_ring.hpp"
#include "pmg/hal/timing.hpp"
#include "pmg/hal/types.hpp"

namespace lcm {
class LCM;
class LogFile;
}  // namespace lcm

namespace pmg {

/// One telemetry frame (trivially copyable; crosses the SPSC ring). Joint order of the robot
/// config; base pose in the world frame (simulation truth where available).
struct TelemetryFrame {
  double time = 0;  ///< controller time [s]
  std::int64_t tick = 0;
  Mode mode = Mode::kPassive;
  FaultCode fault = FaultCode::kNone;
  int num_joints = 0;
  std::array<double, kMaxMotors> q{}, qd{}, tau{}, q_ref{}, qd_ref{};  ///< [rad, rad/s, N·m]
  double phase = 0, period = 0;
  std::array<bool, 2> in_contact{};
  std::array<double, 6> command{};      ///< shaped u: vx, vy, wz, pitch, roll, height
  std::array<double, 6> command_opt{};  ///< u' after GCO (eq. 19)
  std::array<double, 3> command_feedback{};  ///< u_fb: vx, vy, wz after the velocity feedback (= u when off)
  std::array<double, 3> velocity_estimate{};  ///< leg-odometry vx, vy [m/s], wz [rad/s] in H (NaN when off)
  std::array<double, 3> posture_feedback{};   ///< pitch, roll [rad], height [m] after the posture feedback (= u when off)
  std::int32_t gco_status = 0;
  std::array<double, 3> base_position{};
  std::array<double, 4> base_quat{1, 0, 0, 0};
  std::array<double, 3> imu_gyro{}, imu_acc{};
  std::int32_t generator_status = 0;
  std::int32_t policy_status = -1;           ///< -1: no policy
  std::uint64_t commands_rejected = 0;       ///< LCM decode failures + NaN commands so far
  std::uint64_t reference_limited = 0;       ///< ticks the reference rate limiter acted, so far
  std::int32_t teleop = -1;                  ///< VR teleop state bits (controller_state_t.teleop); -1 disabled
  double loop_runtime = 0;   ///< compute time of this tick [s]
  double loop_period = 0;    ///< time since the previous tick start [s] (wall clock)
  double loop_budget = 0.01; ///< the loop period [s] (deadline)
  double hal_runtime = 0, hal_period = 0;  ///< the HAL cycle before this tick [s] (real time)
  double hal_budget = 0.002;
  std::uint64_t hal_overruns = 0;
};

/// The publisher thread. Construct at setup (opens LCM / the log; throws naming the file); the
/// loop calls push() every tick.
class TelemetryPublisher {
 public:
  /// @param lcm_url "" = no LCM publishing; @param log_file "" = no event log.
  /// @throws std::runtime_error if the log cannot be opened. An unavailable LCM is reported on
  /// stderr at setup and telemetry then goes to the log only.
  TelemetryPublisher(const std::string& lcm_url, const std::string& log_file);
  ~TelemetryPublisher();
  TelemetryPublisher(const TelemetryPublisher&) = delete;
  TelemetryPublisher& operator=(const TelemetryPublisher&) = delete;

  /// Loop side: queue a frame (noexcept, allocation-free; dropped and counted when full).
  void push(const TelemetryFrame& f) noexcept { ring_.push(f); }
  /// Starts the publisher thread.
  void start();
  /// Drains what is queued, stops the thread and closes the log (idempotent).
  void stop();

  std::uint64_t written() const noexcept { return written_.load(); }
  std::uint64_t dropped() const noexcept { return ring_.dropped(); }
  /// Loop and HAL timing recorded from the frames (read after stop()).
  TimingStats& loopTiming() noexcept { return loop_timing_; }
  TimingStats& halTiming() noexcept { return hal_timing_; }

 private:
  void drain();
  void writeEvent(const char* channel, std::int64_t utime, const void* data, int size);
  SpscRing<TelemetryFrame, 1024> ring_;
  TimingStats loop_timing_, hal_timing_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<lcm::LogFile> log_;
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> written_{0};
  std::thread thread_;
};

}  // namespace pmg
