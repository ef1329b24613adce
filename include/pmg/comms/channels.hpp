#pragma once
/// @file channels.hpp
/// LCM channel names of the operator command streams (lcmtypes/*.lcm). One place: the senders
/// (pmg::comms::CommandPublisher, pmg_command_script, pmg_gamepad, pmg_vr_bridge) and the receiver
/// (pmg::LcmCommandDecoder, include/pmg/controller/lcm_command_source.hpp) use these constants.

namespace pmg {

inline constexpr const char* kVelocityChannel = "PMG_VELOCITY_COMMAND";  ///< pmg_lcm::velocity_command_t
inline constexpr const char* kPostureChannel = "PMG_POSTURE_COMMAND";    ///< pmg_lcm::posture_command_t
inline constexpr const char* kModeChannel = "PMG_MODE_COMMAND";          ///< pmg_lcm::mode_command_t
inline constexpr const char* kVrPoseChannel = "PMG_VR_POSE";             ///< pmg_lcm::vr_pose_t

/// The default LCM URL of every pmg sender and receiver: multicast with ttl=0, so command traffic
/// never leaves the host unless a URL with ttl ≥ 1 is configured (docs/teleop.md).
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

}  // namespace pmg
