#pragma once
/// @file controller_app.hpp
/// The composition root of `pmg_controller` (and of every tool that runs its loop:
/// pmg_policy_sil, the SIL tests, bench_controller). From one ControllerConfig it builds
///
///   clips → PMG generator + GCO ─┐
///   policy stage (optional) ─────┼─ Controller (the 100 Hz tick)
///   makeHalStack() → HalRunner ──┘        │
///   TelemetryPublisher (thread) ←─────────┤ frames
///   LcmCommandSource (thread) / script ───┘ commands
///   Runner (one clock; real time or lockstep)
///
/// and runs it. docs/architecture.md draws the threads and hand-overs.

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/controller/lcm_command_source.hpp"
#include "pmg/hal/runner.hpp"
#include "pmg/hal/timing.hpp"
#include "pmg/policy/policy_stage.hpp"

namespace pmg {
namespace hal::safety {
class SafeBackend;
}
class TelemetryPublisher;

/// How a run ended, in numbers and words (printed by pmg_controller, written by pmg_policy_sil,
/// asserted by the SIL tests).
struct RunSummary {
  RunReport run;                      ///< ticks, controller/wall time, real-time factor, stopped by a signal
  TimingSummary loop, hal;            ///< tick and HAL cycle runtimes
  std::int64_t deadline_misses = 0;   ///< loop ticks (and, in real time, HAL cycles) over their period
  CommandCounters commands;           ///< NaN rejected, clamped, stale ticks
  std::array<std::uint64_t, kNumDecodeResults> lcm_input{};  ///< LCM command packets per outcome
  std::uint64_t lcm_rejected = 0;     ///< LCM command packets rejected (all causes)
  std::uint64_t reference_limited_ticks = 0;  ///< ticks the reference rate limiter acted
  std::uint64_t mode_requests_posted = 0, mode_requests_refused = 0;
  /// HAL supervisor cycles, and joint-cycles whose command it clamped (position, velocity, gains,
  /// torque or slew), of which by its slew limit (safety.q_rate_max): the motors got a later set-point.
  std::uint64_t hal_cycles = 0, clamped_joint_cycles = 0, slew_clamped_joint_cycles = 0;
  std::uint64_t telemetry_written = 0, telemetry_dropped = 0;
  Mode final_mode = Mode::kPassive;
  FaultCode fault = FaultCode::kNone;  ///< the supervisor's latched fault at the end
  int fault_joint = -1;                ///< joint index for per-joint faults
  std::string fault_joint_name;        ///< that joint's name in the robot config ("" otherwise)
  double fault_time = 0.0;             ///< [s] HAL time of the fault
  double fault_value = 0.0;            ///< offending value (height [m], angle [rad], ...)
  /// safety.startup: active, yet the motors or the IMU never all answered, so the robot never stood up.
  bool never_active = false;
  std::string backend_report;          ///< the backend's own account (HalBackend::report()), "" if none
  bool teleop_enabled = false;         ///< the config's teleop.enabled
  std::uint64_t teleop_engagements = 0, teleop_stale_events = 0;  ///< VR teleop engage / stale-stream events
  bool fell() const noexcept { return fault == FaultCode::kFallTilt || fault == FaultCode::kFallHeight; }
  /// 0: ended without a fault; 3: fell or faulted (the robot is in damping); 4: never became active
  /// although the config asked for it.
  int exitCode() const noexcept { return fault != FaultCode::kNone ? 3 : (never_active ? 4 : 0); }
  /// Multi-line human-readable summary naming the final mode and the fault in words.
  std::string text() const;
};

/// Optional parts a tool substitutes (evaluation, tests); the rest of the stack is the config's.
struct ControllerAppOptions {
  std::unique_ptr<HalBackend> backend;    ///< replaces the configured backend (wrapped by the same stack)
  std::vector<std::string> clip_files;    ///< non-empty: the generator uses these clips only
  policy::PolicyStageOptions policy;      ///< noise / mode; period, gco and engine come from the config
  bool telemetry = true;                  ///< run the telemetry publisher (LCM / log per the config)
};

/// Called after every loop tick (lockstep evaluation: metrics from simulator truth). Runs on the
/// loop thread; in real time it must be allocation-free.
using TickObserver = std::function<void(double now, const TickStatus& status, std::size_t segment)>;

class ControllerApp {
 public:
  /// Builds everything (setup: allocates, throws ConfigError / std::runtime_error naming the file).
  explicit ControllerApp(ControllerConfig config, ControllerAppOptions options = {});
  ~ControllerApp();
  ControllerApp(const ControllerApp&) = delete;
  ControllerApp& operator=(const ControllerApp&) = delete;

  /// Runs for @p duration [s] of controller time (≤ 0: until *stop) in the config's timing mode.
  /// Commands come from @p script (injected at its times, mode requests at segment starts) or,
  /// without one, in real time, from LCM. Stops cleanly on *stop (SIGINT/SIGTERM), then drains the
  /// telemetry, closes the log and summarises.
  RunSummary run(double duration, const CommandScript* script, const std::atomic<bool>* stop,
                 const TickObserver& observer = {});
  /// Lockstep for tests: one tick with @p sample as the operator input, then the HAL cycles.
  TickStatus stepLockstep(const CommandSample& sample) noexcept;
  /// Summary of what ran so far (stops the telemetry publisher).
  RunSummary finish();

  Controller& controller() noexcept { return *controller_; }
  HalRunner& hal() noexcept { return *hal_; }
  hal::safety::SafeBackend& safety() noexcept { return *safety_; }
  /// The innermost backend (the MuJoCo SIL, the CAN buses or the caller's).
  HalBackend& backend() noexcept { return *inner_; }
  Runner& runner() noexcept { return *runner_; }
  const ControllerConfig& config() const noexcept { return config_; }

 private:
  /// The runner's tick: script input (during run()), controller tick, observer.
  void loopTick(double now) noexcept;

  ControllerConfig config_;
  std::unique_ptr<HalRunner> hal_;
  hal::safety::SafeBackend* safety_ = nullptr;
  HalBackend* inner_ = nullptr;
  std::unique_ptr<TelemetryPublisher> telemetry_;
  std::unique_ptr<LcmCommandSource> lcm_input_;
  std::unique_ptr<Controller> controller_;
  std::unique_ptr<Runner> runner_;
  TickStatus last_status_{};
  RunReport report_{};
  const CommandScript* script_ = nullptr;  // during run()
  const TickObserver* observer_ = nullptr; // during run()
  CommandSample script_sample_{};
  std::size_t segment_ = 0, last_segment_ = static_cast<std::size_t>(-1);
};

}  // namespace pmg
