#pragma once
/// @file hal_runner.hpp
/// The 500 Hz HAL: each cycle takes the newest LowCommand from the controller loop, exchanges it
/// with the backend, and publishes the new LowState. The two sides meet only through lock-free
/// LatestValue hand-overs, so neither the HAL nor the loop ever waits for the other.
///
/// Two ways to run it:
///  - real time: start() spawns the HAL thread, which wakes on absolute deadlines
///    (clock_nanosleep TIMER_ABSTIME) every cycle_period, optionally with SCHED_FIFO priority,
///    and CPU affinity; stop() joins it;
///  - lockstep: the caller invokes cycle() itself (the controller does cycles_per_tick of them per
///    control tick), which runs faster than real time and is deterministic (tests, CI).

#include <atomic>
#include <memory>
#include <thread>

#include "pmg/hal/backend.hpp"
#include "pmg/hal/latest_value.hpp"
#include "pmg/hal/timing.hpp"

namespace pmg {

struct HalRunnerOptions {
  int fifo_priority = 0;  ///< SCHED_FIFO priority 1..99 for the HAL thread; 0 = normal scheduling
  int cpu = -1;           ///< CPU to pin the HAL thread to; -1 = no affinity
};

class HalRunner {
 public:
  HalRunner(std::unique_ptr<HalBackend> backend, int num_motors, HalRunnerOptions options = {});
  ~HalRunner();
  HalRunner(const HalRunner&) = delete;
  HalRunner& operator=(const HalRunner&) = delete;

  /// Loop side: hand the newest command to the HAL (wait-free).
  void submit(const LowCommand& command) noexcept { commands_.write(command); }
  /// Loop side: newest state (wait-free). Returns true if new since the last call.
  bool latest(LowState& state) noexcept { return states_.read(state); }

  /// One HAL cycle (lockstep mode, or called by the HAL thread). noexcept, allocation-free.
  BackendStatus cycle() noexcept;

  /// Real-time mode: spawn the 500 Hz thread. Returns false (with a reason in @p error) if the
  /// requested SCHED_FIFO priority could not be set; the thread then runs with normal priority.
  bool start(std::string* error = nullptr);
  void stop();
  bool running() const noexcept { return running_.load(); }

  HalBackend& backend() noexcept { return *backend_; }
  double cyclePeriod() const noexcept { return backend_->cyclePeriod(); }
  /// Timing of the HAL cycles (read from the reporting side only).
  TimingStats& timing() noexcept { return timing_; }
  std::uint64_t faultCycles() const noexcept { return fault_cycles_.load(); }

 private:
  void threadMain();

  std::unique_ptr<HalBackend> backend_;
  HalRunnerOptions options_;
  LatestValue<LowCommand> commands_;
  LatestValue<LowState> states_;
  LowCommand command_{};
  LowState state_{};
  TimingStats timing_;
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> fault_cycles_{0};
  double last_runtime_ = 0.0, last_period_ = 0.0;  // HAL thread only
  std::uint64_t overruns_ = 0;                      // HAL thread only
  std::thread thread_;
};

/// Monotonic clock in seconds.
double monotonicSeconds() noexcept;
/// Sleeps until the absolute CLOCK_MONOTONIC time @p t [s].
void sleepUntil(double t) noexcept;

}  // namespace pmg
