// The evaluation SIL shared by pmg_policy_sil and pmg_sim2real_eval (include/pmg/controller/sil_eval.hpp).
#include "pmg/controller/sil_eval.hpp"

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include <mujoco/mujoco.h>

#include "pmg/common/config_error.hpp"

namespace pmg {

ControllerConfig loadSilEvalConfig(const std::string& path) {
  ControllerConfig config = loadControllerConfig(path);
  config.makeOffline();
  config.mujoco.gantry.enabled = false;
  return config;
}

std::vector<int> silJointQposAddresses(const MujocoBackend& sim, const RobotConfig& robot) {
  const mjModel* m = sim.model();
  std::vector<int> adr;
  adr.reserve(robot.numJoints());
  for (const JointConfig& j : robot.joints) {
    const int id = mj_name2id(m, mjOBJ_JOINT, j.name.c_str());
    if (id < 0) throw ConfigError(robot.mjcf_path + ": joint '" + j.name + "' of " + robot.source_file + " not in the MJCF");
    adr.push_back(m->jnt_qposadr[id]);
  }
  return adr;
}

SilRun makeSilRun(const ControllerConfig& config, const SilRunOptions& options) {
  const RobotConfig& physics = options.physics_robot ? *options.physics_robot : config.robot;
  if (physics.numJoints() != config.robot.numJoints())
    throw ConfigError(physics.source_file + ": the simulated robot has " + std::to_string(physics.numJoints()) +
                      " joints, the controller's (" + config.robot.source_file + ") " +
                      std::to_string(config.robot.numJoints()));
  for (std::size_t i = 0; i < physics.numJoints(); ++i)
    if (physics.joints[i].name != config.robot.joints[i].name)
      throw ConfigError(physics.source_file + ": joints[" + std::to_string(i) + "] is '" + physics.joints[i].name +
                        "', the controller's robot config (" + config.robot.source_file + ") has '" +
                        config.robot.joints[i].name + "'");
  auto sim_owned = std::make_unique<MujocoBackend>(physics, options.mujoco ? *options.mujoco : config.mujoco);
  MujocoBackend* sim = sim_owned.get();
  const mjModel* m = sim->model();
  mjData* d = sim->data();
  if (!options.initial_q_offsets.empty()) {
    if (options.initial_q_offsets.size() != physics.numJoints())
      throw std::invalid_argument("makeSilRun: initial_q_offsets has " + std::to_string(options.initial_q_offsets.size()) +
                                  " values, expected " + std::to_string(physics.numJoints()) + " (one per joint)");
    const std::vector<int> adr = silJointQposAddresses(*sim, physics);
    for (std::size_t j = 0; j < adr.size(); ++j) d->qpos[adr[j]] += options.initial_q_offsets[j];
  }
  mj_forward(m, d);

  ControllerAppOptions opt;
  opt.backend = std::move(sim_owned);
  opt.telemetry = options.telemetry;
  opt.clip_files = options.clip_files;
  const double noise = options.sensor_noise ? 1.0 : 0.0;
  opt.policy.noise_gyro = noise * SilSensorNoise::kGyro;
  opt.policy.noise_gravity = noise * SilSensorNoise::kGravity;
  opt.policy.noise_q = noise * SilSensorNoise::kQ;
  opt.policy.noise_qd = noise * SilSensorNoise::kQd;
  opt.policy.noise_seed = options.noise_seed;
  opt.policy.mode = options.policy_mode;
  SilRun run;
  run.sim = sim;
  run.app = std::make_unique<ControllerApp>(config, std::move(opt));
  return run;
}

bool silRobotFell(const LowState& state, const TickStatus& status) noexcept {
  const double x = state.base_quat_wxyz[1], y = state.base_quat_wxyz[2];
  const double up_z = 1 - 2 * (x * x + y * y);  // z of the pelvis z axis in the world (R[2][2])
  return state.base_position[2] < 0.4 || up_z < 0.5 || status.fault == FaultCode::kFallHeight ||
         status.fault == FaultCode::kFallTilt;
}

}  // namespace pmg
