#pragma once
/// @file limb_separation.hpp
/// Limb-separated whole-body command (PMG paper, "limb separation"): the actor commands the
/// lower body (legs, and the waist if the contract says controls_waist); every other joint
/// (arms, and the waist otherwise) follows PMG or teleoperation targets open-loop.
///
/// Setup: constructed once from a checked contract. Loop: compose() is noexcept and writes
/// into a JointCommand sized at setup.

#include <vector>

#include "pmg/policy/contract.hpp"

namespace pmg::policy {

/// Whole-body joint PD command, robot joint order (nj entries each).
/// Motor torque law (applied by the HAL): tau = kp (q_des - q) + kd (qd_des - qd).
struct JointCommand {
  std::vector<double> q_des;   ///< (nj) [rad]
  std::vector<double> qd_des;  ///< (nj) [rad/s]
  std::vector<double> kp;      ///< (nj) [N*m/rad]
  std::vector<double> kd;      ///< (nj) [N*m*s/rad]
  /// Sizes all four vectors to nj (setup).
  void resize(std::size_t nj);
};

class LimbSeparation {
 public:
  /// @param contract a contract that passed checkContract (actuated joints are in joint_names).
  explicit LimbSeparation(const PolicyContract& contract);

  std::size_t numJoints() const noexcept { return is_actor_.size(); }
  /// True if robot joint j is commanded by the actor.
  bool isActorJoint(std::size_t j) const noexcept { return is_actor_[j]; }
  /// Robot joint index of actuated entry i (actuated order -> robot order).
  const std::vector<int>& actorJointIndex() const noexcept { return actor_index_; }

  /// Merges the actor's targets with the upper-body targets.
  /// @param actor_q_des (n_act) actor joint targets [rad], actuated order (PolicyRunner::jointTargets)
  /// @param upper_q_des (nj) PMG/teleop position targets [rad], robot order; only non-actor
  ///                    joints are read
  /// @param upper_qd_des (nj) PMG/teleop velocity targets [rad/s], robot order, or nullptr (= 0)
  /// @param out sized with out.resize(numJoints()); actor joints get qd_des = 0; kp/kd are the
  ///            contract's (equal to the robot config's after checkContract)
  void compose(const double* actor_q_des, const double* upper_q_des, const double* upper_qd_des,
               JointCommand& out) const noexcept;

 private:
  std::vector<bool> is_actor_;
  std::vector<int> actor_index_;
  std::vector<double> kp_, kd_;
};

}  // namespace pmg::policy
