#pragma once
/// @file joint_space.hpp
/// The joint space the PMG generator and the clip library work in: joint order, standing pose,
/// limits and the left/right mirror map (filled from the robot config by generatorJointSpace(),
/// include/pmg/generator/robot_joint_space.hpp). Plain data, header-only.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace pmg {

/// Joint order, standing pose, limits and mirror map of one robot (n joints).
///
/// Mirror convention (the robot config's `mirror` / `mirror_sign`): the left/right mirror image of
/// a joint vector q (reflection of the robot in its sagittal x-z plane) is
/// (M q)_j = mirror_sign_j · q_{mirror_index_j}. Joints about the y axis (pitch, knee, elbow) keep
/// their sign (+1); joints about x or z (roll, yaw) change it (−1), including the sagittal joints
/// that mirror onto themselves (waist yaw and roll). M is an involution: M M q = q.
struct GeneratorJointSpace {
  std::vector<std::string> joint_names;  ///< (n)
  Eigen::VectorXd q_stand;               ///< (n) standing pose [rad]
  Eigen::VectorXd lower, upper;          ///< (n) joint limits [rad]
  std::vector<int> mirror_index;         ///< (n) left/right mirror partner of each joint
  std::vector<int> mirror_sign;          ///< (n) ±1
  double standing_base_height = 0.78;    ///< pelvis height in q_stand [m]
  /// Where the joint space came from (robot config file), named in clip errors; may be empty.
  std::string source;
};

}  // namespace pmg
