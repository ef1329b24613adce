#include "pmg/controller/commands.hpp"

#include <algorithm>
#include <cmath>

#include "pmg/common/config_error.hpp"
#include "pmg/common/yaml_archive.hpp"

namespace pmg {

namespace {
bool finitePositive(double v) { return std::isfinite(v) && v > 0; }
bool validRange(const std::array<double, 2>& r) { return std::isfinite(r[0]) && std::isfinite(r[1]) && r[0] <= r[1]; }
}  // namespace

std::string CommandLimits::validate() const {
  if (!(timeout > 0 && timeout < 10)) return "commands.timeout_s: expected in (0, 10) s";
  for (std::size_t i = 0; i < 3; ++i) {
    if (!finitePositive(max_velocity[i])) return "commands.max_velocity: expected finite values > 0";
    if (!finitePositive(max_acceleration[i])) return "commands.max_acceleration: expected finite values > 0";
  }
  if (!validRange(pitch_range)) return "commands.pitch_range: expected finite [min, max] with min <= max [rad]";
  if (!validRange(roll_range)) return "commands.roll_range: expected finite [min, max] with min <= max [rad]";
  if (!validRange(height_range) || !(height_range[0] > 0))
    return "commands.height_range: expected finite [min, max] with 0 < min <= max [m]";
  if (!finitePositive(posture_rate)) return "commands.posture_rate: expected a finite value > 0 [rad/s]";
  if (!finitePositive(height_rate)) return "commands.height_rate: expected a finite value > 0 [m/s]";
  if (!(standing_height >= height_range[0] && standing_height <= height_range[1]))
    return "commands.height_range: must contain the standing height " + std::to_string(standing_height) + " m";
  if (!(std::isfinite(crouched_height) && crouched_height >= 0.0))
    return "commands.crouched_height: expected 0 (off) or a height in [height_range min, standing height) [m]";
  if (crouched_height > 0.0) {
    if (!(crouched_height >= height_range[0] && crouched_height < standing_height))
      return "commands.crouched_height: expected 0 (off) or a height in [" + std::to_string(height_range[0]) + ", " +
             std::to_string(standing_height) + ") m";
    for (std::size_t i = 0; i < 3; ++i)
      if (!(finitePositive(crouched_max_velocity[i]) && crouched_max_velocity[i] <= max_velocity[i]))
        return "commands.crouched_max_velocity: expected each in (0, max_velocity]";
  }
  if (!(std::isfinite(bent_pitch) && (bent_pitch == 0.0 || (bent_pitch > 0.0 && bent_pitch <= pitch_range[1]))))
    return "commands.bent_pitch: expected 0 (off) or a torso pitch in (0, pitch_range max = " +
           std::to_string(pitch_range[1]) + "] rad";
  if (bent_pitch > 0.0)
    for (std::size_t i = 0; i < 3; ++i)
      if (!(finitePositive(bent_max_velocity[i]) && bent_max_velocity[i] <= max_velocity[i]))
        return "commands.bent_max_velocity: expected each in (0, max_velocity]";
  if (!(std::isfinite(walking_min_height) && (walking_min_height == 0.0 || (walking_min_height >= height_range[0] &&
                                                                              walking_min_height <= standing_height))))
    return "commands.walking_min_height: expected 0 (off) or a height in [" + std::to_string(height_range[0]) + ", " +
           std::to_string(standing_height) + "] m";
  if (!(std::isfinite(walking_min_height_hold_s) && walking_min_height_hold_s >= 0.0 && walking_min_height_hold_s <= 10.0))
    return "commands.walking_min_height_hold_s: expected in [0, 10] s";
  if (!finitePositive(max_reference_speed) || max_reference_speed > 50)
    return "commands.max_reference_speed: expected in (0, 50] rad/s";
  return {};
}

namespace {
double slew(double current, double target, double max_step) noexcept {
  return current + std::clamp(target - current, -max_step, max_step);
}
/// Clamps v into [lo, hi]; sets *clamped when it was outside.
double clampCount(double v, double lo, double hi, bool* clamped) noexcept {
  if (v < lo || v > hi) *clamped = true;
  return std::clamp(v, lo, hi);
}
}  // namespace

CommandShaper::CommandShaper(CommandLimits limits) : limits_(limits) { reset(); }

void CommandShaper::reset() noexcept {
  velocity_ = {};
  target_ = {};
  posture_ = {0.0, 0.0, limits_.standing_height};
  posture_target_ = posture_;
  last_walking_time_ = -1e9;
  held_ = false;
}

void CommandShaper::update(const CommandSample& s, double now, double dt, bool hold_velocity, bool upright) noexcept {
  const Command& u = s.command;
  if (s.velocity_time >= 0 && s.velocity_time != last_velocity_time_) {
    last_velocity_time_ = s.velocity_time;
    if (!std::isfinite(u.vx) || !std::isfinite(u.vy) || !std::isfinite(u.wz)) {
      ++counters_.rejected_nan;
    } else {
      bool clamped = false;
      const auto& m = limits_.max_velocity;
      target_ = {clampCount(u.vx, -m[0], m[0], &clamped), clampCount(u.vy, -m[1], m[1], &clamped),
                 clampCount(u.wz, -m[2], m[2], &clamped)};
      if (clamped) ++counters_.clamped;
    }
  }
  if (s.posture_time >= 0 && s.posture_time != last_posture_time_) {
    last_posture_time_ = s.posture_time;
    const bool height_ok = !u.height || std::isfinite(*u.height);
    if (!std::isfinite(u.pitch) || !std::isfinite(u.roll) || !height_ok) {
      ++counters_.rejected_nan;
    } else {
      bool clamped = false;
      const double h = u.height ? *u.height : limits_.standing_height;  // "none": the standing height
      posture_target_ = {clampCount(u.pitch, limits_.pitch_range[0], limits_.pitch_range[1], &clamped),
                         clampCount(u.roll, limits_.roll_range[0], limits_.roll_range[1], &clamped),
                         clampCount(h, limits_.height_range[0], limits_.height_range[1], &clamped)};
      if (clamped) ++counters_.clamped;
    }
  }
  // Staleness: no fresh velocity command within the timeout → stop (zero velocity), slewed.
  stale_ = last_velocity_time_ < 0 || (now - last_velocity_time_) > limits_.timeout;
  if (stale_) {
    ++counters_.stale_ticks;
    target_ = {};
  }
  // Walking height floor (CommandLimits::walking_min_height): walking, and for the hold after it,
  // the height goal is at least the floor; the height slew below keeps the change continuous.
  double height_goal = posture_target_.height;
  if (limits_.walking_min_height > 0.0) {
    const bool walking = target_.vx != 0.0 || target_.vy != 0.0 || target_.wz != 0.0 || velocity_.vx != 0.0 ||
                         velocity_.vy != 0.0 || velocity_.wz != 0.0;
    if (walking) last_walking_time_ = now;
    if (now - last_walking_time_ <= limits_.walking_min_height_hold_s && height_goal < limits_.walking_min_height) {
      height_goal = limits_.walking_min_height;
      ++counters_.height_floor_ticks;
    }
  }
  // Crouched (CommandLimits::crouched_height) and bent (CommandLimits::bent_pitch) velocity envelopes,
  // on the shaped height and pitch: the larger scale wins, applied along the command's direction.
  VelocityCommand goal = target_;
  double crouch_scale = 0.0, bent_scale = 0.0;
  envelopeScales(target_, {0.0, 0.0, 0.0}, &crouch_scale, &bent_scale);
  const double scale = std::max(crouch_scale, bent_scale);
  if (scale > 1.0) {
    goal = {target_.vx / scale, target_.vy / scale, target_.wz / scale};
    if (crouch_scale > 1.0) ++counters_.crouch_limited_ticks;
    if (bent_scale > 1.0) ++counters_.bent_limited_ticks;
  }
  if (hold_velocity) {  // UpsetGuard: to zero at the slew limits below
    goal = {};
    ++counters_.upset_hold_ticks;
    if (!held_) ++counters_.upsets;
  }
  held_ = hold_velocity;
  velocity_.vx = slew(velocity_.vx, goal.vx, limits_.max_acceleration[0] * dt);
  velocity_.vy = slew(velocity_.vy, goal.vy, limits_.max_acceleration[1] * dt);
  velocity_.wz = slew(velocity_.wz, goal.wz, limits_.max_acceleration[2] * dt);
  // UpsetGuard with upright: the torso straightens at the posture slew (continuous) while latched.
  const bool straighten = hold_velocity && upright;
  posture_.pitch = slew(posture_.pitch, straighten ? 0.0 : posture_target_.pitch, limits_.posture_rate * dt);
  posture_.roll = slew(posture_.roll, straighten ? 0.0 : posture_target_.roll, limits_.posture_rate * dt);
  posture_.height = slew(posture_.height, height_goal, limits_.height_rate * dt);
}

double CommandShaper::envelopeScale(const VelocityCommand& v, const std::array<double, 3>& min_limit) const noexcept {
  double crouch_scale = 0.0, bent_scale = 0.0;
  envelopeScales(v, min_limit, &crouch_scale, &bent_scale);
  return std::max(crouch_scale, bent_scale);
}

double CommandShaper::envelopeScaleBesideYaw(const VelocityCommand& v, const std::array<double, 3>& min_limit) const noexcept {
  // The edge (1), or where the shaped ω alone already lies beyond it (a transient of the slews): then
  // v_x and v_y go to 0, continuously, as the room the turn leaves them closes.
  const double target = std::max(1.0, envelopeScale({0.0, 0.0, velocity_.wz}, min_limit));
  const auto scale_at = [&](double s) { return envelopeScale({v.vx / s, v.vy / s, velocity_.wz}, min_limit); };
  if (scale_at(1.0) <= target) return 1.0;
  double lo = 1.0, hi = 2.0;
  for (int k = 0; k < 20 && scale_at(hi) > target; ++k) {
    lo = hi;
    hi *= 2.0;
  }
  for (int k = 0; k < 50; ++k) {
    const double mid = 0.5 * (lo + hi);
    (scale_at(mid) > target ? lo : hi) = mid;
  }
  return hi;
}

double CommandShaper::crouchFraction() const noexcept {
  if (!(limits_.crouched_height > 0.0)) return 0.0;
  return std::clamp((limits_.standing_height - posture_.height) / (limits_.standing_height - limits_.crouched_height), 0.0, 1.0);
}

void CommandShaper::envelopeScales(const VelocityCommand& v, const std::array<double, 3>& min_limit, double* crouch_scale,
                                   double* bent_scale) const noexcept {
  const double t[3] = {v.vx, v.vy, v.wz};
  // Axis i's limit blended from max_velocity (f = 0) to an envelope's own (f = 1), never below min_limit.
  const auto blended = [this, &min_limit](std::size_t i, double f, const std::array<double, 3>& at_full) {
    return std::max(min_limit[i], limits_.max_velocity[i] + f * (at_full[i] - limits_.max_velocity[i]));
  };
  *crouch_scale = 0.0;
  *bent_scale = 0.0;
  if (const double f = crouchFraction(); f > 0.0) {  // 0 with the crouched envelope off
    double box = 0.0, l1 = 0.0, per_axis = 0.0;
    for (std::size_t i = 0; i < 3; ++i) {
      box = std::max(box, std::fabs(t[i]) / std::max(min_limit[i], limits_.max_velocity[i]));
      const double r = std::fabs(t[i]) / blended(i, f, limits_.crouched_max_velocity);
      l1 += r;
      per_axis = std::max(per_axis, r);
    }
    *crouch_scale = (1.0 - f) * box + f * (limits_.crouched_per_axis ? per_axis : l1);
  }
  if (limits_.bent_pitch > 0.0) {
    const double f = std::clamp(posture_.pitch / limits_.bent_pitch, 0.0, 1.0);
    if (f > 0.0)
      for (std::size_t i = 0; i < 3; ++i) *bent_scale = std::max(*bent_scale, std::fabs(t[i]) / blended(i, f, limits_.bent_max_velocity));
  }
}

void ReferenceRateLimiter::reset(const double* q, int n) noexcept {
  for (int i = 0; i < n && i < static_cast<int>(prev_.size()); ++i) prev_[static_cast<std::size_t>(i)] = q[i];
  have_prev_ = true;
}

bool ReferenceRateLimiter::apply(double* q, int n, double dt) noexcept {
  n = std::min(n, static_cast<int>(prev_.size()));
  bool limited = false;
  if (have_prev_) {
    const double step = max_speed_ * dt;
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const double d = q[i] - prev_[k];
      if (d > step || d < -step) {
        q[i] = prev_[k] + std::clamp(d, -step, step);
        limited = true;
      }
    }
  }
  reset(q, n);
  if (limited) ++limited_ticks_;
  return limited;
}

