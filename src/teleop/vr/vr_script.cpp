#include "pmg/teleop/vr_script.hpp"

#include <algorithm>
#include <cmath>

#include "pmg/common/config_error.hpp"

namespace pmg::teleop {

std::vector<std::pair<std::string, VrScriptButton>> yamlEnumNames(VrScriptButton) {
  return {{"lower", VrScriptButton::kLower},
          {"upper", VrScriptButton::kUpper},
          {"thumbstick", VrScriptButton::kThumbstick},
          {"menu", VrScriptButton::kMenu}};
}

namespace {

std::uint32_t bits(const std::vector<VrScriptButton>& b) noexcept {
  std::uint32_t out = 0;
  for (VrScriptButton x : b) {
    switch (x) {
      case VrScriptButton::kLower: out |= kVrButtonLower; break;
      case VrScriptButton::kUpper: out |= kVrButtonUpper; break;
      case VrScriptButton::kThumbstick: out |= kVrButtonThumbstick; break;
      case VrScriptButton::kMenu: out |= kVrButtonMenu; break;
    }
  }
  return out;
}

// The keyframe value of one continuous channel at t: the previous step that sets it and the next
// one that does; linear between them, held after the last.
template <class T, class Get>
T keyframe(const std::vector<VrScriptStep>& steps, double t, const T& fallback, Get get) noexcept {
  const VrScriptStep* prev = nullptr;
  const VrScriptStep* next = nullptr;
  for (const VrScriptStep& s : steps) {
    if (!get(s)) continue;
    if (s.t <= t) {
      prev = &s;
    } else {
      next = &s;
      break;
    }
  }
  if (prev == nullptr) return next != nullptr ? *get(*next) : fallback;
  if (next == nullptr) return *get(*prev);
  // The value moves from the previous keyframe towards the next one over the next step's span:
  // from the start of the step that precedes `next` (a keyframe is reached at its own t).
  double t0 = prev->t;
  for (const VrScriptStep& s : steps)
    if (s.t < next->t) t0 = std::max(t0, s.t);
  const double a = t <= t0 ? 0.0 : std::min(1.0, (t - t0) / (next->t - t0));
  T out = *get(*prev);
  if constexpr (std::is_same_v<T, double>) {
    out = (1 - a) * *get(*prev) + a * *get(*next);
  } else {
    for (std::size_t k = 0; k < out.size(); ++k) out[k] = (1 - a) * (*get(*prev))[k] + a * (*get(*next))[k];
  }
  return out;
}

}  // namespace

double VrScript::end() const noexcept {
  if (duration > 0) return duration;
  return steps.empty() ? 0.0 : steps.back().t + 1.0;
}

std::size_t VrScript::stepAt(double t) const noexcept {
  std::size_t i = 0;
  while (i + 1 < steps.size() && steps[i + 1].t <= t) ++i;
  return i;
}

bool VrScript::sample(double t, std::int64_t frame, VrSample& out) const noexcept {
  if (steps.empty()) return false;
  const VrScriptStep& step = steps[stepAt(t)];
  if (!step.stream) return false;
  const auto head = keyframe<std::array<double, 3>>(steps, t, {0.0, 0.0, 1.6}, [](const VrScriptStep& s) { return s.head ? &*s.head : nullptr; });
  const double yaw = keyframe<double>(steps, t, 0.0, [](const VrScriptStep& s) { return s.yaw ? &*s.yaw : nullptr; });
  const double pitch = keyframe<double>(steps, t, 0.0, [](const VrScriptStep& s) { return s.pitch ? &*s.pitch : nullptr; });
  const auto left = keyframe<std::array<double, 3>>(steps, t, {0.1, 0.3, -0.75}, [](const VrScriptStep& s) { return s.left_hand ? &*s.left_hand : nullptr; });
  const auto right = keyframe<std::array<double, 3>>(steps, t, {0.1, -0.3, -0.75}, [](const VrScriptStep& s) { return s.right_hand ? &*s.right_hand : nullptr; });
  out = VrSample{};
  out.frame = frame;
  out.xr_time_us = static_cast<std::int64_t>(std::llround(t * 1e6));
  out.head_position = head;
  // Head orientation: yaw about z, then pitch about the head's y (looking down positive).
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2), cp = std::cos(pitch / 2), sp = std::sin(pitch / 2);
  out.head_quat = {cy * cp, -sy * sp, cy * sp, sy * cp};
  // Hands: relative to the head in its yaw frame; pointing forward, tilted down by 0.3 rad.
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double ch = std::cos(0.15), sh = std::sin(0.15);
  const std::array<std::array<double, 3>, 2> rel{left, right};
  for (std::size_t h = 0; h < 2; ++h) {
    out.hand_valid[h] = true;
    out.hand_position[h] = {head[0] + c * rel[h][0] - s * rel[h][1], head[1] + s * rel[h][0] + c * rel[h][1],
                            head[2] + rel[h][2]};
    out.hand_quat[h] = {cy * ch, -sy * sh, cy * sh, sy * ch};
    out.grip[h] = step.grip[h];
  }
  out.buttons = {bits(step.buttons_left), bits(step.buttons_right)};
  return true;
}

VrScript loadVrScript(const std::string& path) {
  const yaml::YamlDocument doc = yaml::loadYamlDocument(path);
  VrScript s;
  yaml::readYaml(doc, &s);
  const auto fail = [&](const std::string& msg) { throw ConfigError(path + ": " + msg); };
  if (!(s.rate_hz >= 1 && s.rate_hz <= 500)) fail("rate_hz: expected 1..500 Hz");
  if (!(s.duration >= 0 && s.duration <= 3600)) fail("duration: expected 0..3600 s");
  if (s.steps.empty()) fail("steps: expected at least one step");
  for (std::size_t i = 0; i < s.steps.size(); ++i) {
    const VrScriptStep& st = s.steps[i];
    const std::string where = "steps[" + std::to_string(i) + "]";
    if (!(st.t >= 0) || (i > 0 && !(st.t > s.steps[i - 1].t))) fail(where + ".t: expected >= 0 and strictly increasing");
    for (double g : st.grip)
      if (!(g >= 0 && g <= 1)) fail(where + ".grip: expected values in [0, 1]");
    if (st.yaw && std::fabs(*st.yaw) > 3.2) fail(where + ".yaw: expected -3.2..3.2 rad");
    if (st.pitch && std::fabs(*st.pitch) > 1.5) fail(where + ".pitch: expected -1.5..1.5 rad");
    for (const auto* hand : {&st.left_hand, &st.right_hand})
      if (*hand)
        for (double v : **hand)
          if (std::fabs(v) > 1.5) fail(where + ": hand offsets: expected within 1.5 m of the headset");
    if (st.head)
      for (double v : *st.head)
        if (std::fabs(v) > 100) fail(where + ".head: expected within 100 m");
  }
  return s;
}

}  // namespace pmg::teleop
