#include "pmg/hal/hal_stack.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "pmg/common/robot_config.hpp"
#include "pmg/hal/bus/can_backend.hpp"
#include "pmg/hal/safety/safe_backend.hpp"
#include "pmg/hal/zero_offset_backend.hpp"

namespace pmg {

std::unique_ptr<HalBackend> makeCanBackendFor(const HalStackConfig& config) {
  hal::bus::CanBackendSetup setup;
  setup.plan_file = config.can.plan_file;
  setup.transport = config.can.transport;
  setup.udp_base_port = static_cast<std::uint16_t>(config.can.udp_port);
  setup.lockstep = config.lockstep;
  setup.paced = config.can.paced;
  return hal::bus::makeCanBackend(setup);
}

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
  options.envelope.q_rate_max = config.q_rate_max;
  const std::size_t n = options.joints.size();
  if ((!config.kp_max.empty() && config.kp_max.size() != n) || (!config.kd_max.empty() && config.kd_max.size() != n))
    throw std::invalid_argument("makeHalStack: kp_max / kd_max need " + std::to_string(n) + " values (one per joint) or none");
  if ((!config.stand_kp.empty() && config.stand_kp.size() != n) || (!config.stand_kd.empty() && config.stand_kd.size() != n))
    throw std::invalid_argument("makeHalStack: stand_kp / stand_kd need " + std::to_string(n) + " values (one per joint) or none");
  if (!config.stand_kp.empty()) options.stand_kp = config.stand_kp;
  if (!config.stand_kd.empty()) options.stand_kd = config.stand_kd;
  for (std::size_t j = 0; j < n; ++j) {
    options.joints[j].kp_max = std::max(options.joints[j].kp_max, options.stand_kp[j]);
    options.joints[j].kd_max = std::max(options.joints[j].kd_max, options.stand_kd[j]);
    if (!config.kp_max.empty()) options.joints[j].kp_max = std::max(options.joints[j].kp_max, config.kp_max[j]);
    if (!config.kd_max.empty()) options.joints[j].kd_max = std::max(options.joints[j].kd_max, config.kd_max[j]);
  }
  if (const std::string e = imuAccLowpassError(config.imu_acc_lowpass_s, backend->cyclePeriod()); !e.empty())
    throw std::invalid_argument("timing." + e);
  hal::safety::SafeBackendOptions backend_options;
  backend_options.imu_acc_lowpass_s = config.imu_acc_lowpass_s;
  auto safe = std::make_unique<hal::safety::SafeBackend>(std::move(backend), options, backend_options);
  HalStack stack;
  stack.safety = safe.get();
  stack.device = device;
  stack.backend = std::move(safe);
  return stack;
}

void engageActive(HalStack& stack, const RobotConfig& robot, double timeout_s) {
  LowCommand cmd;
  LowState st;
  cmd.num_motors = static_cast<int>(robot.numJoints());
  for (std::size_t i = 0; i < robot.numJoints(); ++i) {
    const JointConfig& j = robot.joints[i];
    cmd.motors[i] = MotorCommand{j.default_position, 0.0, j.kp, j.kd, 0.0};
  }
  const auto cycles = static_cast<long>(timeout_s / stack.backend->cyclePeriod());
  bool stand_posted = false, active_posted = false;
  long calm = 0;
  for (long c = 0; c < cycles; ++c) {
    ++cmd.sequence;
    stack.backend->exchange(cmd, st);
    bool answered = st.imu.valid;
    for (int i = 0; i < cmd.num_motors; ++i) answered = answered && st.motors[static_cast<std::size_t>(i)].valid;
    // Stand up only once the IMU reads plausibly (half the supervisor's ranges) for 50 ms: a
    // simulated robot placed on a stiff floor starts with a contact transient.
    const auto norm = [](const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
    const auto& w = stack.safety->supervisor().options().watchdog;
    calm = answered && norm(st.imu.acc) < 0.5 * w.imu_acc_max && norm(st.imu.gyro) < 0.5 * w.imu_omega_max ? calm + 1 : 0;
    answered = answered && calm >= static_cast<long>(0.05 / stack.backend->cyclePeriod());
    if (st.mode == Mode::kDamping) break;
    if (!stand_posted && st.mode == Mode::kPassive && answered) {
      stack.safety->requests().post(ModeRequest::kSoftStand);
      stand_posted = true;
    } else if (!active_posted && st.mode == Mode::kSoftStand && st.stand_progress >= 1.0) {
      stack.safety->requests().post(ModeRequest::kActive);
      active_posted = true;
    } else if (st.mode == Mode::kActive) {
      return;
    }
  }
  throw std::runtime_error(std::string("the HAL supervisor did not reach active (mode ") + toString(st.mode) +
                           ", fault " + toString(st.fault) + ")");
}

}  // namespace pmg
