#include "pmg/hal/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace pmg::hal::rt {

double now() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void sleepUntil(double t) noexcept {
  timespec ts{};
  const double s = std::floor(t);
  ts.tv_sec = static_cast<time_t>(s);
  ts.tv_nsec = static_cast<long>((t - s) * 1e9);
  if (ts.tv_nsec >= 1000000000L) {
    ts.tv_sec += 1;
    ts.tv_nsec -= 1000000000L;
  }
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

bool lockMemory(std::string* why) {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return true;
  if (why) *why = std::string("mlockall: ") + std::strerror(errno);
  return false;
}

bool setThreadFifo(int priority, std::string* why) {
  sched_param sp{};
  sp.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  if (rc == 0) return true;
  if (why) *why = "SCHED_FIFO " + std::to_string(priority) + ": " + std::strerror(rc);
  return false;
}

bool setThreadAffinity(int cpu, std::string* why) {
  const long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  if (cpu < 0 || cpu >= ncpu || cpu >= CPU_SETSIZE) {
    if (why) *why = "affinity: cpu " + std::to_string(cpu) + " not in [0, " + std::to_string(ncpu) + ")";
    return false;
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
  if (rc == 0) return true;
  if (why) *why = "affinity cpu " + std::to_string(cpu) + ": " + std::strerror(rc);
  return false;
}

std::string PeriodicOptions::validate() const {
  if (!(period_s >= 1e-5 && period_s <= 10.0)) return "period_s: expected 1e-5..10 s";
  if (fifo_priority < 0 || fifo_priority > 99) return "fifo_priority: expected 0..99";
  if (cpu < -1) return "cpu: expected -1 (any) or a CPU index";
  return {};
}

PeriodicTask::PeriodicTask(PeriodicOptions options, std::function<void()> body)
    : opt_(options), body_(std::move(body)) {
  const std::string msg = opt_.validate();
  if (!msg.empty()) throw std::invalid_argument("periodic task options: " + msg);
  if (!body_) throw std::invalid_argument("periodic task: empty body");
}

PeriodicTask::~PeriodicTask() { stop(); }

RtReport PeriodicTask::setupThread() {
  RtReport r;
  std::string why;
  if (opt_.lock_memory) {
    r.memory_locked = lockMemory(&why);
    if (!r.memory_locked) r.notes += why + " (continuing without locked memory)\n";
  }
  if (opt_.fifo_priority > 0) {
    r.fifo = setThreadFifo(opt_.fifo_priority, &why);
    if (!r.fifo) r.notes += why + " (continuing with normal scheduling)\n";
  }
  if (opt_.cpu >= 0) {
    r.affinity = setThreadAffinity(opt_.cpu, &why);
    if (!r.affinity) r.notes += why + " (continuing without affinity)\n";
  }
  return r;
}

void PeriodicTask::loop(std::int64_t max_cycles) {
  const double period = opt_.period_s;
  double next = now();
  double last_start = -1.0;
  for (std::int64_t k = 0; (max_cycles < 0 || k < max_cycles) && running_.load(std::memory_order_relaxed); ++k) {
    const double start = now();
    body_();
    const double end = now();
    next += period;
    const bool missed = end > next;
    stats_.record(end - start, last_start > 0 ? start - last_start : 0.0, missed);
    last_start = start;
    if (end > next + period) next = end;  // overran by more than a period: re-anchor
    sleepUntil(next);
  }
}

RtReport PeriodicTask::start() {
  if (running_.exchange(true)) return report_;
  ready_ = false;
  thread_ = std::thread([this] {
    report_ = setupThread();
    ready_ = true;
    loop(-1);
  });
  while (!ready_.load()) std::this_thread::yield();
  return report_;
}

void PeriodicTask::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

RtReport PeriodicTask::runFor(std::int64_t cycles) {
  RtReport r = setupThread();
  running_ = true;
  loop(cycles);
  running_ = false;
  // Drop FIFO again on the caller's thread.
  if (r.fifo) {
    sched_param sp{};
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
  }
  return r;
}

}  // namespace pmg::hal::rt
