#include "pmg/teleop/vr_synthetic.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "pmg/teleop/vr_protocol.hpp"

namespace pmg::teleop {

namespace {
constexpr double kPi = 3.14159265358979323846;

/// Triangle 0 → 20 → 0 over 40 s: distance walked forward divided by the speed [s].
double triangle(double t) {
  const double u = std::fmod(t, 40.0);
  return u <= 20.0 ? u : 40.0 - u;
}

void appendNumber(std::string& s, double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  s += buf;
}

template <std::size_t N>
void appendArray(std::string& s, const std::array<double, N>& v) {
  s += '[';
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) s += ',';
    appendNumber(s, v[i]);
  }
  s += ']';
}
}  // namespace

VrWirePose syntheticWirePose(std::int64_t frame) {
  VrWirePose p;
  p.frame = frame;
  const double t = static_cast<double>(frame) / kVrSyntheticRateHz;
  p.t_ms = t * 1000.0;
  const double walked = 0.3 * triangle(t);
  p.head_p = {0.0, 1.6, -walked};
  const double yaw = 0.15 * std::sin(2.0 * kPi * 0.25 * t);
  p.head_q = {0.0, std::sin(yaw / 2.0), 0.0, std::cos(yaw / 2.0)};
  const double w = 2.0 * kPi * 0.5 * t;
  const double pitch = -0.3;
  for (std::size_t h = 0; h < 2; ++h) {
    const double side = h == 0 ? -1.0 : 1.0;  // left hand at −x (WebXR x is right)
    p.valid[h] = true;
    p.hand_p[h] = {side * 0.25 - side * 0.08 * std::cos(w), 1.2 + 0.08 * std::sin(w), -0.35 - walked};
    p.hand_q[h] = {std::sin(pitch / 2.0), 0.0, 0.0, std::cos(pitch / 2.0)};
    p.grip[h] = 1.0;
    p.trigger[h] = 0.5 + 0.5 * std::sin(w);
  }
  p.buttons[kRightHand] = (static_cast<std::int64_t>(std::floor(t)) % 2 == 1) ? kVrButtonLower : 0u;
  p.stick[kLeftHand] = {0.2 * std::sin(w), 0.0};
  p.stick[kRightHand] = {0.0, -0.5};
  return p;
}

std::string toWireJson(const VrWirePose& p) {
  std::string s = "{\"type\":\"pose\",\"frame\":" + std::to_string(p.frame) + ",\"t\":";
  appendNumber(s, p.t_ms);
  s += ",\"head\":{\"p\":";
  appendArray(s, p.head_p);
  s += ",\"q\":";
  appendArray(s, p.head_q);
  s += "},\"hands\":[";
  for (std::size_t h = 0; h < 2; ++h) {
    if (h > 0) s += ',';
    s += std::string("{\"valid\":") + (p.valid[h] ? "true" : "false") + ",\"p\":";
    appendArray(s, p.hand_p[h]);
    s += ",\"q\":";
    appendArray(s, p.hand_q[h]);
    s += ",\"grip\":";
    appendNumber(s, p.grip[h]);
    s += ",\"trigger\":";
    appendNumber(s, p.trigger[h]);
    s += ",\"buttons\":" + std::to_string(p.buttons[h]) + ",\"stick\":";
    appendArray(s, p.stick[h]);
    s += '}';
  }
  s += "]}";
  return s;
}

VrSample syntheticSample(std::int64_t frame) {
  VrSample s;
  std::string why;
  if (parseVrMessage(toWireJson(syntheticWirePose(frame)), s, &why) != VrReject::kAccepted)
    throw std::logic_error("synthetic VR pose at frame " + std::to_string(frame) + " refused: " + why);
  return s;
}

}  // namespace pmg::teleop
