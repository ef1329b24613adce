#pragma once
/// @file controller_config.hpp
/// Configuration of `pmg_controller` (config/controller/*.yaml): which robot, which clips, which
/// backend (the SIL or the motor buses), timing, command limits, telemetry. Validated once at
/// start-up; every error names the file, key and expected range.

#include <string>

#include "pmg/common/robot_config.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/gco/gco.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/hal/hal_runner.hpp"
#include "pmg/hal/mujoco_backend.hpp"

namespace pmg {

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
enum class TimingMode {
  kLockstep,  ///< the loop drives the HAL cycles itself, as fast as possible (tests, CI)
  kRealtime,  ///< 100 Hz loop thread + 500 Hz HAL thread paced to the wall clock
};

struct ControllerConfig {
  std::string source_file;
  std::string robot_file;        ///< absolute path of the robot config
  std::string clips_dir;         ///< absolute path of the clip library folder
  RobotConfig robot;
  BackendKind backend = BackendKind::kMujoco;
  CanSettings can;
  /// Run the 500 Hz safety supervisor inside the HAL (guard mode: per-input watchdogs, envelope,
  /// torque bound, latched damping; docs/hal.md). Default on for backend: can.
  bool hal_supervisor = false;
  bool lock_memory = false;      ///< mlockall() before real-time operation
  TimingMode timing = TimingMode::kLockstep;
  double loop_rate_hz = 100.0;   ///< controller loop rate [Hz]
  double hal_rate_hz = 500.0;    ///< HAL rate [Hz], an integer multiple of loop_rate_hz
  int loop_fifo_priority = 0;    ///< SCHED_FIFO priority of the loop thread (0: normal)
  HalRunnerOptions hal;          ///< HAL thread priority / CPU
  MujocoBackendOptions mujoco;
  GeneratorParams generator;
  std::string gco_file;          ///< absolute path of the GCO options ("" = defaults)
  gco::GcoOptions gco;           ///< Ground-aware Command Optimization; gco.enabled = false: "PMG w/o GCO"
  CommandLimits commands;
  double soft_stand_duration = 1.0;   ///< interpolation time from the measured to the standing pose [s]
  double damping_kd_scale = 1.0;      ///< damping mode: kd = scale · config kd
  /// Consecutive loop ticks with an invalid state (missing reply, NaN) or a backend fault that are
  /// tolerated (the last valid command is held) before damping latches. 0 = latch at once.
  int max_invalid_ticks = 3;
  /// Trained actor (ONNX with its pmg contract); "" = none (PMG references go to the motors
  /// directly, as in the gantry bring-up). With a policy the gantry is normally off.
  std::string policy_file;
  bool policy_native = true;     ///< allocation-free native evaluator (else ONNX Runtime)
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  bool lcm_enabled = true;       ///< receive commands / publish telemetry over LCM
  std::string log_file;          ///< LCM event log to record ("" = none)

  int cyclesPerTick() const { return static_cast<int>(hal_rate_hz / loop_rate_hz + 0.5); }
};

/// Loads and validates a controller config. Relative paths resolve against the file's folder.
/// @throws ConfigError.
ControllerConfig loadControllerConfig(const std::string& path);

}  // namespace pmg
