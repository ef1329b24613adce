#pragma once
/// @file types.hpp
/// Data exchanged between the 100 Hz controller loop and the 500 Hz HAL, and between the HAL and
/// its backend (MuJoCo SIL, CAN buses). Fixed-capacity, trivially copyable: they cross the
/// lock-free hand-over (pmg::LatestValue) without allocation.

#include <array>
#include <cstdint>

#include "pmg/hal/modes.hpp"

namespace pmg {

/// Maximum number of motors one HAL drives (G1: 29).
inline constexpr int kMaxMotors = 32;

/// Motor-level command of one joint, in the joint (link-side) frame. The motor driver applies
/// τ = kp (q − q_meas) + kd (qd − qd_meas) + tau_ff, clipped at the joint's torque limit.
struct MotorCommand {
  double q = 0.0;       ///< position target [rad]
  double qd = 0.0;      ///< velocity target [rad/s]
  double kp = 0.0;      ///< stiffness [N·m/rad]
  double kd = 0.0;      ///< damping [N·m·s/rad]
  double tau_ff = 0.0;  ///< feed-forward torque [N·m]
};

/// Measured state of one joint as the motor driver reports it (encoder side).
struct MotorState {
  double q = 0.0;      ///< position [rad]
  double qd = 0.0;     ///< velocity [rad/s]
  double tau = 0.0;    ///< applied (estimated) torque [N·m]
  bool valid = false;  ///< a reply arrived this cycle
};

/// IMU reading. Orientation of the IMU frame in the world frame; rates and specific force in the
/// IMU frame.
struct ImuState {
  std::array<double, 4> quat_wxyz{1, 0, 0, 0};  ///< orientation, world ← IMU (unit quaternion)
  std::array<double, 3> gyro{};                 ///< angular velocity, IMU frame [rad/s]
  std::array<double, 3> acc{};                  ///< specific force, IMU frame [m/s²]
  bool valid = false;
};

/// Commands for all motors for one HAL cycle (written by the loop, read by the HAL).
struct LowCommand {
  std::uint64_t sequence = 0;  ///< increments with every loop tick that wrote it
  int num_motors = 0;
  std::array<MotorCommand, kMaxMotors> motors{};
};

/// States of all motors and the IMU after one HAL cycle (written by the HAL, read by the loop).
struct LowState {
  std::uint64_t sequence = 0;     ///< HAL cycle counter
  double time = 0.0;              ///< backend time [s] (simulated time in the SIL)
  int num_motors = 0;
  std::array<MotorState, kMaxMotors> motors{};
  ImuState imu{};
  /// Simulation ground truth of the floating base (telemetry only; zero/invalid on hardware).
  std::array<double, 3> base_position{};        ///< pelvis position, world [m]
  std::array<double, 4> base_quat_wxyz{1, 0, 0, 0};
  std::array<double, 3> base_linear_velocity{}; ///< pelvis linear velocity, world [m/s]
  bool base_truth_valid = false;
  std::uint32_t backend_faults = 0;  ///< cumulative backend error count (bus errors, sim warnings)
  /// HAL task timing of the previous cycle (real-time mode; 0 in lockstep) [s] and the cumulative
  /// overrun count, so the loop can put the HAL's timing into telemetry.
  double hal_runtime = 0.0;
  double hal_period = 0.0;
  std::uint64_t hal_overruns = 0;
  /// The HAL's mode after this cycle (written by hal::safety::SafeBackend, the only mode state
  /// machine), its latched fault and the soft-stand progress 0..1.
  Mode mode = Mode::kPassive;
  FaultCode fault = FaultCode::kNone;
  double stand_progress = 0.0;
};

}  // namespace pmg
