#pragma once
/// @file controller_config.hpp
/// Configuration of `pmg_controller` (config/controller/*.yaml): which robot, which clips, which
/// backend (the SIL or the motor buses), timing, command limits, safety, policy, telemetry.
/// Read through the one YAML archive (pmg/common/yaml_archive.hpp): unknown keys are errors that
/// name the file, line, key and the nearest valid key; every number must be finite; relative
/// paths resolve against the folder of the file. Validated once at load; every error names the
/// file, key and expected range (pmg::ConfigError).

#include <string>

#include "pmg/common/robot_config.hpp"
#include "pmg/comms/auth.hpp"
#include "pmg/controller/commands.hpp"
#include "pmg/controller/velocity_feedback.hpp"
#include "pmg/gco/gco.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/hal/hal_stack.hpp"
#include "pmg/hal/mujoco_backend.hpp"
#include "pmg/hal/runner.hpp"
#include "pmg/controller/upper_body.hpp"
#include "pmg/teleop/teleop_mode.hpp"

namespace pmg {

/// What the loop requests at start-up (safety.startup).
enum class StartupMode {
  kActive,   ///< request soft stand as soon as every input is healthy, then active once standing
  kPassive,  ///< stay passive until an operator requests a mode (robot hardware default)
};

/// Authentication of the LCM command channels (`security:`; docs/teleop.md).
struct SecurityConfig {
  /// Absolute path of the MAC key (pmg_keygen; owner-only file); "" = commands are not
  /// authenticated (plain LCM, anyone who reaches the multicast group can command).
  std::string key_file;
  comms::AuthKey key;               ///< loaded from key_file by loadControllerConfig()
  comms::VerifierOptions verifier;  ///< max_message_age_s [s], max_senders (per channel)
  bool enabled() const noexcept { return !key_file.empty(); }
};

struct ControllerConfig {
  std::string source_file;
  std::string robot_file;        ///< absolute path of the robot config
  std::string clips_dir;         ///< absolute path of the clip library folder
  RobotConfig robot;
  BackendKind backend = BackendKind::kMujoco;
  CanSettings can;
  TimingMode timing = TimingMode::kLockstep;
  double loop_rate_hz = 100.0;   ///< controller loop rate [Hz]
  double hal_rate_hz = 500.0;    ///< HAL rate [Hz], an integer multiple of loop_rate_hz
  int loop_fifo_priority = 0;    ///< SCHED_FIFO priority of the loop thread (0: normal)
  int hal_fifo_priority = 0;     ///< SCHED_FIFO priority of the HAL thread (0: normal)
  int hal_cpu = -1;              ///< CPU of the HAL thread (-1: any)
  bool lock_memory = false;      ///< mlockall() before real-time operation
  /// Low-pass of the IMU's specific force in the HAL before the loop samples it [s] (`timing:
  /// imu_acc_lowpass_s`; hal::safety::SafeBackendOptions::imu_acc_lowpass_s); 0 = raw samples.
  double imu_acc_lowpass_s = 0.0;
  MujocoBackendOptions mujoco;
  GeneratorParams generator;
  std::string gco_file;          ///< absolute path of the GCO options ("" = defaults)
  gco::GcoOptions gco;           ///< Ground-aware Command Optimization; gco.enabled = false: "PMG w/o GCO"
  CommandLimits commands;
  /// Closed-loop velocity tracking on leg odometry (`velocity_feedback:`, velocity_feedback.hpp);
  /// off unless the file enables it.
  VelocityFeedbackConfig velocity_feedback;
  /// Closed-loop torso pitch/roll tracking (`posture_feedback:`, velocity_feedback.hpp); off unless enabled.
  PostureFeedbackConfig posture_feedback;
  /// Upper-body gravity compensation and damping through tau_ff (`upper_body:`, upper_body.hpp);
  /// off unless enabled.
  UpperBodyConfig upper_body;
  double soft_stand_duration = 1.0;  ///< supervisor soft stand: measured → standing pose [s]
  double damping_kd_scale = 1.0;     ///< damping mode: kd = scale · robot config kd
  double q_rate_max = hal::safety::EnvelopeOptions{}.q_rate_max;  ///< supervisor slew on commanded q [rad/s]
  StartupMode startup = StartupMode::kActive;
  /// Trained actor (ONNX with its pmg contract); "" = none (PMG references go to the motors
  /// directly, as in the gantry bring-up). With a policy the gantry is normally off.
  std::string policy_file;
  bool policy_native = true;     ///< allocation-free native evaluator (else ONNX Runtime)
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  bool lcm_enabled = true;       ///< receive commands / publish telemetry over LCM
  std::string log_file;          ///< LCM event log to record ("" = none)
  /// VR teleoperation (`teleop:`; docs/teleop.md): headset → locomotion/posture, hands → arm IK.
  teleop::TeleopConfig teleop;
  SecurityConfig security;       ///< authenticated command channels (`security:`)

  /// Offline evaluation (tests, benchmarks, pmg_policy_sil): lockstep timing, no LCM, no event log.
  void makeOffline() noexcept {
    lcm_enabled = false;
    log_file.clear();
    timing = TimingMode::kLockstep;
  }
  int cyclesPerTick() const { return static_cast<int>(hal_rate_hz / loop_rate_hz + 0.5); }
  /// The HAL stack this config asks for (makeHalStack()).
  HalStackConfig halStack() const;
  /// The runner options this config asks for.
  RunnerOptions runner() const;
};

/// Loads and validates a controller config. @throws ConfigError naming file:line, key and range.
ControllerConfig loadControllerConfig(const std::string& path);

}  // namespace pmg
