#pragma once
/// @file runner.hpp
/// The one periodic runner of pmg, with one clock. It runs the 100 Hz loop (a tick function) over
/// the 500 Hz HAL (HalRunner::cycle), either
///  - in real time: two hal::rt::PeriodicTask threads (HAL at the backend's period, the loop at
///    loop_period_s) on absolute CLOCK_MONOTONIC deadlines, optional SCHED_FIFO / CPU pinning /
///    mlockall; now() = CLOCK_MONOTONIC − start; or
///  - in lockstep: stepLockstep() runs one loop tick at now() and then hal_cycles_per_tick HAL
///    cycles on the calling thread; now() = ticks · loop_period_s (simulated time, deterministic).
/// run() does either until a duration or a stop flag (SIGINT/SIGTERM); both end the same way.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "pmg/hal/hal_runner.hpp"

namespace pmg {

namespace hal::rt {
class PeriodicTask;
}

/// Timing mode of a run.
enum class TimingMode {
  kLockstep,  ///< the loop drives the HAL cycles itself, as fast as possible (tests, CI)
  kRealtime,  ///< 100 Hz loop thread + 500 Hz HAL thread paced to the wall clock
};

struct RunnerOptions {
  TimingMode mode = TimingMode::kLockstep;
  double loop_period_s = 0.01;  ///< [s] (100 Hz)
  int hal_cycles_per_tick = 5;  ///< HAL cycles per loop tick (500 Hz / 100 Hz)
  int loop_fifo_priority = 0;   ///< SCHED_FIFO 1..99 for the loop thread (real time); 0 = normal
  int loop_cpu = -1;
  int hal_fifo_priority = 0;    ///< SCHED_FIFO 1..99 for the HAL thread (real time); 0 = normal
  int hal_cpu = -1;
  bool lock_memory = false;     ///< mlockall before real-time operation
  /// "" if valid, else the first bad field and its expected range.
  std::string validate() const;
};

/// What a run did.
struct RunReport {
  std::int64_t ticks = 0;
  double sim_time = 0;    ///< controller time covered [s]
  double wall_time = 0;   ///< [s]
  double real_time_factor = 0;
  bool stopped_by_flag = false;  ///< the stop flag (a signal) ended it
  std::string rt_notes;   ///< real-time privileges refused (real time only)
};

class Runner {
 public:
  /// The loop tick: called with the controller time now() [s]; must be noexcept and
  /// allocation-free (it runs on the real-time loop thread).
  using Tick = std::function<void(double now)>;
  /// @throws std::invalid_argument on invalid options.
  Runner(RunnerOptions options, HalRunner& hal, Tick tick);
  ~Runner();
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;

  /// The one clock [s]: lockstep → ticks · loop period; real time → CLOCK_MONOTONIC since run().
  double now() const noexcept;
  /// Lockstep: one loop tick at now(), then the HAL cycles of one loop period; advances now().
  void stepLockstep() noexcept;
  /// Runs until @p duration seconds of controller time (≤ 0: no limit) or until *stop becomes
  /// true (checked every tick in lockstep, every 10 ms in real time).
  RunReport run(double duration, const std::atomic<bool>* stop);

  const RunnerOptions& options() const noexcept { return options_; }
  std::int64_t ticks() const noexcept { return ticks_.load(); }

 private:
  void countedTick(double now) noexcept;
  RunnerOptions options_;
  HalRunner& hal_;
  Tick tick_;
  std::atomic<std::int64_t> ticks_{0};
  std::atomic<double> t0_{0.0};        // real time: CLOCK_MONOTONIC at the start
  std::atomic<bool> realtime_{false};  // the clock in use (read by command threads through now())
};

}  // namespace pmg
