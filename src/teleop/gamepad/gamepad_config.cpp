// Gamepad config (config/teleop/gamepad.yaml): names, validation against the controller's command
// limits (pmg::CommandLimits), loading through the YAML archive.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "pmg/common/config_error.hpp"
#include "pmg/common/yaml_archive.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/teleop/gamepad.hpp"

namespace pmg::teleop {
namespace {

constexpr const char* kLimitsSource = "include/pmg/controller/commands.hpp";

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}
bool finite(double v) { return std::isfinite(v); }
bool within(double v, double lo, double hi) { return finite(v) && v >= lo && v <= hi; }

// "[a, b]" inside [lo, hi] with a ≤ b and containing `must`.
std::string checkRange(const char* field, const std::array<double, 2>& r, const std::array<double, 2>& limit,
                       const char* limit_name, double must, const char* unit) {
  const std::string shown = std::string(field) + " = [" + num(r[0]) + ", " + num(r[1]) + "]";
  if (!finite(r[0]) || !finite(r[1]) || r[0] > r[1])
    return shown + ": expected finite [min, max] with min <= max " + unit;
  if (r[0] < limit[0] || r[1] > limit[1])
    return shown + ": expected inside [" + num(limit[0]) + ", " + num(limit[1]) + "] " + unit +
           " (CommandLimits::" + limit_name + ", " + kLimitsSource + ")";
  if (must < r[0] || must > r[1]) return shown + ": must contain " + num(must) + " " + unit;
  return {};
}

std::string checkBinding(const char* name, const std::vector<GamepadControl>& b, std::size_t min_size) {
  if (b.size() < min_size || b.size() > 2)
    return std::string(name) + ": expected " + (min_size == 2 ? "exactly 2" : "1 or 2") +
           " controls held together, got " + std::to_string(b.size());
  if (b.size() == 2 && b[0] == b[1]) return std::string(name) + ": the two controls must differ";
  return {};
}

std::uint32_t maskOf(const std::vector<GamepadControl>& b) {
  std::uint32_t m = 0;
  for (GamepadControl c : b) m |= controlBit(c);
  return m;
}

bool isDpad(GamepadControl c) {
  return c == GamepadControl::kDpadUp || c == GamepadControl::kDpadDown || c == GamepadControl::kDpadLeft ||
         c == GamepadControl::kDpadRight;
}

}  // namespace

const char* toString(GamepadControl c) noexcept {
  static constexpr const char* kNames[] = {"a",
                                           "b",
                                           "x",
                                           "y",
                                           "back",
                                           "guide",
                                           "start",
                                           "leftstick",
                                           "rightstick",
                                           "leftshoulder",
                                           "rightshoulder",
                                           "dpup",
                                           "dpdown",
                                           "dpleft",
                                           "dpright",
                                           "misc1",
                                           "paddle1",
                                           "paddle2",
                                           "paddle3",
                                           "paddle4",
                                           "touchpad",
                                           "lefttrigger",
                                           "righttrigger"};
  static_assert(sizeof(kNames) / sizeof(kNames[0]) == static_cast<std::size_t>(GamepadControl::kCount));
  const auto i = static_cast<std::size_t>(c);
  return i < static_cast<std::size_t>(GamepadControl::kCount) ? kNames[i] : "?";
}

std::vector<std::pair<std::string, GamepadControl>> yamlEnumNames(GamepadControl) {
  std::vector<std::pair<std::string, GamepadControl>> t;
  for (int i = 0; i < static_cast<int>(GamepadControl::kCount); ++i) {
    const auto c = static_cast<GamepadControl>(i);
    t.emplace_back(toString(c), c);
  }
  return t;
}

const char* toString(GamepadLink l) noexcept {
  switch (l) {
    case GamepadLink::kNone:
      return "no controller";
    case GamepadLink::kOk:
      return "ok";
    case GamepadLink::kLost:
      return "lost";
  }
  return "?";
}

std::string GamepadAxisConfig::validate() const {
  if (!within(dead_zone, 0.0, 0.5)) return "dead_zone = " + num(dead_zone) + ": expected 0..0.5";
  if (!within(expo, 0.0, 1.0)) return "expo = " + num(expo) + ": expected 0..1";
  if (!(finite(max) && max > 0)) return "max = " + num(max) + ": expected > 0";
  if (!(finite(accel) && accel > 0 && accel <= 100)) return "accel = " + num(accel) + ": expected (0, 100]";
  if (!(finite(decel) && decel > 0 && decel <= 100)) return "decel = " + num(decel) + ": expected (0, 100]";
  return {};
}

