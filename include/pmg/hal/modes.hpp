#pragma once
/// @file modes.hpp
/// The one mode vocabulary of pmg, shared by the LCM wire format (pmg_lcm::mode_command_t), the
/// command sources (scripts, LCM, gamepad), the 100 Hz loop, telemetry and the HAL's safety
/// supervisor — which is the only mode state machine (include/pmg/hal/safety/supervisor.hpp,
/// docs/architecture.md).
///
/// Wire codes (mode_command_t.mode, controller_state_t.mode):
///   Mode:        0 passive, 1 soft stand, 2 active (PMG / policy), 3 damping (latched e-stop)
///   ModeRequest: 0 passive, 1 soft stand, 2 active, 3 damping (e-stop), 4 reset (damping latch →
///                passive). Any other code is rejected by modeRequestFromWire() and counted by the
///                receiver; it never changes the mode.

#include <cstddef>
#include <cstdint>

namespace pmg {

/// Operating mode of the robot (the supervisor's state).
enum class Mode : std::int8_t {
  kPassive = 0,    ///< zero torque (kp = kd = tau_ff = 0); start-up mode
  kSoftStand = 1,  ///< blend from the pose measured on entry to the standing pose, stand gains
  kActive = 2,     ///< the 100 Hz loop's command (PMG references or the policy), guarded
  kDamping = 3,    ///< latched e-stop: kp = 0, kd = damping kd, tau_ff = 0
};

/// A request to change the mode. kNone is "no request" and has no wire code.
enum class ModeRequest : std::int8_t {
  kNone = -1,
  kPassive = 0,
  kSoftStand = 1,
  kActive = 2,
  kDamping = 3,  ///< e-stop; always accepted, latches
  kReset = 4,    ///< clear the damping latch: damping → passive (only when the robot is still)
};

/// Why the robot went to damping (latched with the first cause).
enum class FaultCode : std::uint8_t {
  kNone = 0,
  kEstop,           ///< operator requested damping
  kCommandStale,    ///< no command from the 100 Hz loop for command_timeout_s
  kCommandInvalid,  ///< command contains NaN/Inf
  kPolicyStale,     ///< policy output older than policy_timeout_s
  kPolicyInvalid,   ///< policy output flagged invalid (NaN) by the loop
  kMotorStale,      ///< no valid reply from a motor for motor_timeout_s
  kMotorInvalid,    ///< measured q/qd/tau of a joint non-finite
  kImuStale,        ///< no IMU sample for imu_timeout_s
  kImuInvalid,      ///< IMU sample non-finite, quaternion not unit, or rate/acceleration out of range
  kImuFrozen,       ///< new IMU samples bit-identical imu_frozen_samples times in a row
  kJointPosition,   ///< measured q of a joint beyond its limits by more than q_fault_margin
  kJointVelocity,   ///< measured |qd| of a joint above qd_fault
  kJointTorque,     ///< measured |tau| of a joint above tau_fault
  kFallTilt,        ///< base tilt above max_tilt_rad
  kFallHeight,      ///< base height below min_base_height_m
  kBackend,         ///< the backend reported a fault (bus down, simulation diverged, peer lost)
  kCount
};
inline constexpr std::size_t kNumFaultCodes = static_cast<std::size_t>(FaultCode::kCount);

/// Wire code → request. Returns false (and leaves @p out unchanged) for any code outside 0..4.
bool modeRequestFromWire(std::int32_t code, ModeRequest& out) noexcept;
/// Mode as a wire code (0..3).
inline std::int8_t toWire(Mode m) noexcept { return static_cast<std::int8_t>(m); }

/// Words for summaries and logs ("passive", "soft_stand", "active", "damping").
const char* toString(Mode m) noexcept;
const char* toString(ModeRequest r) noexcept;
/// Words for a fault ("none", "fall: base height", ...).
const char* toString(FaultCode c) noexcept;

}  // namespace pmg
