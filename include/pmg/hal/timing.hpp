#pragma once
/// @file timing.hpp
/// Runtime and period statistics of a periodic task (p50 / p99 / max) and its deadline misses,
/// recorded allocation-free in the task and summarised outside it.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

namespace pmg {

/// Summary of a window of samples [s].
struct TimingSummary {
  std::int64_t cycles = 0;
  double runtime_p50 = 0, runtime_p99 = 0, runtime_max = 0;
  double period_p50 = 0, period_p99 = 0, period_max = 0;
  std::int64_t deadline_misses = 0;
};

/// Keeps the last kWindow runtime/period samples of a task. record() is noexcept and
/// allocation-free (call it from the task); summary() sorts copies and is meant for the
/// reporting side (it allocates nothing either, but costs O(kWindow log kWindow)).
class TimingStats {
 public:
  static constexpr std::size_t kWindow = 4096;

  /// @param runtime compute time of this cycle [s]; @param period time since the previous start [s]
  /// (≤ 0 for the first cycle); @param missed whether this cycle overran its deadline.
  void record(double runtime, double period, bool missed) noexcept {
    runtime_[head_] = runtime;
    period_[head_] = period;
    head_ = (head_ + 1) % kWindow;
    if (count_ < kWindow) ++count_;
    ++cycles_;
    if (missed) ++misses_;
  }
  std::int64_t cycles() const noexcept { return cycles_; }
  std::int64_t deadlineMisses() const noexcept { return misses_; }

  TimingSummary summary() noexcept {
    TimingSummary s;
    s.cycles = cycles_;
    s.deadline_misses = misses_;
    if (count_ == 0) return s;
    percentiles(runtime_, s.runtime_p50, s.runtime_p99, s.runtime_max);
    percentiles(period_, s.period_p50, s.period_p99, s.period_max);
    return s;
  }

 private:
  void percentiles(const std::array<double, kWindow>& src, double& p50, double& p99, double& max) noexcept {
    std::size_t m = 0;
    for (std::size_t i = 0; i < count_; ++i)
      if (src[i] > 0) scratch_[m++] = src[i];
    if (m == 0) return;
    std::sort(scratch_.begin(), scratch_.begin() + static_cast<std::ptrdiff_t>(m));
    p50 = scratch_[m / 2];
    p99 = scratch_[std::min(m - 1, (m * 99) / 100)];
    max = scratch_[m - 1];
  }

  std::array<double, kWindow> runtime_{}, period_{}, scratch_{};
  std::size_t head_ = 0, count_ = 0;
  std::int64_t cycles_ = 0, misses_ = 0;
};

}  // namespace pmg
