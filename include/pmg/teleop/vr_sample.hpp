#pragma once
/// @file vr_sample.hpp
/// One sample of the VR teleoperation stream (headset + two hand controllers), as the controller
/// sees it after pmg::LcmCommandDecoder checked the LCM message `pmg_lcm::vr_pose_t`
/// (lcmtypes/vr_pose_t.lcm, channel PMG_VR_POSE) that `pmg_vr_bridge` publishes.
///
/// Frame V ("VR floor frame"): right-handed, x forward, y left, z up [m], origin on the floor
/// where the XR session's `local-floor` reference space starts. The bridge converts from WebXR's
/// y-up / −z-forward convention: p_V = (−z_xr, −x_xr, y_xr), and likewise for the quaternion's
/// vector part. Quaternions are w, x, y, z and unit norm (checked by the decoder to 1e-3).
/// Trivially copyable: it crosses pmg::LatestValue inside pmg::CommandSample.

#include <array>
#include <cstdint>

namespace pmg::teleop {

/// Hand index into the per-hand arrays.
enum Hand : int { kLeftHand = 0, kRightHand = 1 };

/// Button bits of VrSample::buttons (per hand controller). Quest 3 naming: A/X lower face
/// button, B/Y upper face button.
enum VrButton : std::uint32_t {
  kVrButtonLower = 1u << 0,       ///< A (right) / X (left)
  kVrButtonUpper = 1u << 1,       ///< B (right) / Y (left)
  kVrButtonThumbstick = 1u << 2,  ///< thumbstick press
  kVrButtonMenu = 1u << 3,        ///< menu (left only on Quest)
};

struct VrSample {
  std::int64_t frame = 0;        ///< page frame counter (increments per XR frame)
  std::int64_t xr_time_us = 0;   ///< headset frame time [µs] (XRFrame time)
  std::array<double, 3> head_position{};          ///< headset position, frame V [m]
  std::array<double, 4> head_quat{1, 0, 0, 0};    ///< headset orientation, frame V, w x y z
  std::array<bool, 2> hand_valid{};               ///< controller tracked (left, right)
  std::array<std::array<double, 3>, 2> hand_position{};  ///< controller grip pose position, frame V [m]
  std::array<std::array<double, 4>, 2> hand_quat{{{1, 0, 0, 0}, {1, 0, 0, 0}}};  ///< w x y z, frame V
  std::array<double, 2> grip{};                   ///< squeeze value [0, 1]
  std::array<double, 2> trigger{};                ///< trigger value [0, 1]
  std::array<std::uint32_t, 2> buttons{};         ///< VrButton bits per hand
  std::array<std::array<double, 2>, 2> thumbstick{};  ///< per hand: x right, y forward [-1, 1]
};

}  // namespace pmg::teleop
