#include "pmg/policy/policy_stage.hpp"

#include <cmath>

#include "pmg/policy/contract.hpp"

namespace pmg::policy {

PolicyStage::PolicyStage(const std::string& onnx_path, const RobotConfig& robot, const PolicyStageOptions& options)
    : options_(options), rng_(options.noise_seed) {
  PolicyRobotSpec spec = makePolicyRobotSpec(robot, options_.control_period);
  spec.pmg = {{"enabled", "true"}, {"gco", options_.gco ? "true" : "false"}, {"mode", options_.mode},
              {"sole_levelling", options_.sole_levelling ? "true" : "false"},
              {"stride_adaptation", options_.stride_adaptation ? "true" : "false"},
              {"stride_standing_hold", options_.stride_adaptation && options_.stride_standing_hold ? "true" : "false"},
              {"upright_walking", options_.upright_walking ? "true" : "false"},
              {"upper_body_ff", options_.upper_body_ff ? "true" : "false"}};
  if (!options_.clips_digest.empty()) spec.pmg["clips_digest"] = options_.clips_digest;
  PolicyRunnerOptions ropt;
  ropt.backend = options_.backend;
  runner_ = std::make_unique<PolicyRunner>(onnx_path, spec, ropt);
  obs_ = std::make_unique<ObservationAssembler>(runner_->contract().observation);
  split_ = std::make_unique<LimbSeparation>(runner_->contract());
  num_joints_ = static_cast<int>(robot.numJoints());
  num_actuated_ = runner_->actionSize();
  joint_command_.resize(robot.numJoints());
  const Eigen::VectorXd q0 = robot.defaultPose();
  q_default_.assign(q0.data(), q0.data() + q0.size());
  buffer_.assign(static_cast<std::size_t>(std::max(num_joints_, 8)), 0.0);
  // Every term the training environment writes must exist (throws naming the missing one).
  i_gyro_ = obs_->termIndex("base_ang_vel_B");
  i_grav_ = obs_->termIndex("projected_gravity_B");
  i_cmd_ = obs_->termIndex("command");
  i_q_ = obs_->termIndex("joint_pos_rel");
  i_qd_ = obs_->termIndex("joint_vel");
  i_act_ = obs_->termIndex("last_action");
  i_ref_ = obs_->termIndex("pmg_ref_q_rel");
  i_phase_ = obs_->termIndex("pmg_phase");
}

void PolicyStage::reset() noexcept {
  runner_->resetAction();
  obs_->reset();
}

PolicyStepStatus PolicyStage::step(const LowState& state, const std::array<double, 6>& command,
                                   const GeneratorOutput& g, LowCommand& out) noexcept {
  double* b = buffer_.data();
  const auto& qw = state.imu.quat_wxyz;  // world <- IMU
  // Gravity direction (0, 0, -1)_W in the IMU frame: −(third row of R_WI).
  const double w = qw[0], x = qw[1], y = qw[2], z = qw[3];
  const double r20 = 2 * (x * z - w * y), r21 = 2 * (y * z + w * x), r22 = 1 - 2 * (x * x + y * y);
  for (int i = 0; i < 3; ++i) b[i] = state.imu.gyro[static_cast<std::size_t>(i)] + noise(options_.noise_gyro);
  obs_->setTerm(i_gyro_, b);
  b[0] = -r20 + noise(options_.noise_gravity);
  b[1] = -r21 + noise(options_.noise_gravity);
  b[2] = -r22 + noise(options_.noise_gravity);
  obs_->setTerm(i_grav_, b);
  obs_->setTerm(i_cmd_, command.data());
  for (int j = 0; j < num_actuated_; ++j)
    b[j] = state.motors[static_cast<std::size_t>(j)].q - q_default_[static_cast<std::size_t>(j)] + noise(options_.noise_q);
  obs_->setTerm(i_q_, b);
  for (int j = 0; j < num_actuated_; ++j) b[j] = state.motors[static_cast<std::size_t>(j)].qd + noise(options_.noise_qd);
  obs_->setTerm(i_qd_, b);
  obs_->setTerm(i_act_, runner_->action());
  for (int j = 0; j < num_actuated_; ++j) b[j] = g.q_ref[j] - q_default_[static_cast<std::size_t>(j)];
  obs_->setTerm(i_ref_, b);
  const double phase[2] = {std::sin(2 * M_PI * g.phase), std::cos(2 * M_PI * g.phase)};
  obs_->setTerm(i_phase_, phase);
  PolicyStepStatus status;
  if (obs_->commit()) {
    status = runner_->step(obs_->data());
  } else {
    status.code = PolicyStepCode::kNonFiniteObservation;
  }
  if (!status.ok()) ++rejected_;
  split_->compose(runner_->jointTargets(), g.q_ref.data(), g.qd_ref.data(), joint_command_);
  for (int j = 0; j < num_joints_; ++j) {
    const auto k = static_cast<std::size_t>(j);
    out.motors[k] = MotorCommand{joint_command_.q_des[k], joint_command_.qd_des[k], joint_command_.kp[k],
                                 joint_command_.kd[k], 0.0};
  }
  return status;
}

}  // namespace pmg::policy
