// Gamepad scripts for the virtual controller (include/pmg/teleop/gamepad_script.hpp).
#include "pmg/teleop/gamepad_script.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "pmg/common/yaml_archive.hpp"

namespace pmg::teleop {
namespace {
std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}
bool within(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }
}  // namespace

std::string GamepadScriptStep::validate() const {
  if (!within(t, 0.0, 1e6)) return "t = " + num(t) + ": expected 0..1e6 s";
  const std::pair<const char*, double> axes[] = {
      {"left_x", left_x}, {"left_y", left_y}, {"right_x", right_x}, {"right_y", right_y}};
  for (const auto& [field, v] : axes)
    if (!within(v, -1.0, 1.0)) return std::string(field) + " = " + num(v) + ": expected -1..1";
  if (!within(left_trigger, 0.0, 1.0)) return "left_trigger = " + num(left_trigger) + ": expected 0..1";
  if (!within(right_trigger, 0.0, 1.0)) return "right_trigger = " + num(right_trigger) + ": expected 0..1";
  return {};
}

GamepadState GamepadScriptStep::state() const noexcept {
  GamepadState s;
  s.left_x = left_x;
  s.left_y = left_y;
  s.right_x = right_x;
  s.right_y = right_y;
  s.left_trigger = left_trigger;
  s.right_trigger = right_trigger;
  for (GamepadControl c : buttons) {
    if (c == GamepadControl::kLeftTrigger)
      s.left_trigger = 1.0;
    else if (c == GamepadControl::kRightTrigger)
      s.right_trigger = 1.0;
    else
      s.buttons |= controlBit(c);
  }
  s.attached = attached;
  s.time = -1.0;
  return s;
}

std::string GamepadScript::validate() const {
  if (steps.empty()) return "steps: expected at least one step";
  for (std::size_t i = 1; i < steps.size(); ++i)
    if (!(steps[i].t > steps[i - 1].t))
      return "steps[" + std::to_string(i) + "].t = " + num(steps[i].t) + ": expected > " + num(steps[i - 1].t) +
             " (the previous step's t)";
  if (!(std::isfinite(duration) && duration >= 0))
    return "duration = " + num(duration) + ": expected >= 0 s (0 = last step + 1 s)";
  if (duration > 0 && duration < steps.back().t)
    return "duration = " + num(duration) + ": expected >= " + num(steps.back().t) + " (the last step's t) or 0";
  return {};
}

double GamepadScript::end() const noexcept {
  if (duration > 0) return duration;
  return steps.empty() ? 0.0 : steps.back().t + 1.0;
}

std::size_t GamepadScript::stepIndex(double t) const noexcept {
  std::size_t k = 0;
  for (std::size_t i = 0; i < steps.size(); ++i)
    if (steps[i].t <= t) k = i;
  return k;
}

GamepadScript loadGamepadScript(const std::string& path) { return yaml::loadYamlFile<GamepadScript>(path); }

GamepadScript parseGamepadScript(const std::string& yaml_text, const std::string& source_name) {
  return yaml::parseYamlString<GamepadScript>(yaml_text, source_name);
}

}  // namespace pmg::teleop
