#pragma once
/// @file gamepad_script.hpp
/// A small YAML script of gamepad states over time, played into pmg::teleop::SdlVirtualGamepad by
/// `pmg_gamepad --virtual-script FILE` (demos and tests without hardware). Each step holds from its
/// time `t` until the next step's (no interpolation); values use GamepadState's convention (stick y
/// DOWN positive: `left_y: -1` is the left stick fully up = full forward speed).
///
///   duration: 8.0        # optional [s]: end of the script (default: the last step's t + 1 s)
///   steps:
///     - {t: 0.0, name: idle}                                  # everything released
///     - {t: 0.5, name: stand, buttons: [lefttrigger, dpup]}   # LT + d-pad up (a trigger named
///     - {t: 1.0}                                              #   in `buttons` = fully pressed)
///     - {t: 1.5, name: walk, buttons: [rightshoulder, x]}
///     - {t: 2.0, name: forward, left_y: -0.8}
///     - {t: 5.0, name: unplugged, attached: false}
///
/// Keys of a step: t [s] (required, strictly increasing, first ≥ 0), name, left_x, left_y, right_x,
/// right_y ([-1, 1]), left_trigger, right_trigger ([0, 1]), buttons (GamepadControl names, as in
/// config/teleop/gamepad.yaml), attached (default true). Unknown keys are errors (file:line).

#include <cstddef>
#include <string>
#include <vector>

#include "pmg/common/yaml_archive.hpp"
#include "pmg/teleop/gamepad.hpp"

namespace pmg::teleop {

/// One step of a gamepad script.
struct GamepadScriptStep {
  double t = 0.0;  ///< start [s] since the script start
  std::string name;
  double left_x = 0.0, left_y = 0.0, right_x = 0.0, right_y = 0.0;  ///< [-1, 1], y down positive
  double left_trigger = 0.0, right_trigger = 0.0;                   ///< [0, 1]
  std::vector<GamepadControl> buttons;                              ///< held during the step
  bool attached = true;                                             ///< false: the controller is unplugged
  template <class A>
  void Serialize(A* a) {
    a->Visit("t", &t, "start of the step [s]", yaml::kRequired);
    a->Visit("name", &name, "label printed when the step starts");
    a->Visit("left_x", &left_x, "left stick, right positive [-1, 1]");
    a->Visit("left_y", &left_y, "left stick, DOWN positive [-1, 1] (-1 = full forward)");
    a->Visit("right_x", &right_x, "right stick, right positive [-1, 1] (-1 = turn left)");
    a->Visit("right_y", &right_y, "right stick, down positive [-1, 1]");
    a->Visit("left_trigger", &left_trigger, "LT [0, 1]");
    a->Visit("right_trigger", &right_trigger, "RT [0, 1]");
    a->Visit("buttons", &buttons, "controls held (lefttrigger/righttrigger = fully pressed)");
    a->Visit("attached", &attached, "false: controller unplugged during the step");
  }
  /// "" when valid (ranges of the values).
  std::string validate() const;
  /// The state this step sets (time = -1, attached as given).
  GamepadState state() const noexcept;
};

/// A whole script.
struct GamepadScript {
  double duration = 0.0;  ///< end [s]; 0 = the last step's t + 1 s
  std::vector<GamepadScriptStep> steps;
  template <class A>
  void Serialize(A* a) {
    a->Visit("duration", &duration, "end of the script [s] (0 or absent: last step + 1 s)");
    a->Visit("steps", &steps, "gamepad states over time", yaml::kRequired);
  }
  /// "" when valid: at least one step, t strictly increasing from ≥ 0, duration 0 or ≥ the last t.
  std::string validate() const;
  /// End of the script [s].
  double end() const noexcept;
  /// Index of the step active at @p t [s] (0 before the first step's time).
  std::size_t stepIndex(double t) const noexcept;
};

/// Loads and validates a script. @throws pmg::ConfigError naming file, line, step and field.
GamepadScript loadGamepadScript(const std::string& path);
/// The same from text (tests). @throws pmg::ConfigError.
GamepadScript parseGamepadScript(const std::string& yaml_text, const std::string& source_name = "<gamepad script>");

}  // namespace pmg::teleop
