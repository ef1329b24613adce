#pragma once
/// @file hal_runner.hpp
/// One 500 Hz HAL cycle: take the newest LowCommand from the 100 Hz loop, exchange it with the
/// backend (the stack from makeHalStack()), and publish the new LowState. The loop and the HAL
/// meet only through lock-free LatestValue hand-overs, so neither ever waits for the other.
///
/// HalRunner has no thread and no clock of its own: pmg::Runner (runner.hpp) calls cycle() from
/// its HAL task (real time, hal::rt::PeriodicTask) or from stepLockstep() (lockstep).

#include <atomic>
#include <memory>

#include "pmg/hal/backend.hpp"
#include "pmg/hal/latest_value.hpp"
#include "pmg/hal/timing.hpp"

namespace pmg {

class HalRunner {
 public:
  /// @param backend the HAL stack (owned); @param num_motors joints driven (≤ kMaxMotors).
  HalRunner(std::unique_ptr<HalBackend> backend, int num_motors);
  HalRunner(const HalRunner&) = delete;
  HalRunner& operator=(const HalRunner&) = delete;

  /// Loop side: hand the newest command to the HAL (wait-free).
  void submit(const LowCommand& command) noexcept { commands_.write(command); }
  /// Loop side: newest state (wait-free). Returns true if new since the last call.
  bool latest(LowState& state) noexcept { return states_.read(state); }

  /// One HAL cycle. noexcept, allocation-free. Measures its own runtime and the time since the
  /// previous cycle (hal::rt::now), records them in timing() and hands them to the loop in the
  /// LowState (hal_runtime, hal_period, hal_overruns).
  BackendStatus cycle() noexcept;

  HalBackend& backend() noexcept { return *backend_; }
  double cyclePeriod() const noexcept { return backend_->cyclePeriod(); }
  /// Runtime/period of the HAL cycles (summarised from the reporting side after a run).
  TimingStats& timing() noexcept { return timing_; }
  std::uint64_t faultCycles() const noexcept { return fault_cycles_.load(); }

 private:
  std::unique_ptr<HalBackend> backend_;
  LatestValue<LowCommand> commands_;
  LatestValue<LowState> states_;
  LowCommand command_{};
  LowState state_{};
  TimingStats timing_;
  std::atomic<std::uint64_t> fault_cycles_{0};
  double last_start_ = -1.0, last_runtime_ = 0.0, last_period_ = 0.0;
  std::uint64_t overruns_ = 0;
};

}  // namespace pmg
