#pragma once
/// @file vr_synthetic.hpp
/// The synthetic VR pose pattern: a deterministic function of the frame counter that the page
/// (data/vr/web/vr.js, `?synthetic=1`) and the tests compute identically, so that a test can check
/// every pose that arrives on LCM against the value it must have.
///
/// Time t = frame / kVrSyntheticRateHz [s]. In the WebXR frame F_xr (x right, y up, −z forward):
///  - head: walks forward at 0.3 m/s for 20 s, then back for 20 s (triangle, period 40 s):
///    p = (0, 1.6, −s(t)), s(t) = 0.3 · tri(t); yaw a(t) = 0.15 · sin(2π · 0.25 · t) [rad] about +y;
///  - hands: circles of radius 0.08 m at 0.5 Hz in the x–y plane around (∓0.25, 1.2, −0.35 − s(t))
///    (left: +cos, right: −cos on x; both +sin on y), pitched down by 0.3 rad (about +x);
///  - both controllers tracked; grip = 1 (deadman held); trigger = 0.5 + 0.5 · sin(2π · 0.5 · t);
///    right A button pressed during odd seconds; left stick axes = (0.2 · sin(2π · 0.5 · t), 0),
///    right stick axes = (0, −0.5) (pushed forward: Gamepad y is down/back).
/// `t` on the wire is t · 1000 [ms].

#include <array>
#include <cstdint>
#include <string>

#include "pmg/teleop/vr_sample.hpp"

namespace pmg::teleop {

/// Frame rate of the synthetic source [Hz] (the Quest's default display rate).
inline constexpr double kVrSyntheticRateHz = 72.0;

/// One synthetic pose in the page's wire convention (frame F_xr, quaternions x y z w, raw
/// Gamepad stick axes).
struct VrWirePose {
  std::int64_t frame = 0;
  double t_ms = 0.0;                         ///< XR time [ms]
  std::array<double, 3> head_p{};            ///< F_xr [m]
  std::array<double, 4> head_q{0, 0, 0, 1};  ///< F_xr, x y z w
  std::array<bool, 2> valid{};
  std::array<std::array<double, 3>, 2> hand_p{};  ///< F_xr [m]
  std::array<std::array<double, 4>, 2> hand_q{};  ///< F_xr, x y z w
  std::array<double, 2> grip{};
  std::array<double, 2> trigger{};
  std::array<std::uint32_t, 2> buttons{};
  std::array<std::array<double, 2>, 2> stick{};  ///< Gamepad axes[2], axes[3] (y down)
};

/// The synthetic pattern at @p frame (≥ 0).
VrWirePose syntheticWirePose(std::int64_t frame);

/// @p p as the page's JSON message ({"type":"pose",...}), numbers printed with 17 significant
/// digits (round-trip exact).
std::string toWireJson(const VrWirePose& p);

/// What the bridge must make of syntheticWirePose(@p frame): parseVrMessage(toWireJson(...)).
/// @throws std::logic_error if the pattern fails the protocol's checks (a bug).
VrSample syntheticSample(std::int64_t frame);

}  // namespace pmg::teleop
