#include "pmg/hal/runner.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "pmg/hal/realtime.hpp"

namespace pmg {

std::string RunnerOptions::validate() const {
  if (!(loop_period_s >= 1e-4 && loop_period_s <= 1.0)) return "loop_period_s: expected 1e-4..1 s";
  if (hal_cycles_per_tick < 1 || hal_cycles_per_tick > 100) return "hal_cycles_per_tick: expected 1..100";
  if (loop_fifo_priority < 0 || loop_fifo_priority > 99) return "loop_fifo_priority: expected 0..99";
  if (hal_fifo_priority < 0 || hal_fifo_priority > 99) return "hal_fifo_priority: expected 0..99";
  if (loop_cpu < -1 || hal_cpu < -1) return "cpu: expected -1 (any) or a CPU index";
  return {};
}

Runner::Runner(RunnerOptions options, HalRunner& hal, Tick tick)
    : options_(options), hal_(hal), tick_(std::move(tick)) {
  if (const std::string e = options_.validate(); !e.empty()) throw std::invalid_argument("runner options: " + e);
  if (!tick_) throw std::invalid_argument("runner: empty tick function");
}

Runner::~Runner() = default;

double Runner::now() const noexcept {
  if (realtime_) return hal::rt::now() - t0_;
  return static_cast<double>(ticks_.load(std::memory_order_relaxed)) * options_.loop_period_s;
}

void Runner::countedTick(double now) noexcept {
  tick_(now);  // the tick's own runtime is measured by the loop (telemetry frames)
  ticks_.fetch_add(1, std::memory_order_relaxed);
}

void Runner::stepLockstep() noexcept {
  countedTick(now());
  for (int c = 0; c < options_.hal_cycles_per_tick; ++c) hal_.cycle();
}

RunReport Runner::run(double duration, const std::atomic<bool>* stop) {
  RunReport report;
  const std::int64_t ticks0 = ticks_.load();
  const double wall0 = hal::rt::now();
  const auto stopped = [stop] { return stop != nullptr && stop->load(); };
  if (options_.mode == TimingMode::kLockstep) {
    const auto n = duration > 0 ? static_cast<std::int64_t>(std::llround(duration / options_.loop_period_s)) : -1;
    for (std::int64_t k = 0; n < 0 || k < n; ++k) {
      if (stopped()) {
        report.stopped_by_flag = true;
        break;
      }
      stepLockstep();
    }
    report.sim_time = static_cast<double>(ticks_.load() - ticks0) * options_.loop_period_s;
  } else {
    hal::rt::PeriodicOptions ho;
    ho.period_s = hal_.cyclePeriod();
    ho.fifo_priority = options_.hal_fifo_priority;
    ho.cpu = options_.hal_cpu;
    ho.lock_memory = options_.lock_memory;
    hal::rt::PeriodicOptions lo;
    lo.period_s = options_.loop_period_s;
    lo.fifo_priority = options_.loop_fifo_priority;
    lo.cpu = options_.loop_cpu;
    t0_ = hal::rt::now();
    realtime_ = true;
    hal::rt::PeriodicTask hal_task(ho, [this] { hal_.cycle(); });
    hal::rt::PeriodicTask loop_task(lo, [this] { countedTick(now()); });
    report.rt_notes += hal_task.start().notes;
    report.rt_notes += loop_task.start().notes;
    while (!(duration > 0 && now() >= duration)) {
      if (stopped()) {
        report.stopped_by_flag = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    report.sim_time = now();
    loop_task.stop();
    hal_task.stop();
    realtime_ = false;
  }
  report.ticks = ticks_.load() - ticks0;
  report.wall_time = hal::rt::now() - wall0;
  report.real_time_factor = report.wall_time > 0 ? report.sim_time / report.wall_time : 0.0;
  return report;
}

}  // namespace pmg
