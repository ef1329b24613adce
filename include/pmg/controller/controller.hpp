#pragma once
/// @file controller.hpp
/// `pmg_controller`'s core: the 100 Hz loop (read → update → write) over the 500 Hz HAL.
///
/// Each tick: take the newest HAL state and operator input (lock-free), validate and shape the
/// command, run the mode logic (passive → soft stand → active PMG → latched damping), step the PMG
/// generator, hand the motor commands to the HAL, and queue a telemetry frame for the publisher
/// thread (LCM + event log). tick() is noexcept and allocation-free (tested); everything that may
/// allocate or block (LCM, file I/O) runs on other threads.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "pmg/controller/commands.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/controller/spsc_ring.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/hal/hal_runner.hpp"
#include "pmg/hal/latest_value.hpp"

namespace pmg::hal::safety {
class SafeBackend;
}  // namespace pmg::hal::safety
namespace pmg::policy {
class PolicyStage;
}  // namespace pmg::policy

namespace lcm {
class LCM;
class LogFile;
}  // namespace lcm

namespace pmg {

/// Fault codes (first fault latched into damping; also in telemetry).
enum class ControllerFault : std::int32_t {
  kNone = 0,
  kInvalidState = 1,    ///< NaN/Inf or missing motor/IMU data from the HAL
  kBackendFault = 2,    ///< the backend reported a fault (bus down, simulation diverged)
  kEstopRequest = 3,    ///< damping requested by the operator
};

/// One telemetry frame (trivially copyable; crosses the SPSC ring).
struct TelemetryFrame {
  double time = 0;
  std::int64_t tick = 0;
  std::int8_t mode = 0;
  int num_joints = 0;
  std::array<double, kMaxMotors> q{}, qd{}, tau{}, q_ref{}, qd_ref{};
  double phase = 0, period = 0;
  std::array<bool, 2> in_contact{};
  std::array<double, 6> command{};
  std::array<double, 6> command_opt{};  ///< u' after GCO (eq. 19)
  std::int32_t gco_status = 0;
  std::array<double, 3> base_position{};
  std::array<double, 4> base_quat{1, 0, 0, 0};
  std::array<double, 3> imu_gyro{}, imu_acc{};
  std::int32_t generator_status = 0;
  std::int32_t fault = 0;
  double loop_runtime = 0;   ///< compute time of this tick [s]
  double loop_period = 0;    ///< time since the previous tick start [s] (wall clock)
  double hal_runtime = 0, hal_period = 0;  ///< the HAL cycle before this tick [s] (real time)
  std::uint64_t hal_overruns = 0;
};

/// Summary of a run (printed by pmg_controller, asserted by the SIL tests).
struct RunSummary {
  std::int64_t ticks = 0;
  double sim_time = 0;            ///< controller time covered [s]
  double wall_time = 0;           ///< wall-clock duration [s]
  double real_time_factor = 0;    ///< sim_time / wall_time
  TimingSummary loop, hal;
  std::int64_t deadline_misses = 0;  ///< loop ticks that overran their period (or woke late)
  CommandCounters commands;
  std::uint64_t telemetry_dropped = 0;
  std::uint64_t telemetry_written = 0;
  ControllerFault fault = ControllerFault::kNone;
  ControllerMode final_mode = ControllerMode::kPassive;
};

class Controller {
 public:
  /// Setup: loads the clips, builds the generator, the backend and the HAL, opens LCM and the
  /// event log. @throws ConfigError / std::runtime_error naming the file and field.
  explicit Controller(ControllerConfig config);
  /// Same with an explicit backend (test mocks, custom hardware) instead of the config's; the HAL
  /// supervisor (config safety.hal_supervisor) still wraps it.
  Controller(ControllerConfig config, std::unique_ptr<HalBackend> backend);
  ~Controller();
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;

