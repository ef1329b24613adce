#include "pmg/controller/commands.hpp"

#include <algorithm>
#include <cmath>

#include <yaml-cpp/yaml.h>

#include "pmg/common/robot_config.hpp"

namespace pmg {

std::string CommandLimits::validate() const {
  if (!(timeout > 0 && timeout < 10)) return "commands.timeout_s: expected in (0, 10) s";
  for (int i = 0; i < 3; ++i) {
    if (!(max_velocity[static_cast<std::size_t>(i)] > 0)) return "commands.max_velocity: expected > 0";
    if (!(max_acceleration[static_cast<std::size_t>(i)] > 0)) return "commands.max_acceleration: expected > 0";
    if (!(posture_min[static_cast<std::size_t>(i)] <= posture_max[static_cast<std::size_t>(i)]))
      return "commands.posture_min/max: expected min <= max";
  }
  if (!(posture_rate > 0)) return "commands.posture_rate: expected > 0";
  return {};
}

namespace {
double slew(double current, double target, double max_step) noexcept {
  return current + std::clamp(target - current, -max_step, max_step);
}
}  // namespace

void CommandShaper::reset() noexcept {
  velocity_ = {};
  target_ = {};
  posture_ = {};
  posture_target_ = {};
}

void CommandShaper::update(const CommandSample& s, double now, double dt) noexcept {
  if (s.velocity_time >= 0 && s.velocity_time != last_velocity_time_) {
    last_velocity_time_ = s.velocity_time;
    const VelocityCommand& v = s.velocity;
    if (!std::isfinite(v.vx) || !std::isfinite(v.vy) || !std::isfinite(v.wz)) {
      ++counters_.rejected_nan;
    } else {
      std::array<double, 3> u{v.vx, v.vy, v.wz};
      bool clamped = false;
      for (std::size_t i = 0; i < 3; ++i) {
        if (std::fabs(u[i]) > limits_.max_velocity[i]) clamped = true;
        u[i] = std::clamp(u[i], -limits_.max_velocity[i], limits_.max_velocity[i]);
      }
      if (clamped) ++counters_.clamped;
      target_ = {u[0], u[1], u[2]};
    }
  }
  if (s.posture_time >= 0 && s.posture_time != last_posture_time_) {
    last_posture_time_ = s.posture_time;
    const PostureCommand& p = s.posture;
    if (!std::isfinite(p.pitch) || !std::isfinite(p.roll) || !std::isfinite(p.height)) {
      ++counters_.rejected_nan;
    } else {
      std::array<double, 3> u{p.pitch, p.roll, p.height};
      bool clamped = false;
      for (std::size_t i = 0; i < 3; ++i) {
        if (i == 2 && u[i] <= 0) continue;  // height <= 0: standing height
        if (u[i] < limits_.posture_min[i] || u[i] > limits_.posture_max[i]) clamped = true;
        u[i] = std::clamp(u[i], limits_.posture_min[i], limits_.posture_max[i]);
      }
      if (clamped) ++counters_.clamped;
      posture_target_ = {u[0], u[1], u[2]};
    }
  }
  // Staleness: no fresh velocity command within the timeout → stop (zero velocity), slewed.
  stale_ = last_velocity_time_ < 0 || (now - last_velocity_time_) > limits_.timeout;
  if (stale_) {
    ++counters_.stale_ticks;
    target_ = {};
  }
  velocity_.vx = slew(velocity_.vx, target_.vx, limits_.max_acceleration[0] * dt);
  velocity_.vy = slew(velocity_.vy, target_.vy, limits_.max_acceleration[1] * dt);
  velocity_.wz = slew(velocity_.wz, target_.wz, limits_.max_acceleration[2] * dt);
  posture_.pitch = slew(posture_.pitch, posture_target_.pitch, limits_.posture_rate * dt);
  posture_.roll = slew(posture_.roll, posture_target_.roll, limits_.posture_rate * dt);
  // Height: 0 means "standing"; slew between explicit heights only.
  if (posture_target_.height <= 0 || posture_.height <= 0)
    posture_.height = posture_target_.height;
  else
    posture_.height = slew(posture_.height, posture_target_.height, limits_.posture_rate * dt);
}

double CommandScript::duration() const {
  double t = 0;
  for (const auto& s : segments) t += s.duration;
  return t;
}

const CommandSegment& CommandScript::at(double t) const {
  double start = 0;
  for (const auto& s : segments) {
    if (t < start + s.duration) return s;
    start += s.duration;
  }
  return segments.back();
}

CommandScript loadCommandScript(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": cannot read command script: " + e.what());
  }
  CommandScript script;
  script.source_file = path;
  const YAML::Node segs = root["segments"];
  if (!segs || !segs.IsSequence() || segs.size() == 0)
    throw ConfigError(path + ": segments: missing or empty (expected a list of {duration, vx, vy, wz, pitch, roll, height})");
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const std::string k = path + ": segments[" + std::to_string(i) + "]";
    CommandSegment s;
    const auto get = [&](const char* key, double fallback) {
      if (!segs[i][key]) return fallback;
      double v;
      try {
        v = segs[i][key].as<double>();
      } catch (const YAML::Exception&) {
        throw ConfigError(k + "." + key + ": not a number");
      }
      if (!std::isfinite(v)) throw ConfigError(k + "." + key + ": not finite");
      return v;
    };
    s.duration = get("duration", -1.0);
    if (!(s.duration > 0 && s.duration < 3600)) throw ConfigError(k + ".duration: expected in (0, 3600) s");
    s.velocity = {get("vx", 0), get("vy", 0), get("wz", 0)};
    s.posture = {get("pitch", 0), get("roll", 0), get("height", 0)};
    if (segs[i]["label"]) s.label = segs[i]["label"].as<std::string>();
    script.segments.push_back(s);
  }
  return script;
}

}  // namespace pmg
