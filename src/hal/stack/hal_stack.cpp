#include "pmg/hal/hal_stack.hpp"

#include "pmg/common/robot_config.hpp"
#include "pmg/hal/bus/can_backend.hpp"
#include "pmg/hal/safety/safe_backend.hpp"
#include "pmg/hal/zero_offset_backend.hpp"

namespace pmg {

HalStack makeHalStack(const RobotConfig& robot, const HalStackConfig& config, std::unique_ptr<HalBackend> backend) {
  if (!backend) {
    if (config.backend == BackendKind::kCan) {
      hal::bus::CanBackendSetup setup;
      setup.plan_file = config.can.plan_file;
      setup.robot = &robot;  // the robot config is the source of truth for bus/motor ids
      setup.transport = config.can.transport;
      setup.udp_base_port = static_cast<std::uint16_t>(config.can.udp_port);
      setup.lockstep = config.lockstep;
      setup.paced = config.can.paced;
      backend = hal::bus::makeCanBackend(setup);
    } else {
      backend = std::make_unique<MujocoBackend>(robot, config.mujoco);
    }
  }
  HalBackend* device = backend.get();
  if (robot.zeroOffsets().size() > 0 && robot.zeroOffsets().cwiseAbs().maxCoeff() > 0.0)
    backend = std::make_unique<ZeroOffsetBackend>(std::move(backend), robot.zeroOffsets());
  auto options = hal::safety::SafetyOptions::fromRobot(robot);
  options.period_s = backend->cyclePeriod();
  options.soft_stand_duration_s = config.soft_stand_duration_s;
  for (double& kd : options.damping_kd) kd *= config.damping_kd_scale;
  auto safe = std::make_unique<hal::safety::SafeBackend>(std::move(backend), options);
  HalStack stack;
  stack.safety = safe.get();
  stack.device = device;
  stack.backend = std::move(safe);
  return stack;
}

}  // namespace pmg
