#pragma once
/// @file vr_script.hpp
/// A scripted VR operator: a YAML script of keyframes (headset pose, hands relative to the
/// headset, grips, buttons) played as a VR pose stream by `pmg_vr_script` — live on LCM through
/// pmg::comms::CommandPublisher (signed with a key, like pmg_vr_bridge), or into an LCM log that
/// `pmg_vr_replay` replays (docs/teleop.md). For demos and tests of teleoperation without a
/// headset, with a stream whose meaning is known (walk that way, reach there, drop the stream).
///
///   rate_hz: 72                 # stream rate [Hz], 1..500
///   duration: 12.0              # end [s]; 0 = the last step's t + 1 s
///   steps:                      # t strictly increasing, first ≥ 0
///     - {t: 0.0, name: ready, head: [0, 0, 1.6], yaw: 0.0, left_hand: [0.1, 0.3, -0.75], right_hand: [0.1, -0.3, -0.75]}
///     - {t: 1.0, name: engage, buttons_right: [lower]}   # right A pressed (engage)
///     - {t: 1.2, grip: [1, 1]}                            # deadman on both hands
///     - {t: 2.0, name: "step forward", head: [0.3, 0, 1.6]}
///     - {t: 8.0, name: "stream dropped", stream: false}
///
/// Frame V (vr_sample.hpp): x forward, y left, z up [m]. `head` [m] and `yaw` [rad] (about +z)
/// are the headset pose; `left_hand` / `right_hand` [m] are the hand controllers relative to the
/// headset in its yaw frame; `pitch` [rad] tilts the head (looking down positive). These
/// continuous values are keyframes: a value given at a step is reached linearly from the previous
/// step's and then held; a value not given carries over. `grip` [0, 1] (per hand), the buttons
/// (`lower` = A/X, `upper` = B/Y, `thumbstick`, `menu`) and `stream` (false: nothing is sent) hold
/// from their step until the next step. The hand controllers point forward, tilted down by
/// 0.3 rad. Unknown keys are errors (file:line).

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "pmg/common/yaml_archive.hpp"
#include "pmg/teleop/vr_sample.hpp"

namespace pmg::teleop {

/// Button names of a script step.
enum class VrScriptButton { kLower, kUpper, kThumbstick, kMenu };
std::vector<std::pair<std::string, VrScriptButton>> yamlEnumNames(VrScriptButton);

struct VrScriptStep {
  double t = 0.0;  ///< start [s]
  std::string name;
  std::optional<std::array<double, 3>> head;        ///< headset position, frame V [m]
  std::optional<double> yaw;                        ///< headset yaw [rad]
  std::optional<double> pitch;                      ///< headset pitch, looking down positive [rad]
  std::optional<std::array<double, 3>> left_hand;   ///< relative to the headset, its yaw frame [m]
  std::optional<std::array<double, 3>> right_hand;
  std::array<double, 2> grip{0.0, 0.0};             ///< squeeze [0, 1], held during the step
  std::vector<VrScriptButton> buttons_left, buttons_right;
  bool stream = true;                               ///< false: nothing is sent during the step
  template <class A>
  void Serialize(A* a) {
    a->Visit("t", &t, "start of the step [s]", yaml::kRequired);
    a->Visit("name", &name, "label printed when the step starts");
    a->Visit("head", &head, "headset position, frame V [m] (keyframe)");
    a->Visit("yaw", &yaw, "headset yaw [rad] (keyframe)");
    a->Visit("pitch", &pitch, "headset pitch, looking down positive [rad] (keyframe)");
    a->Visit("left_hand", &left_hand, "left controller relative to the headset, its yaw frame [m] (keyframe)");
    a->Visit("right_hand", &right_hand, "right controller relative to the headset [m] (keyframe)");
    a->Visit("grip", &grip, "squeeze [left, right] in [0, 1]");
    a->Visit("buttons_left", &buttons_left, "held: lower | upper | thumbstick | menu");
    a->Visit("buttons_right", &buttons_right, "held: lower (A) | upper (B) | thumbstick | menu");
    a->Visit("stream", &stream, "false: the stream is dropped during the step");
  }
};

struct VrScript {
  double rate_hz = 72.0;
  double duration = 0.0;
  std::vector<VrScriptStep> steps;
  template <class A>
  void Serialize(A* a) {
    a->Visit("rate_hz", &rate_hz, "stream rate, 1..500 Hz");
    a->Visit("duration", &duration, "end of the script [s]; 0 = last step's t + 1 s");
    a->Visit("steps", &steps, "keyframes", yaml::kRequired);
  }
  /// End of the script [s].
  double end() const noexcept;
  /// Index of the step active at @p t.
  std::size_t stepAt(double t) const noexcept;
  /// The sample at time @p t (frame counter @p frame); false when the stream is off then.
  bool sample(double t, std::int64_t frame, VrSample& out) const noexcept;
};

/// Loads and validates a script. @throws ConfigError naming file:line, key and range.
VrScript loadVrScript(const std::string& path);

}  // namespace pmg::teleop