// ------------------------------------------------------------------------------------ scripts

double CommandScript::duration() const {
  return segments.empty() ? 0.0 : segments.back().start + segments.back().duration;
}

std::size_t CommandScript::segmentIndex(double t) const {
  std::size_t k = 0;
  while (k + 1 < segments.size() && t >= segments[k + 1].start) ++k;
  return k;
}

Command CommandScript::at(double t) const {
  if (segments.empty()) return {};
  const std::size_t k = segmentIndex(t);
  const Command& to = segments[k].command;
  if (k == 0 || !(ramp > 0)) return to;
  const Command& from = segments[k - 1].command;
  const double a = std::clamp((t - segments[k].start) / ramp, 0.0, 1.0);
  const auto mix = [a](double x, double y) { return x + a * (y - x); };
  Command u{mix(from.vx, to.vx), mix(from.vy, to.vy), mix(from.wz, to.wz), mix(from.pitch, to.pitch),
            mix(from.roll, to.roll), to.height};
  if (from.height && to.height) u.height = mix(*from.height, *to.height);
  return u;
}

namespace {

/// The YAML form of one segment (keys of both placements; loadCommandScript checks which is used).
struct SegmentYaml {
  std::string name, label;
  std::optional<double> t, duration;
  double vx = 0, vy = 0, wz = 0, pitch = 0, roll = 0;
  std::optional<double> height;
  std::optional<ModeRequest> mode;
  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &name, "segment name");
    a->Visit("label", &label, "segment name (alias of name)");
    a->Visit("t", &t, "start time [s] since the script start");
    a->Visit("duration", &duration, "segment length [s]");
    a->Visit("vx", &vx, "forward velocity, heading frame [m/s]");
    a->Visit("vy", &vy, "lateral velocity, left positive [m/s]");
    a->Visit("wz", &wz, "yaw rate, counter-clockwise positive [rad/s]");
    a->Visit("pitch", &pitch, "torso forward bend [rad]");
    a->Visit("roll", &roll, "torso lean, right positive [rad]");
    a->Visit("height", &height, "pelvis height [m]; absent: no height command (standing height)");
    a->Visit("mode", &mode, "mode request posted when the segment starts");
  }
};

