#pragma once
// The shipped G1 clips (config/clips/g1) behind a generator model, with the leg chains and their joint
// columns: the fixture of the reference-setting tests (sole levelling, stride adaptation).
#include <memory>

#include "g1_fixture.hpp"
#include "pmg/clips/clip_io.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace pmg::gco::test {

struct G1Reference {
  G1Reference()
      : robot(pmg::test::g1Robot()),
        model(std::make_shared<const GeneratorModel>(loadClipLibrary(pmg::test::g1ClipDir(), robot),
                                                     pmg::generatorJointSpace(robot))),
        legs(LegModel::fromRobotConfig(robot)),
        idx(legs->jointIndices(model->jointSpace().joint_names)) {}
  RobotConfig robot;
  std::shared_ptr<const GeneratorModel> model;
  std::shared_ptr<const LegModel> legs;
  LegJointIndex idx;
};

}  // namespace pmg::gco::test
