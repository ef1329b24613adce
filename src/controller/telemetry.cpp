#include "pmg/controller/telemetry.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>
#include <pmg_lcm/timing_t.hpp>

namespace pmg {
namespace {
std::int64_t toUtime(double t) { return static_cast<std::int64_t>(std::llround(t * 1e6)); }
}  // namespace

TelemetryPublisher::TelemetryPublisher(const std::string& lcm_url, const std::string& log_file) {
  if (!lcm_url.empty()) {
    lcm_ = std::make_unique<lcm::LCM>(lcm_url);
    if (!lcm_->good()) {
      std::fprintf(stderr, "[pmg] warning: LCM '%s' not available; telemetry is not published\n", lcm_url.c_str());
      lcm_.reset();
    }
  }
  if (!log_file.empty()) {
    log_ = std::make_unique<lcm::LogFile>(log_file, "w");
    if (!log_->good()) throw std::runtime_error(log_file + ": cannot open LCM event log for writing");
  }
}

TelemetryPublisher::~TelemetryPublisher() { stop(); }

void TelemetryPublisher::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] {
    while (running_.load()) {
      drain();
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
}

void TelemetryPublisher::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  drain();
  if (log_) log_.reset();  // flush and close
}

void TelemetryPublisher::writeEvent(const char* channel, std::int64_t utime, const void* data, int size) {
  if (lcm_) lcm_->publish(channel, data, static_cast<unsigned>(size));
  if (log_) {
    lcm::LogEvent ev{};
    ev.eventnum = static_cast<int64_t>(written_.load());
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = size;
    ev.data = const_cast<void*>(data);
    log_->writeEvent(&ev);
  }
}

void TelemetryPublisher::drain() {
  TelemetryFrame f;
  pmg_lcm::controller_state_t msg;
  std::vector<std::uint8_t> buffer;
  while (ring_.pop(f)) {
    loop_timing_.record(f.loop_runtime, f.loop_period, f.loop_runtime > f.loop_budget);
    if (f.hal_period > 0) hal_timing_.record(f.hal_runtime, f.hal_period, false);
    if (!lcm_ && !log_) {
      written_.fetch_add(1);
      continue;
    }
    msg.utime = toUtime(f.time);
    msg.tick = f.tick;
    msg.mode = toWire(f.mode);
    msg.num_joints = f.num_joints;
    const auto nj = static_cast<std::ptrdiff_t>(f.num_joints);
    msg.q.assign(f.q.begin(), f.q.begin() + nj);
    msg.qd.assign(f.qd.begin(), f.qd.begin() + nj);
    msg.tau.assign(f.tau.begin(), f.tau.begin() + nj);
    msg.q_ref.assign(f.q_ref.begin(), f.q_ref.begin() + nj);
    msg.qd_ref.assign(f.qd_ref.begin(), f.qd_ref.begin() + nj);
    msg.phase = f.phase;
    msg.period = f.period;
    msg.in_contact[0] = f.in_contact[0];
    msg.in_contact[1] = f.in_contact[1];
    for (std::size_t i = 0; i < 6; ++i) {
      msg.command[i] = f.command[i];
      msg.command_opt[i] = f.command_opt[i];
    }
    msg.gco_status = f.gco_status;
    for (std::size_t i = 0; i < 3; ++i) {
      msg.base_position[i] = f.base_position[i];
      msg.command_feedback[i] = f.command_feedback[i];
      msg.velocity_estimate[i] = f.velocity_estimate[i];
      msg.posture_feedback[i] = f.posture_feedback[i];
      msg.imu_gyro[i] = f.imu_gyro[i];
      msg.imu_acc[i] = f.imu_acc[i];
    }
    for (std::size_t i = 0; i < 4; ++i) msg.base_quat[i] = f.base_quat[i];
    msg.generator_status = f.generator_status;
    msg.fault = static_cast<std::int32_t>(f.fault);
    msg.policy_status = f.policy_status;
    msg.commands_rejected = static_cast<std::int64_t>(f.commands_rejected);
    msg.reference_limited = static_cast<std::int64_t>(f.reference_limited);
    msg.teleop = f.teleop;
    const int size = msg.getEncodedSize();
    buffer.resize(static_cast<std::size_t>(size));
    msg.encode(buffer.data(), 0, size);
    writeEvent("PMG_STATE", msg.utime, buffer.data(), size);
    written_.fetch_add(1);
    if (f.tick % 100 == 99) {  // 1 Hz timing reports: the loop, and the HAL (real time)
      const auto report = [&](const char* task, TimingStats& stats, double period, std::int64_t misses) {
        const TimingSummary s = stats.summary();
        pmg_lcm::timing_t t;
        t.utime = msg.utime;
        t.task = task;
        t.cycles = s.cycles;
        t.period_target_s = period;
        t.runtime_p50_s = s.runtime_p50;
        t.runtime_p99_s = s.runtime_p99;
        t.runtime_max_s = s.runtime_max;
        t.period_p50_s = s.period_p50;
        t.period_p99_s = s.period_p99;
        t.period_max_s = s.period_max;
        t.deadline_misses = misses;
        const int n = t.getEncodedSize();
        std::vector<std::uint8_t> b(static_cast<std::size_t>(n));
        t.encode(b.data(), 0, n);
        writeEvent("PMG_TIMING", msg.utime, b.data(), n);
      };
      report("loop", loop_timing_, f.loop_budget, loop_timing_.deadlineMisses());
      if (hal_timing_.cycles() > 0)
        report("hal", hal_timing_, f.hal_budget, static_cast<std::int64_t>(f.hal_overruns));
    }
  }
}

}  // namespace pmg