std::string GamepadSticksConfig::validate() const {
  const CommandLimits limits;
  const char* names[3] = {"vx", "vy", "wz"};
  const GamepadAxisConfig* axes[3] = {&vx, &vy, &wz};
  const char* units[3] = {"m/s", "m/s", "rad/s"};
  for (int i = 0; i < 3; ++i) {
    const std::string e = axes[i]->validate();
    if (!e.empty()) return std::string(names[i]) + "." + e;
    const double lim = limits.max_velocity[static_cast<std::size_t>(i)];
    if (axes[i]->max > lim)
      return std::string(names[i]) + ".max = " + num(axes[i]->max) + ": expected (0, " + num(lim) + "] " + units[i] +
             " (CommandLimits::max_velocity[" + std::to_string(i) + "], " + kLimitsSource + ")";
  }
  return {};
}

std::string GamepadPostureConfig::validate() const {
  const CommandLimits limits;
  if (!within(standing_height, limits.height_range[0], limits.height_range[1]))
    return "standing_height = " + num(standing_height) + ": expected " + num(limits.height_range[0]) + ".." +
           num(limits.height_range[1]) + " m (CommandLimits::height_range)";
  std::string e = checkRange("height_range", height_range, limits.height_range, "height_range", standing_height, "m");
  if (!e.empty()) return e;
  e = checkRange("pitch_range", pitch_range, limits.pitch_range, "pitch_range", 0.0, "rad");
  if (!e.empty()) return e;
  e = checkRange("roll_range", roll_range, limits.roll_range, "roll_range", 0.0, "rad");
  if (!e.empty()) return e;
  const std::pair<const char*, double> steps[] = {
      {"height_step", height_step}, {"pitch_step", pitch_step}, {"roll_step", roll_step}};
  for (const auto& [name, v] : steps)
    if (!within(v, 0.0, 0.2)) return std::string(name) + " = " + num(v) + ": expected 0..0.2";
  const std::pair<const char*, double> rates[] = {
      {"height_rate", height_rate}, {"pitch_rate", pitch_rate}, {"roll_rate", roll_rate}};
  for (const auto& [name, v] : rates)
    if (!within(v, 0.0, 2.0)) return std::string(name) + " = " + num(v) + ": expected 0..2 per second";
  if (!within(hold_delay, 0.0, 5.0)) return "hold_delay = " + num(hold_delay) + ": expected 0..5 s";
  return {};
}

std::string GamepadButtonsConfig::validate() const {
  if (!within(trigger_threshold, 0.05, 0.95))
    return "trigger_threshold = " + num(trigger_threshold) + ": expected 0.05..0.95";
  const std::pair<const char*, const std::vector<GamepadControl>*> bindings[] = {
      {"estop", &estop},     {"stand", &stand}, {"walk", &walk},
      {"damping", &damping}, {"reset", &reset}, {"neutral_posture", &neutral_posture}};
  for (const auto& [name, b] : bindings) {
    const std::string e = checkBinding(name, *b, std::string(name) == "estop" ? 2 : 1);
    if (!e.empty()) return e;
  }
  for (const auto& [na, a] : bindings)
    for (const auto& [nb, b] : bindings) {
      if (a == b) continue;
      const std::uint32_t ma = maskOf(*a), mb = maskOf(*b);
      if ((ma & mb) == ma)
        return std::string(na) + (ma == mb ? " is the same binding as " : " is contained in ") + nb + ": pressing " +
               nb + " would also trigger " + na;
    }
  if (isDpad(mode_layer))
    return std::string("mode_layer = ") + toString(mode_layer) + ": expected a control that is not on the d-pad";
  if (isDpad(pitch_layer))
    return std::string("pitch_layer = ") + toString(pitch_layer) + ": expected a control that is not on the d-pad";
  if (mode_layer == pitch_layer) return "pitch_layer: must differ from mode_layer";
  return {};
}

std::string GamepadLinkConfig::validate() const {
  if (!within(stale_timeout, 0.05, 5.0)) return "stale_timeout = " + num(stale_timeout) + ": expected 0.05..5 s";
  if (!(finite(damping_timeout) && damping_timeout > 0 && damping_timeout <= 60))
    return "damping_timeout = " + num(damping_timeout) + ": expected (0, 60] s";
  if (!within(estop_repeat, 0.0, 10.0)) return "estop_repeat = " + num(estop_repeat) + ": expected 0..10 s (0 = once)";
  return {};
}

GamepadConfig loadGamepadConfig(const std::string& path) { return yaml::loadYamlFile<GamepadConfig>(path); }

GamepadConfig parseGamepadConfig(const std::string& yaml_text, const std::string& source_name) {
  return yaml::parseYamlString<GamepadConfig>(yaml_text, source_name);
}

std::string GamepadConfig::validate() const {
  const std::pair<const char*, std::string> checks[] = {{"sticks", sticks.validate()},
                                                        {"posture", posture.validate()},
                                                        {"buttons", buttons.validate()},
                                                        {"link", link.validate()}};
  for (const auto& [section, e] : checks)
    if (!e.empty()) return std::string(section) + ": " + e;
  return {};
}

}  // namespace pmg::teleop
