#include "pmg/render/state_track.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>

namespace pmg::render {

namespace {

std::runtime_error fail(const std::string& file, const std::string& what) {
  return std::runtime_error(file + ": " + what);
}

bool allFinite(const double* v, std::size_t n) {
  return std::all_of(v, v + n, [](double x) { return std::isfinite(x); });
}

}  // namespace

std::size_t StateTrack::indexAt(double t) const {
  // First sample with t_i > t, then one back: the last sample at or before t.
  const auto it = std::upper_bound(samples.begin(), samples.end(), t,
                                   [](double value, const StateSample& s) { return value < s.t; });
  if (it == samples.begin()) return 0;
  return static_cast<std::size_t>(it - samples.begin()) - 1;
}

StateTrack readStateTrack(const std::string& log_path, int num_joints, const std::string& channel) {
  if (num_joints <= 0) throw std::invalid_argument("readStateTrack: num_joints must be > 0");
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw fail(log_path, "cannot open as an LCM event log");
  StateTrack track;
  track.source = log_path;
  pmg_lcm::controller_state_t m;
  long other_channels = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel != channel) {
      ++other_channels;
      continue;
    }
    std::ostringstream where;
    where << channel << " message #" << track.samples.size() << " (event " << ev->eventnum << ")";
    if (m.decode(ev->data, 0, ev->datalen) < 0) {
      // LCM messages start with the type's 64-bit fingerprint (big-endian).
      int64_t hash = 0;
      if (ev->datalen >= 8) {
        const auto* b = static_cast<const uint8_t*>(ev->data);
        uint64_t h = 0;
        for (int i = 0; i < 8; ++i) h = (h << 8) | b[i];
        hash = static_cast<int64_t>(h);
      }
      if (ev->datalen >= 8 && hash != pmg_lcm::controller_state_t::getHash())
        throw fail(log_path, where.str() +
                                 " has another pmg_lcm::controller_state_t fingerprint than this build: the log was "
                                 "written by a pmg_controller built from another version of "
                                 "lcmtypes/controller_state_t.lcm (record it again, or render it with a matching build)");
      throw fail(log_path, where.str() + " does not decode as pmg_lcm::controller_state_t (truncated or corrupt)");
    }
    if (m.num_joints != num_joints) {
      std::ostringstream s;
      s << where.str() << ": num_joints = " << m.num_joints << ", expected " << num_joints
        << " (the robot config's joint count: is the log from another robot?)";
      throw fail(log_path, s.str());
    }
    StateSample sample;
    sample.t = 1e-6 * static_cast<double>(m.utime);
    where << " at t = " << sample.t << " s";
    if (!allFinite(m.q.data(), m.q.size())) throw fail(log_path, where.str() + ": q has a non-finite value");
    if (!allFinite(m.base_position, 3))
      throw fail(log_path, where.str() + ": base_position has a non-finite value");
    if (!allFinite(m.base_quat, 4)) throw fail(log_path, where.str() + ": base_quat has a non-finite value");
    sample.q = Eigen::Map<const Eigen::VectorXd>(m.q.data(), num_joints);
    sample.p_WB = Eigen::Vector3d(m.base_position[0], m.base_position[1], m.base_position[2]);
    sample.quat_WB = Eigen::Vector4d(m.base_quat[0], m.base_quat[1], m.base_quat[2], m.base_quat[3]);
    const double norm = sample.quat_WB.norm();
    if (!(norm >= 0.9 && norm <= 1.1)) {
      std::ostringstream s;
      s << where.str() << ": |base_quat| = " << norm << ", expected a unit quaternion (w x y z) in [0.9, 1.1]";
      throw fail(log_path, s.str());
    }
    sample.quat_WB /= norm;
    sample.command = Eigen::Vector3d(m.command[0], m.command[1], m.command[2]);
    sample.phase = m.phase;
    sample.period = m.period;
    sample.mode = m.mode;
    if (!track.samples.empty() && !(sample.t > track.samples.back().t)) {
      std::ostringstream s;
      s << where.str() << ": time is not increasing (previous sample at t = " << track.samples.back().t << " s)";
      throw fail(log_path, s.str());
    }
    track.samples.push_back(std::move(sample));
  }
  if (track.samples.empty()) {
    std::ostringstream s;
    s << "no message on channel " << channel << " (" << other_channels
      << " events on other channels): is this a pmg_controller --log file?";
    throw fail(log_path, s.str());
  }
  return track;
}

std::vector<double> evenlySpacedTimes(double t0, double t1, int count) {
  if (count < 1) throw std::invalid_argument("evenlySpacedTimes: count must be >= 1");
  if (!(t1 >= t0)) throw std::invalid_argument("evenlySpacedTimes: expected t0 <= t1");
  std::vector<double> times(static_cast<std::size_t>(count), t0);
  for (int i = 1; i < count; ++i) times[static_cast<std::size_t>(i)] = t0 + (t1 - t0) * i / (count - 1);
  return times;
}

}  // namespace pmg::render