  /// Lockstep run for @p duration seconds of controller time; the loop drives the HAL cycles.
  /// @p script (optional) provides the operator commands, injected as if received.
  RunSummary runLockstep(double duration, const CommandScript* script);
  /// Real-time run: HAL thread at hal_rate_hz, loop at loop_rate_hz on this thread, LCM input
  /// thread; stops after @p duration (≤ 0: until @p stop becomes true).
  RunSummary runRealtime(double duration, const std::atomic<bool>* stop, const CommandScript* script);

  /// One 100 Hz tick at controller time @p now [s]. noexcept, allocation-free.
  void tick(double now) noexcept;

  /// Operator input (single producer at a time: the LCM thread, a script, or a test).
  void setInput(const CommandSample& sample) noexcept { input_.write(sample); }

  ControllerMode mode() const noexcept { return mode_; }
  ControllerFault fault() const noexcept { return fault_; }
  const MotionGenerator& generator() const noexcept { return pmg_->generator(); }
  /// GCO result of the last active tick (u' = the policy's command observation, PMG eq. 19).
  const gco::GcoResult& gcoResult() const noexcept { return pmg_->gcoResult(); }
  HalRunner& hal() noexcept { return *hal_; }
  /// The policy stage, or nullptr when the motors follow PMG directly.
  const policy::PolicyStage* policy() const noexcept { return policy_.get(); }
  /// The HAL's safety supervisor (config safety.hal_supervisor), or nullptr.
  hal::safety::SafeBackend* halSafety() noexcept { return hal_safety_; }
  const ControllerConfig& config() const noexcept { return config_; }
  const LowCommand& lastCommand() const noexcept { return command_; }
  const LowState& lastState() const noexcept { return state_; }
  const CommandShaper& commands() const noexcept { return shaper_; }

 private:
  void publisherMain();
  void drainTelemetry();
  void publishTiming(const char* task, const TimingSummary& summary, double period, std::int64_t utime,
                     std::int64_t misses);
  void lcmInputMain();
  void enterDamping(ControllerFault why) noexcept;
  /// End of a run: stops the publisher (draining the telemetry), fills the summary, closes the log.
  void finishRun(RunSummary& summary, bool count_hal_misses);
  /// Writes the script's command at time @p now as operator input (as if received).
  void injectScript(const CommandScript& script, double now, CommandSample& sample) noexcept;

  ControllerConfig config_;
  std::shared_ptr<const GeneratorModel> generator_model_;
  std::unique_ptr<gco::GeneratorWithGco> pmg_;  // PMG generator + GCO (the complete generator)
  std::unique_ptr<policy::PolicyStage> policy_;  // trained actor (legs), if configured
  std::unique_ptr<HalRunner> hal_;
  CommandShaper shaper_;
  LatestValue<CommandSample> input_;
  CommandSample sample_{};
  LowState state_{};
  LowCommand command_{};
  ControllerMode mode_ = ControllerMode::kSoftStand;
  ControllerFault fault_ = ControllerFault::kNone;
  std::uint32_t last_mode_seq_ = 0;
  double mode_start_time_ = 0;
  bool have_stand_start_ = false;
  std::array<double, kMaxMotors> stand_start_{};
  std::uint64_t backend_faults_seen_ = 0;
  int invalid_ticks_ = 0;                       // consecutive ticks with an invalid state
  hal::safety::SafeBackend* hal_safety_ = nullptr;  // the HAL's supervisor, if any (owned by hal_)
  std::int64_t ticks_ = 0;
  double last_tick_wall_ = -1;
  std::int64_t deadline_misses_ = 0;
  double dt_ = 0.01;

  SpscRing<TelemetryFrame, 1024> telemetry_;
  TelemetryFrame frame_{};
  TimingStats loop_timing_;  // recorded by the publisher thread from the frames
  TimingStats hal_timing_;   // HAL cycles sampled once per tick (real time), ditto
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<lcm::LogFile> log_;
  std::atomic<bool> publisher_running_{false};
  std::atomic<bool> input_running_{false};
  std::thread publisher_, input_thread_;
  std::uint64_t telemetry_written_ = 0;
};

}  // namespace pmg
