#pragma once
// The 4-joint synthetic joint space of the generator tests: j0 <-> j1 a mirror pair (sign +1),
// j2 self-mirrored with sign -1, j3 self-mirrored with sign +1; limits ±3 rad; standing pelvis
// height 0.75 m.
#include <Eigen/Core>

#include "pmg/generator/joint_space.hpp"

namespace pmg::test {

inline constexpr int kSyntheticJoints = 4;

inline GeneratorJointSpace syntheticJointSpace() {
  GeneratorJointSpace js;
  js.joint_names = {"l", "r", "yaw", "pitch"};
  js.q_stand = Eigen::Vector4d(0.1, 0.1, 0.0, -0.2);
  js.lower = Eigen::VectorXd::Constant(kSyntheticJoints, -3.0);
  js.upper = Eigen::VectorXd::Constant(kSyntheticJoints, 3.0);
  js.mirror_index = {1, 0, 2, 3};
  js.mirror_sign = {1, 1, -1, 1};
  js.standing_base_height = 0.75;
  return js;
}

}  // namespace pmg::test
