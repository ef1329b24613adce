#pragma once
/// @file realtime.hpp (pmg::hal core; used by pmg::Runner for the HAL thread and the 100 Hz loop)
/// @brief Real-time helpers for periodic tasks: mlockall, SCHED_FIFO, CPU affinity, and a periodic
/// runner that wakes on absolute deadlines (clock_nanosleep TIMER_ABSTIME) and records runtime /
/// period statistics (pmg::TimingStats: p50/p99/max) and overruns, allocation-free in the cycle.
///
/// Every privileged step is optional and degrades gracefully: without CAP_SYS_NICE / RLIMIT_RTPRIO
/// the task runs with normal scheduling and RtReport says why; without RLIMIT_MEMLOCK mlockall is
/// skipped likewise. Used by pmg_sil, the HAL bench, and available to the 100 Hz loop.

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>

#include "pmg/hal/timing.hpp"

namespace pmg::hal::rt {

/// What a real-time setup actually obtained.
struct RtReport {
  bool memory_locked = false;
  bool fifo = false;
  bool affinity = false;
  std::string notes;  ///< One line per refused request, with the reason (errno text).
};

/// mlockall(MCL_CURRENT | MCL_FUTURE). False (reason in `why`) if refused.
bool lockMemory(std::string* why = nullptr);
/// SCHED_FIFO with `priority` (1..99) for the calling thread. False (reason in `why`) if refused.
bool setThreadFifo(int priority, std::string* why = nullptr);
/// Pin the calling thread to `cpu`. False (reason in `why`) if refused or cpu does not exist.
bool setThreadAffinity(int cpu, std::string* why = nullptr);
/// CLOCK_MONOTONIC now [s].
double now() noexcept;
/// Sleep until the absolute CLOCK_MONOTONIC time t [s] (TIMER_ABSTIME; restarts on EINTR).
void sleepUntil(double t) noexcept;

/// Options of a periodic task.
struct PeriodicOptions {
  double period_s = 0.002;   ///< [s]
  int fifo_priority = 0;     ///< 1..99 for SCHED_FIFO, 0 = normal scheduling.
  int cpu = -1;              ///< CPU to pin to, -1 = any.
  bool lock_memory = false;  ///< mlockall before the first cycle.
  std::string validate() const;
};

/// Runs `body` every period on its own thread. The body must be noexcept and allocation-free; the
/// runner itself allocates nothing per cycle. A cycle that ends after the next deadline counts as
/// an overrun; if it overran by more than a whole period the schedule re-anchors (skips) instead
/// of bursting.
class PeriodicTask {
 public:
  /// Throws std::invalid_argument on invalid options.
  PeriodicTask(PeriodicOptions options, std::function<void()> body);
  ~PeriodicTask();
  PeriodicTask(const PeriodicTask&) = delete;
  PeriodicTask& operator=(const PeriodicTask&) = delete;

  /// Start the thread; returns what the RT setup obtained (after the thread applied it).
  RtReport start();
  /// Stop and join.
  void stop();
  /// Run `cycles` cycles on the calling thread (applies the same RT setup to it), then return.
  RtReport runFor(std::int64_t cycles);
  /// Statistics (read after stop() or from a reporting thread; see pmg::TimingStats).
  TimingStats& timing() noexcept { return stats_; }
  std::int64_t overruns() const noexcept { return stats_.deadlineMisses(); }

 private:
  RtReport setupThread();
  void loop(std::int64_t max_cycles);
  PeriodicOptions opt_;
  std::function<void()> body_;
  TimingStats stats_;
  std::atomic<bool> running_{false};
  std::thread thread_;
  RtReport report_;
  std::atomic<bool> ready_{false};
};

}  // namespace pmg::hal::rt
