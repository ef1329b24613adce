#pragma once
// The shipped G1 clips (config/clips/g1) behind a generator model, with the leg chains and their joint
// columns: the fixture of the reference-setting tests (sole levelling, stride adaptation).
#include <algorithm>
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

/// Tick k of a command step from (ud0, us0) to (ud1, us1), ramped over 0.5 s at 100 Hz as the controller's
/// command shaper does; written into *ud, *us.
inline void rampedCommand(const VelocityCommand& ud0, const PostureCommand& us0, const VelocityCommand& ud1,
                          const PostureCommand& us1, int k, VelocityCommand* ud, PostureCommand* us) {
  const double a = std::min(1.0, k / 50.0);
  *ud = {ud0.vx + a * (ud1.vx - ud0.vx), ud0.vy + a * (ud1.vy - ud0.vy), ud0.wz + a * (ud1.wz - ud0.wz)};
  *us = {us0.pitch + a * (us1.pitch - us0.pitch), us0.roll + a * (us1.roll - us0.roll),
         us0.height + a * (us1.height - us0.height)};
}

}  // namespace pmg::gco::test
