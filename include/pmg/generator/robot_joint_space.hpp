#pragma once
/// @file robot_joint_space.hpp
/// Builds the generator's joint space (q_stand, limits, mirror map) from the robot config.
/// Setup-time helper (allocates); links with pmg::common.

#include "pmg/common/robot_config.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/generator/joint_space.hpp"

namespace pmg {

/// Joint names, default standing pose, limits, mirror map and standing height of @p robot.
inline GeneratorJointSpace generatorJointSpace(const RobotConfig& robot) {
  GeneratorJointSpace js;
  js.joint_names = robot.jointNames();
  js.q_stand = robot.defaultPose();
  js.lower = robot.lowerLimits();
  js.upper = robot.upperLimits();
  js.mirror_index = robot.mirrorIndex();
  for (const auto& j : robot.joints) js.mirror_sign.push_back(j.mirror_sign);
  js.standing_base_height = robot.standing_base_height;
  js.source = robot.source_file;
  return js;
}

}  // namespace pmg