struct ScriptYaml {
  double ramp = 0.0;
  std::optional<double> duration;
  std::vector<SegmentYaml> segments;
  template <class A>
  void Serialize(A* a) {
    a->Visit("ramp", &ramp, "linear ramp between segments [s]");
    a->Visit("duration", &duration, "total length [s] (required with t)");
    a->Visit("segments", &segments, "the segments", yaml::kRequired);
  }
  std::string validate() const {
    if (!(ramp >= 0 && ramp < 60)) return "ramp: expected in [0, 60) s";
    if (segments.empty()) return "segments: expected at least one segment";
    return {};
  }
};

}  // namespace

std::vector<std::pair<std::string, ModeRequest>> yamlEnumNames(ModeRequest) {
  return {{"passive", ModeRequest::kPassive}, {"soft_stand", ModeRequest::kSoftStand},
          {"active", ModeRequest::kActive},   {"damping", ModeRequest::kDamping},
          {"reset", ModeRequest::kReset}};
}

CommandScript loadCommandScript(const std::string& path) {
  const yaml::YamlDocument doc = yaml::loadYamlDocument(path);
  ScriptYaml y;
  yaml::readYaml(doc, &y);
  CommandScript script;
  script.source_file = path;
  script.ramp = y.ramp;
  const YAML::Node segs = doc.root["segments"];
  const bool by_start = y.segments[0].t.has_value();
  for (std::size_t i = 0; i < y.segments.size(); ++i) {
    const SegmentYaml& g = y.segments[i];
    const yaml::YamlSource where{path, doc.source.base_dir, "segments[" + std::to_string(i) + "]"};
    const auto fail = [&](const std::string& msg) { yaml::fail(where, segs[i], msg); };
    if (g.t.has_value() != by_start || g.duration.has_value() == by_start)
      fail(by_start ? "expected 't' (start time) and no 'duration', like segments[0]"
                    : "expected 'duration' and no 't', like segments[0]");
    if (!g.name.empty() && !g.label.empty()) fail("give 'name' or 'label', not both");
    CommandSegment s;
    s.name = g.name.empty() ? g.label : g.name;
    s.command = Command{g.vx, g.vy, g.wz, g.pitch, g.roll, g.height};
    if (g.height && !(*g.height > 0 && *g.height < 3)) fail("height: expected in (0, 3) m, or absent for none");
    s.mode = g.mode.value_or(ModeRequest::kNone);
    if (by_start) {
      s.start = *g.t;
      if (i == 0 && s.start != 0.0) fail("t: the first segment must start at t: 0");
      if (i > 0 && !(s.start > script.segments.back().start))
        fail("t: expected later than the previous segment's t");
      if (i > 0) script.segments.back().duration = s.start - script.segments.back().start;
    } else {
      s.duration = *g.duration;
      if (!(s.duration > 0 && s.duration < 3600)) fail("duration: expected in (0, 3600) s");
      s.start = i == 0 ? 0.0 : script.segments.back().start + script.segments.back().duration;
    }
    script.segments.push_back(s);
  }
  if (by_start) {
    if (!y.duration) yaml::fail(doc.source, doc.root, "duration: required when the segments give 't'");
    const double end = *y.duration - script.segments.back().start;
    if (!(end > 0 && *y.duration < 36000))
      yaml::fail(doc.source, doc.root, "duration: expected after the last segment's t and < 36000 s");
    script.segments.back().duration = end;
  } else if (y.duration && std::fabs(*y.duration - script.duration()) > 1e-9) {
    yaml::fail(doc.source, doc.root,
               "duration: " + std::to_string(*y.duration) + " s disagrees with the sum of the segments' durations (" +
                   std::to_string(script.duration()) + " s); omit it");
  }
  return script;
}

}  // namespace pmg
