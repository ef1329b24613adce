#include "pmg/hal/hal_runner.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <string>

#include <pthread.h>
#include <sched.h>

namespace pmg {

double monotonicSeconds() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void sleepUntil(double t) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(std::floor(t));
  ts.tv_nsec = static_cast<long>((t - std::floor(t)) * 1e9);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

HalRunner::HalRunner(std::unique_ptr<HalBackend> backend, int num_motors, HalRunnerOptions options)
    : backend_(std::move(backend)), options_(options) {
  command_.num_motors = num_motors;
  commands_.write(command_);  // zero gains: passive until the loop writes
}

HalRunner::~HalRunner() { stop(); }

BackendStatus HalRunner::cycle() noexcept {
  commands_.read(command_);
  const BackendStatus status = backend_->exchange(command_, state_);
  if (status == BackendStatus::kFault) fault_cycles_.fetch_add(1);
  state_.hal_runtime = last_runtime_;
  state_.hal_period = last_period_;
  state_.hal_overruns = overruns_;
  states_.write(state_);
  return status;
}

bool HalRunner::start(std::string* error) {
  if (running_.exchange(true)) return true;
  bool ok = true;
  thread_ = std::thread([this] { threadMain(); });
  if (options_.fifo_priority > 0) {
    sched_param sp{};
    sp.sched_priority = options_.fifo_priority;
    const int rc = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &sp);
    if (rc != 0) {
      ok = false;
      if (error) *error = std::string("SCHED_FIFO priority ") + std::to_string(options_.fifo_priority) +
                          " not granted: " + std::strerror(rc) + " (running with normal priority)";
    }
  }
  if (options_.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(options_.cpu, &set);
    pthread_setaffinity_np(thread_.native_handle(), sizeof(set), &set);
  }
  return ok;
}

void HalRunner::stop() {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
}

void HalRunner::threadMain() {
  const double period = backend_->cyclePeriod();
  double next = monotonicSeconds();
  double last_start = -1.0;
  while (running_.load(std::memory_order_relaxed)) {
    const double start = monotonicSeconds();
    cycle();
    const double end = monotonicSeconds();
    const bool missed = (end - next) > period;  // finished after the next deadline
    timing_.record(end - start, last_start > 0 ? start - last_start : 0.0, missed);
    last_runtime_ = end - start;
    last_period_ = last_start > 0 ? start - last_start : 0.0;
    if (missed) ++overruns_;
    last_start = start;
    next += period;
    if (end > next + period) next = end;  // overran by more than a cycle: re-anchor, count it
    sleepUntil(next);
  }
}

}  // namespace pmg
