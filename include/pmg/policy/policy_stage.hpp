#pragma once
/// @file policy_stage.hpp
/// The policy step of the 100 Hz loop, exactly as the training environment (training/pmg_train)
/// builds it: observation from the IMU, the joint encoders, the operator command, the last action,
/// the PMG reference and phase → PolicyRunner → limb separation (the actor drives the legs, and the
/// waist if its contract says so; every other joint follows the PMG/teleop targets open-loop).
///
/// Observation terms (names in the contract): base_ang_vel_B (IMU gyro, pelvis frame [rad/s]),
/// projected_gravity_B (gravity direction in the IMU frame, from the IMU orientation),
/// command (v_x, v_y, ω, pitch, roll, height), joint_pos_rel (q − q_default of the actuated joints
/// [rad]), joint_vel [rad/s], last_action, pmg_ref_q_rel (q_ref − q_default [rad]),
/// pmg_phase (sin 2πφ, cos 2πφ).
///
/// Setup (constructor) loads and checks the model against the robot config (throws naming the
/// field). step() is noexcept; it allocates nothing of its own (with PolicyBackend::kNative it is
/// allocation-free as a whole; ONNX Runtime allocates inside Run, docs/policy.md).

#include <array>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "pmg/common/robot_config.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/hal/types.hpp"
#include "pmg/policy/limb_separation.hpp"
#include "pmg/policy/observation.hpp"
#include "pmg/policy/policy_runner.hpp"

namespace pmg::policy {

struct PolicyStageOptions {
  PolicyBackend backend = PolicyBackend::kNative;  ///< kNative: allocation-free tick
  double control_period = 0.01;   ///< [s], must equal the contract's
  bool gco = false;               ///< the controller runs GCO (must match the contract)
  bool sole_levelling = false;    ///< the reference's stance soles are levelled (GcoOptions::sole_levelling; must match)
  bool stride_adaptation = false; ///< the reference's stance soles are held still (GcoOptions::stride_adaptation; must match)
  /// Standing, the stride adaptation keeps the feet where they landed (StrideAdaptationOptions::standing_hold).
  /// The contract's pmg.stride_standing_hold must equal stride_adaptation && stride_standing_hold.
  bool stride_standing_hold = false;
  bool upright_walking = false;   ///< the walking clips' waist lean is removed (GeneratorParams::upright_walking; must match)
  /// The controller feeds the waist joints' gravity torque forward (`upper_body: enabled`,
  /// pmg::UpperBodyCompensation). Must match the contract's pmg.upper_body_ff: an actor trained with
  /// the feed-forward in its environment (pmg-train --upper-body-ff) balances a waist that holds its
  /// reference, one trained without it a waist that sags under the arms.
  bool upper_body_ff = false;
  /// Reference the actor was trained on (must match the contract's pmg.mode): "pmg" = the PMG
  /// generator on all clips (the controller); "single_gait" = the generator on the forward-walk
  /// clip alone at its nominal speed (the Table I baseline; only pmg_policy_sil runs it).
  std::string mode = "pmg";
  /// pmg::clipsDigest of the clips the controller runs. Compared with the contract's
  /// pmg.clips_digest where the contract has one (actors exported since 2026-11-27); empty = not
  /// checked.
  std::string clips_digest;
  /// Gaussian sensor noise on the observation (evaluation as in training); 0 = none.
  double noise_gyro = 0, noise_gravity = 0, noise_q = 0, noise_qd = 0;
  unsigned noise_seed = 0;
};

class PolicyStage {
 public:
  PolicyStage(const std::string& onnx_path, const RobotConfig& robot, const PolicyStageOptions& options);

  /// Forgets the action history (call when the actor starts driving).
  void reset() noexcept;
  /// One tick: @p command = (v_x, v_y, ω, pitch, roll, height) as the actor was trained to see it;
  /// @p g the generator output of this tick; writes q/qd/kp/kd of all motors into @p out.
  /// Returns the runner's status (on a non-finite observation/action the last action is held).
  PolicyStepStatus step(const LowState& state, const std::array<double, 6>& command, const GeneratorOutput& g,
                        LowCommand& out) noexcept;

  const PolicyContract& contract() const noexcept { return runner_->contract(); }
  const PolicyRunner& runner() const noexcept { return *runner_; }
  /// The actor input of the last step() (runner().observationSize() floats: scaled, clipped, stacked
  /// as the contract lays it out), for probes that compare it with the training environment's.
  const float* observation() const noexcept { return obs_->data(); }
  std::uint64_t rejectedTicks() const noexcept { return rejected_; }

 private:
  double noise(double stddev) noexcept { return stddev > 0 ? stddev * gauss_(rng_) : 0.0; }

  PolicyStageOptions options_;
  std::unique_ptr<PolicyRunner> runner_;
  std::unique_ptr<ObservationAssembler> obs_;
  std::unique_ptr<LimbSeparation> split_;
  JointCommand joint_command_;
  std::vector<double> q_default_, buffer_;
  int i_gyro_, i_grav_, i_cmd_, i_q_, i_qd_, i_act_, i_ref_, i_phase_;
  int num_actuated_ = 0, num_joints_ = 0;
  std::mt19937 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  std::uint64_t rejected_ = 0;
};

}  // namespace pmg::policy
