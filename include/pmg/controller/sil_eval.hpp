#pragma once
/// @file sil_eval.hpp
/// The evaluation SIL that pmg_policy_sil and pmg_sim2real_eval share: pmg_controller's composition
/// root (ControllerApp: the same HAL stack with its supervisor, shaper, reference limiter,
/// generator + GCO, policy stage and runner) built from a controller config, with the configured
/// backend replaced by an in-process MuJoCo 2.2 SIL that the tool keeps a handle on, so that
/// metrics can read simulator truth. The command script is injected by ControllerApp::run() as
/// `pmg_controller --script` does.
///
/// ```cpp
/// pmg::ControllerConfig config = pmg::loadSilEvalConfig("config/controller/g1_sil_policy.yaml");
/// pmg::SilRunOptions o;                      // seed 0: no perturbation, no sensor noise
/// pmg::SilRun run = pmg::makeSilRun(config, o);
/// run.app->run(script.duration(), &script, &stop, observer);   // observer reads run.sim->data()
/// ```
/// Setup code: allocates and throws (ConfigError / std::runtime_error naming the file or field).

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pmg/controller/controller_app.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/hal/mujoco_backend.hpp"

namespace pmg {

/// Sensor noise on the policy's observation in the SIL evaluations, as in training (standard
/// deviations: gyro [rad/s], projected gravity [1], joint position [rad], joint velocity [rad/s]).
struct SilSensorNoise {
  static constexpr double kGyro = 0.1, kGravity = 0.03, kQ = 0.01, kQd = 0.5;
};

/// What one evaluation run needs besides the controller config.
struct SilRunOptions {
  /// The simulated robot (its MJCF, torque limits and `actuator:` blocks make the physics);
  /// nullptr = the controller config's robot (the controller always runs on config.robot).
  const RobotConfig* physics_robot = nullptr;
  /// The simulator's options (hidden encoder offsets, body mass scales, ...); empty = config.mujoco.
  std::optional<MujocoBackendOptions> mujoco;
  /// Added to the initial joint positions before the first HAL cycle (n values or empty) [rad].
  std::vector<double> initial_q_offsets;
  bool sensor_noise = false;   ///< SilSensorNoise on the observation
  unsigned noise_seed = 0;     ///< seed of the sensor noise
  std::vector<std::string> clip_files;  ///< non-empty: the generator runs on these clips only
  std::string policy_mode = "pmg";      ///< PolicyStageOptions::mode ("pmg" | "single_gait")
  bool telemetry = true;       ///< run the telemetry publisher (timing statistics; no LCM offline)
};

/// A ControllerApp over an in-process MuJoCo SIL.
struct SilRun {
  std::unique_ptr<ControllerApp> app;
  MujocoBackend* sim = nullptr;  ///< the simulator (owned by app), for metrics from truth
};

/// Loads a controller config for offline SIL evaluation: lockstep timing, no LCM, no event log,
/// gantry off (the robot stands on the ground). @throws ConfigError naming the file, line and key.
ControllerConfig loadSilEvalConfig(const std::string& path);

/// Builds the simulator (options.physics_robot / options.mujoco), applies the initial joint
/// offsets, and the ControllerApp of @p config over it. @throws ConfigError / std::runtime_error.
SilRun makeSilRun(const ControllerConfig& config, const SilRunOptions& options);

/// Whether the robot fell (the evaluations' rule): the pelvis below 0.4 m, tilted more than 60 deg
/// (from the true base state in @p state), or the supervisor latched a fall fault.
bool silRobotFell(const LowState& state, const TickStatus& status) noexcept;

/// The qpos address of each of @p robot's joints in @p sim's model (robot order).
/// @throws ConfigError naming the joint if the model lacks it.
std::vector<int> silJointQposAddresses(const MujocoBackend& sim, const RobotConfig& robot);

}  // namespace pmg
