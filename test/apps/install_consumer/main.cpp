// Uses an installed pmg: the G1 config from the installed data directory (PMG_DATA_DIR or
// <prefix>/share/pmg), its KDL model and the generator's joint space.
#include <cstdio>
#include <exception>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/kinematics.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/generator/robot_joint_space.hpp"

int main() {
  try {
    const pmg::RobotConfig robot = pmg::loadRobotConfig(pmg::resolveData("config/robots/g1/g1.yaml").string());
    const pmg::KinematicModel kinematics(robot);
    const pmg::GeneratorJointSpace js = pmg::generatorJointSpace(robot);
    std::printf("pmg_consumer: %s, %zu joints, %u KDL segments, standing height %.2f m\n", robot.name.c_str(),
                js.joint_names.size(), kinematics.tree().getNrOfSegments(), js.standing_base_height);
    return js.joint_names.size() == robot.numJoints() && robot.numJoints() > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_consumer: %s\n", e.what());
    return 1;
  }
}
