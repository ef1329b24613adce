#include "pmg/teleop/vr_replay.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>
#include <thread>

#include "pmg/comms/channels.hpp"
#include "pmg/teleop/vr_protocol.hpp"

namespace pmg::teleop {

std::vector<VrLogEvent> readVrLog(const std::string& path, VrLogReadStats* stats) {
  VrLogReadStats local;
  VrLogReadStats& st = stats != nullptr ? *stats : local;
  st = VrLogReadStats{};
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error(path + ": cannot open as an LCM log");
  std::vector<VrLogEvent> out;
  std::int64_t previous = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ++st.events;
    if (e->channel != kVrPoseChannel) {
      ++st.other_channels;
      continue;
    }
    const auto reject = [&](const std::string& why) {
      ++st.rejected;
      if (st.first_error.empty()) st.first_error = "event " + std::to_string(e->eventnum) + ": " + why;
    };
    if (e->datalen <= 0 || e->data == nullptr) {
      reject("empty message");
      continue;
    }
    VrLogEvent ev;
    ev.log_utime = e->timestamp;
    // decode() checks the fingerprint and every length; trailing bytes (an authentication
    // trailer) are ignored.
    if (ev.msg.decode(e->data, 0, e->datalen) < 0) {
      reject("does not decode as vr_pose_t");
      continue;
    }
    std::string why;
    if (const VrReject r = checkVrPoseMessage(ev.msg, &why); r != VrReject::kAccepted) {
      reject(std::string(toString(r)) + ": " + why);
      continue;
    }
    if (!out.empty() && ev.log_utime < previous) ++st.time_reversals;
    previous = ev.log_utime;
    out.push_back(std::move(ev));
  }
  if (st.events == 0) throw std::runtime_error(path + ": no LCM events (not an LCM log, or empty)");
  return out;
}

void VrReplayOptions::validate() const {
  if (!std::isfinite(speed) || speed <= 0.0 || speed > 100.0)
    throw std::invalid_argument("speed = " + std::to_string(speed) + ": expected a finite number in (0, 100]");
}

VrReplayStats replayVrLog(const std::vector<VrLogEvent>& events, const VrReplayOptions& options,
                          const std::function<bool(const pmg_lcm::vr_pose_t&)>& publish,
                          const std::atomic<bool>* stop) {
  options.validate();
  VrReplayStats st;
  if (events.empty()) return st;
  using Clock = std::chrono::steady_clock;
  const auto stopped = [&] { return stop != nullptr && stop->load(); };
  // One pass lasts from the first event to the last plus one typical period (median spacing), so
  // that the loop seam keeps the stream's rate.
  std::vector<std::int64_t> gaps;
  for (std::size_t i = 1; i < events.size(); ++i)
    gaps.push_back(std::max<std::int64_t>(0, events[i].log_utime - events[i - 1].log_utime));
  std::int64_t period = 0;
  if (!gaps.empty()) {
    std::nth_element(gaps.begin(), gaps.begin() + static_cast<long>(gaps.size() / 2), gaps.end());
    period = gaps[gaps.size() / 2];
  }
  const std::int64_t pass_us = std::max<std::int64_t>(1, events.back().log_utime - events.front().log_utime + period);
  const std::int64_t frames_per_pass =
      std::max<std::int64_t>(1, events.back().msg.frame - events.front().msg.frame + 1);
  const std::int64_t xr_per_pass =
      std::max<std::int64_t>(0, events.back().msg.xr_time_us - events.front().msg.xr_time_us) + period;
  const auto start = Clock::now();
  for (std::int64_t pass = 0; !stopped(); ++pass) {
    std::int64_t offset_us = 0;  // log time since the first event, kept monotonic
    std::int64_t prev = events.front().log_utime;
    for (const VrLogEvent& e : events) {
      offset_us += std::max<std::int64_t>(0, e.log_utime - prev);
      prev = e.log_utime;
      const double t = static_cast<double>(pass * pass_us + offset_us) * 1e-6 / options.speed;
      const auto due = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t));
      while (!stopped()) {
        const auto now = Clock::now();
        if (now >= due) break;
        std::this_thread::sleep_for(std::min<Clock::duration>(due - now, std::chrono::milliseconds(50)));
      }
      if (stopped()) break;
      st.max_late_s = std::max(st.max_late_s, std::chrono::duration<double>(Clock::now() - due).count());
      pmg_lcm::vr_pose_t m = e.msg;
      m.frame += pass * frames_per_pass;
      m.xr_time_us += pass * xr_per_pass;
      if (publish(m))
        ++st.published;
      else
        ++st.failed;
    }
    if (stopped()) break;
    ++st.loops;
    if (!options.loop) break;
  }
  return st;
}

}  // namespace pmg::teleop
