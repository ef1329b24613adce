#pragma once
/// @file hal_stack.hpp
/// The one HAL stack factory. Every tool that can move a motor (pmg_controller, pmg_policy_sil,
/// pmg_calib_zero, the SIL tests) builds its backend here, so they all run the same safety stack:
///
///   backend (MuJoCo SIL | CAN buses | a caller's backend)
///     → ZeroOffsetBackend (calibrated encoder zeros of the robot config, when any is non-zero)
///       → hal::safety::SafeBackend (watchdogs, envelope, fall detection, slew and torque clamps,
///         the mode state machine; always on)
///
/// The result goes to pmg::HalRunner. docs/architecture.md draws it.

#include <memory>
#include <string>
#include <vector>

#include "pmg/hal/backend.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/safety/supervisor.hpp"

namespace pmg {
struct RobotConfig;
namespace hal::safety {
class SafeBackend;
}

enum class BackendKind {
  kMujoco,  ///< in-process MuJoCo 2.2 SIL
  kCan,     ///< motor buses (SocketCAN on the robot, UDP towards the pmg_sil process); docs/hal.md
};

/// Motor-bus backend settings (backend: can).
struct CanSettings {
  std::string plan_file;           ///< bus plan YAML (absolute after loading)
  std::string transport = "udp";   ///< "socketcan" (robot) or "udp" (pmg_sil)
  int udp_port = 47000;            ///< UDP base port of pmg_sil
  bool paced = false;              ///< send each motor at its slot time instead of at the slot start
};

/// What makeHalStack() builds.
struct HalStackConfig {
  BackendKind backend = BackendKind::kMujoco;
  CanSettings can;
  MujocoBackendOptions mujoco;
  bool lockstep = true;                ///< CAN: lockstep with pmg_sil (else real time)
  double soft_stand_duration_s = 1.0;  ///< supervisor soft stand [s]
  double damping_kd_scale = 1.0;       ///< damping mode kd = scale · robot config kd
  /// Supervisor slew limit on the commanded q [rad/s] (hal::safety::EnvelopeOptions::q_rate_max).
  double q_rate_max = hal::safety::EnvelopeOptions{}.q_rate_max;
  /// Per-joint gain ceilings of the supervisor [N·m/rad, N·m·s/rad] (n values or empty). A tool
  /// that needs stiffer gains than 2 kp / 4 kd of the robot config (the zero-point protocol's
  /// 400 N·m/rad legs) declares them here; the ceiling is the larger of the two.
  std::vector<double> kp_max, kd_max;
  /// Per-joint soft-stand gains (n values or empty = the robot config's kp / kd).
  std::vector<double> stand_kp, stand_kd;
  /// The IMU specific force's low-pass before the loop [s] (hal::safety::SafeBackendOptions::
  /// imu_acc_lowpass_s): 0 (off) or in [one HAL cycle, 0.1].
  double imu_acc_lowpass_s = 0.0;
};

/// Empty if @p lowpass_s is a valid HalStackConfig::imu_acc_lowpass_s for a HAL cycle of
/// @p cycle_period_s [s] (0, or in [one cycle, 0.1] s), else "imu_acc_lowpass_s: expected ...". The one
/// rule for the YAML loader (timing:) and makeHalStack().
inline std::string imuAccLowpassError(double lowpass_s, double cycle_period_s) {
  if (lowpass_s == 0.0 || (lowpass_s >= cycle_period_s - 1e-12 && lowpass_s <= 0.1)) return {};
  return "imu_acc_lowpass_s: expected 0 (off) or in [1 / hal_rate_hz, 0.1] s (one HAL cycle: " +
         std::to_string(cycle_period_s) + " s), got " + std::to_string(lowpass_s);
}

/// The stack: the outermost backend (owns the others) and its supervisor.
struct HalStack {
  std::unique_ptr<HalBackend> backend;
  hal::safety::SafeBackend* safety = nullptr;  ///< owned by `backend` (its outermost layer)
  HalBackend* device = nullptr;  ///< the innermost backend (MuJoCo SIL, CAN buses, the caller's); owned by `backend`
};

/// Builds backend → zero offsets → SafeBackend. With @p custom (test mocks, other hardware) that
/// backend replaces the configured one; the rest of the stack is the same.
/// @throws ConfigError / std::runtime_error naming the file, port or field (setup only).
HalStack makeHalStack(const RobotConfig& robot, const HalStackConfig& config,
                      std::unique_ptr<HalBackend> custom = nullptr);

/// The motor-bus backend of @p config (config.can, config.lockstep), without the layers above it;
/// for tools that wrap it (pacing) before handing it to makeHalStack() as its backend.
/// @throws std::runtime_error naming the plan file, interface or port.
std::unique_ptr<HalBackend> makeCanBackendFor(const HalStackConfig& config);

/// For tools that exchange with the stack directly (no HalRunner, e.g. pmg_calib_zero): requests
/// soft stand once the motors and the IMU answer, holds the standing pose until the stand is
/// complete, then requests active. @throws std::runtime_error naming the mode and the fault if the
/// supervisor does not get there within @p timeout_s [s].
void engageActive(HalStack& stack, const RobotConfig& robot, double timeout_s = 10.0);

}  // namespace pmg
