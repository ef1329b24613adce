#pragma once
/// @file envelope.hpp
/// @brief Safety envelope primitives: per-joint set-point clamps (position, velocity, gains,
/// torque), command slew limits and base tilt. Pure functions, noexcept, no allocation.
///
/// Units: rad, rad/s, N m, N m/rad, N m s/rad; joint-side values in the robot's joint order.

#include <cstdint>

namespace pmg::hal::safety {

/// Limits of one joint (from the robot config: URDF limits, motor datasheet).
struct JointLimits {
  double q_min = -1.0;    ///< Lowest commanded position [rad].
  double q_max = 1.0;     ///< Highest commanded position [rad].
  double qd_max = 10.0;   ///< Largest |commanded velocity| [rad/s].
  double tau_max = 10.0;  ///< Largest |torque| the motor may be asked for [N m].
  double kp_max = 500.0;  ///< Largest stiffness [N m/rad].
  double kd_max = 20.0;   ///< Largest damping [N m s/rad].
};

/// The set-point of the motor-side PD law tau = kp (q - q_meas) + kd (qd - qd_meas) + tau_ff.
struct JointSetpoint {
  double q = 0.0;       ///< [rad]
  double qd = 0.0;      ///< [rad/s]
  double kp = 0.0;      ///< [N m/rad]
  double kd = 0.0;      ///< [N m s/rad]
  double tau_ff = 0.0;  ///< [N m]
};

/// Bits returned by the clamps: which part of the set-point was changed.
enum ClampBits : std::uint8_t {
  kClampPosition = 1u << 0,  ///< q outside [q_min, q_max].
  kClampVelocity = 1u << 1,  ///< |qd| > qd_max.
  kClampGain = 1u << 2,      ///< kp or kd outside [0, max].
  kClampTorque = 1u << 3,    ///< Predicted |tau| > tau_max (q, qd or tau_ff moved towards the measurement).
  kClampSlew = 1u << 4,      ///< q or tau_ff changed faster than allowed.
  kClampNonFinite = 1u << 5, ///< A non-finite field was replaced (q -> q_meas, others -> 0).
};

/// Torque the motor's PD law produces for `sp` at the measured state (q_meas, qd_meas) [N m].
double predictedTorque(const JointSetpoint& sp, double q_meas, double qd_meas) noexcept;

/// Clamp gains to [0, max], q to [q_min, q_max], qd to +-qd_max, tau_ff to +-tau_max, then move qd
/// and q towards the measurement until |predictedTorque| <= tau_max (at this measurement). If the
/// measurement itself is non-finite the set-point becomes pure zero torque (kp = kd = tau_ff = 0).
/// Returns ClampBits.
std::uint8_t clampSetpoint(const JointLimits& lim, double q_meas, double qd_meas, JointSetpoint& sp) noexcept;

/// Limit the change of q and tau_ff since the previous tick's output: |q - q_prev| <= max_dq,
/// |tau_ff - tau_prev| <= max_dtau. Returns kClampSlew if anything changed.
std::uint8_t slewLimit(double q_prev, double tau_prev, double max_dq, double max_dtau, JointSetpoint& sp) noexcept;

/// Tilt of the base [rad]: angle between the base z axis and world z, from the orientation
/// quaternion q_WB = (w, x, y, z) (need not be exactly unit). Returns NaN for a zero/non-finite input.
double baseTilt(const double quat_wxyz[4]) noexcept;

}  // namespace pmg::hal::safety
